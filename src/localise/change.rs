//! A change model between a reference and a frame that absorbs what is not contact, for real
//! sensors' frames: the LEDs drift (each channel's gain and offset vary smoothly over the
//! image circle: a degree-1 field, fitted robustly), the gel's features shift by a fraction
//! of a pixel (the frame is compared with the reference's 3x3 min/max band), JPEG blocks and
//! pixel noise (a 1 px blur), and a channel clipped black or white says nothing (values past
//! the black and white levels are censored: a black reference pixel is expected to stay
//! black). What is left, in units of the pair's own noise, smoothed, is scored against its own
//! spread over the circle; a region whose peak passes [`ChangeConfig::score_threshold`] is a
//! contact. [`super::Localiser::localise_change`] places it on the finger: the middle of the
//! region's stronger part ([`ChangeConfig::outline_fraction`]) on the surface, or the surface
//! detector's contact where that lies within [`ChangeConfig::agree_mm`] of it (on clean
//! rendered frames the surface detector is finer; on real ones drift pulls it elsewhere and
//! the check falls back). `pixel` is the region's weighted centroid, for callers without a
//! sensor model.
//!
//! On the AllSight's real frames (400 presses, 200 drift-only pairs) its constants hold with
//! margin when each is moved by 30%; the threshold was chosen on one session, 30% above its
//! highest drift-only score.

use super::raster::median;
use super::AreaWindow;
use crate::calibrate::solve::solve_dense;
use glam::DVec2;
use image::RgbImage;

/// The change model's constants (pixels and 8-bit levels).
#[derive(Debug, Clone, PartialEq)]
pub struct ChangeConfig {
    /// Pixels inside the image circle's edge left out.
    pub edge_margin_px: f64,
    /// Gaussian blur of both images (JPEG blocks, pixel noise), px.
    pub blur_px: f64,
    /// Values at or below this (black) and at or above `white_level` (clipped) are censored.
    pub black_level: f64,
    pub white_level: f64,
    /// Every this many pixels in x and y feed the drift fit.
    pub fit_step: usize,
    /// Tukey-reweighted least-squares rounds, and Tukey's constant in robust sigmas.
    pub irls_rounds: usize,
    pub tukey_c: f64,
    /// Half-width of the reference's min/max band (sub-pixel shifts), px.
    pub band_px: usize,
    /// The smallest noise per channel, levels.
    pub noise_floor: f64,
    /// Gaussian smoothing of the change map (blobs over thin edges), px.
    pub smooth_px: f64,
    /// The smallest spread of the smoothed map (noise-free renders).
    pub spread_floor: f64,
    /// Candidate regions: pixels above this many spreads, covering an area of the finger
    /// within `area_mm2` (the sensor model's area per pixel: the same limit on every
    /// sensor's pixels).
    pub region_threshold: f64,
    pub area_mm2: AreaWindow,
    /// The contact is placed by its region's pixels at or above this fraction of its peak
    /// (the change map's smoothing spreads a contact's change well past its edge).
    pub outline_fraction: f64,
    /// The surface detector's contact is taken where it lies within this of the change's
    /// own (mm on the finger): it places a contact more finely on a clean frame, and a
    /// real frame's drift pulls it elsewhere.
    pub agree_mm: f64,
    /// A region whose peak passes this many spreads is a contact.
    pub score_threshold: f64,
}

impl Default for ChangeConfig {
    fn default() -> Self {
        ChangeConfig {
            edge_margin_px: 6.0,
            blur_px: 1.0,
            black_level: 10.0,
            white_level: 250.0,
            fit_step: 3,
            irls_rounds: 6,
            tukey_c: 4.685,
            band_px: 1,
            noise_floor: 1.0,
            smooth_px: 3.0,
            spread_floor: 0.1,
            region_threshold: 4.0,
            area_mm2: AreaWindow {
                min_mm2: MIN_AREA_MM2,
                max_mm2: f64::INFINITY,
            },
            outline_fraction: 0.1,
            agree_mm: 1.0,
            score_threshold: 20.0,
        }
    }
}

