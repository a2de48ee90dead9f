//! Stage 1, contact: how far the object pushes the skin inward along the surface normal, at
//! each heightfield texel. CPU mirror of `shaders/contact.wgsl` (same names).
//!
//! Penetration at a surface point S with outward normal n is the largest lambda in [0, L]
//! with S - lambda n inside the object: found by sphere tracing the object's SDF from the
//! deep end (lambda = L) outwards, so the first object point met is the deepest.

use super::{ContactPose, HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::object::Object;
use crate::sensor::Sensor;
use glam::DVec2;

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

/// Inward displacement (mm) of the skin at `coord` where the object presses it, traced from
/// `max_depth` inwards. The skin cannot bend tighter than `drape` mm, so it is the object
/// grown by `drape` (its SDF minus `drape`) that is traced, less `drape`: under the object the
/// skin follows it, past an edge it falls away on a circle of that radius instead of a cliff
/// (computed from the SDF itself, so no grid can turn the edge into a staircase).
/// `hit_tolerance` > TRACE_EPSILON_MM makes it conservative (used by the footprint scan).
pub fn penetration(
    finger: &Finger,
    pose: &ContactPose,
    object: &Object,
    coord: SurfaceCoord,
    max_depth: f64,
    drape: f64,
    hit_tolerance: f64,
) -> f64 {
    let sp = finger.point_at(coord);
    let mut lambda = max_depth + drape;
    for _ in 0..MAX_TRACE_STEPS {
        let q = sp.point - lambda * sp.normal;
        let d = object.sdf(pose.to_object(q)) - drape;
        if d <= hit_tolerance {
            return (lambda - drape).max(0.0);
        }
        lambda -= d;
        if lambda < drape {
            return 0.0;
        }
    }
    0.0
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

/// Texels of the heightfield the object touches (conservatively), grown by `blend_mm` of
/// surface distance for the elastomer's blur; `None` when the object touches nothing.
pub fn footprint(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    pose: &ContactPose,
    object: &Object,
    blend_reach_mm: f64,
) -> Option<Rect> {
    let f = &sensor.finger;
    let max_depth = max_trace_depth(f, pose.depth_mm);
    // Coarse cells of 2x2 texels; the disc-to-surface map never stretches distances, so every
    // surface point in a cell lies within half its diagonal of the cell's centre.
    const CELL: u32 = 2;
    let cells = grid.texels.div_ceil(CELL);
    let cell_mm = grid.texel_mm() * CELL as f64;
    let tolerance = cell_mm * std::f64::consts::FRAC_1_SQRT_2 + TRACE_EPSILON_MM;
    let drape = sensor.config.elastomer.drape_mm;
    let reach = object.bounding_radius() + max_depth + drape + tolerance;
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    let mut s_hi: f64 = 0.0;
    // Largest |cos phi| and |sin phi| over the footprint: the radial and tangential
    // directions on the disc, along which the elastomer's kernels reach.
    let mut trig = DVec2::ZERO;
    for cj in 0..cells {
        for ci in 0..cells {
            let disc = DVec2::new(ci as f64 + 0.5, cj as f64 + 0.5) * cell_mm
                - DVec2::splat(grid.half_size_mm);
            let coord = SurfaceCoord::from_disc(disc);
            if coord.s > grid.half_size_mm {
                continue;
            }
            if (f.point_at(coord).point - pose.origin).length() > reach {
                continue;
            }
            if penetration(f, pose, object, coord, max_depth, drape, tolerance) > 0.0 {
                let t = grid.texel_of(disc);
                lo = lo.min(t);
                hi = hi.max(t);
                s_hi = s_hi.max(coord.s + cell_mm);
                trig = trig.max(DVec2::new(coord.phi.cos().abs(), coord.phi.sin().abs()));
                if coord.s <= cell_mm {
                    trig = DVec2::ONE;
                }
            }
        }
    }
    if lo.x > hi.x {
        return None;
    }
    // Azimuthal surface distance maps to s / rho(s) times as much disc distance.
    // A tangential step at azimuth phi moves along (-sin, cos) on the disc, a radial one
    // along (cos, sin).
    let stretch = (s_hi / parallel_radius(f, s_hi).max(1e-9)).max(1.0);
    let pad = DVec2::new(stretch * trig.y + trig.x, stretch * trig.x + trig.y) * blend_reach_mm
        / grid.texel_mm()
        + DVec2::splat(CELL as f64);
    Rect::covering(lo, hi, pad, (grid.texels, grid.texels))
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
    let max_depth = max_trace_depth(f, pose.depth_mm);
    let drape = sensor.config.elastomer.drape_mm;
    let mut field = vec![0.0f32; n * n];
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            // The mean of 2x2 samples: an edge crossing the texel gives a partial value
            // instead of a staircase along the grid (the skin's normals would show it).
            let centre = grid.texel_centre(i, j);
            let mut p = 0.0;
            for k in 0..4u32 {
                let offset =
                    (DVec2::new((k & 1) as f64, (k >> 1) as f64) - 0.5) * 0.5 * grid.texel_mm();
                let coord = SurfaceCoord::from_disc(centre + offset);
                if coord.s <= grid.half_size_mm {
                    p += 0.25
                        * penetration(f, pose, object, coord, max_depth, drape, TRACE_EPSILON_MM);
                }
            }
            field[j as usize * n + i as usize] = p as f32;
        }
    }
    field
}
