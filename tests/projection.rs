//! The projection map m and its inverse, round-tripped over the whole field of view of every
//! preset and every lens model: points to pixels and back within 1e-9 mm, pixels to points
//! and back within 1e-9 px, with the image centre, both sides of the sphere/cylinder junction
//! and the last 0.01 degree before the lens edge sampled on purpose.

mod common;

use geltip::finger::SurfaceCoord;
use geltip::{NotVisible, Region, Sensor};
use glam::{DVec2, DVec3};
use proptest::prelude::*;

const MM_TOL: f64 = 1e-9;
const PX_TOL: f64 = 1e-9;

/// Point -> pixel -> point. Returns whether the point was visible in the image.
fn check_point(sensor: &Sensor, coord: SurfaceCoord) -> bool {
    let sp = sensor.finger.point_at(coord);
    assert!(
        sp.point.is_finite() && sp.normal.is_finite(),
        "{}: non-finite surface point",
        sensor.name
    );
    match sensor.project(sp.point) {
        Ok(px) => {
            assert!(px.is_finite(), "{}: non-finite pixel", sensor.name);
            let back = sensor.unproject(px).unwrap_or_else(|| {
                panic!(
                    "{}: pixel {px} of {coord:?} unprojects to nothing",
                    sensor.name
                )
            });
            let err = (back.point - sp.point).length();
            assert!(
                err <= MM_TOL,
                "{}: {coord:?} -> {px} -> {} is {err:e} mm off",
                sensor.name,
                back.point
            );
            assert!(
                (back.normal - sp.normal).length() <= 1e-9,
                "{}: normal differs at {coord:?}",
                sensor.name
            );
            assert!(back.point.is_finite() && back.normal.is_finite());
            // Regions may only disagree on the junction ring itself.
            if (coord.s - sensor.finger.junction_s()).abs() > 1e-9 {
                assert_eq!(
                    back.region, sp.region,
                    "{}: region at {coord:?}",
                    sensor.name
                );
            }
            true
        }
        Err(NotVisible::OutsideImage { u, v }) => {
            assert!(u.is_finite() && v.is_finite());
            false
        }
        Err(why) => panic!(
            "{}: surface point {coord:?} inside the fov is not visible: {why}",
            sensor.name
        ),
    }
}

/// Pixel -> point -> pixel. Returns whether the pixel saw the finger.
fn check_pixel(sensor: &Sensor, px: DVec2) -> bool {
    match sensor.unproject(px) {
        Some(sp) => {
            assert!(
                sp.point.is_finite() && sp.normal.is_finite(),
                "{}: NaN at {px}",
                sensor.name
            );
            assert!(sensor.finger.signed_distance(sp.point).abs() < 1e-9);
            let back = sensor.project(sp.point).unwrap_or_else(|why| {
                panic!(
                    "{}: {px} -> {} is not visible: {why}",
                    sensor.name, sp.point
                )
            });
            let err = (back - px).length();
            assert!(
                err <= PX_TOL,
                "{}: {px} -> {} -> {back} is {err:e} px off",
                sensor.name,
                sp.point
            );
            true
        }
        None => {
            let rho = (px - sensor.principal).length();
            assert!(
                rho > sensor.lens.max_rho() * (1.0 - 1e-12),
                "{}: pixel {px} inside the lens circle saw nothing",
                sensor.name
            );
            false
        }
    }
}

/// Arc length from the tip of the last surface point inside the lens's field of view.
fn s_at_fov_edge(sensor: &Sensor) -> f64 {
    let t = sensor.lens.max_theta;
    let edge = sensor
        .finger
        .surface_along(DVec3::new(t.sin(), 0.0, t.cos()))
        .unwrap();
    sensor.finger.coord_of(edge.point).s
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn surface_points_round_trip(idx in 0usize..9, frac in 0.0f64..=1.0, phi in -std::f64::consts::PI..std::f64::consts::PI) {
        let sensors = common::all_sensors();
        let sensor = &sensors[idx % sensors.len()];
        let coord = SurfaceCoord { s: frac * s_at_fov_edge(sensor), phi };
        check_point(sensor, coord);
    }

    #[test]
    fn pixels_round_trip(idx in 0usize..9, fu in 0.0f64..=1.0, fv in 0.0f64..=1.0) {
        let sensors = common::all_sensors();
        let sensor = &sensors[idx % sensors.len()];
        let px = DVec2::new(fu * sensor.width as f64 - 0.5, fv * sensor.height as f64 - 0.5);
        check_pixel(sensor, px);
    }
}

#[test]
fn image_centre_and_tip() {
    for sensor in common::all_sensors() {
        let sp = sensor.unproject(sensor.principal).unwrap();
        assert_eq!(sp.region, Region::Hemisphere);
        assert!(
            (sp.point - sensor.finger.tip()).length() < 1e-12,
            "{}",
            sensor.name
        );
        assert!(check_pixel(&sensor, sensor.principal));
        let px = sensor.project(sensor.finger.tip()).unwrap();
        assert!((px - sensor.principal).length() < 1e-12);
        for offset in [1e-12, 1e-9, 1e-6, 0.5] {
            assert!(check_pixel(
                &sensor,
                sensor.principal + DVec2::new(offset, -offset)
            ));
            assert!(check_point(
                &sensor,
                SurfaceCoord {
                    s: offset,
                    phi: 0.7
                }
            ));
        }
    }
}