impl ChangeConfig {
    /// The defaults with the decision threshold at `threshold` spreads (finite, > 0).
    pub fn with_threshold(threshold: f64) -> crate::error::Result<ChangeConfig> {
        super::DetectorOptions {
            threshold: Some(threshold),
            ..Default::default()
        }
        .change_config()
    }
}

/// Regions smaller than this on the finger are left out: specks, far too weak to be
/// decided (about 20 px of the AllSight's cylinder; on the AllSight's real frames and the
/// paper's rendered taps no region under it peaks past 6 spreads).
pub const MIN_AREA_MM2: f64 = 0.15;

/// What the change model found.
#[derive(Debug, Clone, PartialEq)]
pub struct ChangeDetection {
    pub detected: bool,
    /// The strongest region's weighted centroid (also when it scores under the threshold).
    pub pixel: Option<DVec2>,
    /// The strongest region's peak, in spreads of the smoothed change map.
    pub score: f64,
    /// 0.5 at the threshold, towards 1 above it (logistic, width 15% of the threshold); 0
    /// when nothing was detected.
    pub confidence: f64,
    pub regions: usize,
    /// The strongest region's pixels that place it ([`ChangeConfig::outline_fraction`]),
    /// as indices `y * width + x`; empty when there is none.
    pub region: Vec<usize>,
}

/// The change between `reference` and `frame` (the same size) inside the circle of `radius`
/// about `centre`, decided; `areas` is the finger's area each pixel sees, mm^2, row-major
/// (0 where it sees none: [`super::surface::SurfaceCache::areas`]).
pub fn detect(
    reference: &RgbImage,
    frame: &RgbImage,
    centre: DVec2,
    radius: f64,
    areas: &[f64],
    config: &ChangeConfig,
) -> ChangeDetection {
    let (w, h) = (reference.width() as usize, reference.height() as usize);
    let inner = radius - config.edge_margin_px;
    let norm = |x: usize, y: usize| ((x as f64 - centre.x) / inner, (y as f64 - centre.y) / inner);
    let mask: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = norm(i % w, i / w);
            x * x + y * y <= 1.0
        })
        .collect();
    let mut z2 = vec![0.0f64; w * h];
    let (lo, hi) = (config.black_level, config.white_level);
    for c in 0..3 {
        let plane = |img: &RgbImage| -> Vec<f64> {
            let raw: Vec<f64> = img.pixels().map(|p| p[c] as f64).collect();
            gaussian(&raw, w, h, config.blur_px)
        };
        let r = plane(reference);
        let f = plane(frame);
        let basis = |i: usize| {
            let (x, y) = norm(i % w, i / w);
            [1.0, x, y]
        };
        let fit: Vec<usize> = (0..w * h)
            .filter(|&i| {
                mask[i]
                    && (i % w) % config.fit_step == 0
                    && (i / w) % config.fit_step == 0
                    && r[i] > lo
                    && r[i] < hi
                    && f[i] > lo
                    && f[i] < hi
            })
            .collect();
        if fit.len() < 50 {
            continue;
        }
        let rows: Vec<[f64; 6]> = fit
            .iter()
            .map(|&i| {
                let b = basis(i);
                [b[0] * r[i], b[1] * r[i], b[2] * r[i], b[0], b[1], b[2]]
            })
            .collect();
        let target: Vec<f64> = fit.iter().map(|&i| f[i]).collect();
        let beta = robust_fit(&rows, &target, config.irls_rounds, config.tukey_c);
        let gain_offset = |i: usize| {
            let b = basis(i);
            (
                beta[0] * b[0] + beta[1] * b[1] + beta[2] * b[2],
                beta[3] * b[0] + beta[4] * b[1] + beta[5] * b[2],
            )
        };
        let (rmin, rmax) = band(&r, w, h, config.band_px);
        let predict = |v: f64, g: f64, o: f64| {
            if v <= lo {
                lo
            } else if v >= hi {
                hi
            } else {
                (g * v + o).clamp(lo, hi)
            }
        };
        let mut raw_residuals = Vec::new();
        let mut residual = vec![0.0; w * h];
        for i in (0..w * h).filter(|&i| mask[i]) {
            let (g, o) = gain_offset(i);
            let (pmin, pmax) = (predict(rmin[i], g, o), predict(rmax[i], g, o));
            let fc = f[i].clamp(lo, hi);
            residual[i] = if fc > pmax {
                fc - pmax
            } else if fc < pmin {
                fc - pmin
            } else {
                0.0
            };
            if r[i] > lo && r[i] < hi && f[i] > lo && f[i] < hi {
                raw_residuals.push((f[i] - (g * r[i] + o)).abs());
            }
        }
        let sigma = if raw_residuals.is_empty() {
            config.noise_floor
        } else {
            (1.4826 * median(&mut raw_residuals)).max(config.noise_floor)
        };
        for (z, res) in z2.iter_mut().zip(&residual) {
            *z += (res / sigma).powi(2);
        }
    }
    let z: Vec<f64> = z2
        .iter()
        .zip(&mask)
        .map(|(v, &m)| if m { (v / 3.0).sqrt() } else { 0.0 })
        .collect();
    decide(&z, &mask, areas, w, h, config)
}

