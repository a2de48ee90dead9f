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
//! constants ([`dims`] here, `OBJ_*` there); `tests/objects_wgsl.rs` checks that the constants
//! agree.

use glam::{DVec2, DVec3};

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
pub(super) fn sd_box2(p: DVec2, c: DVec2, h: DVec2) -> f64 {
    let d = (p - c).abs() - h;
    d.max(DVec2::ZERO).length() + d.x.max(d.y).min(0.0)
}

/// Exact SDF of an axis-aligned box with centre `c` and half-extents `h`. Twin: `obj_sd_box3`.
pub(super) fn sd_box3(p: DVec3, c: DVec3, h: DVec3) -> f64 {
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

mod meshes;
#[cfg(test)]
mod tests;
