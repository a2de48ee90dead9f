//! Contacts defined by first touch: objects whose top is not a single point on the
//! contact normal (a ring, a flat disc on the cylinder, a tilted cylinder). Several objects
//! in one frame, rigid poses and contacts that cannot touch are in tests/contact_scenes.rs.

mod presses;

use geltip::object::{dims, Object, Solid};
use geltip::render::{contact, Frame, Place, Press};
use geltip::sensor::Sensor;
use glam::DVec3;
use presses::*;
use std::sync::Arc;

/// First touch against analytic answers: a top point on the normal touches at offset 0
/// exactly (so the paper's seven solids sit with their tops at the place); the torus at the tip comes
/// in by exactly its minor radius (its tube's centre circle, radius 4, meets the 7.5 mm
/// hemisphere grown by 1 mm at sqrt(8.5^2 - 4^2) = 7.5 above the centre); the tube's inner
/// rim (radius 2) touches sqrt(7.5^2 - 2^2) - 7.5 mm in.
#[test]
fn first_touch_offsets_match_the_geometry() {
    let sensor = Sensor::preset("paper").unwrap();
    for solid in Solid::ALL {
        if solid == Solid::Tube {
            continue;
        }
        for place in [
            Place::Rotation(0.0),
            Place::Rotation(45.0),
            Place::Translation(5.0),
        ] {
            let pose = press(solid, place, 30.0, 1.0).pose(&sensor).unwrap();
            assert_eq!(pose.first_touch_offset_mm, 0.0, "{solid:?} at {place:?}");
            assert_eq!(pose.origin, pose.point - 1.0 * pose.normal);
        }
    }
    let r = sensor.finger.radius;
    let torus = press(Solid::Torus, Place::Rotation(0.0), 0.0, 0.6)
        .pose(&sensor)
        .unwrap();
    let want = -dims::TORUS_MINOR_RADIUS;
    assert!(
        (torus.first_touch_offset_mm - want).abs() < 1e-5,
        "torus at the tip: {} vs {want}",
        torus.first_touch_offset_mm
    );
    let tube = press(Solid::Tube, Place::Rotation(0.0), 0.0, 1.0)
        .pose(&sensor)
        .unwrap();
    let want = (r * r - dims::TUBE_INNER_RADIUS.powi(2)).sqrt() - r;
    assert!(
        (tube.first_touch_offset_mm - want).abs() < 1e-5,
        "tube at the tip: {} vs {want}",
        tube.first_touch_offset_mm
    );
    // On the cylinder's side the tube's flat rim meets the straight meridian at offset 0.
    let tube = press(Solid::Tube, Place::Translation(8.0), 0.0, 1.0)
        .pose(&sensor)
        .unwrap();
    assert!(tube.first_touch_offset_mm.abs() < 1e-5);
}

/// An edge's knife-sharp ridge lying across the finger at a slant: random dataset poses
/// (seed 2), where a search along the meridian and the parallel alone creeps along the
/// ridge and stops short (up to 0.046 mm, with 84 000 traces for one pose). Placed at its
/// first touch, no point of the ridge may be inside the finger, and the nearest must touch
/// it.
#[test]
fn first_touch_follows_a_slanted_ridge_to_its_top() {
    use geltip::jobs::dataset;
    let sensor = Sensor::preset("paper").unwrap();
    let objects = vec![Arc::new(Object::Solid(Solid::Edge))];
    let depths = dataset::default_depth_range(sensor.finger.shell_thickness);
    for k in 0..100 {
        let contact = dataset::sample_contact(&sensor, &objects, depths, 2, k).unwrap();
        let pose = contact.pose(&sensor).unwrap();
        let touching = pose.origin + pose.depth_mm * pose.normal;
        // The ridge: along x at the object's top (z = 0), 2001 points.
        let half = 0.5 * dims::EDGE_LENGTH;
        let deepest = (0..=2000)
            .map(|i| {
                let q = DVec3::new(-half + half * i as f64 / 1000.0, 0.0, 0.0);
                sensor
                    .finger
                    .signed_distance(touching + pose.world_from_object * q)
            })
            .fold(f64::INFINITY, f64::min);
        // The ridge need not touch at all (a face's corner may come first): then it stays
        // outside. Where the ridge touches, it touches to the search's tolerance.
        assert!(
            deepest > -1e-5,
            "sample {k}: the ridge is {deepest} mm inside at first touch"
        );
        if pose
            .first_touch
            .iter()
            .all(|p| pose.to_object(*p).z.abs() < 1e-6)
        {
            assert!(
                deepest < 1e-4,
                "sample {k}: the ridge stops {deepest} mm short"
            );
        }
    }
}

