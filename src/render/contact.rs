//! Stage 1, contact: how far the object pushes the skin inward along the surface normal, at
//! each heightfield texel. CPU mirror of `shaders/contact.wgsl` (same names).
//!
//! Penetration at a surface point S with outward normal n is the largest lambda in [0, L]
//! with S - lambda n inside the object: found by sphere tracing the object's SDF from the
//! deep end (lambda = L) outwards, so the first object point met is the deepest.

use super::{ContactPose, HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord, SurfacePoint};
use crate::object::Object;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Sphere-tracing steps before a texel is declared untouched.
pub const MAX_TRACE_STEPS: u32 = 48;
/// Distance (mm) at which the trace counts as having reached the object's surface.
pub const TRACE_EPSILON_MM: f64 = 1e-3;

/// Deepest inward distance (mm) worth tracing for a contact pressed `depth_mm` deep: the
/// object lies above the plane `depth` below the tangent plane, so along a normal tilted by
/// up to 60 degrees it reaches at most 2 depth; beyond the shell thickness it is capped anyway.
pub fn max_trace_depth(finger: &Finger, depth_mm: f64) -> f64 {
    (2.0 * depth_mm).min(finger.shell_thickness) + 0.5
}

/// Inward displacement (mm) of the skin at surface point `at` where the object presses it,
/// traced from
/// `max_depth` inwards. The skin cannot bend tighter than `drape` mm, so it is the object
/// grown by `drape` (its SDF minus `drape`) that is traced, less `drape`: under the object the
/// skin follows it, past an edge it falls away on a circle of that radius instead of a cliff
/// (computed from the SDF itself, so no grid can turn the edge into a staircase).
/// `hit_tolerance` > TRACE_EPSILON_MM makes it conservative (used by the footprint scan).
pub fn penetration(
    pose: &ContactPose,
    object: &Object,
    at: &SurfacePoint,
    max_depth: f64,
    drape: f64,
    hit_tolerance: f64,
) -> f64 {
    // A hit at lambda <= drape is no press, as is a trace that stops there.
    match trace_inward(
        pose,
        object,
        at,
        max_depth + drape,
        drape,
        hit_tolerance,
        drape,
    ) {
        Trace::Hit(lambda) => (lambda - drape).max(0.0),
        Trace::Missed | Trace::OutOfSteps => 0.0,
    }
}

/// Whether the object grown by `drape + tolerance` reaches the inward normal at `at`
/// deeper than `drape` (within `max_depth + drape`): true for every coord within
/// `tolerance` of a point [`penetration`] finds pressed. Sphere tracing by the grown SDF,
/// so that no region within the tolerance is stepped over; a trace that runs out of steps
/// counts as touching (this only prunes work).
pub fn may_touch(
    pose: &ContactPose,
    object: &Object,
    at: &SurfacePoint,
    max_depth: f64,
    drape: f64,
    tolerance: f64,
) -> bool {
    let start = max_depth + drape;
    match trace_inward(
        pose,
        object,
        at,
        start,
        drape + tolerance,
        TRACE_EPSILON_MM,
        drape,
    ) {
        Trace::Hit(lambda) => lambda > drape,
        Trace::Missed => false,
        Trace::OutOfSteps => true,
    }
}

/// How a trace along a surface normal ended.
enum Trace {
    /// The grown object's surface, at this distance along the inward normal.
    Hit(f64),
    /// Nothing before `floor`.
    Missed,
    /// MAX_TRACE_STEPS steps without an answer (grazing).
    OutOfSteps,
}

