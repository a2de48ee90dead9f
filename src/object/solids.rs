//! The seven 3D-printed test solids of the GelTip paper (IROS 2020, section on contact
//! localisation): cone, sphere, irregular prism, cylinder, edge, tube and slab.
//!
//! Every solid lives in the object frame: its contact top is at the origin, its body lies in
//! `z <= 0` and the finger comes from `+z`. Each has an exact analytic signed distance
//! function (mm, negative inside) and a closed, outward-wound triangle mesh.
//!
//! The SDFs are built from three exact pieces: a 2D SDF of a cross-section, turned into 3D
//! either by revolution about the z axis (evaluate the 2D SDF of the section mirrored about
//! the axis at `(sqrt(x^2 + y^2), z)`) or by extrusion along an axis. Both are exact for the
//! shapes used here, so every SDF is 1-Lipschitz and equal to the true Euclidean distance.
//!
//! Twin: `shaders/shared/object.wgsl` implements the same functions in f32 with the same
//! constants ([`dims`] here, `OBJ_*` there); `tests/objects.rs` checks that the constants
//! agree.

use super::mesh::Mesh;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// The solids' dimensions in millimetres: the one place they are written on the Rust side.
///
/// Twin: the `OBJ_*` constants of `shaders/shared/object.wgsl` (same names without the
/// prefix); change both together.
pub mod dims {
    /// Cone: base radius, apex up at the origin.
    pub const CONE_RADIUS: f64 = 5.0;
    /// Cone: apex to base.
    pub const CONE_HEIGHT: f64 = 10.0;
    /// Sphere radius (centre at `(0, 0, -SPHERE_RADIUS)`).
    pub const SPHERE_RADIUS: f64 = 5.0;
    /// Irregular prism: height of the upright prism (flat top at z = 0).
    pub const PRISM_HEIGHT: f64 = 10.0;
    /// Irregular prism: its cross-section, a convex irregular pentagon, counter-clockwise,
    /// 7.0 mm (x) by 6.5 mm (y), its bounding box centred on the z axis. Multiples of 1/8 so
    /// that f32 and f64 hold them exactly.
    pub const PRISM_PENTAGON: [[f64; 2]; 5] = [
        [3.5, 0.5],
        [1.0, 3.25],
        [-2.875, 2.5],
        [-3.5, -1.5],
        [0.625, -3.25],
    ];
    /// Cylinder radius (flat top disc at z = 0).
    pub const CYLINDER_RADIUS: f64 = 2.0;
    /// Cylinder height.
    pub const CYLINDER_HEIGHT: f64 = 10.0;
    /// Edge: a triangular prism lying down, its ridge along x at z = 0; ridge length.
    pub const EDGE_LENGTH: f64 = 10.0;
    /// Edge: width of its base (along y).
    pub const EDGE_WIDTH: f64 = 6.0;
    /// Edge: ridge to base.
    pub const EDGE_HEIGHT: f64 = 5.0;
    /// Tube: outer radius (the contact is a ring).
    pub const TUBE_OUTER_RADIUS: f64 = 3.0;
    /// Tube: inner radius (hollow through its whole height).
    pub const TUBE_INNER_RADIUS: f64 = 2.0;
    /// Tube height.
    pub const TUBE_HEIGHT: f64 = 10.0;
    /// Slab: size along x.
    pub const SLAB_X: f64 = 10.0;
    /// Slab: size along y.
    pub const SLAB_Y: f64 = 6.0;
    /// Slab: size along z (its large 10 x 6 face is up, at z = 0).
    pub const SLAB_Z: f64 = 3.0;
    /// Segments around round solids in their meshes (not used by the SDFs).
    pub const ROUND_SEGMENTS: u32 = 64;
    /// Torus (a ring, not one of the paper's seven): radius of its centre circle, axis z.
    pub const TORUS_MAJOR_RADIUS: f64 = 4.0;
    /// Torus: radius of its tube (top at z = 0, centre circle at z = -TORUS_MINOR_RADIUS).
    pub const TORUS_MINOR_RADIUS: f64 = 1.0;
    /// Disc (a coin, not one of the paper's seven): radius, flat face at z = 0.
    pub const DISC_RADIUS: f64 = 5.0;
    /// Disc: thickness.
    pub const DISC_THICKNESS: f64 = 1.0;
}

