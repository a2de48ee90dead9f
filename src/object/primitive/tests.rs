use super::*;
use crate::object::test_rng::Rng;
use crate::object::Solid;
use std::f64::consts::PI;

fn parse(text: &str) -> Primitive {
    Primitive::parse(text)
        .unwrap_or_else(|e| panic!("{text}: {e}"))
        .unwrap_or_else(|| panic!("{text}: not a primitive"))
}

fn all() -> Vec<Primitive> {
    [
        "sphere:r=5",
        "capsule:r=2,l=8",
        "cylinder:r=2,l=10",
        "box:x=10,y=6,z=4",
        "ellipsoid:x=8,y=6,z=4",
        "ellipsoid:x=3,y=9,z=5.5",
        "ellipsoid:x=6,y=6,z=2",
    ]
    .map(parse)
    .to_vec()
}

#[test]
fn text_round_trips_and_names_the_kind() {
    for p in all() {
        let text = p.to_string();
        assert_eq!(parse(&text), p, "{text}");
        assert!(text.starts_with(&format!("{}:", p.name())));
        assert_eq!(
            Primitive::NAMES[(p.kind() - FIRST_PRIMITIVE_KIND) as usize],
            p.name()
        );
    }
    assert_eq!(
        parse(" box : z=4 , x=10,y=6 "),
        Primitive::Box {
            size: DVec3::new(10.0, 6.0, 4.0)
        }
    );
    assert_eq!(parse("sphere:r=12.5").to_string(), "sphere:r=12.5");
    assert_eq!(
        parse("capsule:r=0.1,l=1e2").to_string(),
        "capsule:r=0.1,l=100"
    );
    // Not a primitive's text: left to the other kinds of object.
    for text in ["sphere", "cone:r=2", "meshes/box.obj", "C:/box.obj", ""] {
        assert!(Primitive::parse(text).unwrap().is_none(), "{text}");
    }
    // Every example of the syntax parses.
    for example in PRIMITIVE_SYNTAX.split(", ") {
        parse(example);
    }
}

#[test]
fn bad_sizes_are_refused_naming_them() {
    for (text, says) in [
        (
            "box:x=10,y=6",
            "object 'box:x=10,y=6': a box needs x, y, z (its edge lengths, mm); z is missing",
        ),
        (
            "sphere:r=0",
            "object 'sphere:r=0': r must be a size from 0.001 to 10000 mm, got 0",
        ),
        (
            "sphere:r=-2",
            "r must be a size from 0.001 to 10000 mm, got -2",
        ),
        (
            "cylinder:r=2,l=1e9",
            "l must be a size from 0.001 to 10000 mm, got 1000000000",
        ),
        (
            "capsule:r=NaN,l=2",
            "r must be a size from 0.001 to 10000 mm, got NaN",
        ),
        (
            "capsule:r=inf,l=2",
            "r must be a size from 0.001 to 10000 mm, got inf",
        ),
        ("sphere:r=x", "r: 'x' is not a number"),
        ("sphere:r=1,r=2", "r is given twice"),
        (
            "sphere:5",
            "expected sizes as key=value (e.g. sphere:r=5), got '5'",
        ),
        ("sphere:", "expected sizes as key=value"),
        (
            "box:x=1,y=1,z=1,w=1",
            "unknown size 'w' for a box (it takes x, y, z)",
        ),
        ("ellipsoid:r=2", "unknown size 'r' for a ellipsoid"),
    ] {
        let e = Primitive::parse(text).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(says), "{text}: {msg}");
        assert!(!msg.contains('\n'), "{text}: {msg}");
        assert!(matches!(e, GeltipError::InvalidInput { .. }), "{text}");
    }
}

