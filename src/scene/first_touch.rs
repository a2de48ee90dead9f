//! Where an object brought towards the finger first touches its undeformed surface: a coarse
//! scan of surface samples (bounded in cells and blocks of cells, taken from a queue most
//! promising first), then the best sample refined on the surface (Nelder-Mead, then a
//! pattern search).

use crate::finger::{Finger, SurfaceCoord};
use crate::object::Object;
use crate::render::contact::{arc_length_at_height, parallel_radius};
use crate::render::HeightfieldGrid;
use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

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

/// First touch of `object` (rotation `world_from_object`, origin `origin` at offset 0),
/// moved along `-b` (unit `b`: the backing-off direction) towards the undeformed finger,
/// searched over offsets `t_lo..=t_hi`. Coarse surface samples every
/// [`FIRST_TOUCH_SAMPLE_MM`] within the object's reach of its path, each traced to
/// [`FIRST_TOUCH_TOLERANCE_MM`], then the best refined on the surface.
/// `None` when the object touches nothing on that path.
pub fn first_touch(
    finger: &Finger,
    grid: &HeightfieldGrid,
    object: &Object,
    world_from_object: DMat3,
    origin: DVec3,
    b: DVec3,
    (t_lo, t_hi): (f64, f64),
) -> Option<FirstTouch> {
    let sweep = Sweep::new(
        finger,
        grid,
        object,
        world_from_object,
        origin,
        b,
        (t_lo, t_hi),
    );
    let samples = sweep.coarse_samples();
    let &(best, best_t) = samples.iter().max_by(|x, y| x.1.total_cmp(&y.1))?;
    let (best, mut best_t) = sweep.refine(best, best_t);
    // The offset is known to the tolerance: a top point on the normal touches at 0 exactly
    // (not at a rounding error's distance from it).
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

/// The largest offset t in [`t_lo`, `t_hi`] at which a point at `rel` from the origin lies
/// inside the object placed at `origin + t b` (sphere tracing downwards from `t_hi`), or
/// None. `b_obj` is `b` in the object's frame.
pub fn touching_offset(
    object: &Object,
    object_from_world: DMat3,
    rel: DVec3,
    b_obj: DVec3,
    t_hi: f64,
    t_lo: f64,
) -> Option<f64> {
    // The point in the frame of the object at offset t: object_from_world (S - O) - t b.
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

/// One first-touch search: the object, its path, and the square of surface samples on the
/// unrolled disc that the search scans.
struct Sweep<'a> {
    finger: &'a Finger,
    object: &'a Object,
    object_from_world: DMat3,
    origin: DVec3,
    /// The backing-off direction in the object's frame.
    b_obj: DVec3,
    t_lo: f64,
    t_hi: f64,
    /// The origin's path: at offset `t_hi` and at `t_lo`.
    a: DVec3,
    c: DVec3,
    radius: f64,
    /// Half the side of the sample square on the disc (mm).
    half: f64,
    /// Samples along each side of the square.
    n: i64,
    /// Arc lengths the swept object can reach.
    s_lo: f64,
    s_hi: f64,
}

impl<'a> Sweep<'a> {
    fn new(
        finger: &'a Finger,
        grid: &HeightfieldGrid,
        object: &'a Object,
        world_from_object: DMat3,
        origin: DVec3,
        b: DVec3,
        (t_lo, t_hi): (f64, f64),
    ) -> Sweep<'a> {
        let object_from_world = world_from_object.transpose();
        let radius = object.bounding_radius();
        let (a, c) = (origin + t_hi * b, origin + t_lo * b);
        // A square grid on the unrolled disc over the whole finger (the heightfield may
        // cover less of it than an object can touch, on a narrow lens).
        let half = grid
            .half_size_mm
            .max(finger.junction_s() + finger.cylinder_length);
        let (z_lo, z_hi) = (a.z.min(c.z) - radius, a.z.max(c.z) + radius);
        // Arc length falls as height rises: the heights the swept object spans bound the s
        // of the samples worth a look (checked before any trigonometry).
        Sweep {
            finger,
            object,
            object_from_world,
            origin,
            b_obj: object_from_world * b,
            t_lo,
            t_hi,
            a,
            c,
            radius,
            half,
            n: (2.0 * half / FIRST_TOUCH_SAMPLE_MM).ceil() as i64,
            s_lo: arc_length_at_height(finger, z_hi) - 1e-9,
            s_hi: (arc_length_at_height(finger, z_lo) + 1e-9).min(half),
        }
    }

    /// Whether `p` lies within the object's reach (plus `slack`) of the origin's path.
    fn near_path(&self, p: DVec3, slack: f64) -> bool {
        let (a, c) = (self.a, self.c);
        let ab = c - a;
        let k = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
        (p - (a + k * ab)).length() <= self.radius + slack + 1e-9
    }

    /// The touching offset of the surface point at `coord`, over the whole path.
    fn offset_at(&self, coord: SurfaceCoord) -> Option<f64> {
        let sp = self.finger.point_at(coord);
        touching_offset(
            self.object,
            self.object_from_world,
            sp.point - self.origin,
            self.b_obj,
            self.t_hi,
            self.t_lo,
        )
    }

    /// The largest offset at which the object comes within `reach` of the surface point at
    /// disc position `disc` (traced downwards from t_hi): a bound on the offsets of every
    /// surface point that close to it on the disc. None when it stays farther all the way
    /// down to t_lo, or the point is out of the swept object's way.
    fn bound_at(&self, disc: DVec2, reach: f64) -> Option<f64> {
        let s = disc.length();
        if s < self.s_lo - reach || s > self.s_hi + reach {
            return None;
        }
        let sp = self.finger.point_at_disc(disc);
        if !self.near_path(sp.point, reach) {
            return None;
        }
        let q0 = self.object_from_world * (sp.point - self.origin);
        let mut t = self.t_hi;
        for _ in 0..400 {
            let d = self.object.sdf(q0 - t * self.b_obj);
            if d <= reach {
                return Some(t);
            }
            t -= d - reach + 1e-6;
            if t < self.t_lo {
                return None;
            }
        }
        Some(t)
    }

    /// The coarse samples the object touches, each with its touching offset: every sample
    /// whose offset lies within [`FIRST_TOUCH_BAND_MM`] of the best is among them (with
    /// others above the floor the scan had reached when they were traced).
    ///
    /// Cells of 4 x 4 samples are bounded first, each traced with a tolerance of its radius:
    /// an upper bound on its samples' offsets (every surface point of a cell lies within that
    /// radius of its centre, and the SDF is 1-Lipschitz). Cells are refined sample by sample,
    /// the most promising first, only while their bound can still reach the best offset so
    /// far (less the band); a sample's trace stops once it falls below that too.
    fn coarse_samples(&self) -> Vec<(SurfaceCoord, f64)> {
        let cells = CoarseCells::new(self);
        let mut queue = self.bounded_blocks(&cells);
        let mut floor = self.t_lo;
        let mut samples: Vec<(SurfaceCoord, f64)> = Vec::new();
        while let Some(next) = queue.pop() {
            if next.bound < floor {
                break;
            }
            if next.block {
                let (bj, bi) = next.at;
                for cj in cells.of_block(bj) {
                    for ci in cells.of_block(bi) {
                        if let Some(u) = self.bound_at(cells.disc(ci, cj), cells.cell_radius) {
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
            self.sample_cell(next.at, &mut floor, &mut samples);
        }
        samples
    }

    /// Every block of cells the object can come near, with its bound (rows of blocks in
    /// parallel), as the queue the scan starts from.
    fn bounded_blocks(&self, cells: &CoarseCells) -> std::collections::BinaryHeap<Candidate> {
        let block_row = |bj: i64| -> Vec<Candidate> {
            (0..cells.blocks)
                .filter_map(|bi| {
                    self.bound_at(cells.block_centre(bi, bj), cells.block_radius)
                        .map(|u| Candidate {
                            bound: u + 1e-5,
                            block: true,
                            at: (bj, bi),
                        })
                })
                .collect()
        };
        (0..cells.blocks)
            .into_par_iter()
            .flat_map_iter(block_row)
            .collect()
    }

    /// Traces the samples of cell (row, column) `at` whose offsets can still reach `floor`,
    /// adding those that touch to `samples` and raising the floor to the best less the band.
    fn sample_cell(
        &self,
        (cj, ci): (i64, i64),
        floor: &mut f64,
        samples: &mut Vec<(SurfaceCoord, f64)>,
    ) {
        let n = self.n;
        for j in cj * SUB..(cj * SUB + SUB).min(n) {
            for i in ci * SUB..(ci * SUB + SUB).min(n) {
                let disc = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * FIRST_TOUCH_SAMPLE_MM
                    - DVec2::splat(self.half);
                let s = disc.length();
                if s < self.s_lo || s > self.s_hi {
                    continue;
                }
                let sp = self.finger.point_at_disc(disc);
                if !self.near_path(sp.point, 0.0) {
                    continue;
                }
                let rel = sp.point - self.origin;
                if let Some(t) = touching_offset(
                    self.object,
                    self.object_from_world,
                    rel,
                    self.b_obj,
                    self.t_hi,
                    *floor,
                ) {
                    samples.push((SurfaceCoord::from_disc(disc), t));
                    *floor = floor.max(t - FIRST_TOUCH_BAND_MM);
                }
            }
        }
    }

    /// The best sample refined on the surface by two searches. Nelder-Mead first (x = s,
    /// y = arc along the parallel at the start): its simplex stretches along a sharp ridge
    /// (an edge's crease lying across the finger) at any slant, where steps along the
    /// meridian and the parallel both fall off it; a pattern search alone stops up to
    /// 0.09 mm short of the top on random edge poses, or creeps along the crease in 2 um
    /// steps (84 000 traces for one pose). Then a pattern search polishes it to the
    /// tolerance.
    fn refine(&self, mut best: SurfaceCoord, mut best_t: f64) -> (SurfaceCoord, f64) {
        let rho0 = parallel_radius(self.finger, best.s).max(1e-6);
        let to_coord = |v: DVec2| SurfaceCoord {
            s: v.x.clamp(0.0, self.half),
            phi: v.y / rho0,
        };
        let score = |v: DVec2| self.offset_at(to_coord(v)).unwrap_or(f64::NEG_INFINITY);
        let v0 = DVec2::new(best.s, best.phi * rho0);
        let (v, t) = nelder_mead(score, (v0, best_t), FIRST_TOUCH_SAMPLE_MM);
        if t > best_t {
            (best, best_t) = (to_coord(v), t);
        }
        self.pattern_search(best, best_t)
    }

    /// From a point and its offset, keeps going (ds, dphi), twice as far each time while
    /// that improves; whether it moved at all.
    fn walk(
        &self,
        (mut best, mut best_t): (SurfaceCoord, f64),
        (mut ds, mut dphi): (f64, f64),
    ) -> (SurfaceCoord, f64, bool) {
        let mut moved = false;
        loop {
            let coord = SurfaceCoord {
                s: (best.s + ds).clamp(0.0, self.half),
                phi: best.phi + dphi,
            };
            match self.offset_at(coord) {
                Some(t) if t > best_t + 1e-12 => {
                    (best, best_t, moved) = (coord, t, true);
                    (ds, dphi) = (2.0 * ds, 2.0 * dphi);
                }
                _ => return (best, best_t, moved),
            }
        }
    }

    /// Pattern search (Hooke and Jeeves) to [`FIRST_TOUCH_TOLERANCE_MM`]: explore one step
    /// along the meridian and the parallel, halved when no neighbour is better; after a move
    /// that improves, keep going the way it went, twice as far each time while that
    /// improves.
    fn pattern_search(&self, mut best: SurfaceCoord, mut best_t: f64) -> (SurfaceCoord, f64) {
        let mut step = FIRST_TOUCH_SAMPLE_MM;
        // Where the search stood when its step last changed (or a trail move last failed):
        // the way it has gone since is the way the ridge runs.
        let mut trail = best;
        while step > FIRST_TOUCH_TOLERANCE_MM {
            let rho = parallel_radius(self.finger, best.s).max(1e-6);
            let start = best;
            let mut moved = false;
            for (ds, dphi) in [
                (step, 0.0),
                (-step, 0.0),
                (0.0, step / rho),
                (0.0, -step / rho),
            ] {
                let coord = SurfaceCoord {
                    s: (best.s + ds).clamp(0.0, self.half),
                    phi: best.phi + dphi,
                };
                if let Some(t) = self.offset_at(coord) {
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
            (best, best_t, _) = self.walk((best, best_t), (best.s - start.s, best.phi - start.phi));
            // On a ridge each exploring step off it loses more than a step along it gains, so
            // the search creeps; the trail since the step last changed points along the
            // ridge: walk it too (on random edge poses after Nelder-Mead, up to 3e-5 mm
            // higher).
            let along = (best.s - trail.s, best.phi - trail.phi);
            let mut trailed = false;
            if along != (best.s - start.s, best.phi - start.phi) {
                (best, best_t, trailed) = self.walk((best, best_t), along);
            }
            if !trailed {
                trail = start;
            }
        }
        (best, best_t)
    }
}

/// Samples per side of a coarse cell.
const SUB: i64 = 4;
/// Cells per side of a block.
const GROUP: i64 = 4;

/// The coarse cells of a sweep's sample square, in blocks of GROUP x GROUP: each block is
/// bounded first with its own radius, and a cell's bound is at most its block's (its centre
/// lies within the block's radius less its own of the block's centre; 1e-5 mm of slack for
/// the traces' steps), so cells are bounded only in the blocks taken, the most promising
/// first, and far-off blocks cost one trace instead of sixteen. Cells come out of the queue
/// in the order of their bounds (ties by row, then column), as a sorted list of every cell's
/// bound would give them.
struct CoarseCells {
    cell_mm: f64,
    cell_radius: f64,
    half: f64,
    /// The cells scanned along each side: `first..last`.
    first: i64,
    last: i64,
    blocks: i64,
    block_radius: f64,
}

impl CoarseCells {
    fn new(sweep: &Sweep) -> CoarseCells {
        let cell_mm = FIRST_TOUCH_SAMPLE_MM * SUB as f64;
        let cells = (sweep.n + SUB - 1) / SUB;
        let first = ((sweep.half - sweep.s_hi - cell_mm) / cell_mm)
            .floor()
            .max(0.0) as i64;
        let last = (cells - first).min(cells);
        let span = (last - first).max(0);
        CoarseCells {
            cell_mm,
            cell_radius: cell_mm * std::f64::consts::FRAC_1_SQRT_2 + 1e-9,
            half: sweep.half,
            first,
            last,
            blocks: (span + GROUP - 1) / GROUP,
            block_radius: cell_mm * GROUP as f64 * std::f64::consts::FRAC_1_SQRT_2 + 1e-9,
        }
    }

    /// Disc position of cell (column, row)'s centre.
    fn disc(&self, ci: i64, cj: i64) -> DVec2 {
        DVec2::new(ci as f64 + 0.5, cj as f64 + 0.5) * self.cell_mm - DVec2::splat(self.half)
    }

    /// Disc position of block (column, row)'s centre.
    fn block_centre(&self, bi: i64, bj: i64) -> DVec2 {
        DVec2::splat(self.first as f64 + GROUP as f64 * 0.5) * self.cell_mm
            + DVec2::new(bi as f64, bj as f64) * (GROUP as f64 * self.cell_mm)
            - DVec2::splat(self.half)
    }

    /// The cells (along one side) of block `b`.
    fn of_block(&self, b: i64) -> std::ops::Range<i64> {
        self.first + b * GROUP..(self.first + (b + 1) * GROUP).min(self.last)
    }
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
