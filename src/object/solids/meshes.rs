//! The solids' triangle meshes: each a profile revolved about the z axis or a polygon
//! extruded, its vertices on the exact surface.

use super::dims::*;
use super::{Solid, EDGE_SECTION};
use crate::object::mesh::Mesh;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

impl Solid {
    /// A closed, consistently outward-wound triangle mesh of the solid
    /// ([`super::dims::ROUND_SEGMENTS`] segments around round solids), its vertices on the exact
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
            Solid::Sphere => revolve(&sphere_profile(n), false, n),
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
            Solid::Edge => edge_mesh(),
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
            Solid::Torus => revolve(&torus_profile(n), true, n),
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

/// The sphere's meridian, pole to pole, in `n / 2` steps.
fn sphere_profile(n: u32) -> Vec<DVec2> {
    let v2 = |x: f64, y: f64| DVec2::new(x, y);
    let rings = n / 2;
    (0..=rings)
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
        .collect()
}

/// The edge: its section in (y, z), extruded along x. Built in (a, b, c) = (y, z, x) and
/// mapped back with a cyclic permutation of the axes (a rotation: winding kept).
fn edge_mesh() -> Mesh {
    let poly: Vec<DVec2> = [EDGE_SECTION[1], EDGE_SECTION[2], EDGE_SECTION[0]]
        .iter()
        .map(|&[a, b]| DVec2::new(a, b))
        .collect();
    let mut m = extrude_z(&poly, EDGE_LENGTH / 2.0, -EDGE_LENGTH / 2.0);
    for p in &mut m.positions {
        *p = DVec3::new(p.z, p.x, p.y);
    }
    m
}

/// The torus's tube section, a circle of `n` points starting at its top.
fn torus_profile(n: u32) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let a = 2.0 * PI * f64::from(k) / f64::from(n);
            DVec2::new(
                TORUS_MAJOR_RADIUS + TORUS_MINOR_RADIUS * a.sin(),
                TORUS_MINOR_RADIUS * a.cos() - TORUS_MINOR_RADIUS,
            )
        })
        .collect()
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
