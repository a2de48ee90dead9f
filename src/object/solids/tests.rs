use super::*;
use crate::object::test_rng::Rng;
use std::collections::HashMap;
use std::f64::consts::PI;

#[test]
fn names_and_ids_round_trip() {
    for (i, s) in Solid::ALL.into_iter().enumerate() {
        assert_eq!(s.id() as usize, i);
        assert_eq!(Solid::from_name(s.name()), Some(s));
        assert_eq!(Solid::from_id(s.id()), Some(s));
    }
    for (i, s) in Solid::EXTRA.into_iter().enumerate() {
        assert_eq!(s.id() as usize, Solid::ALL.len() + i);
        assert_eq!(Solid::from_name(s.name()), Some(s));
        assert_eq!(Solid::from_id(s.id()), Some(s));
    }
    assert_eq!(Solid::from_name("Cone"), None);
    assert_eq!(Solid::from_id(9), None);
}

#[test]
fn pentagon_is_convex_counter_clockwise_and_centred() {
    let v: Vec<DVec2> = PRISM_PENTAGON
        .iter()
        .map(|&[x, y]| DVec2::new(x, y))
        .collect();
    for i in 0..5 {
        let (a, b, c) = (v[i], v[(i + 1) % 5], v[(i + 2) % 5]);
        assert!((b - a).perp_dot(c - b) > 0.0, "corner {} not convex", i + 1);
    }
    let lo = v.iter().fold(DVec2::INFINITY, |m, &q| m.min(q));
    let hi = v.iter().fold(DVec2::NEG_INFINITY, |m, &q| m.max(q));
    assert_eq!((lo + hi) / 2.0, DVec2::ZERO);
}

#[test]
fn polygon_sdf_matches_brute_force() {
    // Distance to the nearest edge, sign from a winding test: independent of sd_polygon.
    let v: Vec<DVec2> = PRISM_PENTAGON
        .iter()
        .map(|&[x, y]| DVec2::new(x, y))
        .collect();
    let mut rng = Rng(7);
    for _ in 0..2000 {
        let p = DVec2::new(rng.next() * 12.0 - 6.0, rng.next() * 12.0 - 6.0);
        let mut d = f64::INFINITY;
        let mut inside = true;
        for i in 0..5 {
            let (a, b) = (v[i], v[(i + 1) % 5]);
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            d = d.min((p - (a + (b - a) * t)).length());
            inside &= (b - a).perp_dot(p - a) > 0.0;
        }
        let expected = if inside { -d } else { d };
        assert!((sd_polygon(&PRISM_PENTAGON, p) - expected).abs() < 1e-12);
    }
}

#[test]
fn known_points() {
    use Solid::*;
    let cases: [(Solid, [f64; 3], f64); 16] = [
        (Cone, [0.0, 0.0, 1.0], 1.0),
        (Cone, [0.0, 0.0, -11.0], 1.0),
        (Cone, [0.0, 0.0, -9.0], -1.0),
        (Sphere, [0.0, 0.0, -5.0], -5.0),
        (Sphere, [3.0, 4.0, -5.0], 0.0),
        (Sphere, [0.0, 0.0, 2.0], 2.0),
        (IrregularPrism, [0.0, 0.0, 1.0], 1.0),
        (Cylinder, [3.0, 0.0, -5.0], 1.0),
        (Cylinder, [0.0, 0.0, -5.0], -2.0),
        (Edge, [7.0, 0.0, 0.0], 2.0),
        (Edge, [0.0, 0.0, -6.0], 1.0),
        (Tube, [0.0, 0.0, -5.0], 2.0),
        (Tube, [2.5, 0.0, -5.0], -0.5),
        (Tube, [2.5, 0.0, 1.0], 1.0),
        (Slab, [0.0, 0.0, -1.5], -1.5),
        (Slab, [8.0, 7.0, -1.5], 5.0),
    ];
    for (s, p, d) in cases {
        let got = s.sdf(DVec3::from(p));
        assert!((got - d).abs() < 1e-12, "{s} at {p:?}: {got} != {d}");
    }
    assert!(IrregularPrism.sdf(DVec3::new(0.0, 0.0, -5.0)) < -2.0);
    // The cone's slanted side: distance along the side's normal.
    let n = DVec2::new(CONE_HEIGHT, CONE_RADIUS).normalize();
    let on_side = DVec2::new(2.5, -5.0);
    let q = on_side + n * 0.3;
    assert!((Cone.sdf(DVec3::new(q.x, 0.0, q.y)) - 0.3).abs() < 1e-12);
}

