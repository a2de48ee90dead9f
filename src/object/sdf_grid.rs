//! Signed distance fields baked from triangle meshes onto a regular voxel grid.
//!
//! The bake follows Bridson's `makelevelset3` (SDFGen): exact point-triangle distances in a
//! narrow band around every triangle, then fast sweeping that hands each voxel its
//! neighbours' nearest triangles (the distance stays an exact distance to some triangle, and
//! is the nearest one in practice), and the sign from ray parity along grid rows with a
//! simulation-of-simplicity tie-break, so a row through a vertex or an edge, or lying in a
//! face's plane, still counts each crossing exactly once. Parity is taken along all three
//! axes and the majority wins, which keeps a stray row of a mesh with a small hole from
//! flipping a whole line of voxels.
//!
//! # Layout
//! `values[x + dims[0] * (y + dims[1] * z)]` (x fastest, then y, then z) is the signed
//! distance (mm, negative inside) at the voxel centre `origin + voxel_mm * (x, y, z)`.
//! Between centres the field is trilinear; outside the box of centres
//! `[origin, origin + voxel_mm * (dims - 1)]` see [`SdfGrid::sample`]. A GPU sampler must
//! follow the same rules.

use super::mesh::Mesh;
use crate::error::{GeltipError, Result};
use glam::{DVec2, DVec3};

/// The largest number of voxels along any side of a baked grid.
pub const MAX_GRID_SIDE: u32 = 256;
/// Voxels of empty space kept on every side of the mesh's bounding box.
pub const PAD_VOXELS: u32 = 4;
/// Each triangle's exact distances are computed this many voxels beyond its bounding box.
const EXACT_BAND_VOXELS: i64 = 2;
/// Sentinel for "no nearest triangle known yet".
const NONE: u32 = u32::MAX;

/// A signed distance field on a regular grid (see the module docs for the layout).
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGrid {
    /// Centre of voxel (0, 0, 0), in the mesh's frame (mm).
    pub origin: DVec3,
    /// Spacing of voxel centres (mm).
    pub voxel_mm: f64,
    /// Voxels along x, y, z.
    pub dims: [u32; 3],
    /// Signed distances (mm), x fastest, then y, then z.
    pub values: Vec<f32>,
}

impl SdfGrid {
    /// Bakes the signed distance field of a closed mesh on voxels of `voxel_mm`, padded by
    /// [`PAD_VOXELS`] around the mesh's bounding box.
    ///
    /// Refuses an invalid mesh, a voxel size that is not a positive number, and a mesh that
    /// would need more than [`MAX_GRID_SIDE`] voxels along a side.
    pub fn bake(mesh: &Mesh, voxel_mm: f64) -> Result<SdfGrid> {
        SdfGrid::bake_padded(mesh, voxel_mm, 0.0)
    }

    /// [`SdfGrid::bake`] with at least `pad_mm` of exact distances around the mesh's bounding
    /// box (outside the grid, [`SdfGrid::sample`] gives only a lower bound).
    pub fn bake_padded(mesh: &Mesh, voxel_mm: f64, pad_mm: f64) -> Result<SdfGrid> {
        if !(voxel_mm.is_finite() && voxel_mm > 0.0) {
            return Err(GeltipError::input(
                "sdf bake",
                format!("voxel size must be a positive number of mm, got {voxel_mm}"),
            ));
        }
        mesh.validate()
            .map_err(|r| GeltipError::input("sdf bake", r))?;
        let (lo, hi) = mesh.bounds();
        let pad = f64::from(PAD_VOXELS).max((pad_mm.max(0.0) / voxel_mm).ceil());
        let origin = lo - pad * voxel_mm;
        let extent = hi - lo;
        let side = |e: f64| (e / voxel_mm).ceil() + 1.0 + 2.0 * pad;
        let sides = [side(extent.x), side(extent.y), side(extent.z)];
        if sides.iter().any(|&s| s > f64::from(MAX_GRID_SIDE)) {
            return Err(GeltipError::input(
                "sdf bake",
                format!(
                    "mesh of {:.1} x {:.1} x {:.1} mm needs {} x {} x {} voxels of {voxel_mm} mm, \
                     more than {MAX_GRID_SIDE} per side: scale the mesh to millimetres or use larger voxels",
                    extent.x, extent.y, extent.z, sides[0], sides[1], sides[2]
                ),
            ));
        }
        let dims = sides.map(|s| s as u32);
        let mut grid = SdfGrid {
            origin,
            voxel_mm,
            dims,
            values: Vec::new(),
        };
        let (mut phi, closest) = grid.unsigned_distances(mesh);
        let inside = grid.inside_votes(mesh);
        for (d, votes) in phi.iter_mut().zip(&inside) {
            if *votes >= 2 {
                *d = -*d;
            }
        }
        debug_assert!(closest.iter().all(|&t| t != NONE));
        grid.values = phi.into_iter().map(|d| d as f32).collect();
        Ok(grid)
    }