#[test]
fn sizes_equal_to_a_builtin_solid_give_its_sdf() {
    use crate::object::dims::*;
    let twins = [
        (Solid::Sphere, parse(&format!("sphere:r={SPHERE_RADIUS}"))),
        (
            Solid::Cylinder,
            parse(&format!("cylinder:r={CYLINDER_RADIUS},l={CYLINDER_HEIGHT}")),
        ),
        (
            Solid::Slab,
            parse(&format!("box:x={SLAB_X},y={SLAB_Y},z={SLAB_Z}")),
        ),
        (
            Solid::Disc,
            parse(&format!("cylinder:r={DISC_RADIUS},l={DISC_THICKNESS}")),
        ),
    ];
    let mut rng = Rng(3);
    for (solid, p) in twins {
        for _ in 0..2000 {
            let q = rng.in_box(DVec3::new(-8.0, -8.0, -14.0), DVec3::new(8.0, 8.0, 3.0));
            assert!((solid.sdf(q) - p.sdf(q)).abs() < 1e-12, "{p} at {q}");
        }
        assert_eq!(solid.bounding_radius(), p.bounding_radius(), "{p}");
        assert_eq!(solid.footprint_radius(), p.footprint_radius(), "{p}");
    }
    // A round ellipsoid is a sphere.
    let ball = parse("ellipsoid:x=10,y=10,z=10");
    for _ in 0..2000 {
        let q = rng.in_box(DVec3::new(-8.0, -8.0, -14.0), DVec3::new(8.0, 8.0, 3.0));
        assert!((ball.sdf(q) - Solid::Sphere.sdf(q)).abs() < 1e-9, "at {q}");
    }
}

/// Points on the primitive's surface, about `step` mm apart, in the object frame.
fn surface_points(p: &Primitive, step: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    let top = DVec3::new(0.0, 0.0, -p.top());
    let ring = |r: f64| ((2.0 * PI * r / step).ceil() as usize).max(8);
    match *p {
        Primitive::Sphere { r } => {
            return surface_points(
                &Primitive::Ellipsoid {
                    size: DVec3::splat(2.0 * r),
                },
                step,
            )
        }
        Primitive::Ellipsoid { size } => {
            let e = size / 2.0;
            let n = ((PI * e.max_element() / step).ceil() as usize).max(8);
            for i in 0..=n {
                let t = PI * i as f64 / n as f64;
                let m = ring(e.max_element() * t.sin());
                for j in 0..m {
                    let f = 2.0 * PI * j as f64 / m as f64;
                    out.push(top + e * DVec3::new(t.sin() * f.cos(), t.sin() * f.sin(), t.cos()));
                }
            }
        }
        Primitive::Capsule { r, l } => {
            let n = ((PI * r / step).ceil() as usize).max(8);
            for i in 0..=n {
                let t = PI * i as f64 / n as f64;
                let z = if i <= n / 2 { l / 2.0 } else { -l / 2.0 } + r * t.cos();
                for j in 0..ring(r) {
                    let f = 2.0 * PI * j as f64 / ring(r) as f64;
                    out.push(top + DVec3::new(r * t.sin() * f.cos(), r * t.sin() * f.sin(), z));
                }
            }
            for k in 0..=((l / step).ceil() as usize) {
                let z = -l / 2.0 + l * k as f64 / (l / step).ceil();
                for j in 0..ring(r) {
                    let f = 2.0 * PI * j as f64 / ring(r) as f64;
                    out.push(top + DVec3::new(r * f.cos(), r * f.sin(), z));
                }
            }
        }
        Primitive::Cylinder { .. } | Primitive::Box { .. } => {
            // A fine grid over the bounding box, kept where the SDF is ~0 (both are exact
            // piecewise simple shapes; this only feeds the bounds checks).
            let h = match *p {
                Primitive::Cylinder { r, l } => DVec3::new(r, r, l / 2.0),
                Primitive::Box { size } => size / 2.0,
                _ => unreachable!(),
            };
            let n = (2.0 * h / step).ceil().as_uvec3();
            for i in 0..=n.x {
                for j in 0..=n.y {
                    for k in 0..=n.z {
                        let q = top - h
                            + 2.0
                                * h
                                * DVec3::new(
                                    i as f64 / n.x as f64,
                                    j as f64 / n.y as f64,
                                    k as f64 / n.z as f64,
                                );
                        if p.sdf(q).abs() < step {
                            out.push(q);
                        }
                    }
                }
            }
        }
    }
    out
}