/// Sphere-traces the object grown by `grow` (its SDF minus `grow`) along the inward normal
/// at `sp`, from `start` inwards: a hit where the grown SDF falls to `hit`, a miss once
/// the trace reaches `floor`. Shared by [`penetration`] and [`may_touch`].
#[allow(clippy::too_many_arguments)]
fn trace_inward(
    pose: &ContactPose,
    object: &Object,
    sp: &SurfacePoint,
    start: f64,
    grow: f64,
    hit: f64,
    floor: f64,
) -> Trace {
    let mut lambda = start;
    for _ in 0..MAX_TRACE_STEPS {
        let d = object.sdf(pose.to_object(sp.point - lambda * sp.normal)) - grow;
        if d <= hit {
            return Trace::Hit(lambda);
        }
        lambda -= d;
        if lambda <= floor {
            return Trace::Missed;
        }
    }
    Trace::OutOfSteps
}

/// Radius of the surface's parallel circle at arc length `s` from the tip: r sin(s / r) on
/// the hemisphere, r on the cylinder. Azimuthal distances on the surface are rho(s) dphi.
pub fn parallel_radius(finger: &Finger, s: f64) -> f64 {
    if s <= finger.junction_s() {
        finger.radius * (s / finger.radius).sin()
    } else {
        finger.radius
    }
}

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
    let f = &sensor.finger;
    let max_depth = pose.trace_depth_mm;
    const CELL: u32 = 2;
    let cells = grid.texels.div_ceil(CELL);
    let cell_mm = grid.texel_mm() * CELL as f64;
    let tolerance = cell_mm * std::f64::consts::FRAC_1_SQRT_2 + TRACE_EPSILON_MM;
    let drape = sensor.config.elastomer.drape_mm;
    let reach = object.bounding_radius() + max_depth + drape + tolerance;
    let centre = |ci: u32, cj: u32| {
        DVec2::new(ci as f64 + 0.5, cj as f64 + 0.5) * cell_mm - DVec2::splat(grid.half_size_mm)
    };
    // Arc length falls as height rises, over the whole finger: only cells whose s lies
    // between those of the heights origin.z +- reach can be within reach (a cheap first test
    // before the trigonometry; 1 µm of slack for rounding).
    let s_of_height = |z: f64| {
        let (r, d) = (f.radius, f.cylinder_length);
        if z >= d {
            r * ((z - d) / r).clamp(-1.0, 1.0).acos()
        } else {
            f.junction_s() + (d - z)
        }
    };
    let s_lo = s_of_height(pose.origin.z + reach) - 1e-3;
    let s_hi = (s_of_height(pose.origin.z - reach) + 1e-3).min(grid.half_size_mm);
    // Blocks of BLOCK x BLOCK cells first, each traced with its own (larger) tolerance: a
    // block none of whose surface points can be touched holds no touched cell, so only the
    // cells of touched blocks are traced (the marks are those of tracing every cell).
    const BLOCK: u32 = 4;
    let blocks = cells.div_ceil(BLOCK);
    let block_mm = cell_mm * BLOCK as f64;
    // Every surface point of a block lies within its half diagonal of the centre's, and its
    // normal within half diagonal / radius of the centre's normal, so a point traced
    // max_depth + drape in along it lies at most that much further off.
    let half_diagonal = block_mm * std::f64::consts::FRAC_1_SQRT_2;
    let block_tolerance = half_diagonal * (1.0 + (max_depth + drape) / f.radius) + TRACE_EPSILON_MM;
    let block_reach = reach - tolerance + half_diagonal + TRACE_EPSILON_MM;
    let mut touched_blocks = vec![false; (blocks * blocks) as usize];
    touched_blocks
        .par_chunks_mut(blocks as usize)
        .enumerate()
        .for_each(|(bj, row)| {
            for (bi, mark) in row.iter_mut().enumerate() {
                let c = DVec2::new(bi as f64 + 0.5, bj as f64 + 0.5) * block_mm
                    - DVec2::splat(grid.half_size_mm);
                let s = c.length();
                if s < s_lo - block_tolerance || s > s_hi + block_tolerance {
                    continue;
                }
                let at = f.point_at_disc(c);
                if (at.point - pose.origin).length() > block_reach {
                    continue;
                }
                *mark = may_touch(pose, object, &at, max_depth, drape, block_tolerance);
            }
        });
    // Rows of cells in parallel: the GPU waits for this (prepare is on the frame's path).
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
                let s = centre(ci, cj).length();
                if s < s_lo || s > s_hi {
                    continue;
                }
                let at = f.point_at_disc(centre(ci, cj));
                if (at.point - pose.origin).length() > reach {
                    continue;
                }
                *mark = penetration(pose, object, &at, max_depth, drape, tolerance) > 0.0;
            }
        });
    let is_marked = |ci: i64, cj: i64| {
        ci >= 0
            && cj >= 0
            && ci < cells as i64
            && cj < cells as i64
            && marked[(cj * cells as i64 + ci) as usize]
    };
    // How far the imprint's influence reaches beyond a marked cell's centre (surface mm);
    // a 10% margin covers the bounding box falling between the 8 sampled directions.
    let grow = 1.1 * blend_reach_mm + cell_mm;
    let depths = [
        -0.5 * f.shell_thickness,
        0.0,
        0.5 * f.shell_thickness,
        f.shell_thickness,
    ];
    // The eight directions the boundary cells grow in, as (sine, cosine).
    let directions: [(f64, f64); 8] =
        std::array::from_fn(|k| (k as f64 * std::f64::consts::FRAC_PI_4).sin_cos());
    // Per row of cells, then merged: the bounds of the grown boundary cells on the disc and
    // in the image (min and max do not depend on the order, so neither does the result).
    let row_bounds = |cj: i64| {
        let mut b = Bounds::default();
        for ci in 0..cells as i64 {
            if !is_marked(ci, cj) {
                continue;
            }
            let interior = (-1..=1).all(|dj| (-1..=1).all(|di| is_marked(ci + di, cj + dj)));
            if interior {
                continue;
            }
            let c = SurfaceCoord::from_disc(centre(ci as u32, cj as u32));
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
                // One sine and cosine of the azimuth for both the disc position and the point.
                let (sin_phi, cos_phi) = p.phi.sin_cos();
                let disc = p.s * DVec2::new(cos_phi, sin_phi);
                b.disc_lo = b.disc_lo.min(disc);
                b.disc_hi = b.disc_hi.max(disc);
                let sp = f.point_towards(p.s, cos_phi, sin_phi);
                for depth in depths {
                    // Samples beyond the lens count at its edge: where the imprint runs out
                    // of view, what is seen of it reaches the edge (a short arc, inside the
                    // rectangle's padding).
                    let (px, seen) = pixel_towards(sensor, sp.point - depth * sp.normal);
                    b.any_seen |= seen;
                    // Pixel centres are at integers: shift to cell space.
                    b.px_lo = b.px_lo.min(px + DVec2::splat(0.5));
                    b.px_hi = b.px_hi.max(px + DVec2::splat(0.5));
                }
            }
        }
        b
    };
    let Bounds {
        disc_lo,
        disc_hi,
        px_lo,
        px_hi,
        any_seen,
    } = (0..cells as i64)
        .into_par_iter()
        .map(row_bounds)
        .reduce(Bounds::default, Bounds::merge);
    if disc_lo.x > disc_hi.x {
        return None;
    }
    // The marked cells' texels (CELL x CELL each), by rows of cells.
    let (mut c_lo, mut c_hi) = ((u32::MAX, u32::MAX), (0, 0));
    for (cj, row) in marked.chunks(cells as usize).enumerate() {
        if let (Some(first), Some(last)) =
            (row.iter().position(|&m| m), row.iter().rposition(|&m| m))
        {
            c_lo = (c_lo.0.min(first as u32), c_lo.1.min(cj as u32));
            c_hi = (c_hi.0.max(last as u32), c_hi.1.max(cj as u32));
        }
    }
    let texel_end = |c: u32| ((c + 1) * CELL).min(grid.texels);
    let pressed = Rect {
        x: c_lo.0 * CELL,
        y: c_lo.1 * CELL,
        w: texel_end(c_hi.0) - c_lo.0 * CELL,
        h: texel_end(c_hi.1) - c_lo.1 * CELL,
    };
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

