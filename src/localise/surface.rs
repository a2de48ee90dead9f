//! The surface detector: find the contact where the frame differs from the reference by
//! more than the image's own noise, and locate it on the finger surface, not in the image.
//!
//! 1. Signed difference `frame - reference` per channel, smoothed by a mean filter. Noise:
//!    each smoothed channel's robust standard deviation (1.4826 x median absolute
//!    deviation) over the pixels that see the finger; a contact covers far less than half
//!    of them, so it does not inflate the estimate. A pixel's difference magnitude is the
//!    Euclidean norm of its three smoothed channels and `sigma` the RMS of that norm under
//!    noise alone (floored at [`super::NOISE_FLOOR`]).
//! 2. Detection: the largest magnitude must reach `detect_snr * sigma` (and `min_peak`).
//!    The smoothing scales are tried from the finest (5 x 5) up (to 25 x 25) and the first
//!    at which the contact clears that level is used: strong contacts keep their detail,
//!    and weak ones, lost in the noise of a fine scale, are found at a coarser one. A frame
//!    without contact, or with noise only, stays below the level at every scale.
//! 3. Support: pixels whose magnitude exceeds both `support_snr * sigma` and
//!    `relative_threshold * peak`: a low threshold, so that the faint margins of an imprint
//!    count. Their 8-connected components are the candidate regions; the largest on the
//!    surface is the contact, joined by every component whose extent on the surface comes
//!    within `merge_gap_mm` of it (an imprint's difference splits into lobes where the
//!    shading change passes through zero, and a ring-shaped object leaves a ring).
//! 4. Location, on the surface: every pixel is unprojected once per sensor (the map m, in a
//!    [`SurfaceCache`]). Starting from the area-weighted mean of the contact's points,
//!    snapped onto the surface along its normal (`Finger::coord_of`, `Finger::point_at`),
//!    the contact's points are projected onto the tangent plane there, along the meridian
//!    and the azimuth, and the point moves to the middle of their extent; repeated until it
//!    stays put. The middle of the outline is used rather than a weighted centroid because
//!    how strongly a pressed patch changes the image depends on how it faces the camera
//!    and the LEDs, not only on how deep it is pressed: across a 4 mm imprint the flank
//!    nearer the lens edge changes two to three times as much as the flank nearer the tip,
//!    which drags any intensity- or area-weighted centroid by a good fraction of a
//!    millimetre, while the outline, where the deformation fades out, moves far less.
//!    Working on the surface removes the fisheye's bias: an image-space centre of a patch
//!    seen obliquely is pulled towards the compressed side.
//! 5. Confidence: `1 - detection level / peak` (0 at the level, 0.5 at twice it).

use super::paper::mean_filter;
use super::raster::{components, robust_sigma, FloatImage, NEIGHBOURS_8};
use super::{check_sizes, Detection, NOISE_FLOOR};
use crate::error::Result;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use image::RgbImage;

/// Settings of the surface detector. The defaults suit 8-bit images of the paper's sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceConfig {
    /// Sides of the mean filters applied to the signed difference (px, odd), tried in
    /// order until the contact clears the detection level.
    pub scales: Vec<usize>,
    /// The peak magnitude must reach this many noise deviations to count as a contact.
    pub detect_snr: f64,
    /// ... and at least this many grey levels.
    pub min_peak: f64,
    /// Pixels above this many noise deviations belong to the contact ...
    pub support_snr: f64,
    /// ... and above this fraction of the peak magnitude.
    pub relative_threshold: f64,
    /// Components whose extents on the surface come this close (mm) join the contact.
    pub merge_gap_mm: f64,
    /// Joined components smaller than this fraction of the contact's surface area (specks
    /// of noise next to it) do not widen its outline.
    pub min_part_fraction: f64,
}

impl Default for SurfaceConfig {
    fn default() -> Self {
        SurfaceConfig {
            scales: vec![5, 9, 15, 25],
            detect_snr: 4.5,
            min_peak: 1.0,
            support_snr: 3.0,
            relative_threshold: 0.05,
            merge_gap_mm: 2.0,
            min_part_fraction: 0.02,
        }
    }
}

