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
use glam::DVec3;

mod footprint;
pub use footprint::{footprint, meridian_margin, Footprint};

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

/// Arc length from the tip of the surface point at height `z` (mm along the axis from the
/// camera): it falls as height rises, over the whole finger.
pub fn arc_length_at_height(finger: &Finger, z: f64) -> f64 {
    let (r, d) = (finger.radius, finger.cylinder_length);
    if z >= d {
        r * ((z - d) / r).clamp(-1.0, 1.0).acos()
    } else {
        finger.junction_s() + (d - z)
    }
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