/// The penetration field over `rect` of a `grid.texels`^2 heightfield (zero elsewhere).
pub fn penetration_field(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    pose: &ContactPose,
    object: &Object,
    rect: Rect,
) -> Vec<f32> {
    let f = &sensor.finger;
    let n = grid.texels as usize;
    let max_depth = pose.trace_depth_mm;
    let drape = sensor.config.elastomer.drape_mm;
    let mut field = vec![0.0f32; n * n];
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            // One sample per texel is enough: the drape makes the skin continuous at edges.
            let disc = grid.texel_centre(i, j);
            if disc.length() <= grid.half_size_mm {
                let at = f.point_at_disc(disc);
                field[j as usize * n + i as usize] =
                    penetration(pose, object, &at, max_depth, drape, TRACE_EPSILON_MM) as f32;
            }
        }
    }
    field
}

/// Tolerance (mm) to which [`first_touch`] finds the first-touch offset: each surface
/// sample's touching offset is traced to this, and the best sample is refined on the surface
/// until its step falls below it.
pub const FIRST_TOUCH_TOLERANCE_MM: f64 = 1e-6;

/// Spacing (mm, on the unrolled disc) of the coarse surface samples [`first_touch`] searches
/// before refining; thinner object features than this along the surface could be missed.
pub const FIRST_TOUCH_SAMPLE_MM: f64 = 0.25;

