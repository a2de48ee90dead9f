//! Where a contact can change anything: the texels the object may press (a coarse scan of
//! cells traced with a tolerance), grown by the elastomer's reach, and the pixels whose
//! rays can meet them.

use super::{arc_length_at_height, may_touch, parallel_radius, penetration, TRACE_EPSILON_MM};
use crate::finger::SurfaceCoord;
use crate::object::Object;
use crate::render::{ContactPose, HeightfieldGrid, Rect};
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// What a contact can change: the heightfield texels its imprint (grown by the elastomer's
/// reach) covers, and the pixels whose rays can meet them; and the texels the object itself
/// can press, where the contact stage traces it (inside `texels`; the rest of `texels` is
/// moved by the elastomer alone).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    pub texels: Rect,
    pub pixels: Option<Rect>,
    pub pressed: Rect,
    /// The texels of `texels` whose blends along the meridian can differ from zero, where
    /// the elastomer's meridians pass runs: those within the kernels' reach of `pressed`
    /// (about half of `texels` over the paper's taps, which grows by the reach along the
    /// meridian and then along the parallel, all the way round near the tip).
    pub meridians: Rect,
}

/// Texels the meridians pass's taps can reach from a texel's centre, each way along both
/// axes: the kernels' reach (the taps lie within it on the disc, where the meridian is
/// straight), one more for the 2x2 block a bilinear sample reads, and one for rounding.
pub fn meridian_margin(grid: &HeightfieldGrid, blend_reach_mm: f64) -> u32 {
    (blend_reach_mm / grid.texel_mm()).ceil() as u32 + 2
}

/// Bounds of a footprint's samples on the disc and in the image.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    disc_lo: DVec2,
    disc_hi: DVec2,
    px_lo: DVec2,
    px_hi: DVec2,
    any_seen: bool,
}

impl Default for Bounds {
    fn default() -> Self {
        let (lo, hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        Bounds {
            disc_lo: lo,
            disc_hi: hi,
            px_lo: lo,
            px_hi: hi,
            any_seen: false,
        }
    }
}

impl Bounds {
    /// Takes in surface point `p` (its disc position, and the pixels that see it at each of
    /// `depths` under the surface).
    fn extend(&mut self, sensor: &Sensor, p: SurfaceCoord, depths: &[f64]) {
        // One sine and cosine of the azimuth for both the disc position and the point.
        let (sin_phi, cos_phi) = p.phi.sin_cos();
        let disc = p.s * DVec2::new(cos_phi, sin_phi);
        self.disc_lo = self.disc_lo.min(disc);
        self.disc_hi = self.disc_hi.max(disc);
        let sp = sensor.finger.point_towards(p.s, cos_phi, sin_phi);
        for &depth in depths {
            // Samples beyond the lens count at its edge: where the imprint runs out of view,
            // what is seen of it reaches the edge (a short arc, inside the rectangle's
            // padding).
            let (px, seen) = pixel_towards(sensor, sp.point - depth * sp.normal);
            self.any_seen |= seen;
            // Pixel centres are at integers: shift to cell space.
            self.px_lo = self.px_lo.min(px + DVec2::splat(0.5));
            self.px_hi = self.px_hi.max(px + DVec2::splat(0.5));
        }
    }