use dims::*;

/// The cone's meridian section, mirrored about the axis: (r, z) triangle, apex at the origin.
const CONE_SECTION: [[f64; 2]; 3] = [
    [0.0, 0.0],
    [-CONE_RADIUS, -CONE_HEIGHT],
    [CONE_RADIUS, -CONE_HEIGHT],
];

/// The edge's cross-section in the (y, z) plane, ridge at the origin.
const EDGE_SECTION: [[f64; 2]; 3] = [
    [0.0, 0.0],
    [-EDGE_WIDTH / 2.0, -EDGE_HEIGHT],
    [EDGE_WIDTH / 2.0, -EDGE_HEIGHT],
];

/// One of the seven built-in test solids.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Solid {
    Cone,
    Sphere,
    IrregularPrism,
    Cylinder,
    Edge,
    Tube,
    Slab,
    /// Not one of the paper's seven: a ring whose top is a circle around the axis (its
    /// origin lies in the hole).
    Torus,
    /// Not one of the paper's seven: a thin flat disc.
    Disc,
}

impl Solid {
    /// All solids, in the paper's order (which is also the order of their ids).
    pub const ALL: [Solid; 7] = [
        Solid::Cone,
        Solid::Sphere,
        Solid::IrregularPrism,
        Solid::Cylinder,
        Solid::Edge,
        Solid::Tube,
        Solid::Slab,
    ];

    /// Extra solids for testing contacts that are not a single top point (not in the
    /// paper's experiment, not written by `geltip objects`).
    pub const EXTRA: [Solid; 2] = [Solid::Torus, Solid::Disc];