/// Surface points within this offset (mm) of the first touch count as touched first.
pub const FIRST_TOUCH_BAND_MM: f64 = 0.01;

/// Where an object moving towards the finger first touches its undeformed surface.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstTouch {
    /// The offset along the backing-off direction `b` at which it touches: the object placed
    /// at `origin + offset b` just touches the surface (and at any larger offset does not).
    pub offset_mm: f64,
    /// The surface point touched first (refined to [`FIRST_TOUCH_TOLERANCE_MM`]).
    pub point: SurfaceCoord,
    /// Coarse surface samples touched within [`FIRST_TOUCH_BAND_MM`] of the first touch
    /// (a ring's circle, a face's line), the refined point first.
    pub band: Vec<SurfaceCoord>,
}

/// The largest offset t in [`t_lo`, `t_hi`] at which surface point `sp` lies inside the
/// object placed at `origin + t b` (sphere tracing downwards from `t_hi`), or None.
fn touching_offset(
    object: &Object,
    object_from_world: glam::DMat3,
    rel: DVec3,
    b_obj: DVec3,
    t_hi: f64,
    t_lo: f64,
) -> Option<f64> {
    // The surface point in the frame of the object at offset t: object_from_world (S - O) - t b.
    let q0 = object_from_world * rel;
    let mut t = t_hi;
    for _ in 0..400 {
        let d = object.sdf(q0 - t * b_obj);
        if d <= FIRST_TOUCH_TOLERANCE_MM {
            return Some(t);
        }
        t -= d;
        if t < t_lo {
            return None;
        }
    }
    None
}

