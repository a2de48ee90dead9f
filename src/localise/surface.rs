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

use super::raster::{components, FloatImage, NEIGHBOURS_8};
use super::{check_sizes, Detection};
use crate::error::Result;
use crate::finger::{Finger, SurfacePoint};
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use image::RgbImage;
use scale::{analyse_footprint, analyse_scale, difference_box, mostly_outside, Scale, Window};

mod scale;
#[cfg(test)]
mod tests;

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
    check_cache(cache, frame)?;
    let Some(bbox) = difference_box(reference.as_raw(), frame.as_raw(), sensor.width as usize)
    else {
        return Ok(Detection::none(
            0,
            "the frame does not differ from the reference",
        ));
    };
    let Some(scale) = detection_scale(
        sensor,
        cache,
        config,
        reference,
        frame,
        bbox,
        allow_footprint,
    ) else {
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

    let support = (config.support_snr * sigma).max(config.relative_threshold * peak);
    let (comps, candidates) =
        candidate_regions(cache, &magnitude, window, support, sensor.width as usize);
    let found = candidates.len();
    let Some(seed) =
        (0..candidates.len()).max_by(|&a, &b| candidates[a].area.total_cmp(&candidates[b].area))
    else {
        return Ok(Detection::none(
            0,
            "no region above the support threshold sees the finger",
        ));
    };
    let (centre, outline) = contact_outline(&comps, candidates, seed, config);
    let sp = outline_middle(&sensor.finger, cache, centre, &outline);
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

/// Where a region of pixels (indices into the image, found by any detector) lies on the
/// finger: the middle of its extent on the surface, as this detector places its own
/// contacts (step 4). `None` when none of its pixels sees the finger.
pub fn region_middle(
    sensor: &Sensor,
    cache: &SurfaceCache,
    region: &[usize],
) -> Option<SurfacePoint> {
    let seen: Vec<usize> = region
        .iter()
        .copied()
        .filter(|&i| cache.areas.get(i).is_some_and(|&a| a > 0.0))
        .collect();
    let area: f64 = seen.iter().map(|&i| cache.areas[i]).sum();
    let sum: DVec3 = seen.iter().map(|&i| cache.points[i] * cache.areas[i]).sum();
    if seen.is_empty() || area <= 0.0 || !sum.is_finite() {
        return None;
    }
    let sp = outline_middle(&sensor.finger, cache, sum / area, &seen);
    sp.point.is_finite().then_some(sp)
}

/// Refuses a cache built for another image size than `frame`'s.
fn check_cache(cache: &SurfaceCache, frame: &RgbImage) -> Result<()> {
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
    Ok(())
}

/// Detection: the difference at the finest scale at which the contact clears the level,
/// else at the one that came closest (for the note); `None` without scales.
fn detection_scale(
    sensor: &Sensor,
    cache: &SurfaceCache,
    config: &SurfaceConfig,
    reference: &RgbImage,
    frame: &RgbImage,
    bbox: Window,
    allow_footprint: bool,
) -> Option<Scale> {
    let (w, h) = (sensor.width, sensor.height);
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
    best
}

/// The candidate regions: 8-connected components of the pixels of `window` whose magnitude
/// exceeds `support` (as image indices, `image_width` wide), and those of them that see the
/// finger.
fn candidate_regions(
    cache: &SurfaceCache,
    magnitude: &[f64],
    window: Window,
    support: f64,
    image_width: usize,
) -> (Vec<Vec<usize>>, Vec<Candidate>) {
    let mask: Vec<bool> = magnitude.iter().map(|&m| m > support).collect();
    let (mut comps, _) = components(&mask, window.width() as u32, window.height() as u32);
    // Window indices to image indices (monotone: raster order is kept).
    for pixels in &mut comps {
        for i in pixels.iter_mut() {
            *i = window.image_index(*i, image_width);
        }
    }
    let candidates = comps
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
    (comps, candidates)
}

/// The contact: the `seed` region (the largest) joined by every region near it. Returns its
/// centre and its outline: the pixels of its parts that are not specks.
fn contact_outline(
    comps: &[Vec<usize>],
    mut candidates: Vec<Candidate>,
    seed: usize,
    config: &SurfaceConfig,
) -> (DVec3, Vec<usize>) {
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
    let outline = parts
        .iter()
        .filter(|(_, a)| *a >= config.min_part_fraction * contact.area)
        .flat_map(|(id, _)| comps[*id].iter().copied())
        .collect();
    (contact.centre(), outline)
}

/// Location: the middle of the outline's extent on the tangent plane, iterated from
/// `centre` snapped onto the surface until it stays put.
fn outline_middle(
    finger: &Finger,
    cache: &SurfaceCache,
    centre: DVec3,
    outline: &[usize],
) -> SurfacePoint {
    let mut sp = finger.point_at(finger.coord_of(centre));
    for _ in 0..8 {
        let (e_s, e_phi) = finger.tangents_at(finger.coord_of(sp.point));
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for &i in outline {
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
    sp
}