    /// Index of voxel `(x, y, z)` in [`SdfGrid::values`].
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        x as usize + self.dims[0] as usize * (y as usize + self.dims[1] as usize * z as usize)
    }

    /// The centre of voxel `(x, y, z)`.
    pub fn voxel_centre(&self, x: u32, y: u32, z: u32) -> DVec3 {
        self.origin + self.voxel_mm * DVec3::new(x.into(), y.into(), z.into())
    }

    /// The centre of the last voxel: the far corner of the box the grid covers.
    pub fn max_corner(&self) -> DVec3 {
        self.voxel_centre(self.dims[0] - 1, self.dims[1] - 1, self.dims[2] - 1)
    }

    /// The signed distance at `p`: trilinear between voxel centres inside the grid's box.
    ///
    /// Outside the box, with `q` the nearest point of the box and `b = |p - q|`, it returns
    /// `max(b, sample(q) - b)`: both are lower bounds of the true distance (the mesh lies in
    /// the box; the field is 1-Lipschitz), so the value is positive, continuous across the
    /// box and conservative for sphere tracing. (The simpler `b + sample(q)` is not a lower
    /// bound: it overestimates beside the box.)
    pub fn sample(&self, p: DVec3) -> f64 {
        let q = p.clamp(self.origin, self.max_corner());
        let inner = self.trilinear(q);
        let b = (p - q).length();
        if b > 0.0 {
            (inner - b).max(b)
        } else {
            inner
        }
    }

    /// Trilinear interpolation at a point inside the box of voxel centres.
    fn trilinear(&self, q: DVec3) -> f64 {
        let g = (q - self.origin) / self.voxel_mm;
        let mut i0 = [0u32; 3];
        let mut t = [0.0f64; 3];
        for a in 0..3 {
            let cell = g[a].floor().clamp(0.0, f64::from(self.dims[a] - 2));
            i0[a] = cell as u32;
            t[a] = (g[a] - cell).clamp(0.0, 1.0);
        }
        let v = |dx: u32, dy: u32, dz: u32| {
            f64::from(self.values[self.index(i0[0] + dx, i0[1] + dy, i0[2] + dz)])
        };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let x00 = lerp(v(0, 0, 0), v(1, 0, 0), t[0]);
        let x10 = lerp(v(0, 1, 0), v(1, 1, 0), t[0]);
        let x01 = lerp(v(0, 0, 1), v(1, 0, 1), t[0]);
        let x11 = lerp(v(0, 1, 1), v(1, 1, 1), t[0]);
        lerp(lerp(x00, x10, t[1]), lerp(x01, x11, t[1]), t[2])
    }

    fn len(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Unsigned distances to the mesh and the nearest triangle of every voxel.
    fn unsigned_distances(&self, mesh: &Mesh) -> (Vec<f64>, Vec<u32>) {
        let n = self.len();
        let far = self.voxel_mm * f64::from(self.dims.iter().sum::<u32>());
        let mut phi = vec![far; n];
        let mut closest = vec![NONE; n];
        self.exact_band(mesh, &mut phi, &mut closest);
        self.sweep(mesh, &mut phi, &mut closest);
        (phi, closest)
    }

    /// Exact distances (`phi`) and nearest triangles (`closest`) in a band around every
    /// triangle.
    fn exact_band(&self, mesh: &Mesh, phi: &mut [f64], closest: &mut [u32]) {
        let tri = |t: u32| mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]);
        for (t, corners) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = corners.map(|i| self.to_grid(mesh.positions[i as usize]));
            let lo = a.min(b).min(c);
            let hi = a.max(b).max(c);
            let range = |axis: usize| {
                let top = i64::from(self.dims[axis]) - 1;
                let start = (lo[axis].floor() as i64 - EXACT_BAND_VOXELS).clamp(0, top);
                let end = (hi[axis].ceil() as i64 + EXACT_BAND_VOXELS).clamp(0, top);
                start as u32..=end as u32
            };
            let points = tri(t as u32);
            for z in range(2) {
                for y in range(1) {
                    for x in range(0) {
                        let idx = self.index(x, y, z);
                        let d = point_triangle_distance(self.voxel_centre(x, y, z), points);
                        if d < phi[idx] {
                            phi[idx] = d;
                            closest[idx] = t as u32;
                        }
                    }
                }
            }
        }
    }

    /// Fast sweeping: propagate nearest triangles from neighbours, in all 8 diagonal
    /// directions, twice. Voxels within the band are exact already. A neighbour's
    /// triangle t is at least phi[nb] - |step| away (triangle inequality), which skips
    /// most exact distance evaluations.
    fn sweep(&self, mesh: &Mesh, phi: &mut [f64], closest: &mut [u32]) {
        let tri = |t: u32| mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]);
        let exact = EXACT_BAND_VOXELS as f64 * self.voxel_mm;
        let dirs: [[i64; 3]; 8] = [
            [1, 1, 1],
            [-1, -1, -1],
            [1, 1, -1],
            [-1, -1, 1],
            [1, -1, 1],
            [-1, 1, -1],
            [1, -1, -1],
            [-1, 1, 1],
        ];
        let offsets: [([i64; 3], f64); 7] = [
            ([1, 0, 0], 1.0),
            ([0, 1, 0], 1.0),
            ([1, 1, 0], 2f64.sqrt()),
            ([0, 0, 1], 1.0),
            ([1, 0, 1], 2f64.sqrt()),
            ([0, 1, 1], 2f64.sqrt()),
            ([1, 1, 1], 3f64.sqrt()),
        ];
        let d = self.dims.map(i64::from);
        let stride = [1i64, d[0], d[0] * d[1]];
        for _pass in 0..2 {
            for dir in dirs {
                // Index offset to each of the 7 neighbours behind, and its distance.
                let behind = offsets.map(|(o, len)| {
                    let off: i64 = (0..3).map(|a| o[a] * dir[a] * stride[a]).sum();
                    (off, len * self.voxel_mm)
                });
                let range = |axis: usize| -> (i64, i64) {
                    if dir[axis] > 0 {
                        (1, d[axis])
                    } else {
                        (d[axis] - 2, -1)
                    }
                };
                let ((z0, z1), (y0, y1), (x0, x1)) = (range(2), range(1), range(0));
                let mut z = z0;
                while z != z1 {
                    let mut y = y0;
                    while y != y1 {
                        let mut x = x0;
                        while x != x1 {
                            let idx = (x + stride[1] * y + stride[2] * z) as usize;
                            x += dir[0];
                            if phi[idx] <= exact {
                                continue;
                            }
                            let mut centre = None;
                            for (off, step) in behind {
                                let nb = (idx as i64 - off) as usize;
                                let t = closest[nb];
                                if t == NONE || t == closest[idx] || phi[nb] - step >= phi[idx] {
                                    continue;
                                }
                                let c = *centre.get_or_insert_with(|| {
                                    self.voxel_centre((x - dir[0]) as u32, y as u32, z as u32)
                                });
                                let dist = point_triangle_distance(c, tri(t));
                                if dist < phi[idx] {
                                    phi[idx] = dist;
                                    closest[idx] = t;
                                }
                            }
                        }
                        y += dir[1];
                    }
                    z += dir[2];
                }
            }
        }
    }

    /// For every voxel, how many of the three axis-aligned ray-parity tests put it inside.
    fn inside_votes(&self, mesh: &Mesh) -> Vec<u8> {
        let n = self.len();
        let grid_pos: Vec<DVec3> = mesh.positions.iter().map(|&p| self.to_grid(p)).collect();
        let mut votes = vec![0u8; n];
        let mut crossings = vec![0u32; n];
        let strides = [
            1usize,
            self.dims[0] as usize,
            (self.dims[0] * self.dims[1]) as usize,
        ];
        for axis in 0..3 {
            // Rows run along `axis`; (u, v) are the other two axes.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            crossings.iter_mut().for_each(|c| *c = 0);
            for corners in &mesh.triangles {
                let [a, b, c] = corners.map(|i| grid_pos[i as usize]);
                let lo = a.min(b).min(c);
                let hi = a.max(b).max(c);
                let rows = |axis: usize| {
                    let top = f64::from(self.dims[axis]) - 1.0;
                    let start = lo[axis].ceil().max(0.0);
                    let end = hi[axis].floor().min(top);
                    (start as u32)..=(end as u32)
                };
                if lo[u].ceil() > hi[u].floor() || lo[v].ceil() > hi[v].floor() {
                    continue;
                }
                for jv in rows(v) {
                    for ju in rows(u) {
                        let q = DVec2::new(ju.into(), jv.into());
                        let Some(w) = point_in_triangle_2d(
                            q,
                            DVec2::new(a[u], a[v]),
                            DVec2::new(b[u], b[v]),
                            DVec2::new(c[u], c[v]),
                        ) else {
                            continue;
                        };
                        let cross = w[0] * a[axis] + w[1] * b[axis] + w[2] * c[axis];
                        // Voxels at or past the crossing along the row are behind it.
                        let first = cross.ceil().max(0.0);
                        if first < f64::from(self.dims[axis]) {
                            let idx = first as usize * strides[axis]
                                + ju as usize * strides[u]
                                + jv as usize * strides[v];
                            crossings[idx] += 1;
                        }
                    }
                }
            }
            for jv in 0..self.dims[v] as usize {
                for ju in 0..self.dims[u] as usize {
                    let row = ju * strides[u] + jv * strides[v];
                    let mut count = 0u32;
                    for i in 0..self.dims[axis] as usize {
                        let idx = row + i * strides[axis];
                        count += crossings[idx];
                        if count % 2 == 1 {
                            votes[idx] += 1;
                        }
                    }
                }
            }
        }
        votes
    }

    /// A point in grid coordinates (voxel centres at integers).
    fn to_grid(&self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.voxel_mm
    }
}