/// Nelder-Mead maximising `score` in the plane from `start` (a point and its score) with a
/// first simplex of side `size`, until the simplex is smaller than
/// [`FIRST_TOUCH_TOLERANCE_MM`] (or 2000 iterations: a bound, the caller refines further).
/// The best point and its score.
fn nelder_mead(score: impl Fn(DVec2) -> f64, start: (DVec2, f64), size: f64) -> (DVec2, f64) {
    let vertex = |v: DVec2| (v, score(v));
    let mut simplex = [
        start,
        vertex(start.0 + DVec2::new(size, 0.0)),
        vertex(start.0 + DVec2::new(0.0, size)),
    ];
    for _ in 0..2000 {
        simplex.sort_by(|a, b| b.1.total_cmp(&a.1));
        let size = (simplex[1].0 - simplex[0].0)
            .length()
            .max((simplex[2].0 - simplex[0].0).length());
        if size < FIRST_TOUCH_TOLERANCE_MM {
            break;
        }
        let centroid = 0.5 * (simplex[0].0 + simplex[1].0);
        let worst = simplex[2];
        let reflected = vertex(centroid + (centroid - worst.0));
        if reflected.1 > simplex[0].1 {
            let expanded = vertex(centroid + 2.0 * (centroid - worst.0));
            simplex[2] = if expanded.1 > reflected.1 {
                expanded
            } else {
                reflected
            };
        } else if reflected.1 > simplex[1].1 {
            simplex[2] = reflected;
        } else {
            let contracted = vertex(if reflected.1 > worst.1 {
                centroid + 0.5 * (reflected.0 - centroid)
            } else {
                centroid + 0.5 * (worst.0 - centroid)
            });
            if contracted.1 > worst.1.max(reflected.1) {
                simplex[2] = contracted;
            } else {
                let best = simplex[0].0;
                for v in simplex.iter_mut().skip(1) {
                    *v = vertex(best + 0.5 * (v.0 - best));
                }
            }
        }
    }
    simplex.sort_by(|a, b| b.1.total_cmp(&a.1));
    simplex[0]
}

/// A block of coarse cells or one cell of [`first_touch`]'s search, with its bound on the
/// offsets there: taken from the queue highest bound first, a block before a cell of the
/// same bound (the block's cells are then queued), cells of the same bound by row and then
/// column.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    bound: f64,
    block: bool,
    /// (row, column), of blocks or of cells.
    at: (i64, i64),
}

impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.bound
            .total_cmp(&other.bound)
            .then(self.block.cmp(&other.block))
            .then(other.at.cmp(&self.at))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}

impl Eq for Candidate {}

