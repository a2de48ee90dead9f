//! Stage 2, elastomer: the gel does not keep a stamped hole. The contact stage already
//! drapes the skin from the object's edges (see [`super::contact::penetration`]); here the
//! imprint p blends (a Gaussian of `blend_mm`: narrow) and the displaced gel bulges around it
//! (the excess of a Gaussian twice as wide: wide), h = max(p, narrow) - bulge * max(wide -
//! narrow, 0), capped to [-T/2, T]. Both Gaussians run as two separable passes along the
//! surface, kernels in surface millimetres: along meridians (the disc's radial direction),
//! then along parallels (circles about the axis). CPU mirror of `shaders/elastomer.wgsl`.

use super::contact::parallel_radius;
use super::{HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::sensor::{ElastomerConfig, SensorConfig};
use glam::DVec2;

/// Most kernel taps on each side of the centre.
pub const MAX_BLEND_TAPS: i32 = 64;

/// The elastomer's kernels as sampled: how far they reach and how many taps each side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    /// Surface distance (mm) the kernels reach: [`blend_reach_mm`].
    pub reach_mm: f64,
    /// Taps on each side of the centre, spaced `reach_mm / taps` apart.
    pub taps: i32,
}

impl Kernel {
    /// Taps every `render.blend_tap_spacing` narrow standard deviations (`blend_mm`), but
    /// never closer than one texel (the grid holds nothing finer) and at most
    /// [`MAX_BLEND_TAPS`]. A Gaussian sampled once per standard deviation sums to its
    /// integral within 1e-8 (Poisson summation: exp(-2 pi^2)), so closer taps buy little.
    pub fn for_config(config: &SensorConfig, grid: &HeightfieldGrid) -> Kernel {
        let reach_mm = blend_reach_mm(&config.elastomer);
        let spacing =
            (config.render.blend_tap_spacing * config.elastomer.blend_mm).max(grid.texel_mm());
        // The epsilon keeps a reach that is a whole number of spacings from gaining a tap.
        let taps = ((reach_mm / spacing - 1e-9).ceil() as i32).clamp(1, MAX_BLEND_TAPS);
        Kernel { reach_mm, taps }
    }
}