/// The distance from `p` to the triangle `[a, b, c]` (Ericson, Real-Time Collision
/// Detection, 5.1.5), with degenerate triangles handled as their edges.
pub(crate) fn point_triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let q = closest_point_on_triangle(p, a, b, c);
    if q.is_finite() {
        (p - q).length()
    } else {
        segment_distance(p, a, b)
            .min(segment_distance(p, b, c))
            .min(segment_distance(p, c, a))
    }
}

fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let e = b - a;
    let len2 = e.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(e) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + e * t)).length()
}

fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Sign of the 2D orientation of `(p1, p2)` seen from the origin, with Bridson's
/// simulation-of-simplicity tie-break (the query point perturbed by `(e, e^2)`), and twice
/// the signed area. Antisymmetric in its arguments, bit for bit.
fn orientation(p1: DVec2, p2: DVec2) -> (i32, f64) {
    let area = p1.y * p2.x - p1.x * p2.y;
    let sign = if area > 0.0 {
        1
    } else if area < 0.0 {
        -1
    } else if p2.y > p1.y {
        1
    } else if p2.y < p1.y {
        -1
    } else if p1.x > p2.x {
        1
    } else if p1.x < p2.x {
        -1
    } else {
        0
    };
    (sign, area)
}

/// Whether `q` lies in the 2D triangle `(a, b, c)` under the simulation-of-simplicity rule
/// of [`orientation`]; if so, its barycentric weights. Zero-area triangles never contain it.
fn point_in_triangle_2d(q: DVec2, a: DVec2, b: DVec2, c: DVec2) -> Option<[f64; 3]> {
    let (a, b, c) = (a - q, b - q, c - q);
    let (sa, wa) = orientation(b, c);
    if sa == 0 {
        return None;
    }
    let (sb, wb) = orientation(c, a);
    if sb != sa {
        return None;
    }
    let (sc, wc) = orientation(a, b);
    if sc != sa {
        return None;
    }
    let sum = wa + wb + wc;
    if sum == 0.0 || !sum.is_finite() {
        return None;
    }
    Some([wa / sum, wb / sum, wc / sum])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(half: f64) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..8 {
            positions.push(DVec3::new(
                if i & 1 == 0 { -half } else { half },
                if i & 2 == 0 { -half } else { half },
                if i & 4 == 0 { -half } else { half },
            ));
        }
        // Outward-wound faces of the cube with corners indexed by bits (x, y, z).
        let quads = [
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
        ];
        let mut triangles = Vec::new();
        for q in quads {
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
        Mesh {
            positions,
            triangles,
        }
    }

    fn box_sdf(p: DVec3, half: f64) -> f64 {
        let d = p.abs() - DVec3::splat(half);
        d.max(DVec3::ZERO).length() + d.max_element().min(0.0)
    }

    #[test]
    fn cube_bakes_to_its_exact_sdf_at_voxel_centres() {
        // Half-size 1 on 0.25 mm voxels: faces, edges and corners all lie on grid rows.
        let mesh = cube(1.0);
        assert!(mesh.signed_volume() > 0.0);
        let grid = SdfGrid::bake(&mesh, 0.25).unwrap();
        assert_eq!(grid.dims, [17, 17, 17]);
        for z in 0..17 {
            for y in 0..17 {
                for x in 0..17 {
                    let p = grid.voxel_centre(x, y, z);
                    let got = f64::from(grid.values[grid.index(x, y, z)]);
                    let want = box_sdf(p, 1.0);
                    assert!(
                        (got - want).abs() < 1e-5,
                        "voxel ({x},{y},{z}) at {p}: {got} != {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn sample_interpolates_and_bounds_outside() {
        let grid = SdfGrid::bake(&cube(1.0), 0.25).unwrap();
        // On a face's normal line the box SDF is linear: trilinear is exact there.
        let p = DVec3::new(0.0, 0.0, 1.6);
        assert!((grid.sample(p) - 0.6).abs() < 1e-6);
        // Outside the grid box: positive, below the true distance, continuous at the box.
        for p in [
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(-3.0, 4.0, 2.5),
            DVec3::new(2.2, 2.2, 2.2),
        ] {
            let s = grid.sample(p);
            assert!(s > 0.0 && s <= box_sdf(p, 1.0) + 1e-6, "{p}: {s}");
        }
        let edge = grid.max_corner().x;
        let inside = grid.sample(DVec3::new(edge - 1e-9, 0.3, 0.2));
        let outside = grid.sample(DVec3::new(edge + 1e-9, 0.3, 0.2));
        assert!((inside - outside).abs() < 1e-6);
    }

    #[test]
    fn refuses_bad_input() {
        let mesh = cube(1.0);
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = SdfGrid::bake(&mesh, v).unwrap_err().to_string();
            assert!(e.contains("voxel size"), "{e}");
        }
        let e = SdfGrid::bake(&cube(40.0), 0.25).unwrap_err().to_string();
        assert!(e.contains("more than 256 per side"), "{e}");
        assert!(!e.contains('\n'));
        let e = SdfGrid::bake(&Mesh::default(), 0.25)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no triangles"), "{e}");
    }

    #[test]
    fn orientation_is_antisymmetric() {
        let pts = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(-1.0, 0.0),
            DVec2::new(0.1, 0.3),
            DVec2::new(0.2, 0.6),
        ];
        for &p in &pts {
            for &q in &pts {
                let (s1, a1) = orientation(p, q);
                let (s2, a2) = orientation(q, p);
                assert_eq!(s1, -s2);
                assert_eq!(a1, -a2);
                assert_eq!(s1 == 0, p == q);
            }
        }
    }

    #[test]
    fn point_triangle_distance_cases() {
        let t = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        let cases = [
            (DVec3::new(0.5, 0.5, 1.0), 1.0),
            (DVec3::new(-1.0, -1.0, 0.0), 2f64.sqrt()),
            (DVec3::new(1.0, -2.0, 0.0), 2.0),
            (DVec3::new(2.0, 2.0, 0.0), 2f64.sqrt()),
            (DVec3::new(3.0, 0.0, 0.0), 1.0),
        ];
        for (p, d) in cases {
            assert!((point_triangle_distance(p, t) - d).abs() < 1e-12, "{p}");
        }
        // Degenerate (collinear) triangle: distance to the segment.
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        assert!((point_triangle_distance(DVec3::new(1.5, 1.0, 0.0), line) - 1.0).abs() < 1e-12);
    }
}