    fn merge(a: Bounds, b: Bounds) -> Bounds {
        Bounds {
            disc_lo: a.disc_lo.min(b.disc_lo),
            disc_hi: a.disc_hi.max(b.disc_hi),
            px_lo: a.px_lo.min(b.px_lo),
            px_hi: a.px_hi.max(b.px_hi),
            any_seen: a.any_seen || b.any_seen,
        }
    }
}

/// The pixel where the camera sees the direction of `p` (for points just outside the
/// finger, such as a bulge, the direction is what matters), and whether the lens sees it;
/// a direction beyond the lens gets the pixel on the lens's edge at its azimuth.
fn pixel_towards(sensor: &Sensor, p: DVec3) -> (DVec2, bool) {
    let lateral = (p.x * p.x + p.y * p.y).sqrt();
    let theta = lateral.atan2(p.z);
    let seen = theta <= sensor.lens.max_theta;
    let rho = sensor.lens.project(theta.min(sensor.lens.max_theta));
    let pixel = if lateral > 0.0 {
        sensor.principal + rho * DVec2::new(p.x, p.y) / lateral
    } else {
        sensor.principal
    };
    (pixel, seen)
}

/// Where the object touches the finger (conservatively): coarse cells of 2x2 texels are
/// traced with a tolerance of half their diagonal (the disc-to-surface map never stretches
/// distances, so every surface point of a cell is that close to its centre); the boundary
/// cells are grown by `blend_reach_mm` of surface distance, along the meridian and the
/// parallel, and bounded on the disc (texels) and in the image, at every depth the skin can
/// take (pixels). `None` when the object touches nothing.
pub fn footprint(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    pose: &ContactPose,
    object: &Object,
    blend_reach_mm: f64,
) -> Option<Footprint> {
    let scan = CellScan::new(sensor, grid, pose, object);
    let marked = scan.touched_cells();
    let Bounds {
        disc_lo,
        disc_hi,
        px_lo,
        px_hi,
        any_seen,
    } = grown_bounds(sensor, &scan.cells, &marked, blend_reach_mm);
    if disc_lo.x > disc_hi.x {
        return None;
    }
    let pressed = scan.cells.texels_of(&marked, grid.texels);
    let texels = Rect::covering(
        grid.texel_of(disc_lo),
        grid.texel_of(disc_hi),
        DVec2::ONE,
        (grid.texels, grid.texels),
    )?;
    let pixels = if !any_seen {
        None
    } else {
        Rect::covering(
            px_lo,
            px_hi,
            DVec2::splat(2.0),
            (sensor.width, sensor.height),
        )
    };
    // Every marked cell was grown into `texels`, so `pressed` lies inside it.
    let meridians = pressed
        .grown_within(meridian_margin(grid, blend_reach_mm), texels)
        .unwrap_or(pressed);
    Some(Footprint {
        texels,
        pixels,
        pressed,
        meridians,
    })
}

/// Texels per side of the footprint scan's coarse cells.
const CELL: u32 = 2;
/// Cells per side of the blocks the scan bounds first.
const BLOCK: u32 = 4;

/// The footprint scan's coarse cells: `count` x `count` cells of CELL x CELL texels over
/// the heightfield's square.
struct Cells {
    count: u32,
    cell_mm: f64,
    half_size_mm: f64,
}

impl Cells {
    /// Disc coordinates of cell (column, row)'s centre.
    fn centre(&self, ci: u32, cj: u32) -> DVec2 {
        DVec2::new(ci as f64 + 0.5, cj as f64 + 0.5) * self.cell_mm
            - DVec2::splat(self.half_size_mm)
    }

    /// Whether cell (column, row) is marked; false outside the grid.
    fn is_marked(&self, marked: &[bool], ci: i64, cj: i64) -> bool {
        let n = self.count as i64;
        ci >= 0 && cj >= 0 && ci < n && cj < n && marked[(cj * n + ci) as usize]
    }