    /// The name used on the command line and for asset files.
    pub fn name(self) -> &'static str {
        match self {
            Solid::Cone => "cone",
            Solid::Sphere => "sphere",
            Solid::IrregularPrism => "irregular-prism",
            Solid::Cylinder => "cylinder",
            Solid::Edge => "edge",
            Solid::Tube => "tube",
            Solid::Slab => "slab",
            Solid::Torus => "torus",
            Solid::Disc => "disc",
        }
    }

    /// The solid called `name` (exactly as [`Solid::name`] writes it), if any.
    pub fn from_name(name: &str) -> Option<Solid> {
        Solid::ALL
            .into_iter()
            .chain(Solid::EXTRA)
            .find(|s| s.name() == name)
    }

    /// The solid's id, 0..=6 for the seven (7, 8 for the extras), as used by `solid_sdf(id, p)` in `shaders/shared/object.wgsl`.
    pub fn id(self) -> u32 {
        match self {
            Solid::Cone => 0,
            Solid::Sphere => 1,
            Solid::IrregularPrism => 2,
            Solid::Cylinder => 3,
            Solid::Edge => 4,
            Solid::Tube => 5,
            Solid::Slab => 6,
            Solid::Torus => 7,
            Solid::Disc => 8,
        }
    }

    /// The solid with id `id`, if any.
    pub fn from_id(id: u32) -> Option<Solid> {
        Solid::ALL
            .into_iter()
            .chain(Solid::EXTRA)
            .find(|s| s.id() == id)
    }

    /// Exact signed distance (mm) from `p` (object frame) to the solid: negative inside.
    ///
    /// Twin: `solid_sdf` in `shaders/shared/object.wgsl`.
    pub fn sdf(&self, p: DVec3) -> f64 {
        let r = p.truncate().length();
        match self {
            Solid::Cone => sd_polygon(&CONE_SECTION, DVec2::new(r, p.z)),
            Solid::Sphere => (p - DVec3::new(0.0, 0.0, -SPHERE_RADIUS)).length() - SPHERE_RADIUS,
            Solid::IrregularPrism => extrude(
                sd_polygon(&PRISM_PENTAGON, p.truncate()),
                (p.z + PRISM_HEIGHT / 2.0).abs() - PRISM_HEIGHT / 2.0,
            ),
            Solid::Cylinder => sd_box2(
                DVec2::new(r, p.z),
                DVec2::new(0.0, -CYLINDER_HEIGHT / 2.0),
                DVec2::new(CYLINDER_RADIUS, CYLINDER_HEIGHT / 2.0),
            ),
            Solid::Edge => extrude(
                sd_polygon(&EDGE_SECTION, DVec2::new(p.y, p.z)),
                p.x.abs() - EDGE_LENGTH / 2.0,
            ),
            Solid::Tube => sd_box2(
                DVec2::new(r, p.z),
                DVec2::new(
                    (TUBE_OUTER_RADIUS + TUBE_INNER_RADIUS) / 2.0,
                    -TUBE_HEIGHT / 2.0,
                ),
                DVec2::new(
                    (TUBE_OUTER_RADIUS - TUBE_INNER_RADIUS) / 2.0,
                    TUBE_HEIGHT / 2.0,
                ),
            ),
            Solid::Slab => sd_box3(
                p,
                DVec3::new(0.0, 0.0, -SLAB_Z / 2.0),
                DVec3::new(SLAB_X / 2.0, SLAB_Y / 2.0, SLAB_Z / 2.0),
            ),
            Solid::Torus => {
                DVec2::new(r - TORUS_MAJOR_RADIUS, p.z + TORUS_MINOR_RADIUS).length()
                    - TORUS_MINOR_RADIUS
            }
            Solid::Disc => sd_box2(
                DVec2::new(r, p.z),
                DVec2::new(0.0, -DISC_THICKNESS / 2.0),
                DVec2::new(DISC_RADIUS, DISC_THICKNESS / 2.0),
            ),
        }
    }

    /// The largest distance from the origin (the contact top) to any point of the solid.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Solid::Cone => CONE_RADIUS.hypot(CONE_HEIGHT),
            Solid::Sphere => 2.0 * SPHERE_RADIUS,
            Solid::IrregularPrism => pentagon_radius().hypot(PRISM_HEIGHT),
            Solid::Cylinder => CYLINDER_RADIUS.hypot(CYLINDER_HEIGHT),
            Solid::Edge => DVec3::new(EDGE_LENGTH / 2.0, EDGE_WIDTH / 2.0, EDGE_HEIGHT).length(),
            Solid::Tube => TUBE_OUTER_RADIUS.hypot(TUBE_HEIGHT),
            Solid::Slab => DVec3::new(SLAB_X / 2.0, SLAB_Y / 2.0, SLAB_Z).length(),
            Solid::Torus => {
                (TORUS_MAJOR_RADIUS + TORUS_MINOR_RADIUS).hypot(2.0 * TORUS_MINOR_RADIUS)
            }
            Solid::Disc => DISC_RADIUS.hypot(DISC_THICKNESS),
        }
    }

    /// The largest distance from the z axis to any point of the solid (its horizontal
    /// half-extent).
    pub fn footprint_radius(&self) -> f64 {
        match self {
            Solid::Cone => CONE_RADIUS,
            Solid::Sphere => SPHERE_RADIUS,
            Solid::IrregularPrism => pentagon_radius(),
            Solid::Cylinder => CYLINDER_RADIUS,
            Solid::Edge => (EDGE_LENGTH / 2.0).hypot(EDGE_WIDTH / 2.0),
            Solid::Tube => TUBE_OUTER_RADIUS,
            Solid::Slab => (SLAB_X / 2.0).hypot(SLAB_Y / 2.0),
            Solid::Torus => TORUS_MAJOR_RADIUS + TORUS_MINOR_RADIUS,
            Solid::Disc => DISC_RADIUS,
        }
    }

    /// A closed, consistently outward-wound triangle mesh of the solid
    /// ([`dims::ROUND_SEGMENTS`] segments around round solids), its vertices on the exact
    /// surface and numbered in first-use order ([`Mesh::compacted`]). Its highest point is at
    /// z = 0 and its top ([`Mesh::top`]) is the origin.
    pub fn mesh(&self) -> Mesh {
        let n = ROUND_SEGMENTS;
        let v2 = |x: f64, y: f64| DVec2::new(x, y);
        let mut mesh = match self {
            Solid::Cone => revolve(
                &[
                    v2(0.0, 0.0),
                    v2(CONE_RADIUS, -CONE_HEIGHT),
                    v2(0.0, -CONE_HEIGHT),
                ],
                false,
                n,
            ),
            Solid::Sphere => {
                let rings = n / 2;
                let profile: Vec<DVec2> = (0..=rings)
                    .map(|i| {
                        if i == 0 {
                            v2(0.0, 0.0)
                        } else if i == rings {
                            v2(0.0, -2.0 * SPHERE_RADIUS)
                        } else {
                            let t = PI * f64::from(i) / f64::from(rings);
                            v2(
                                SPHERE_RADIUS * t.sin(),
                                SPHERE_RADIUS * t.cos() - SPHERE_RADIUS,
                            )
                        }
                    })
                    .collect();
                revolve(&profile, false, n)
            }
            Solid::IrregularPrism => {
                let poly: Vec<DVec2> = PRISM_PENTAGON.iter().map(|&[x, y]| v2(x, y)).collect();
                extrude_z(&poly, 0.0, -PRISM_HEIGHT)
            }
            Solid::Cylinder => revolve(
                &[
                    v2(0.0, 0.0),
                    v2(CYLINDER_RADIUS, 0.0),
                    v2(CYLINDER_RADIUS, -CYLINDER_HEIGHT),
                    v2(0.0, -CYLINDER_HEIGHT),
                ],
                false,
                n,
            ),
            Solid::Edge => {
                // Section in (y, z), extruded along x: build it in (a, b, c) = (y, z, x) and
                // map back with a cyclic permutation of the axes (a rotation: winding kept).
                let poly: Vec<DVec2> = [EDGE_SECTION[1], EDGE_SECTION[2], EDGE_SECTION[0]]
                    .iter()
                    .map(|&[a, b]| v2(a, b))
                    .collect();
                let mut m = extrude_z(&poly, EDGE_LENGTH / 2.0, -EDGE_LENGTH / 2.0);
                for p in &mut m.positions {
                    *p = DVec3::new(p.z, p.x, p.y);
                }
                m
            }
            Solid::Tube => revolve(
                &[
                    v2(TUBE_INNER_RADIUS, 0.0),
                    v2(TUBE_OUTER_RADIUS, 0.0),
                    v2(TUBE_OUTER_RADIUS, -TUBE_HEIGHT),
                    v2(TUBE_INNER_RADIUS, -TUBE_HEIGHT),
                ],
                true,
                n,
            ),
            Solid::Slab => extrude_z(
                &[
                    v2(-SLAB_X / 2.0, -SLAB_Y / 2.0),
                    v2(SLAB_X / 2.0, -SLAB_Y / 2.0),
                    v2(SLAB_X / 2.0, SLAB_Y / 2.0),
                    v2(-SLAB_X / 2.0, SLAB_Y / 2.0),
                ],
                0.0,
                -SLAB_Z,
            ),
            Solid::Torus => {
                let profile: Vec<DVec2> = (0..n)
                    .map(|k| {
                        let a = 2.0 * PI * f64::from(k) / f64::from(n);
                        v2(
                            TORUS_MAJOR_RADIUS + TORUS_MINOR_RADIUS * a.sin(),
                            TORUS_MINOR_RADIUS * a.cos() - TORUS_MINOR_RADIUS,
                        )
                    })
                    .collect();
                revolve(&profile, true, n)
            }
            Solid::Disc => revolve(
                &[
                    v2(0.0, 0.0),
                    v2(DISC_RADIUS, 0.0),
                    v2(DISC_RADIUS, -DISC_THICKNESS),
                    v2(0.0, -DISC_THICKNESS),
                ],
                false,
                n,
            ),
        };
        if mesh.signed_volume() < 0.0 {
            mesh.flip_winding();
        }
        // Vertices in first-use order, as an OBJ file of it loads back.
        mesh.compacted()
    }
}