/// Per-pixel unprojection table for one sensor: for each pixel that sees the finger, the
/// surface point it sees and the area of surface it covers.
#[derive(Debug, Clone)]
pub struct SurfaceCache {
    pub width: u32,
    pub height: u32,
    /// Row-major surface points (mm); meaningless where `areas` is 0.
    pub points: Vec<DVec3>,
    /// Row-major surface area (mm^2) each pixel sees; 0 where it sees no part of the finger.
    pub areas: Vec<f64>,
    /// Indices of the pixels that see the finger.
    pub valid: Vec<usize>,
    /// Row-major: the pixel sees the finger but lies on the image border or next to a pixel
    /// that does not (the edge of the lens's field of view).
    pub edge: Vec<bool>,
}

impl SurfaceCache {
    /// Builds the table: one lens ray per pixel centre. The area a pixel covers is
    /// `t^2 dOmega / cos(incidence)`, with the solid angle per pixel from the lens model
    /// (`sin(theta) / (rho drho/dtheta)`, `1 / rho'(0)^2` at the principal point).
    pub fn new(sensor: &Sensor) -> Self {
        let finger = sensor.finger;
        let (w, h) = (sensor.width as usize, sensor.height as usize);
        let mut points = vec![DVec3::ZERO; w * h];
        let mut areas = vec![0.0; w * h];
        let mut valid = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let pixel = DVec2::new(u as f64, v as f64);
                let Some(dir) = sensor.ray_direction(pixel) else {
                    continue;
                };
                let Some(sp) = finger.surface_along(dir) else {
                    continue;
                };
                let theta = dir.z.clamp(-1.0, 1.0).acos();
                let rho = (pixel - sensor.principal).length();
                let solid_angle = if rho > 1e-9 {
                    theta.sin() / (rho * sensor.lens.project_derivative(theta))
                } else {
                    sensor.lens.project_derivative(0.0).powi(-2)
                };
                let cos_inc = dir.dot(sp.normal).abs().max(0.05);
                let area = sp.point.length_squared() * solid_angle / cos_inc;
                if !(area.is_finite() && area > 0.0 && sp.point.is_finite()) {
                    continue;
                }
                let i = v * w + u;
                points[i] = sp.point;
                areas[i] = area;
                valid.push(i);
            }
        }
        let edge = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i32, (i / w) as i32);
                areas[i] > 0.0
                    && NEIGHBOURS_8.iter().any(|(dx, dy)| {
                        let (nx, ny) = (x + dx, y + dy);
                        nx < 0
                            || ny < 0
                            || nx >= w as i32
                            || ny >= h as i32
                            || areas[ny as usize * w + nx as usize] == 0.0
                    })
            })
            .collect();
        SurfaceCache {
            width: sensor.width,
            height: sensor.height,
            points,
            areas,
            valid,
            edge,
        }
    }
}

/// A rectangle of pixels, `[x0, x1) x [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Window {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

impl Window {
    fn width(&self) -> usize {
        self.x1 - self.x0
    }

    fn height(&self) -> usize {
        self.y1 - self.y0
    }

    /// Grown by `by` pixels on every side, clipped to a `w` x `h` image.
    fn grown(&self, by: usize, w: usize, h: usize) -> Window {
        Window {
            x0: self.x0.saturating_sub(by),
            y0: self.y0.saturating_sub(by),
            x1: (self.x1 + by).min(w),
            y1: (self.y1 + by).min(h),
        }
    }

    /// The image index of the `i`-th pixel of the window (row-major in the window).
    fn image_index(&self, i: usize, image_width: usize) -> usize {
        (self.y0 + i / self.width()) * image_width + self.x0 + i % self.width()
    }
}

/// The bounding box of the pixels where `frame` differs from `reference` (RGB8, `w` wide),
/// or `None` when they are identical.
fn difference_box(reference: &[u8], frame: &[u8], w: usize) -> Option<Window> {
    let row_bytes = 3 * w;
    let mut bbox: Option<Window> = None;
    for (y, (a, b)) in reference
        .chunks_exact(row_bytes)
        .zip(frame.chunks_exact(row_bytes))
        .enumerate()
    {
        if a == b {
            continue;
        }
        let first = a.iter().zip(b).position(|(p, q)| p != q).unwrap_or(0) / 3;
        let last = a.iter().zip(b).rposition(|(p, q)| p != q).unwrap_or(0) / 3;
        bbox = Some(match bbox {
            None => Window {
                x0: first,
                y0: y,
                x1: last + 1,
                y1: y + 1,
            },
            Some(r) => Window {
                x0: r.x0.min(first),
                y0: r.y0,
                x1: r.x1.max(last + 1),
                y1: y + 1,
            },
        });
    }
    bbox
}