    /// The texels of the marked cells' bounding box (by rows of cells), within a
    /// `texels`-wide grid; the marks must hold at least one.
    fn texels_of(&self, marked: &[bool], texels: u32) -> Rect {
        let (mut c_lo, mut c_hi) = ((u32::MAX, u32::MAX), (0, 0));
        for (cj, row) in marked.chunks(self.count as usize).enumerate() {
            if let (Some(first), Some(last)) =
                (row.iter().position(|&m| m), row.iter().rposition(|&m| m))
            {
                c_lo = (c_lo.0.min(first as u32), c_lo.1.min(cj as u32));
                c_hi = (c_hi.0.max(last as u32), c_hi.1.max(cj as u32));
            }
        }
        let texel_end = |c: u32| ((c + 1) * CELL).min(texels);
        Rect {
            x: c_lo.0 * CELL,
            y: c_lo.1 * CELL,
            w: texel_end(c_hi.0) - c_lo.0 * CELL,
            h: texel_end(c_hi.1) - c_lo.1 * CELL,
        }
    }
}

/// The culling scan of [`footprint`]: which coarse cells the object may press, traced to the
/// pose's depth with a tolerance of half a cell's diagonal.
struct CellScan<'a> {
    finger: &'a crate::finger::Finger,
    pose: &'a ContactPose,
    object: &'a Object,
    cells: Cells,
    max_depth: f64,
    drape: f64,
    tolerance: f64,
    /// Farthest a touched cell's surface point can be from the object's origin.
    reach: f64,
    /// Arc lengths within reach of the origin.
    s_lo: f64,
    s_hi: f64,
}

impl<'a> CellScan<'a> {
    fn new(
        sensor: &'a Sensor,
        grid: &HeightfieldGrid,
        pose: &'a ContactPose,
        object: &'a Object,
    ) -> CellScan<'a> {
        let f = &sensor.finger;
        let cell_mm = grid.texel_mm() * CELL as f64;
        let tolerance = cell_mm * std::f64::consts::FRAC_1_SQRT_2 + TRACE_EPSILON_MM;
        let drape = sensor.config.elastomer.drape_mm;
        let max_depth = pose.trace_depth_mm;
        let reach = object.bounding_radius() + max_depth + drape + tolerance;
        // Arc length falls as height rises, over the whole finger: only cells whose s lies
        // between those of the heights origin.z +- reach can be within reach (a cheap first
        // test before the trigonometry; 1 µm of slack for rounding).
        let s_lo = arc_length_at_height(f, pose.origin.z + reach) - 1e-3;
        let s_hi = (arc_length_at_height(f, pose.origin.z - reach) + 1e-3).min(grid.half_size_mm);
        CellScan {
            finger: f,
            pose,
            object,
            cells: Cells {
                count: grid.texels.div_ceil(CELL),
                cell_mm,
                half_size_mm: grid.half_size_mm,
            },
            max_depth,
            drape,
            tolerance,
            reach,
            s_lo,
            s_hi,
        }
    }

    /// Marks of the cells the object may press (row-major, `cells.count` per row). Only the
    /// cells of [`CellScan::touched_blocks`] are traced: the marks are those of tracing every
    /// cell. Rows of cells in parallel: the GPU waits for this (prepare is on the frame's
    /// path).
    fn touched_cells(&self) -> Vec<bool> {
        let (blocks, touched_blocks) = self.touched_blocks();
        let cells = self.cells.count;
        let mut marked = vec![false; (cells * cells) as usize];
        marked
            .par_chunks_mut(cells as usize)
            .enumerate()
            .for_each(|(cj, row)| {
                for (ci, mark) in row.iter_mut().enumerate() {
                    let (ci, cj) = (ci as u32, cj as u32);
                    if !touched_blocks[((cj / BLOCK) * blocks + ci / BLOCK) as usize] {
                        continue;
                    }
                    let centre = self.cells.centre(ci, cj);
                    let s = centre.length();
                    if s < self.s_lo || s > self.s_hi {
                        continue;
                    }
                    let at = self.finger.point_at_disc(centre);
                    if (at.point - self.pose.origin).length() > self.reach {
                        continue;
                    }
                    *mark = penetration(
                        self.pose,
                        self.object,
                        &at,
                        self.max_depth,
                        self.drape,
                        self.tolerance,
                    ) > 0.0;
                }
            });
        marked
    }

    /// Blocks of BLOCK x BLOCK cells, each traced with its own (larger) tolerance: a block
    /// none of whose surface points can be touched holds no touched cell. Blocks per side,
    /// and their marks (row-major).
    fn touched_blocks(&self) -> (u32, Vec<bool>) {
        let f = self.finger;
        let blocks = self.cells.count.div_ceil(BLOCK);
        let block_mm = self.cells.cell_mm * BLOCK as f64;
        // Every surface point of a block lies within its half diagonal of the centre's, and
        // its normal within half diagonal / radius of the centre's normal, so a point traced
        // max_depth + drape in along it lies at most that much further off.
        let half_diagonal = block_mm * std::f64::consts::FRAC_1_SQRT_2;
        let block_tolerance =
            half_diagonal * (1.0 + (self.max_depth + self.drape) / f.radius) + TRACE_EPSILON_MM;
        let block_reach = self.reach - self.tolerance + half_diagonal + TRACE_EPSILON_MM;
        let mut touched = vec![false; (blocks * blocks) as usize];
        touched
            .par_chunks_mut(blocks as usize)
            .enumerate()
            .for_each(|(bj, row)| {
                for (bi, mark) in row.iter_mut().enumerate() {
                    let c = DVec2::new(bi as f64 + 0.5, bj as f64 + 0.5) * block_mm
                        - DVec2::splat(self.cells.half_size_mm);
                    let s = c.length();
                    if s < self.s_lo - block_tolerance || s > self.s_hi + block_tolerance {
                        continue;
                    }
                    let at = f.point_at_disc(c);
                    if (at.point - self.pose.origin).length() > block_reach {
                        continue;
                    }
                    *mark = may_touch(
                        self.pose,
                        self.object,
                        &at,
                        self.max_depth,
                        self.drape,
                        block_tolerance,
                    );
                }
            });
        (blocks, touched)
    }
}