/// First touch of `object` (rotation `world_from_object`, origin `origin` at offset 0),
/// moved along `-b` (unit `b`: the backing-off direction) towards the undeformed finger,
/// searched over offsets `t_lo..=t_hi`. Coarse surface samples every
/// [`FIRST_TOUCH_SAMPLE_MM`] within the object's reach of its path, each traced to
/// [`FIRST_TOUCH_TOLERANCE_MM`], then the best refined by a pattern search on the surface.
/// `None` when the object touches nothing on that path.
pub fn first_touch(
    finger: &Finger,
    grid: &HeightfieldGrid,
    object: &Object,
    world_from_object: glam::DMat3,
    origin: DVec3,
    b: DVec3,
    (t_lo, t_hi): (f64, f64),
) -> Option<FirstTouch> {
    let object_from_world = world_from_object.transpose();
    let b_obj = object_from_world * b;
    let radius = object.bounding_radius();
    let (a, c) = (origin + t_hi * b, origin + t_lo * b);
    let near_path = |p: DVec3, slack: f64| {
        let ab = c - a;
        let k = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
        (p - (a + k * ab)).length() <= radius + slack + 1e-9
    };
    let eval = |coord: SurfaceCoord| {
        let sp = finger.point_at(coord);
        touching_offset(
            object,
            object_from_world,
            sp.point - origin,
            b_obj,
            t_hi,
            t_lo,
        )
    };
    // Coarse samples: a square grid on the unrolled disc over the whole finger (the
    // heightfield may cover less of it than an object can touch, on a narrow lens).
    let half = grid
        .half_size_mm
        .max(finger.junction_s() + finger.cylinder_length);
    let n = (2.0 * half / FIRST_TOUCH_SAMPLE_MM).ceil() as i64;
    let (z_lo, z_hi) = (a.z.min(c.z) - radius, a.z.max(c.z) + radius);
    // Arc length falls as height rises: the heights the swept object spans bound the s of
    // the samples worth a look (checked before any trigonometry).
    let s_of_height = |z: f64| {
        let (r, d) = (finger.radius, finger.cylinder_length);
        if z >= d {
            r * ((z - d) / r).clamp(-1.0, 1.0).acos()
        } else {
            finger.junction_s() + (d - z)
        }
    };
    let (s_lo, s_hi) = (
        s_of_height(z_hi) - 1e-9,
        (s_of_height(z_lo) + 1e-9).min(half),
    );
    // Coarse cells of 4 x 4 samples first, each traced with a tolerance of its radius: an
    // upper bound on its samples' offsets (every surface point of a cell lies within that
    // radius of its centre, and the SDF is 1-Lipschitz). Cells are refined sample by sample,
    // the most promising first, only while their bound can still reach the best offset so
    // far (less the band); a sample's trace stops once it falls below that too.
    const SUB: i64 = 4;
    let cell_mm = FIRST_TOUCH_SAMPLE_MM * SUB as f64;
    let cell_radius = cell_mm * std::f64::consts::FRAC_1_SQRT_2 + 1e-9;
    let cells = (n + SUB - 1) / SUB;
    let first = ((half - s_hi - cell_mm) / cell_mm).floor().max(0.0) as i64;
    let last = (cells - first).min(cells);
    // The largest offset at which the object comes within `reach` of the surface point at
    // disc position `disc` (traced downwards from t_hi): a bound on the offsets of every
    // surface point that close to it on the disc. None when it stays farther all the way
    // down to t_lo, or the point is out of the swept object's way.
    let bound_at = |disc: DVec2, reach: f64| -> Option<f64> {
        let s = disc.length();
        if s < s_lo - reach || s > s_hi + reach {
            return None;
        }
        let sp = finger.point_at_disc(disc);
        if !near_path(sp.point, reach) {
            return None;
        }
        let q0 = object_from_world * (sp.point - origin);
        let mut t = t_hi;
        for _ in 0..400 {
            let d = object.sdf(q0 - t * b_obj);
            if d <= reach {
                return Some(t);
            }
            t -= d - reach + 1e-6;
            if t < t_lo {
                return None;
            }
        }
        Some(t)
    };
    let cell_disc = |ci: i64, cj: i64| {
        DVec2::new(ci as f64 + 0.5, cj as f64 + 0.5) * cell_mm - DVec2::splat(half)
    };
    // The cells in blocks of GROUP x GROUP, each block bounded first with its own radius
    // (rows of blocks in parallel): a cell's bound is at most its block's (its centre lies
    // within the block's radius less its own of the block's centre; 1e-5 mm of slack for the
    // traces' steps), so cells are bounded only in the blocks taken, the most promising
    // first, and far-off blocks cost one trace instead of sixteen. Cells come out of the
    // queue in the order of their bounds (ties by row, then column), as a sorted list of
    // every cell's bound would give them.
    const GROUP: i64 = 4;
    let block_radius = cell_mm * GROUP as f64 * std::f64::consts::FRAC_1_SQRT_2 + 1e-9;
    let span = (last - first).max(0);
    let blocks = (span + GROUP - 1) / GROUP;
    let block_cells = |b: i64| first + b * GROUP..(first + (b + 1) * GROUP).min(last);
    let block_rows = |bj: i64| -> Vec<Candidate> {
        (0..blocks)
            .filter_map(|bi| {
                let centre = DVec2::splat(first as f64 + GROUP as f64 * 0.5) * cell_mm
                    + DVec2::new(bi as f64, bj as f64) * (GROUP as f64 * cell_mm)
                    - DVec2::splat(half);
                bound_at(centre, block_radius).map(|u| Candidate {
                    bound: u + 1e-5,
                    block: true,
                    at: (bj, bi),
                })
            })
            .collect()
    };
    let mut queue: std::collections::BinaryHeap<Candidate> = (0..blocks)
        .into_par_iter()
        .flat_map_iter(block_rows)
        .collect();
    let mut floor = t_lo;
    let mut samples: Vec<(SurfaceCoord, f64)> = Vec::new();
    while let Some(next) = queue.pop() {
        if next.bound < floor {
            break;
        }
        if next.block {
            let (bj, bi) = next.at;
            for cj in block_cells(bj) {
                for ci in block_cells(bi) {
                    if let Some(u) = bound_at(cell_disc(ci, cj), cell_radius) {
                        queue.push(Candidate {
                            bound: u,
                            block: false,
                            at: (cj, ci),
                        });
                    }
                }
            }
            continue;
        }
        let (cj, ci) = next.at;
        for j in cj * SUB..(cj * SUB + SUB).min(n) {
            for i in ci * SUB..(ci * SUB + SUB).min(n) {
                let disc = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * FIRST_TOUCH_SAMPLE_MM
                    - DVec2::splat(half);
                let s = disc.length();
                if s < s_lo || s > s_hi {
                    continue;
                }
                let sp = finger.point_at_disc(disc);
                if !near_path(sp.point, 0.0) {
                    continue;
                }
                let rel = sp.point - origin;
                if let Some(t) = touching_offset(object, object_from_world, rel, b_obj, t_hi, floor)
                {
                    samples.push((SurfaceCoord::from_disc(disc), t));
                    floor = floor.max(t - FIRST_TOUCH_BAND_MM);
                }
            }
        }
    }
    let &(mut best, mut best_t) = samples.iter().max_by(|x, y| x.1.total_cmp(&y.1))?;
    // Refining the best sample on the surface takes two searches. Nelder-Mead first (x = s,
    // y = arc along the parallel at the start): its simplex stretches along a sharp ridge (an
    // edge's crease lying across the finger) at any slant, where steps along the meridian
    // and the parallel both fall off it; a pattern search alone stopped up to 0.09 mm short
    // of the top on random edge poses, or crept along the crease in 2 um steps (84 000
    // traces for one pose).
    {
        let rho0 = parallel_radius(finger, best.s).max(1e-6);
        let to_coord = |v: DVec2| SurfaceCoord {
            s: v.x.clamp(0.0, half),
            phi: v.y / rho0,
        };
        let score = |v: DVec2| eval(to_coord(v)).unwrap_or(f64::NEG_INFINITY);
        let v0 = DVec2::new(best.s, best.phi * rho0);
        let (v, t) = nelder_mead(score, (v0, best_t), FIRST_TOUCH_SAMPLE_MM);
        if t > best_t {
            (best, best_t) = (to_coord(v), t);
        }
    }
    // Then a pattern search (Hooke and Jeeves) polishes it to the tolerance: explore one
    // step along the meridian and the parallel, halved when no neighbour is better; after a
    // move that improves, keep going the way it went, twice as far each time while that
    // improves.
    let mut step = FIRST_TOUCH_SAMPLE_MM;
    // Where the search stood when its step last changed (or a trail move last failed): the
    // way it has gone since is the way the ridge runs.
    let mut trail = best;
    // From a point, keep going (ds, dphi), twice as far each time while that improves.
    let walk = |(mut best, mut best_t): (SurfaceCoord, f64), (mut ds, mut dphi): (f64, f64)| {
        let mut moved = false;
        loop {
            let coord = SurfaceCoord {
                s: (best.s + ds).clamp(0.0, half),
                phi: best.phi + dphi,
            };
            match eval(coord) {
                Some(t) if t > best_t + 1e-12 => {
                    (best, best_t, moved) = (coord, t, true);
                    (ds, dphi) = (2.0 * ds, 2.0 * dphi);
                }
                _ => return (best, best_t, moved),
            }
        }
    };
    while step > FIRST_TOUCH_TOLERANCE_MM {
        let rho = parallel_radius(finger, best.s).max(1e-6);
        let start = best;
        let mut moved = false;
        for (ds, dphi) in [
            (step, 0.0),
            (-step, 0.0),
            (0.0, step / rho),
            (0.0, -step / rho),
        ] {
            let coord = SurfaceCoord {
                s: (best.s + ds).clamp(0.0, half),
                phi: best.phi + dphi,
            };
            if let Some(t) = eval(coord) {
                if t > best_t + 1e-12 {
                    (best, best_t, moved) = (coord, t, true);
                }
            }
        }
        if !moved {
            step *= 0.5;
            trail = best;
            continue;
        }
        (best, best_t, _) = walk((best, best_t), (best.s - start.s, best.phi - start.phi));
        // On a ridge each exploring step off it loses more than a step along it gains, so
        // the search creeps; the trail since the step last changed points along the ridge:
        // walk it too (on random edge poses after Nelder-Mead, up to 3e-5 mm higher).
        let along = (best.s - trail.s, best.phi - trail.phi);
        let mut trailed = false;
        if along != (best.s - start.s, best.phi - start.phi) {
            (best, best_t, trailed) = walk((best, best_t), along);
        }
        if !trailed {
            trail = start;
        }
    }
    // The offset is known to the tolerance: a top point on the normal touches at 0 exactly
    // (not at a rounding error's distance from it), so such contacts are placed as before.
    if best_t.abs() <= FIRST_TOUCH_TOLERANCE_MM {
        best_t = 0.0;
    }
    let mut band = vec![best];
    band.extend(
        samples
            .iter()
            .filter(|(_, t)| *t >= best_t - FIRST_TOUCH_BAND_MM)
            .map(|(c, _)| *c),
    );
    Some(FirstTouch {
        offset_mm: best_t,
        point: best,
        band,
    })
}