/// A torus: a ring (4 mm major radius) pressed 0.6 mm at rotation 60 changes the
/// image where the ring touches and not in its hole, and its labels report the ring.
#[test]
fn torus_marks_its_ring_not_its_hole() {
    let sensor = Sensor::preset("paper").unwrap();
    let mut r = paper();
    for place in [
        Place::Rotation(60.0),
        Place::Rotation(0.0),
        Place::Translation(6.0),
    ] {
        let p = press(Solid::Torus, place, 20.0, 0.6);
        let (frame, truth) = render_one(&mut r, &p);
        let reference = r.reference().clone();
        // Its top circle sits on a straight meridian of the cylinder (offset 0) but has to
        // come in to meet the hemisphere.
        if matches!(place, Place::Translation(_)) {
            assert_eq!(truth.first_touch_offset_mm, 0.0);
        } else {
            assert!(truth.first_touch_offset_mm < -0.3, "{place:?}");
        }
        // Pressed 0.6 mm along the contact normal; the ring meets skin whose normal leans
        // away from it, so the indentation along that skin's normal is about 0.6 cos(lean).
        let touch = truth.first_touch[0];
        let lean = sensor
            .finger
            .point_at(sensor.finger.coord_of(touch))
            .normal
            .dot(truth.normal);
        assert!(
            (truth.indentation_reached_mm - 0.6 * lean).abs() < 0.03,
            "{place:?}: reached {} against {}",
            truth.indentation_reached_mm,
            0.6 * lean
        );
        // The ring: touched first along (part of) a circle about 4 mm from the axis...
        assert!(!truth.first_touch.is_empty());
        for q in &truth.first_touch {
            let d = (*q - truth.point).length();
            assert!(
                (2.5..5.5).contains(&d),
                "{place:?}: first touch {d} mm off the axis"
            );
        }
        let deepest = truth.deepest_point.unwrap();
        let d = (deepest - truth.point).length();
        assert!((2.5..5.5).contains(&d), "{place:?}: deepest {d} mm off");
        // ... its centre in the hole (the ring's middle, within a millimetre).
        let centre = truth.contact_centre.unwrap();
        assert!((centre - truth.point).length() < 1.0, "{place:?}: {centre}");
        // The image: changed where the ring touches, unchanged in the hole.
        let hole = sensor.project(truth.point).unwrap();
        assert_eq!(
            rgb_at(&frame, hole),
            rgb_at(&reference, hole),
            "{place:?}: hole"
        );
        let touched = sensor.project(deepest).unwrap();
        let at = |f: &Frame, du: f64, dv: f64| rgb_at(f, touched + glam::DVec2::new(du, dv));
        let changed = (-3..=3)
            .flat_map(|du| (-3..=3).map(move |dv| (du as f64, dv as f64)))
            .filter(|&(du, dv)| at(&frame, du, dv) != at(&reference, du, dv))
            .count();
        assert!(
            changed > 10,
            "{place:?}: ring: {changed} of 49 pixels changed"
        );
        let index = |p: glam::DVec2| (p.y.round() * frame.width as f64 + p.x.round()) as usize;
        assert!(frame.indentation[index(touched)] > 0.3, "{place:?}");
        // In the hole the gel bulges out a few µm at most: not pressed.
        assert!(frame.indentation[index(hole)] < 0.01, "{place:?}");
        assert!(truth.mask_pixels > 100);
        // And the single-contact API gives the same frame.
        let contact = Press::at(p.object.clone(), place, 20.0, 0.6);
        let (single, truth1) = r.render(&contact).unwrap();
        assert!(single.rgba == frame.rgba);
        assert_eq!(truth1.first_touch_offset_mm, truth.first_touch_offset_mm);
    }
}