/// The difference seen at one smoothing scale, over `window` (zero outside it).
struct Scale {
    size: usize,
    window: Window,
    /// Row-major (in the window) norm of the smoothed signed difference (0 where the pixel
    /// sees no finger).
    magnitude: Vec<f64>,
    /// RMS of that norm under noise alone.
    sigma: f64,
    peak: f64,
    detect_level: f64,
}

/// Over the whole frame: the noise estimated from every pixel that sees the finger.
fn analyse_scale(
    signed: &FloatImage,
    cache: &SurfaceCache,
    size: usize,
    config: &SurfaceConfig,
) -> Scale {
    let smooth = mean_filter(signed, size);
    let mut sigma2 = 0.0;
    let mut values = vec![0.0; cache.valid.len()];
    for c in 0..3 {
        for (v, &i) in values.iter_mut().zip(&cache.valid) {
            *v = smooth.data[3 * i + c];
        }
        sigma2 += robust_sigma(&mut values).powi(2);
    }
    let sigma = sigma2.sqrt().max(NOISE_FLOOR);
    let mut magnitude = vec![0.0; cache.areas.len()];
    let mut peak = 0.0f64;
    for &i in &cache.valid {
        let m = smooth.pixel(i).iter().map(|v| v * v).sum::<f64>().sqrt();
        magnitude[i] = m;
        peak = peak.max(m);
    }
    Scale {
        size,
        window: Window {
            x0: 0,
            y0: 0,
            x1: signed.width as usize,
            y1: signed.height as usize,
        },
        magnitude,
        sigma,
        peak,
        detect_level: (config.detect_snr * sigma).max(config.min_peak),
    }
}

/// Over the difference's footprint only, for a frame that equals the reference outside
/// `bbox` (no sensor noise): the same numbers as [`analyse_scale`], at a fraction of the
/// cost. The smoothed difference is exactly 0 farther than `size / 2` from `bbox` (the
/// differences are whole grey levels, so the box sums are exact), so only the window
/// `bbox` grown by `size / 2` can be non-zero; it is filtered from a crop grown by `size`
/// (whose edges are the image's wherever the window's window reaches them, so the mirrored
/// border samples are the same). When more than half of the pixels that see the finger lie
/// outside the window, the median of each channel and of its absolute deviations is 0, so
/// the robust noise is 0 and `sigma` is the floor. The caller checks that condition.
fn analyse_footprint(
    reference: &RgbImage,
    frame: &RgbImage,
    bbox: Window,
    cache: &SurfaceCache,
    size: usize,
    config: &SurfaceConfig,
) -> Scale {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    let half = (size.max(1) | 1) / 2;
    let window = bbox.grown(half, w, h);
    let crop = bbox.grown(2 * half, w, h);
    let (a, b) = (reference.as_raw(), frame.as_raw());
    let mut data = Vec::with_capacity(crop.width() * crop.height() * 3);
    for y in crop.y0..crop.y1 {
        let row = (y * w + crop.x0) * 3..(y * w + crop.x1) * 3;
        data.extend(
            a[row.clone()]
                .iter()
                .zip(&b[row])
                .map(|(&p, &q)| q as f64 - p as f64),
        );
    }
    let signed = FloatImage {
        width: crop.width() as u32,
        height: crop.height() as u32,
        channels: 3,
        data,
    };
    let smooth = mean_filter(&signed, size);
    let sigma = NOISE_FLOOR;
    let mut magnitude = vec![0.0; window.width() * window.height()];
    let mut peak = 0.0f64;
    for (k, m) in magnitude.iter_mut().enumerate() {
        let i = window.image_index(k, w);
        if cache.areas[i] <= 0.0 {
            continue;
        }
        let (x, y) = (
            window.x0 + k % window.width(),
            window.y0 + k / window.width(),
        );
        let c = (y - crop.y0) * crop.width() + (x - crop.x0);
        *m = smooth.pixel(c).iter().map(|v| v * v).sum::<f64>().sqrt();
        peak = peak.max(*m);
    }
    Scale {
        size,
        window,
        magnitude,
        sigma,
        peak,
        detect_level: (config.detect_snr * sigma).max(config.min_peak),
    }
}