/// The smoothed change map scored against its own spread over the circle, its regions
/// found and the strongest one decided.
fn decide(
    z: &[f64],
    mask: &[bool],
    areas: &[f64],
    w: usize,
    h: usize,
    config: &ChangeConfig,
) -> ChangeDetection {
    let smooth = gaussian(z, w, h, config.smooth_px);
    let mut inside: Vec<f64> = smooth
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v)
        .collect();
    let mid = median(&mut inside);
    let mut deviations: Vec<f64> = inside.iter().map(|v| (v - mid).abs()).collect();
    let spread = (1.4826 * median(&mut deviations)).max(config.spread_floor);
    let scored: Vec<f64> = smooth
        .iter()
        .zip(mask)
        .map(|(v, &m)| if m { (v - mid) / spread } else { 0.0 })
        .collect();
    let above: Vec<bool> = scored
        .iter()
        .map(|&v| v > config.region_threshold)
        .collect();
    let regions = components_4(&above, w, h);
    let best = regions
        .iter()
        .filter(|r| {
            let area: f64 = r
                .iter()
                .map(|&i| areas.get(i).copied().unwrap_or(0.0))
                .sum();
            config.area_mm2.holds(area)
        })
        .map(|r| {
            let peak = r.iter().map(|&i| scored[i]).fold(f64::MIN, f64::max);
            (peak, r)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let overall = scored.iter().copied().fold(0.0, f64::max);
    let (score, pixel, region) = match best {
        Some((peak, region)) => {
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for &i in region {
                let wgt = scored[i];
                sx += wgt * (i % w) as f64;
                sy += wgt * (i / w) as f64;
                sw += wgt;
            }
            let cut = config.outline_fraction * peak;
            let placed = region
                .iter()
                .copied()
                .filter(|&i| scored[i] >= cut)
                .collect();
            (peak, Some(DVec2::new(sx / sw, sy / sw)), placed)
        }
        None => (overall.min(config.region_threshold), None, Vec::new()),
    };
    let detected = pixel.is_some() && score > config.score_threshold;
    let t = config.score_threshold;
    let confidence = if detected {
        1.0 / (1.0 + (-(score - t) / (0.15 * t)).exp())
    } else {
        0.0
    };
    ChangeDetection {
        detected,
        pixel,
        score: if score.is_finite() { score } else { 0.0 },
        confidence,
        regions: regions.len(),
        region,
    }
}

/// Tukey-reweighted least squares of `target` on `rows`: the six gain and offset
/// coefficients.
fn robust_fit(rows: &[[f64; 6]], target: &[f64], rounds: usize, c: f64) -> [f64; 6] {
    let mut weights = vec![1.0; rows.len()];
    let mut beta = [0.0; 6];
    for _ in 0..=rounds {
        let mut ata = [0.0; 36];
        let mut atb = [0.0; 6];
        for ((row, &t), &wgt) in rows.iter().zip(target).zip(&weights) {
            for i in 0..6 {
                for j in 0..6 {
                    ata[i * 6 + j] += wgt * row[i] * row[j];
                }
                atb[i] += wgt * row[i] * t;
            }
        }
        for i in 0..6 {
            ata[i * 6 + i] += 1e-9;
        }
        let Some(solved) = solve_dense(&ata, &atb, 6) else {
            break;
        };
        beta.copy_from_slice(&solved);
        let residuals: Vec<f64> = rows
            .iter()
            .zip(target)
            .map(|(row, t)| t - row.iter().zip(&beta).map(|(a, b)| a * b).sum::<f64>())
            .collect();
        let mut sorted = residuals.clone();
        let mid = median(&mut sorted);
        let mut deviations: Vec<f64> = residuals.iter().map(|r| (r - mid).abs()).collect();
        let scale = 1.4826 * median(&mut deviations) + 1e-6;
        for (wgt, r) in weights.iter_mut().zip(&residuals) {
            let u = r / (c * scale);
            *wgt = if u.abs() < 1.0 {
                (1.0 - u * u).powi(2)
            } else {
                0.0
            };
        }
    }
    beta
}

/// Separable Gaussian blur of a plane (truncated at 4 sigma, edges mirrored).
fn gaussian(plane: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    if sigma <= 0.0 {
        return plane.to_vec();
    }
    let radius = (4.0 * sigma).round() as isize;
    let kernel: Vec<f64> = (-radius..=radius)
        .map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp())
        .collect();
    let sum: f64 = kernel.iter().sum();
    let kernel: Vec<f64> = kernel.iter().map(|k| k / sum).collect();
    let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for (k, kv) in kernel.iter().enumerate() {
                    let o = k as isize - radius;
                    let (sx, sy) = if horizontal {
                        (mirror(x as isize + o, w), y)
                    } else {
                        (x, mirror(y as isize + o, h))
                    };
                    acc += kv * src[sy * w + sx];
                }
                out[y * w + x] = acc;
            }
        }
        out
    };
    pass(&pass(plane, true), false)
}

