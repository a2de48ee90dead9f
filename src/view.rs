//! What the lens sees of the finger: which surface points reach the image, how far down
//! each meridian the view goes, and the image's resolution (pixels per mm) on the surface.
//! Pure geometry from [`Sensor::project`]; the preview and stability jobs build on it.

use crate::finger::SurfaceCoord;
use crate::sensor::Sensor;

/// Step (mm) of finite differences of `project` along the surface.
const H_MM: f64 = 1e-3;

/// Arc length from the tip down to the camera's plane (z = 0): the finger's whole side.
pub fn finger_length(sensor: &Sensor) -> f64 {
    sensor.finger.junction_s() + sensor.finger.cylinder_length
}

/// Whether the camera sees the surface point at arc length `s` and azimuth `phi`.
pub fn visible(sensor: &Sensor, s: f64, phi: f64) -> bool {
    (0.0..=finger_length(sensor)).contains(&s)
        && sensor
            .project(sensor.finger.point_at(SurfaceCoord { s, phi }).point)
            .is_ok()
}

/// How far down the meridian at `phi` the camera sees (arc length from the tip, mm): the
/// visible part of a meridian is one piece from the tip, since the angle off the optical
/// axis grows down it; found by bisection to 1e-9 mm.
pub fn visible_extent(sensor: &Sensor, phi: f64) -> f64 {
    let end = finger_length(sensor);
    if !visible(sensor, 0.0, phi) {
        return 0.0;
    }
    if visible(sensor, end, phi) {
        return end;
    }
    let (mut lo, mut hi) = (0.0, end);
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if visible(sensor, mid, phi) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Pixels per mm along the meridian and the parallel at (s, phi), by finite differences of
/// `project` (central where both neighbours are visible, one-sided at the visible edge), or
/// `None` where the camera does not see the point.
pub fn px_per_mm(sensor: &Sensor, s: f64, phi: f64) -> Option<(f64, f64)> {
    let f = &sensor.finger;
    let px = |s: f64, phi: f64| -> Option<glam::DVec2> {
        if !(0.0..=finger_length(sensor)).contains(&s) {
            return None;
        }
        sensor
            .project(f.point_at(SurfaceCoord { s, phi }).point)
            .ok()
    };
    let centre = px(s, phi)?;
    let diff = |a: Option<glam::DVec2>, b: Option<glam::DVec2>, h: f64| match (a, b) {
        (Some(a), Some(b)) => Some((a - b).length() / (2.0 * h)),
        (Some(a), None) => Some((a - centre).length() / h),
        (None, Some(b)) => Some((centre - b).length() / h),
        (None, None) => None,
    };
    // Along the meridian: s +- h (at the tip, s - h is the point across the tip: use the
    // one-sided difference there).
    let down = px(s + H_MM, phi);
    let up = if s >= H_MM { px(s - H_MM, phi) } else { None };
    let meridian = diff(down, up, H_MM)?;
    // Along the parallel: the ring's radius is the point's distance from the axis; at the
    // tip the ring shrinks to a point and the parallel resolution equals the meridian's.
    let lateral = f
        .point_at(SurfaceCoord { s, phi })
        .point
        .truncate()
        .length();
    let parallel = if lateral < 1e-6 {
        meridian
    } else {
        let dphi = H_MM / lateral;
        diff(px(s, phi + dphi), px(s, phi - dphi), H_MM)?
    };
    Some((meridian, parallel))
}