/// Whether more than half of the pixels that see the finger lie outside `window`.
fn mostly_outside(cache: &SurfaceCache, window: Window) -> bool {
    let w = cache.width as usize;
    let inside: usize = (window.y0..window.y1)
        .map(|y| {
            cache.areas[y * w + window.x0..y * w + window.x1]
                .iter()
                .filter(|&&a| a > 0.0)
                .count()
        })
        .sum();
    2 * (cache.valid.len() - inside) > cache.valid.len()
}

/// One candidate region: its component, surface area, area-weighted sum of points and
/// extent.
struct Candidate {
    id: usize,
    area: f64,
    sum: DVec3,
    /// Largest distance (mm) of its points from its centre.
    radius: f64,
}

impl Candidate {
    fn centre(&self) -> DVec3 {
        self.sum / self.area
    }
}

/// The surface detector (see the module documentation). `cache` must have been built for
/// `sensor`.
pub fn detect(
    sensor: &Sensor,
    cache: &SurfaceCache,
    config: &SurfaceConfig,
    reference: &RgbImage,
    frame: &RgbImage,
) -> Result<Detection> {
    detect_with(sensor, cache, config, reference, frame, true)
}

/// [`detect`], optionally never taking the footprint shortcut (to check that it changes
/// nothing).
fn detect_with(
    sensor: &Sensor,
    cache: &SurfaceCache,
    config: &SurfaceConfig,
    reference: &RgbImage,
    frame: &RgbImage,
    allow_footprint: bool,
) -> Result<Detection> {
    check_sizes(reference, frame, Some(sensor))?;
    if cache.areas.len() != frame.as_raw().len() / 3 {
        return Err(crate::error::GeltipError::input(
            "surface cache",
            format!(
                "built for {}x{} images, not {}x{}",
                cache.width,
                cache.height,
                frame.width(),
                frame.height()
            ),
        ));
    }
    let (w, h) = (sensor.width, sensor.height);
    let Some(bbox) = difference_box(reference.as_raw(), frame.as_raw(), w as usize) else {
        return Ok(Detection::none(
            0,
            "the frame does not differ from the reference",
        ));
    };
    // Noise-free frames differ only around the contact: work on that footprint when the
    // noise estimate is known to be the floor there (see `analyse_footprint`).
    let largest = config.scales.iter().copied().max().unwrap_or(1).max(1) | 1;
    let footprint =
        allow_footprint && mostly_outside(cache, bbox.grown(largest / 2, w as usize, h as usize));
    let signed = (!footprint).then(|| FloatImage {
        width: w,
        height: h,
        channels: 3,
        data: reference
            .as_raw()
            .iter()
            .zip(frame.as_raw())
            .map(|(&a, &b)| b as f64 - a as f64)
            .collect(),
    });

    // Detection: the finest scale at which the contact clears the level, else the one
    // that came closest (for the note).
    let mut best: Option<Scale> = None;
    for &size in &config.scales {
        let scale = match &signed {
            Some(signed) => analyse_scale(signed, cache, size, config),
            None => analyse_footprint(reference, frame, bbox, cache, size, config),
        };
        let passes = scale.peak >= scale.detect_level;
        let closer = best
            .as_ref()
            .is_none_or(|b| scale.peak / scale.detect_level > b.peak / b.detect_level);
        if passes || closer {
            best = Some(scale);
        }
        if passes {
            break;
        }
    }
    let Some(scale) = best else {
        return Ok(Detection::none(0, "no smoothing scales configured"));
    };
    let Scale {
        size,
        window,
        magnitude,
        sigma,
        peak,
        detect_level,
    } = scale;
    if peak.is_nan() || peak < detect_level {
        return Ok(Detection::none(
            0,
            format!(
                "no contact: the largest difference ({peak:.2} grey levels, smoothing {size}x{size}) is below the detection level ({detect_level:.2}: {:.1} x noise {sigma:.2}, at least {:.2})",
                config.detect_snr, config.min_peak
            ),
        ));
    }

    // Support and candidate regions.
    let support = (config.support_snr * sigma).max(config.relative_threshold * peak);
    let mask: Vec<bool> = magnitude.iter().map(|&m| m > support).collect();
    let (mut comps, _) = components(&mask, window.width() as u32, window.height() as u32);
    // Window indices to image indices (monotone: raster order is kept).
    for pixels in &mut comps {
        for i in pixels.iter_mut() {
            *i = window.image_index(*i, w as usize);
        }
    }
    let mut candidates: Vec<Candidate> = comps
        .iter()
        .enumerate()
        .map(|(id, pixels)| {
            let (area, sum) = pixels.iter().fold((0.0, DVec3::ZERO), |(a, s), &i| {
                (a + cache.areas[i], s + cache.areas[i] * cache.points[i])
            });
            let centre = sum / area;
            let radius = pixels
                .iter()
                .map(|&i| (cache.points[i] - centre).length())
                .fold(0.0, f64::max);
            Candidate {
                id,
                area,
                sum,
                radius,
            }
        })
        .filter(|c| c.area > 0.0 && c.sum.is_finite())
        .collect();
    let found = candidates.len();
    let Some(seed) =
        (0..candidates.len()).max_by(|&a, &b| candidates[a].area.total_cmp(&candidates[b].area))
    else {
        return Ok(Detection::none(
            0,
            "no region above the support threshold sees the finger",
        ));
    };

    // The contact: the largest region and every region near it.
    let mut contact = candidates.swap_remove(seed);
    let mut parts = vec![(contact.id, contact.area)];
    while let Some(k) = candidates.iter().position(|c| {
        (c.centre() - contact.centre()).length() <= c.radius + contact.radius + config.merge_gap_mm
    }) {
        let c = candidates.swap_remove(k);
        parts.push((c.id, c.area));
        let before = contact.centre();
        contact.area += c.area;
        contact.sum += c.sum;
        let after = contact.centre();
        contact.radius = ((before - after).length() + contact.radius)
            .max((c.centre() - after).length() + c.radius);
    }
    let outline: Vec<usize> = parts
        .iter()
        .filter(|(_, a)| *a >= config.min_part_fraction * contact.area)
        .flat_map(|(id, _)| comps[*id].iter().copied())
        .collect();

    // Location: the middle of the outline's extent on the tangent plane, iterated.
    let finger = sensor.finger;
    let mut sp = finger.point_at(finger.coord_of(contact.centre()));
    for _ in 0..8 {
        let (e_s, e_phi) = finger.tangents_at(finger.coord_of(sp.point));
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for &i in &outline {
            let d = cache.points[i] - sp.point;
            let ab = DVec2::new(d.dot(e_s), d.dot(e_phi));
            lo = lo.min(ab);
            hi = hi.max(ab);
        }
        let mid = 0.5 * (lo + hi);
        if !mid.is_finite() {
            break;
        }
        let next = finger.point_at(finger.coord_of(sp.point + mid.x * e_s + mid.y * e_phi));
        let moved = (next.point - sp.point).length();
        sp = next;
        if moved < 1e-4 {
            break;
        }
    }
    if !sp.point.is_finite() {
        return Ok(Detection::none(
            found,
            "the contact's position does not map onto the finger",
        ));
    }
    let cut = outline.iter().any(|&i| cache.edge[i]);
    Ok(Detection {
        detected: true,
        pixel: sensor.project(sp.point).ok(),
        point: Some(sp.point),
        region: Some(sp.region),
        confidence: (1.0 - detect_level / peak).clamp(0.0, 1.0),
        regions_found: found,
        note: cut.then(|| {
            "the imprint reaches the edge of the field of view: its centre may be pulled towards the visible part".to_string()
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth reference and a frame with a bump (and optional extra specks) added.
    fn frames(
        cx: f64,
        cy: f64,
        radius: f64,
        amp: f64,
        specks: &[(u32, u32)],
    ) -> (RgbImage, RgbImage) {
        let (w, h) = (640u32, 480u32);
        let reference = RgbImage::from_fn(w, h, |u, v| {
            image::Rgb([(60 + u / 8) as u8, (80 + v / 8) as u8, 120])
        });
        let mut frame = reference.clone();
        for (u, v, p) in frame.enumerate_pixels_mut() {
            let d2 = (u as f64 - cx).powi(2) + (v as f64 - cy).powi(2);
            let bump = amp * (-d2 / (2.0 * radius * radius)).exp();
            p.0[0] = (p.0[0] as f64 + bump).round().clamp(0.0, 255.0) as u8;
            p.0[1] = (p.0[1] as f64 - 0.5 * bump).round().clamp(0.0, 255.0) as u8;
        }
        for &(u, v) in specks {
            frame.get_pixel_mut(u, v).0[2] = 200;
        }
        (reference, frame)
    }

    #[test]
    fn the_footprint_shortcut_changes_nothing() {
        let sensor = Sensor::preset("paper").unwrap();
        let cache = SurfaceCache::new(&sensor);
        let config = SurfaceConfig::default();
        let cases = [
            (320.0, 240.0, 6.0, 40.0, vec![]),
            (100.0, 240.0, 10.0, 3.0, vec![]),
            (540.0, 30.0, 4.0, 80.0, vec![]),
            (300.0, 200.0, 5.0, 30.0, vec![(310, 215), (40, 240)]),
            (60.0, 240.0, 30.0, 1.2, vec![]),
            // The image's corner sees no finger; a bump on the border of the view.
            (320.0, 2.0, 8.0, 25.0, vec![]),
        ];
        let mut shortcut_taken = 0;
        for (cx, cy, r, amp, specks) in cases {
            let (reference, frame) = frames(cx, cy, r, amp, &specks);
            let fast = detect_with(&sensor, &cache, &config, &reference, &frame, true).unwrap();
            let full = detect_with(&sensor, &cache, &config, &reference, &frame, false).unwrap();
            assert_eq!(
                fast, full,
                "bump at ({cx}, {cy}) radius {r} amplitude {amp}"
            );
            let bbox = difference_box(reference.as_raw(), frame.as_raw(), 640).unwrap();
            if !mostly_outside(&cache, bbox.grown(12, 640, 480)) {
                continue;
            }
            shortcut_taken += 1;
            // Every scale's numbers, not only the outcome: bit for bit.
            let signed = FloatImage {
                width: 640,
                height: 480,
                channels: 3,
                data: reference
                    .as_raw()
                    .iter()
                    .zip(frame.as_raw())
                    .map(|(&a, &b)| b as f64 - a as f64)
                    .collect(),
            };
            for &size in &config.scales {
                let full = analyse_scale(&signed, &cache, size, &config);
                let part = analyse_footprint(&reference, &frame, bbox, &cache, size, &config);
                assert_eq!(
                    (part.sigma, part.peak),
                    (full.sigma, full.peak),
                    "size {size}"
                );
                let mut in_window = vec![false; full.magnitude.len()];
                for (k, m) in part.magnitude.iter().enumerate() {
                    let i = part.window.image_index(k, 640);
                    in_window[i] = true;
                    assert_eq!(*m, full.magnitude[i], "size {size}, pixel {i}");
                }
                for (i, m) in full.magnitude.iter().enumerate() {
                    assert!(in_window[i] || *m == 0.0, "size {size}, pixel {i}: {m}");
                }
            }
        }
        assert!(
            shortcut_taken >= 5,
            "the shortcut was taken {shortcut_taken} times"
        );
    }

    #[test]
    fn difference_box_bounds_every_changed_pixel() {
        let a = vec![7u8; 3 * 10 * 4];
        let mut b = a.clone();
        assert_eq!(difference_box(&a, &b, 10), None);
        b[3 * (10 + 2) + 1] = 9; // (2, 1), green
        b[3 * (3 * 10 + 7) + 2] = 0; // (7, 3), blue
        assert_eq!(
            difference_box(&a, &b, 10),
            Some(Window {
                x0: 2,
                y0: 1,
                x1: 8,
                y1: 4
            })
        );
    }
}