/// What the contact stage's penetration field says about one contact, on the undeformed
/// surface: the labels a detector is scored against.
#[derive(Debug, Clone, PartialEq)]
pub struct IndentationLabels {
    /// The deepest penetration over the field (mm): the indentation actually reached.
    pub reached_mm: f64,
    /// Where it is reached (on the undeformed surface); None when nothing is pressed.
    pub deepest: Option<DVec3>,
    /// Centroid of the indented area (texels pressed beyond [`super::MASK_THRESHOLD_MM`]),
    /// weighted by penetration and surface area, projected back onto the surface; None when
    /// nothing is pressed. A ring's lies in its middle, a face's in the face's middle.
    pub centre: Option<DVec3>,
    /// Surface area (mm²) of the indented texels.
    pub area_mm2: f64,
}

/// Labels of a penetration field over `rect`, given as `rect`'s rows of the grid: texel
/// (i, j) at `field[(j - rect.y) * texels + i]` (the renderer reads back only those rows;
/// pass `&whole[rect.y * texels..]` for a whole-grid field from [`penetration_field`]).
pub fn indentation_labels(
    finger: &Finger,
    grid: &HeightfieldGrid,
    field: &[f32],
    rect: Rect,
) -> IndentationLabels {
    let n = grid.texels as usize;
    let texel_area = grid.texel_mm() * grid.texel_mm();
    let (mut reached, mut deepest) = (0.0f64, None);
    let (mut sum, mut weight, mut area) = (DVec3::ZERO, 0.0, 0.0);
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let p = field[(j - rect.y) as usize * n + i as usize] as f64;
            if p <= super::MASK_THRESHOLD_MM {
                continue;
            }
            let coord = SurfaceCoord::from_disc(grid.texel_centre(i, j));
            let point = finger.point_at(coord).point;
            if p > reached {
                (reached, deepest) = (p, Some(point));
            }
            // Surface area of a disc texel: rho(s) / s times its disc area.
            let jac = if coord.s > 1e-9 {
                parallel_radius(finger, coord.s) / coord.s
            } else {
                1.0
            };
            let a = texel_area * jac;
            area += a;
            sum += p * a * point;
            weight += p * a;
        }
    }
    let centre = (weight > 0.0).then(|| {
        let c = sum / weight;
        finger.point_at(finger.coord_of(c)).point
    });
    IndentationLabels {
        reached_mm: reached,
        deepest,
        centre,
        area_mm2: area,
    }
}