impl std::fmt::Display for Solid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Distance from the z axis to the pentagon's farthest corner.
fn pentagon_radius() -> f64 {
    PRISM_PENTAGON
        .iter()
        .map(|&[x, y]| x.hypot(y))
        .fold(0.0, f64::max)
}

/// Exact SDF of an axis-aligned 2D box with centre `c` and half-extents `h`.
/// Twin: `obj_sd_box2`.
fn sd_box2(p: DVec2, c: DVec2, h: DVec2) -> f64 {
    let d = (p - c).abs() - h;
    d.max(DVec2::ZERO).length() + d.x.max(d.y).min(0.0)
}

/// Exact SDF of an axis-aligned box with centre `c` and half-extents `h`. Twin: `obj_sd_box3`.
fn sd_box3(p: DVec3, c: DVec3, h: DVec3) -> f64 {
    let d = (p - c).abs() - h;
    d.max(DVec3::ZERO).length() + d.x.max(d.y).max(d.z).min(0.0)
}

/// Exact SDF of a simple polygon (either winding): distance to the nearest edge, signed by
/// crossing parity (after Inigo Quilez). Twin: `obj_sd_polygon`.
fn sd_polygon(v: &[[f64; 2]], p: DVec2) -> f64 {
    let n = v.len();
    let vi = |i: usize| DVec2::new(v[i][0], v[i][1]);
    let mut d = (p - vi(0)).length_squared();
    let mut s = 1.0;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (vi(i), vi(j));
        let e = b - a;
        let w = p - a;
        let q = w - e * (w.dot(e) / e.dot(e)).clamp(0.0, 1.0);
        d = d.min(q.length_squared());
        let c0 = p.y >= a.y;
        let c1 = p.y < b.y;
        let c2 = e.x * w.y > e.y * w.x;
        if (c0 && c1 && c2) || (!c0 && !c1 && !c2) {
            s = -s;
        }
        j = i;
    }
    s * d.sqrt()
}