#[test]
fn both_sides_of_the_junction() {
    for sensor in common::all_sensors() {
        let f = sensor.finger;
        let js = f.junction_s();
        for eps in [0.0, 1e-12, 1e-9, 1e-6, 1e-3] {
            for phi in [0.0, 1.0, 2.5, -2.0] {
                for (s, region) in [(js - eps, Region::Hemisphere), (js + eps, Region::Cylinder)] {
                    assert!(
                        check_point(&sensor, SurfaceCoord { s, phi }),
                        "{} junction not visible",
                        sensor.name
                    );
                    if eps >= 1e-6 {
                        let px = sensor
                            .project(f.point_at(SurfaceCoord { s, phi }).point)
                            .unwrap();
                        assert_eq!(
                            sensor.unproject(px).unwrap().region,
                            region,
                            "{} s={s}",
                            sensor.name
                        );
                    }
                }
            }
        }
        // Pixels on either side of the junction's image circle.
        let rho_j = sensor.lens.project(f.junction_theta());
        for d in [-1e-6, 0.0, 1e-6, -0.3, 0.3] {
            let px = sensor.principal + DVec2::new(rho_j + d, 0.0);
            assert!(check_pixel(&sensor, px));
        }
    }
}

#[test]
fn last_hundredth_of_a_degree_before_the_lens_edge() {
    for sensor in common::all_sensors() {
        let max = sensor.lens.max_theta;
        let mut seen = 0;
        for i in 0..=100 {
            let theta = max - (0.01f64).to_radians() * i as f64 / 100.0;
            // Along +x and -x, where the image reaches furthest.
            for sign in [1.0, -1.0] {
                let dir = DVec3::new(sign * theta.sin(), 0.0, theta.cos());
                let sp = sensor.finger.surface_along(dir).unwrap();
                let coord = sensor.finger.coord_of(sp.point);
                if check_point(&sensor, coord) {
                    seen += 1;
                }
                let rho = sensor.lens.project(theta);
                let px = sensor.principal + DVec2::new(sign * rho, 0.0);
                if sensor.in_image(px) {
                    assert!(
                        check_pixel(&sensor, px),
                        "{}: edge pixel {px} saw nothing",
                        sensor.name
                    );
                }
            }
        }
        // Every preset's lens edge falls inside the image along x except the webcam, whose
        // 70 degree cone reaches the corners only.
        if sensor.name != "webcam70" {
            assert!(
                seen > 0,
                "{}: lens edge never inside the image",
                sensor.name
            );
        }
        // Just past the edge: not visible, and a pixel there sees nothing.
        let theta = max + 1e-6;
        let dir = DVec3::new(theta.sin(), 0.0, theta.cos());
        let sp = sensor.finger.surface_along(dir).unwrap();
        assert!(
            matches!(sensor.project(sp.point), Err(NotVisible::OutsideFov { .. })),
            "{}",
            sensor.name
        );
        let px = sensor.principal + DVec2::new(sensor.lens.max_rho() * (1.0 + 1e-9), 0.0);
        assert!(sensor.unproject(px).is_none());
    }
}

#[test]
fn points_off_the_finger_and_bad_input() {
    let sensor = Sensor::preset("paper").unwrap();
    assert!(matches!(
        sensor.project(DVec3::new(0.0, 0.0, 40.0)),
        Err(NotVisible::OutsideFinger { .. })
    ));
    assert!(matches!(
        sensor.project(DVec3::new(9.0, 0.0, 10.0)),
        Err(NotVisible::OutsideFinger { .. })
    ));
    assert!(matches!(
        sensor.project(DVec3::ZERO),
        Err(NotVisible::AtCamera)
    ));
    assert!(matches!(
        sensor.project(DVec3::new(f64::NAN, 0.0, 1.0)),
        Err(NotVisible::NotFinite)
    ));
    assert!(matches!(
        sensor.project(DVec3::new(1.0, 0.0, -5.0)),
        Err(NotVisible::OutsideFov { .. })
    ));
    // Inside the finger the camera still sees the point (the renderer relies on it).
    assert!(sensor.project(DVec3::new(1.0, 2.0, 15.0)).is_ok());
    assert!(sensor.unproject(DVec2::new(f64::NAN, 3.0)).is_none());
    assert!(sensor.unproject(DVec2::new(-1.0, 240.0)).is_none());
    assert!(sensor.unproject(DVec2::new(640.0, 240.0)).is_none());
    // The corners of the paper's image lie outside the fisheye's circle.
    assert!(sensor.unproject(DVec2::new(0.0, 0.0)).is_none());
}