#[test]
fn sdfs_are_exact_distances() {
    let mut rng = Rng(11);
    for p in all() {
        let step = 0.02;
        let surface = surface_points(&p, step);
        let r = p.bounding_radius() + 2.0;
        let mut checked = 0;
        while checked < 60 {
            let q = rng.in_box(DVec3::new(-r, -r, -r), DVec3::new(r, r, 2.0));
            let d = p.sdf(q);
            // Outside up to 2 mm (the skin's drape traces that far out), or inside.
            if d > 2.0 {
                continue;
            }
            checked += 1;
            if matches!(p, Primitive::Cylinder { .. } | Primitive::Box { .. }) {
                continue; // their grids are SDF-made; the twins test holds them to the solids
            }
            let nearest = surface
                .iter()
                .map(|s| (*s - q).length())
                .fold(f64::INFINITY, f64::min);
            // No sampled surface point closer than the SDF says, and one about as close (the
            // samples lie `step` apart).
            assert!(
                nearest >= d.abs() - 1e-9,
                "{p} at {q}: sdf {d}, a surface point at {nearest}"
            );
            assert!(
                nearest <= d.abs() + step,
                "{p} at {q}: sdf {d}, nearest sample {nearest}"
            );
        }
    }
}

#[test]
fn top_is_at_the_origin_and_bounds_hold() {
    for p in all() {
        assert!(p.sdf(DVec3::ZERO).abs() < 1e-12, "{p}: top");
        assert!(
            p.sdf(DVec3::new(0.0, 0.0, 1e-3)) > 0.0,
            "{p}: above the top"
        );
        assert!(
            p.sdf(DVec3::new(0.0, 0.0, -1e-3)) < 0.0,
            "{p}: below the top"
        );
        let surface = surface_points(&p, 0.05);
        let radius = surface.iter().map(|s| s.length()).fold(0.0, f64::max);
        let axis = surface
            .iter()
            .map(|s| s.truncate().length())
            .fold(0.0, f64::max);
        let zmax = surface
            .iter()
            .map(|s| s.z)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(zmax <= 0.05, "{p}: reaches z = {zmax}");
        assert!(
            radius <= p.bounding_radius() + 0.05,
            "{p}: {radius} > {}",
            p.bounding_radius()
        );
        assert!(
            axis <= p.footprint_radius() + 0.05,
            "{p}: {axis} > {}",
            p.footprint_radius()
        );
        assert!(
            axis >= p.footprint_radius() - 0.1,
            "{p}: footprint {axis} < {}",
            p.footprint_radius()
        );
    }
}

#[test]
fn gpu_sizes_follow_the_shader_layout() {
    assert_eq!(parse("sphere:r=5").gpu_size(), [5.0, 0.0, 0.0, 0.0]);
    assert_eq!(parse("capsule:r=2,l=8").gpu_size(), [2.0, 8.0, 0.0, 0.0]);
    assert_eq!(parse("cylinder:r=2,l=10").gpu_size(), [2.0, 10.0, 0.0, 0.0]);
    assert_eq!(parse("box:x=10,y=6,z=4").gpu_size(), [5.0, 3.0, 2.0, 0.0]);
    assert_eq!(
        parse("ellipsoid:x=8,y=6,z=4").gpu_size(),
        [4.0, 3.0, 2.0, 0.0]
    );
}

#[test]
fn object_lists_keep_a_primitives_commas() {
    assert_eq!(
        split_objects("sphere,box:x=10,y=6,z=4,cone,capsule:r=2,l=8,m/a=b.obj"),
        [
            "sphere",
            "box:x=10,y=6,z=4",
            "cone",
            "capsule:r=2,l=8",
            "m/a=b.obj"
        ]
    );
    assert_eq!(split_objects("cone"), ["cone"]);
    assert_eq!(split_objects("x=1,sphere:r=2"), ["x=1", "sphere:r=2"]);
}