/// Exact SDF of an extrusion, from the section's SDF `d2` and the signed distance `h` to the
/// slab between the two caps along the extrusion axis (`|axis - centre| - half_length`).
/// Twin: `obj_extrude`.
fn extrude(d2: f64, h: f64) -> f64 {
    let w = DVec2::new(d2, h);
    w.x.max(w.y).min(0.0) + w.max(DVec2::ZERO).length()
}

/// A solid of revolution about the z axis from a meridian profile of `(r, z)` points.
///
/// Open profiles start and end on the axis (r = 0); those points become single pole
/// vertices. Closed profiles (`closed = true`) stay off the axis and are joined last-to-first.
/// The winding is made outward by the caller.
fn revolve(profile: &[DVec2], closed: bool, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    // For each profile point, the index of its ring's first vertex and whether it is a pole.
    let mut rings: Vec<(u32, bool)> = Vec::with_capacity(profile.len());
    for q in profile {
        let start = positions.len() as u32;
        if q.x == 0.0 {
            positions.push(DVec3::new(0.0, 0.0, q.y));
            rings.push((start, true));
        } else {
            for k in 0..segments {
                let a = 2.0 * PI * f64::from(k) / f64::from(segments);
                positions.push(DVec3::new(q.x * a.cos(), q.x * a.sin(), q.y));
            }
            rings.push((start, false));
        }
    }
    let vertex = |ring: (u32, bool), k: u32| {
        if ring.1 {
            ring.0
        } else {
            ring.0 + k % segments
        }
    };
    let mut triangles = Vec::new();
    let links = if closed {
        profile.len()
    } else {
        profile.len() - 1
    };
    for l in 0..links {
        let (a, b) = (rings[l], rings[(l + 1) % profile.len()]);
        for k in 0..segments {
            let (a0, a1) = (vertex(a, k), vertex(a, k + 1));
            let (b0, b1) = (vertex(b, k), vertex(b, k + 1));
            if !b.1 {
                triangles.push([a0, b0, b1]);
            }
            if !a.1 {
                triangles.push([a0, b1, a1]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A prism: the convex counter-clockwise polygon `poly` (in x, y) between `z_top` and
/// `z_bottom`, caps fanned from the polygon's first corner. Wound outward.
fn extrude_z(poly: &[DVec2], z_top: f64, z_bottom: f64) -> Mesh {
    let n = poly.len() as u32;
    let mut positions: Vec<DVec3> = poly.iter().map(|q| q.extend(z_top)).collect();
    positions.extend(poly.iter().map(|q| q.extend(z_bottom)));
    let mut triangles = Vec::new();
    for i in 1..n - 1 {
        triangles.push([0, i, i + 1]);
        triangles.push([n, n + i + 1, n + i]);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        triangles.push([i, n + i, n + j]);
        triangles.push([i, n + j, j]);
    }
    Mesh {
        positions,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A small deterministic generator (SplitMix64) for test points.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
            lo + (hi - lo) * DVec3::new(self.next(), self.next(), self.next())
        }
    }

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
}