#[test]
fn every_top_touches_the_origin() {
    for s in Solid::ALL {
        if s == Solid::Tube {
            // The tube's top is a ring around the origin: the origin is in the hole.
            assert_eq!(s.sdf(DVec3::ZERO), TUBE_INNER_RADIUS);
            let ring = (TUBE_INNER_RADIUS + TUBE_OUTER_RADIUS) / 2.0;
            assert_eq!(s.sdf(DVec3::new(0.0, ring, 0.0)), 0.0);
        } else {
            assert!(s.sdf(DVec3::ZERO).abs() < 1e-12, "{s}");
        }
        assert!(s.sdf(DVec3::new(0.0, 0.0, 0.5)) > 0.49, "{s}");
    }
}

#[test]
fn meshes_are_closed_and_outward() {
    for s in Solid::ALL {
        let m = s.mesh();
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &m.triangles {
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "{s}");
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
            }
        }
        // Each undirected edge used once in each direction: closed and consistent.
        assert!(edges.values().all(|&c| c == 0), "{s}: open or inconsistent");
        assert!(m.signed_volume() > 0.0, "{s}: inward");
        let max_z = m.positions.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        assert_eq!(max_z, 0.0, "{s}");
        // Every vertex lies on the analytic surface.
        for p in &m.positions {
            assert!(s.sdf(*p).abs() < 1e-9, "{s}: vertex {p} off the surface");
        }
    }
}

#[test]
fn mesh_volumes_match_the_shapes() {
    let expected = [
        PI * CONE_RADIUS.powi(2) * CONE_HEIGHT / 3.0,
        4.0 / 3.0 * PI * SPHERE_RADIUS.powi(3),
        f64::NAN,
        PI * CYLINDER_RADIUS.powi(2) * CYLINDER_HEIGHT,
        EDGE_WIDTH * EDGE_HEIGHT / 2.0 * EDGE_LENGTH,
        PI * (TUBE_OUTER_RADIUS.powi(2) - TUBE_INNER_RADIUS.powi(2)) * TUBE_HEIGHT,
        SLAB_X * SLAB_Y * SLAB_Z,
    ];
    for (s, v) in Solid::ALL.into_iter().zip(expected) {
        if v.is_nan() {
            continue;
        }
        let got = s.mesh().signed_volume();
        assert!((got - v).abs() < 0.01 * v, "{s}: volume {got} != {v}");
    }
}

#[test]
fn radii_bound_the_solid() {
    let mut rng = Rng(3);
    for s in Solid::ALL {
        let (br, fr) = (s.bounding_radius(), s.footprint_radius());
        let (mut max_b, mut max_f) = (0.0f64, 0.0f64);
        for _ in 0..20000 {
            let p = rng.in_box(DVec3::new(-br, -br, -br), DVec3::new(br, br, 0.0));
            if s.sdf(p) <= 0.0 {
                max_b = max_b.max(p.length());
                max_f = max_f.max(p.truncate().length());
            }
        }
        for p in s.mesh().positions {
            max_b = max_b.max(p.length());
            max_f = max_f.max(p.truncate().length());
        }
        assert!(
            max_b <= br + 1e-9 && max_b > 0.97 * br,
            "{s}: {max_b} vs {br}"
        );
        assert!(
            max_f <= fr + 1e-9 && max_f > 0.97 * fr,
            "{s}: {max_f} vs {fr}"
        );
    }
}