/// How far (mm of surface) the elastomer's kernels reach: 3 standard deviations of the wide
/// blend (at least a hair, so a zero blend still has a kernel).
pub fn blend_reach_mm(config: &ElastomerConfig) -> f64 {
    (6.0 * config.blend_mm).max(1e-3)
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

/// Bilinear sample of a `texels`^2 field of (narrow, wide), zero outside.
fn sample_channels(field: &[DVec2], texels: u32, t: DVec2) -> DVec2 {
    bilinear_taps(texels, t)
        .iter()
        .filter_map(|&(i, w)| i.map(|i| field[i] * w))
        .sum()
}

/// The kernels' weights for taps k = 0..=taps (tap -k weighs as tap k), normalised so that
/// the taps -taps..=taps sum to one: x the narrow Gaussian (sigma `blend_mm`), y the wide one
/// (twice as wide). They depend on the tap alone, so the GPU reads them from a table
/// (`SensorUniform::blend_weights`) instead of evaluating two exponentials per tap.
pub fn blend_weights(config: &ElastomerConfig, reach: f64, taps: i32) -> Vec<DVec2> {
    let step = reach / taps as f64;
    let sigma = config.blend_mm;
    let raw: Vec<DVec2> = (0..=taps)
        .map(|k| {
            if sigma > 0.0 {
                let q = k as f64 * step / sigma;
                DVec2::new((-0.5 * q * q).exp(), (-0.125 * q * q).exp())
            } else {
                DVec2::splat((k == 0) as i32 as f64)
            }
        })
        .collect();
    let norm = raw.iter().skip(1).sum::<DVec2>() * 2.0 + raw[0];
    raw.into_iter().map(|w| w / norm).collect()
}

/// One separable pass: for samples `sample(x)` at surface offsets x = k * step, the narrow
/// Gaussian of their x channel and the wide Gaussian of their y channel.
fn pass(config: &ElastomerConfig, kernel: Kernel, mut sample: impl FnMut(f64) -> DVec2) -> DVec2 {
    let Kernel { reach_mm, taps } = kernel;
    let step = reach_mm / taps as f64;
    let weights = blend_weights(config, reach_mm, taps);
    (-taps..=taps)
        .map(|k| weights[k.unsigned_abs() as usize] * sample(k as f64 * step))
        .sum()
}

/// Pass 1, along meridians, where disc distance is surface distance: from the penetration,
/// (narrow, wide) over `rect`.
pub fn blend_meridian(
    grid: &HeightfieldGrid,
    config: &ElastomerConfig,
    kernel: Kernel,
    field: &[f32],
    rect: Rect,
) -> Vec<DVec2> {
    let n = grid.texels as usize;
    let mut out = vec![DVec2::ZERO; n * n];
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let u = grid.texel_centre(i, j);
            let dir = if u.length() > 0.0 {
                u / u.length()
            } else {
                DVec2::X
            };
            out[j as usize * n + i as usize] = pass(config, kernel, |x| {
                let at = grid.texel_of(u + x * dir);
                DVec2::splat(sample_field(field, grid.texels, at))
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
    kernel: Kernel,
    penetration: &[f32],
    meridian: &[DVec2],
    rect: Rect,
) -> (Vec<f32>, u32) {
    let n = grid.texels as usize;
    let mut height = vec![0.0f32; n * n];
    let mut over = 0;
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let idx = j as usize * n + i as usize;
            let c = SurfaceCoord::from_disc(grid.texel_centre(i, j));
            let rho = parallel_radius(finger, c.s);
            let v = if rho > 1e-6 {
                pass(config, kernel, |x| {
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
            height[idx] = skin_displacement(p, v, finger.shell_thickness, config.bulge) as f32;
        }
    }
    (height, over)
}

/// Displacements smaller than this (mm) are none: the Gaussians' tails would otherwise mark
/// the whole footprint rectangle as touched, and the camera marches only where it is.
pub const HEIGHT_EPSILON_MM: f64 = 5e-3;

/// The skin's inward displacement from the imprint p and its (narrow, wide) blends.
pub fn skin_displacement(p: f64, blend: DVec2, thickness: f64, bulge: f64) -> f64 {
    let pressed = p.max(blend.x);
    let h = (pressed - bulge * (blend.y - blend.x).max(0.0)).clamp(-0.5 * thickness, thickness);
    if h.abs() < HEIGHT_EPSILON_MM {
        0.0
    } else {
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::Sensor;

    /// The paper sensor's kernels: 3 mm of reach at one tap per 0.5 mm sigma is 6 taps a
    /// side (its 0.27 mm texels would give 11); a spacing finer than a texel falls back to
    /// one tap per texel; and the sampled Gaussians still sum to one.
    #[test]
    fn kernel_taps_follow_the_spacing_and_the_texel() {
        let mut c = Sensor::preset("paper").unwrap().config;
        let grid = HeightfieldGrid {
            texels: 256,
            half_size_mm: 35.0,
        };
        assert_eq!(Kernel::for_config(&c, &grid).taps, 6);
        c.render.blend_tap_spacing = 0.25;
        let fine = Kernel::for_config(&c, &grid);
        assert_eq!(fine.taps, (3.0 / grid.texel_mm()).ceil() as i32);
        c.render.blend_tap_spacing = 2.0;
        let k = Kernel::for_config(&c, &grid);
        assert_eq!(k.taps, 3);
        let w = blend_weights(&c.elastomer, k.reach_mm, k.taps);
        let total = w.iter().skip(1).sum::<DVec2>() * 2.0 + w[0];
        assert!((total - DVec2::ONE).abs().max_element() < 1e-12);
    }
}