/// `i` reflected into 0..n (the edge pixel repeated: d c b a | a b c d).
fn mirror(i: isize, n: usize) -> usize {
    let n = n as isize;
    let period = 2 * n;
    let m = i.rem_euclid(period);
    (if m < n { m } else { period - 1 - m }) as usize
}

/// The (2k+1)x(2k+1) minimum and maximum of a plane.
fn band(plane: &[f64], w: usize, h: usize, k: usize) -> (Vec<f64>, Vec<f64>) {
    let k = k as isize;
    let mut lo = vec![0.0; w * h];
    let mut hi = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let (mut a, mut b) = (f64::MAX, f64::MIN);
            for dy in -k..=k {
                for dx in -k..=k {
                    let v = plane[mirror(y as isize + dy, h) * w + mirror(x as isize + dx, w)];
                    a = a.min(v);
                    b = b.max(v);
                }
            }
            lo[y * w + x] = a;
            hi[y * w + x] = b;
        }
    }
    (lo, hi)
}

/// Regions of `mask` joined by their edges (4-connected), as pixel indices.
fn components_4(mask: &[bool], w: usize, h: usize) -> Vec<Vec<usize>> {
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if seen[start] || !mask[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut region = Vec::new();
        while let Some(i) = stack.pop() {
            region.push(i);
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if !seen[j] && mask[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
        out.push(region);
    }
    out
}
