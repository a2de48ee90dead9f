//! Stage 2, elastomer: the gel does not keep a stamped hole. The contact stage already
//! drapes the skin from the object's edges (see [`super::contact::penetration`]); here the
//! imprint p blends (a Gaussian of `blend_mm`: narrow) and the displaced gel bulges around it
//! (the excess of a Gaussian twice as wide: wide), h = max(p, narrow) - bulge * max(wide -
//! narrow, 0), capped to [-T/2, T]. Both Gaussians run as two separable passes along the
//! surface, kernels in surface millimetres: along meridians (the disc's radial direction),
//! then along parallels (circles about the axis). Then the normals of the skin they leave.
//! CPU mirror of `shaders/elastomer.wgsl` (same names).

use super::contact::parallel_radius;
use super::{HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::sensor::{ElastomerConfig, SensorConfig};
use glam::{DVec2, DVec3};

/// Most kernel taps on each side of the centre.
pub const MAX_BLEND_TAPS: i32 = 64;

/// One Gaussian as sampled: taps `-count..=count`, `step_mm` of surface apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Taps {
    pub count: i32,
    pub step_mm: f64,
}

impl Taps {
    /// Taps every `step` mm out to `reach`, but never closer than one texel (the grid holds
    /// nothing finer) and at most [`MAX_BLEND_TAPS`] a side.
    fn reaching(reach: f64, step: f64, texel_mm: f64) -> Taps {
        let step = step.max(texel_mm);
        // The epsilon keeps a reach that is a whole number of steps from gaining a tap.
        let count = ((reach / step - 1e-9).ceil() as i32).clamp(1, MAX_BLEND_TAPS);
        Taps {
            count,
            step_mm: reach / count as f64,
        }
    }
}

/// The elastomer's kernels as sampled: how far they reach, and each Gaussian's taps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    /// Surface distance (mm) the kernels reach: [`blend_reach_mm`].
    pub reach_mm: f64,
    /// The narrow Gaussian (sigma `blend_mm`) out to its 3 sigma.
    pub narrow: Taps,
    /// The wide Gaussian (twice the sigma) out to its 3 sigma, the kernels' reach.
    pub wide: Taps,
}