/// A flat disc on the cylinder's side touches along the straight meridian through the
/// contact point and indents the skin by the given depth all along that line.
#[test]
fn flat_disc_indents_its_first_touch_line_by_the_depth() {
    let sensor = Sensor::preset("paper").unwrap();
    let f = &sensor.finger;
    let depth = 0.4;
    let p = press(Solid::Disc, Place::Translation(8.0), 45.0, depth);
    let pose = p.pose(&sensor).unwrap();
    assert_eq!(pose.first_touch_offset_mm, 0.0);
    // The first-touch band is the meridian: same azimuth, several mm long.
    let phi = 45f64.to_radians();
    let zs: Vec<f64> = pose.first_touch.iter().map(|q| q.z).collect();
    for q in &pose.first_touch {
        // Within 10 µm of the tangent plane: 7.5 (1 - cos dphi) <= 0.01.
        assert!((q.y.atan2(q.x) - phi).abs() < 0.055, "{q}");
    }
    let span =
        zs.iter().cloned().fold(f64::MIN, f64::max) - zs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 6.0, "first-touch line {span} mm long");
    // The indentation at the surface point nearest `q`, traced to `tolerance`.
    let pen_near = |q: DVec3, tolerance: f64| {
        let at = f.point_at(f.coord_of(q));
        contact::penetration(&pose, &p.object, &at, pose.trace_depth_mm, 0.0, tolerance)
    };
    for dz in [-4.0, -2.0, 0.0, 2.0, 4.0] {
        let pen = pen_near(
            pose.point + DVec3::new(0.0, 0.0, dz),
            contact::TRACE_EPSILON_MM,
        );
        assert!((pen - depth).abs() < 2e-3, "at dz {dz}: {pen}");
    }
    // Across the line the cylinder falls away: less indentation 3 mm to the side.
    let pen = pen_near(
        pose.point + 3.0 * DVec3::new(-phi.sin(), phi.cos(), 0.0),
        1e-3,
    );
    assert!(pen < depth - 0.2, "{pen}");
    let (_, truth) = render_one(&mut paper(), &p);
    assert!((truth.indentation_reached_mm - depth).abs() < 0.01);
}

/// A cylinder tilted 20 degrees touches with its rim first, not its face's centre.
#[test]
fn tilted_cylinder_touches_with_its_rim() {
    let sensor = Sensor::preset("paper").unwrap();
    for (place, towards) in [
        (Place::Rotation(30.0), 0.0),
        (Place::Translation(5.0), 90.0),
        (Place::Rotation(60.0), 200.0),
    ] {
        let p = tilted(Solid::Cylinder, place, 10.0, 0.0, 20.0, towards, 0.5);
        let pose = p.pose(&sensor).unwrap();
        // The object where it first touched, in its own frame.
        let at_touch = pose.origin + (pose.depth_mm) * pose.normal;
        let q = pose.world_from_object.transpose() * (pose.first_touch[0] - at_touch);
        let rim = q.truncate().length();
        assert!(
            (rim - dims::CYLINDER_RADIUS).abs() < 0.02 && q.z.abs() < 0.02,
            "{place:?}: first touch at r {rim}, z {}",
            q.z
        );
        // Tilted about the face's centre, the rim dips into the finger: it backs off.
        assert!(pose.first_touch_offset_mm > 0.0);
        // Untilted, the face's centre (the contact point) touches first.
        let flat = tilted(Solid::Cylinder, place, 10.0, 0.0, 0.0, towards, 0.5)
            .pose(&sensor)
            .unwrap();
        assert_eq!(flat.first_touch_offset_mm, 0.0);
    }
}
