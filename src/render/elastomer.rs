//! Stage 2, elastomer: the gel does not keep a stamped hole. The penetration field is blended
//! along the surface (a separable Gaussian: along the meridian, then along the parallel, with
//! the kernel measured in surface millimetres), the skin follows max(penetration, blend),
//! displaced gel bulges out around the imprint, and nothing goes deeper than the shell.
//! CPU mirror of `shaders/elastomer.wgsl` (same names).

use super::contact::parallel_radius;
use super::{HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::sensor::ElastomerConfig;
use glam::DVec2;

/// Gaussian taps on each side of the centre (the kernel reaches 3 sigma of the wide blend).
pub const BLEND_TAPS: i32 = 12;

/// How far (mm of surface) the blends reach: 3 standard deviations of the wide one.
pub fn blend_reach_mm(config: &ElastomerConfig) -> f64 {
    6.0 * config.blend_mm
}

/// Bilinear sample of a `texels`^2 field at continuous texel coordinates (centres at +0.5),
/// zero outside.
pub fn sample_field(field: &[f32], texels: u32, t: DVec2) -> f64 {
    let p = t - DVec2::splat(0.5);
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let (fx, fy) = (p.x - x0, p.y - y0);
    let at = |x: f64, y: f64| -> f64 {
        if x < 0.0 || y < 0.0 || x >= texels as f64 || y >= texels as f64 {
            0.0
        } else {
            field[y as usize * texels as usize + x as usize] as f64
        }
    };
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Gaussian-weighted sums of samples at surface offsets k * step (k = -TAPS..=TAPS) for
/// standard deviations sigma and 2 sigma: (narrow, wide).
fn blend_taps(sigma: f64, mut sample: impl FnMut(f64) -> f64) -> (f64, f64) {
    let step = 2.0 * 3.0 * sigma / BLEND_TAPS as f64;
    let (mut n, mut nw, mut w, mut ww) = (0.0, 0.0, 0.0, 0.0);
    for k in -BLEND_TAPS..=BLEND_TAPS {
        let x = k as f64 * step;
        let v = sample(x);
        let a = (-0.5 * (x / sigma).powi(2)).exp();
        let b = (-0.5 * (x / (2.0 * sigma)).powi(2)).exp();
        n += a * v;
        nw += a;
        w += b * v;
        ww += b;
    }
    (n / nw, w / ww)
}

/// Pass 1: blend along meridians (the disc's radial direction, where disc distance is surface
/// distance). `field` is the penetration; returns (narrow, wide) blends over `rect`.
pub fn blend_meridian(
    grid: &HeightfieldGrid,
    field: &[f32],
    rect: Rect,
    sigma: f64,
) -> Vec<[f32; 2]> {
    let n = grid.texels as usize;
    let mut out = vec![[0.0f32; 2]; n * n];
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let u = grid.texel_centre(i, j);
            let dir = if u.length() > 0.0 {
                u / u.length()
            } else {
                DVec2::X
            };
            let (a, b) = if sigma > 0.0 {
                blend_taps(sigma, |x| {
                    sample_field(field, grid.texels, grid.texel_of(u + x * dir))
                })
            } else {
                let v = field[j as usize * n + i as usize] as f64;
                (v, v)
            };
            out[j as usize * n + i as usize] = [a as f32, b as f32];
        }
    }
    out
}

/// Pass 2: blend along parallels (circles about the axis), turning surface distance into
/// azimuth with the parallel's radius; then the skin's displacement:
/// h = min(max(p, narrow) - bulge * max(wide - narrow, 0) ... ) capped to [-T/2, T].
/// Returns the inward displacement field and how many texels were pressed beyond the shell.
pub fn blend_azimuth(
    finger: &Finger,
    grid: &HeightfieldGrid,
    penetration: &[f32],
    meridian: &[[f32; 2]],
    rect: Rect,
    config: &ElastomerConfig,
) -> (Vec<f32>, u32) {
    let n = grid.texels as usize;
    let mut height = vec![0.0f32; n * n];
    let mut over = 0;
    let narrow: Vec<f32> = meridian.iter().map(|v| v[0]).collect();
    let wide: Vec<f32> = meridian.iter().map(|v| v[1]).collect();
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let idx = j as usize * n + i as usize;
            let c = SurfaceCoord::from_disc(grid.texel_centre(i, j));
            let rho = parallel_radius(finger, c.s);
            let (a, b) = if config.blend_mm > 0.0 && rho > 1e-9 {
                let along = |field: &[f32], x: f64| {
                    let phi = c.phi + x / rho;
                    let disc = DVec2::new(c.s * phi.cos(), c.s * phi.sin());
                    sample_field(field, grid.texels, grid.texel_of(disc))
                };
                let (a, _) = blend_taps(config.blend_mm, |x| along(&narrow, x));
                let (_, b) = blend_taps(config.blend_mm, |x| along(&wide, x));
                (a, b)
            } else {
                (narrow[idx] as f64, wide[idx] as f64)
            };
            let p = penetration[idx] as f64;
            if p > finger.shell_thickness {
                over += 1;
            }
            height[idx] = skin_displacement(p, a, b, finger.shell_thickness, config.bulge) as f32;
        }
    }
    (height, over)
}

/// The skin's inward displacement from the penetration and its two blends.
pub fn skin_displacement(p: f64, narrow: f64, wide: f64, thickness: f64, bulge: f64) -> f64 {
    let pressed = p.max(narrow);
    let bulged = pressed - bulge * (wide - narrow).max(0.0);
    bulged.clamp(-0.5 * thickness, thickness)
}