impl Kernel {
    /// Each Gaussian tapped every `render.blend_tap_spacing` of its own standard deviations
    /// out to 3 of them (a Gaussian sampled once per standard deviation sums to its integral
    /// within 1e-8, Poisson summation: exp(-2 pi^2), so closer taps buy little). The wide
    /// one's taps lie twice as far apart as the narrow one's, and the narrow one stops at
    /// its own 3 sigma (half the reach; beyond it its weights sum to 3e-4): 7 + 7 taps on
    /// the paper's sensor where one shared set of 13 served both.
    pub fn for_config(config: &SensorConfig, grid: &HeightfieldGrid) -> Kernel {
        let sigma = config.elastomer.blend_mm;
        let spacing = config.render.blend_tap_spacing;
        let reach_mm = blend_reach_mm(&config.elastomer);
        Kernel {
            reach_mm,
            narrow: Taps::reaching(0.5 * reach_mm, spacing * sigma, grid.texel_mm()),
            wide: Taps::reaching(reach_mm, 2.0 * spacing * sigma, grid.texel_mm()),
        }
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

/// The kernels' weights by tap k = 0..=max(narrow, wide taps) (tap -k weighs as tap k), each
/// normalised so that its taps -count..=count sum to one (zero beyond its count): x the
/// narrow Gaussian (sigma `blend_mm`), y the wide one (twice as wide). They depend on the
/// tap alone, so the GPU reads them from a table (`SensorUniform::blend_weights`) instead of
/// evaluating exponentials per tap.
pub fn blend_weights(config: &ElastomerConfig, kernel: Kernel) -> Vec<DVec2> {
    let sigma = config.blend_mm;
    let gaussian = |taps: Taps, sigma: f64| -> Vec<f64> {
        let raw: Vec<f64> = (0..=taps.count)
            .map(|k| {
                if sigma > 0.0 {
                    let q = k as f64 * taps.step_mm / sigma;
                    (-0.5 * q * q).exp()
                } else {
                    (k == 0) as i32 as f64
                }
            })
            .collect();
        let norm = 2.0 * raw.iter().skip(1).sum::<f64>() + raw[0];
        raw.into_iter().map(|w| w / norm).collect()
    };
    let (narrow, wide) = (
        gaussian(kernel.narrow, sigma),
        gaussian(kernel.wide, 2.0 * sigma),
    );
    (0..=kernel.narrow.count.max(kernel.wide.count) as usize)
        .map(|k| {
            DVec2::new(
                narrow.get(k).copied().unwrap_or(0.0),
                wide.get(k).copied().unwrap_or(0.0),
            )
        })
        .collect()
}

/// One separable pass: for samples `sample(x)` at surface offsets x, the narrow Gaussian of
/// their x channel (at its taps) and the wide Gaussian of their y channel (at its own).
fn pass(config: &ElastomerConfig, kernel: Kernel, mut sample: impl FnMut(f64) -> DVec2) -> DVec2 {
    let weights = blend_weights(config, kernel);
    let mut one = |taps: Taps, channel: usize| -> f64 {
        (-taps.count..=taps.count)
            .map(|k| {
                weights[k.unsigned_abs() as usize][channel]
                    * sample(k as f64 * taps.step_mm)[channel]
            })
            .sum()
    };
    let narrow = one(kernel.narrow, 0);
    DVec2::new(narrow, one(kernel.wide, 1))
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

/// Point of the deformed skin over disc position `disc`: S(u) - h(u) n(u).
fn skin_at(finger: &Finger, grid: &HeightfieldGrid, height: &[f32], disc: DVec2) -> DVec3 {
    let c = SurfaceCoord::from_disc(disc);
    let sp = finger.point_at(c);
    sp.point - sample_field(height, grid.texels, grid.texel_of(c.to_disc())) * sp.normal
}

/// Offsets of the deformed skin's outward normal from the undeformed one, per texel of
/// `rect` (zero elsewhere): central differences of the skin S(u) - h(u) n(u) over one texel
/// on the disc, which has no seam or pole. The camera interpolates these offsets bilinearly,
/// so shading stays smooth across texels (differentiating the bilinear heightfield itself
/// would give a normal that jumps at every texel edge).
pub fn skin_normals(
    finger: &Finger,
    grid: &HeightfieldGrid,
    height: &[f32],
    rect: Rect,
) -> Vec<DVec3> {
    let n = grid.texels as usize;
    let mut out = vec![DVec3::ZERO; n * n];
    let e = grid.texel_mm();
    let (ex, ey) = (DVec2::new(e, 0.0), DVec2::new(0.0, e));
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let u = grid.texel_centre(i, j);
            let c = SurfaceCoord::from_disc(u);
            if c.s > grid.half_size_mm {
                continue;
            }
            let n0 = finger.point_at(c).normal;
            let dx = skin_at(finger, grid, height, u + ex) - skin_at(finger, grid, height, u - ex);
            let dy = skin_at(finger, grid, height, u + ey) - skin_at(finger, grid, height, u - ey);
            let mut normal = dx.cross(dy).normalize_or_zero();
            if normal.dot(n0) < 0.0 {
                normal = -normal;
            }
            if normal != DVec3::ZERO {
                out[j as usize * n + i as usize] = normal - n0;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::Sensor;

    /// The paper sensor's kernels (sigma 0.5 mm, texels 0.27 mm): each Gaussian tapped once
    /// per its sigma out to 3 sigma is 3 taps a side, the wide one's 1 mm apart; a spacing
    /// finer than a texel falls back to one tap per texel; and the sampled Gaussians still
    /// sum to one.
    #[test]
    fn kernel_taps_follow_the_spacing_and_the_texel() {
        let mut c = Sensor::preset("paper").unwrap().config;
        let grid = HeightfieldGrid {
            texels: 256,
            half_size_mm: 35.0,
        };
        let k = Kernel::for_config(&c, &grid);
        assert_eq!((k.narrow.count, k.wide.count), (3, 3));
        assert!((k.narrow.step_mm - 0.5).abs() < 1e-12 && (k.wide.step_mm - 1.0).abs() < 1e-12);
        assert_eq!(k.reach_mm, 3.0);
        c.render.blend_tap_spacing = 0.25;
        let fine = Kernel::for_config(&c, &grid);
        assert_eq!(fine.narrow.count, (1.5 / grid.texel_mm()).ceil() as i32);
        assert_eq!(fine.wide.count, (3.0 / grid.texel_mm()).ceil() as i32);
        c.render.blend_tap_spacing = 2.0;
        let k = Kernel::for_config(&c, &grid);
        assert_eq!((k.narrow.count, k.wide.count), (2, 2));
        let w = blend_weights(&c.elastomer, k);
        let total = w.iter().skip(1).sum::<DVec2>() * 2.0 + w[0];
        assert!((total - DVec2::ONE).abs().max_element() < 1e-12);
    }
}