/// The bounds, on the disc and in the image, of the marked boundary cells grown by the
/// imprint's influence (`blend_reach_mm` along the surface) at every depth the skin can take.
/// Per row of cells, then merged (min and max do not depend on the order, so neither does
/// the result).
fn grown_bounds(sensor: &Sensor, cells: &Cells, marked: &[bool], blend_reach_mm: f64) -> Bounds {
    let f = &sensor.finger;
    // How far the imprint's influence reaches beyond a marked cell's centre (surface mm);
    // a 10% margin covers the bounding box falling between the 8 sampled directions.
    let grow = 1.1 * blend_reach_mm + cells.cell_mm;
    let depths = [
        -0.5 * f.shell_thickness,
        0.0,
        0.5 * f.shell_thickness,
        f.shell_thickness,
    ];
    // The eight directions the boundary cells grow in, as (sine, cosine).
    let directions: [(f64, f64); 8] =
        std::array::from_fn(|k| (k as f64 * std::f64::consts::FRAC_PI_4).sin_cos());
    let is_marked = |ci: i64, cj: i64| cells.is_marked(marked, ci, cj);
    let row_bounds = |cj: i64| {
        let mut b = Bounds::default();
        for ci in 0..cells.count as i64 {
            if !is_marked(ci, cj) {
                continue;
            }
            let interior = (-1..=1).all(|dj| (-1..=1).all(|di| is_marked(ci + di, cj + dj)));
            if interior {
                continue;
            }
            let c = SurfaceCoord::from_disc(cells.centre(ci as u32, cj as u32));
            let rho = parallel_radius(f, c.s);
            let grown = directions.iter().map(|&(sin, cos)| SurfaceCoord {
                s: (c.s + grow * cos).max(0.0),
                phi: c.phi + grow * sin / rho.max(1e-9),
            });
            // Near the tip the parallels are too small for azimuth offsets: take the whole
            // circle the grown cell can reach.
            let circle = (0..if c.s < 2.0 * grow { 16 } else { 0 }).map(|k| SurfaceCoord {
                s: c.s + grow,
                phi: k as f64 * std::f64::consts::TAU / 16.0,
            });
            for p in grown.chain(circle).chain([c]) {
                b.extend(sensor, p, &depths);
            }
        }
        b
    };
    (0..cells.count as i64)
        .into_par_iter()
        .map(row_bounds)
        .reduce(Bounds::default, Bounds::merge)
}
