//! Stage 2, elastomer: the gel does not keep a stamped hole. From the penetration field p:
//! - the skin drapes: it cannot bend tighter than `drape_mm`, so where the object's edge is a
//!   cliff the skin falls away on a parabola: d(x) = max_y p(y) - |x - y|^2 / (2 R), a
//!   max-plus (morphological) dilation, separable because the parabola is;
//! - it blends: a Gaussian of `blend_mm` softens the imprint (narrow), and one twice as wide
//!   (wide) gives the bulge of displaced gel around it;
//! - h = max(d, narrow) - bulge * max(wide - narrow, 0), capped to [-T/2, T].
//!
//! Both run as two separable passes along the surface, kernels measured in surface
//! millimetres: along meridians (the disc's radial direction), then along parallels (circles
//! about the axis). CPU mirror of `shaders/elastomer.wgsl` (same names).

use super::contact::parallel_radius;
use super::{HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::sensor::ElastomerConfig;
use glam::{DVec2, DVec3};

/// Most kernel taps on each side of the centre.
pub const MAX_BLEND_TAPS: i32 = 64;

/// Kernel taps on each side of the centre: one per texel of reach (a coarser step would turn
/// the drape's parabola into a staircase), at most [`MAX_BLEND_TAPS`].
pub fn blend_taps(reach_mm: f64, grid: &HeightfieldGrid) -> i32 {
    ((reach_mm / grid.texel_mm()).ceil() as i32).clamp(1, MAX_BLEND_TAPS)
}

/// How far (mm of surface) the elastomer's kernels reach: 3 standard deviations of the wide
/// blend, and at least the drape's width for a full-thickness press.
pub fn blend_reach_mm(config: &ElastomerConfig, thickness: f64) -> f64 {
    (6.0 * config.blend_mm).max((2.0 * config.drape_mm * thickness).sqrt())
}

/// The four texels around continuous texel coordinates `t` (centres at +0.5) and their
/// bilinear weights; texels outside the grid are `None` (they read as zero).
pub fn bilinear_taps(texels: u32, t: DVec2) -> [(Option<usize>, f64); 4] {
    let p = t - DVec2::splat(0.5);
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let (fx, fy) = (p.x - x0, p.y - y0);
    let index = |x: f64, y: f64| {
        (x >= 0.0 && y >= 0.0 && x < texels as f64 && y < texels as f64)
            .then(|| y as usize * texels as usize + x as usize)
    };
    [
        (index(x0, y0), (1.0 - fx) * (1.0 - fy)),
        (index(x0 + 1.0, y0), fx * (1.0 - fy)),
        (index(x0, y0 + 1.0), (1.0 - fx) * fy),
        (index(x0 + 1.0, y0 + 1.0), fx * fy),
    ]
}

/// Bilinear sample of a `texels`^2 scalar field, zero outside.
pub fn sample_field(field: &[f32], texels: u32, t: DVec2) -> f64 {
    bilinear_taps(texels, t)
        .iter()
        .filter_map(|&(i, w)| i.map(|i| field[i] as f64 * w))
        .sum()
}

/// Bilinear sample of a `texels`^2 field of (drape, narrow, wide), zero outside.
fn sample_channels(field: &[DVec3], texels: u32, t: DVec2) -> DVec3 {
    bilinear_taps(texels, t)
        .iter()
        .filter_map(|&(i, w)| i.map(|i| field[i] * w))
        .sum()
}

/// One separable pass: for samples `sample(x)` at surface offsets x = k * step, returns
/// (max-plus drape, narrow Gaussian, wide Gaussian) of the respective channels.
fn pass(
    config: &ElastomerConfig,
    reach: f64,
    taps: i32,
    mut sample: impl FnMut(f64) -> DVec3,
) -> DVec3 {
    let step = reach / taps as f64;
    let sigma = config.blend_mm;
    let (mut drape, mut n, mut nw, mut w, mut ww) = (f64::NEG_INFINITY, 0.0, 0.0, 0.0, 0.0);
    for k in -taps..=taps {
        let x = k as f64 * step;
        let v = sample(x);
        drape = drape.max(v.x - x * x / (2.0 * config.drape_mm));
        let (a, b) = if sigma > 0.0 {
            (
                (-0.5 * (x / sigma).powi(2)).exp(),
                (-0.125 * (x / sigma).powi(2)).exp(),
            )
        } else {
            ((k == 0) as i32 as f64, (k == 0) as i32 as f64)
        };
        n += a * v.y;
        nw += a;
        w += b * v.z;
        ww += b;
    }
    DVec3::new(drape, n / nw, w / ww)
}

/// Pass 1, along meridians, where disc distance is surface distance: from the penetration,
/// (drape, narrow, wide) over `rect`.
pub fn blend_meridian(
    grid: &HeightfieldGrid,
    config: &ElastomerConfig,
    reach: f64,
    field: &[f32],
    rect: Rect,
) -> Vec<DVec3> {
    let n = grid.texels as usize;
    let taps = blend_taps(reach, grid);
    let mut out = vec![DVec3::ZERO; n * n];
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let u = grid.texel_centre(i, j);
            let dir = if u.length() > 0.0 {
                u / u.length()
            } else {
                DVec2::X
            };
            out[j as usize * n + i as usize] = pass(config, reach, taps, |x| {
                let at = grid.texel_of(u + x * dir);
                DVec3::splat(sample_field(field, grid.texels, at))
            });
        }
    }
    out
}

/// Pass 2, along parallels, turning surface distance into azimuth with the parallel's
/// radius; then the skin. Returns the skin's inward displacement and how many texels the
/// object pressed beyond the shell.
pub fn blend_azimuth(
    finger: &Finger,
    grid: &HeightfieldGrid,
    config: &ElastomerConfig,
    reach: f64,
    penetration: &[f32],
    meridian: &[DVec3],
    rect: Rect,
) -> (Vec<f32>, u32) {
    let n = grid.texels as usize;
    let taps = blend_taps(reach, grid);
    let mut height = vec![0.0f32; n * n];
    let mut over = 0;
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let idx = j as usize * n + i as usize;
            let c = SurfaceCoord::from_disc(grid.texel_centre(i, j));
            let rho = parallel_radius(finger, c.s);
            let v = if rho > 1e-6 {
                pass(config, reach, taps, |x| {
                    let phi = c.phi + x / rho;
                    sample_channels(
                        meridian,
                        grid.texels,
                        grid.texel_of(DVec2::new(c.s * phi.cos(), c.s * phi.sin())),
                    )
                })
            } else {
                meridian[idx]
            };
            let p = penetration[idx] as f64;
            if p > finger.shell_thickness {
                over += 1;
            }
            height[idx] = skin_displacement(v, finger.shell_thickness, config.bulge) as f32;
        }
    }
    (height, over)
}

/// Displacements smaller than this (mm) are none: the Gaussians' tails would otherwise mark
/// the whole footprint rectangle as touched, and the camera marches only where it is.
pub const HEIGHT_EPSILON_MM: f64 = 1e-3;

/// The skin's inward displacement from (drape, narrow, wide).
pub fn skin_displacement(v: DVec3, thickness: f64, bulge: f64) -> f64 {
    let pressed = v.x.max(v.y);
    let h = (pressed - bulge * (v.z - v.y).max(0.0)).clamp(-0.5 * thickness, thickness);
    if h.abs() < HEIGHT_EPSILON_MM {
        0.0
    } else {
        h
    }
}
