//! Fitting the model to an empty frame: robust residuals in 8-bit levels (saturated values
//! only ask the model to reach 255; seams and specks are damped by a soft-L1 loss), LED
//! colours started by linear least squares, several starting rotations of the LEDs tried on
//! a coarse sample, the best polished on a fine one.

use super::frames::SATURATED;
use super::model::{recorded, Model, Samples};
use super::solve::{invert, levenberg_marquardt, solve_dense, Fit};
use crate::render::leds;
use crate::sensor::Lighting;
use glam::DVec3;
use rayon::prelude::*;

/// Residuals past this many levels count less and less (soft L1): a seam or a speck is a
/// few such values, a wrong light many.
pub const ROBUST_SCALE: f64 = 6.0;

/// One start: a model (its LED count), the LEDs' starting rotation, and where the coarse
/// fit from there ended.
#[derive(Debug, Clone)]
pub struct Start {
    pub leds: usize,
    pub rotation_deg: f64,
    pub cost: f64,
    pub params: Vec<f64>,
}

/// How a fit went.
#[derive(Debug, Clone)]
pub struct EmptyFit {
    /// The model chosen (its LED count).
    pub model: Model,
    pub params: Vec<f64>,
    pub fit: Fit,
    /// Every start tried, with the cost it reached on the coarse sample.
    pub starts: Vec<Start>,
    /// The values fitted, when not all of them (the rest held at the start's); `fit` is
    /// then over these alone.
    pub only: Option<std::ops::Range<usize>>,
}

/// The residuals of `p` on `samples`, soft-L1 damped.
pub fn residuals(model: &Model, samples: &Samples, p: &[f64]) -> Vec<f64> {
    robust(&model.predict(p, samples), &samples.observed)
}

/// The soft-L1 damped residuals of `predicted` levels against `observed` ones.
fn robust(predicted: &[[f64; 3]], observed: &[[f64; 3]]) -> Vec<f64> {
    let mut out = Vec::with_capacity(observed.len() * 3);
    for (pred, obs) in predicted.iter().zip(observed) {
        for c in 0..3 {
            let r = if obs[c] >= SATURATED {
                (pred[c] - 255.0).min(0.0)
            } else {
                pred[c] - obs[c]
            };
            out.push(soft_l1(r));
        }
    }
    out
}

/// sign(r) sqrt(2 c^2 (sqrt(1 + (r/c)^2) - 1)): r for small residuals, sqrt(2 c |r|) for
/// large ones.
pub fn soft_l1(r: f64) -> f64 {
    let c = ROBUST_SCALE;
    let q = r / c;
    r.signum() * c * (2.0 * ((1.0 + q * q).sqrt() - 1.0)).sqrt()
}

/// An extra LED must lower the coarse cost by this share to be kept: a fit with more LEDs
/// is chosen only when it explains clearly more of the frame.
pub const EXTRA_LED_GAIN: f64 = 0.05;

/// Fits the frame with each of `models` (one per LED count) from every rotation in
/// `start_rotations` on the `coarse` samples, keeps the fewest LEDs whose best start comes
/// within [`EXTRA_LED_GAIN`] per extra LED of the best, and polishes that start on the
/// `fine` samples.
pub fn fit_empty(
    models: &[Model],
    coarse: &Samples,
    fine: &Samples,
    start_rotations: &[f64],
    polish_iterations: usize,
) -> EmptyFit {
    let jobs: Vec<(usize, f64)> = (0..models.len())
        .flat_map(|m| start_rotations.iter().map(move |&r| (m, r)))
        .collect();
    let starts: Vec<Start> = jobs
        .par_iter()
        .map(|&(m, rotation)| coarse_start(&models[m], coarse, rotation))
        .collect();
    let best_of = |leds: usize| {
        starts
            .iter()
            .filter(|s| s.leds == leds)
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
            .expect("every model has a start")
    };
    let best = models
        .iter()
        .map(|m| best_of(m.leds))
        .min_by(|a, b| {
            let penalised = |s: &Start| s.cost * (1.0 + EXTRA_LED_GAIN).powi(s.leds as i32);
            penalised(a).total_cmp(&penalised(b))
        })
        .expect("at least one model")
        .clone();
    let model = models
        .iter()
        .find(|m| m.leds == best.leds)
        .expect("the start's model")
        .clone();
    // A lens freed from the start's light wanders to explain the light's errors (a
    // costlier end, by the robust cost and by PSNR): the light is polished with the lens
    // held first, then everything together.
    let lens = lens_slots(&model);
    let from = if lens.is_empty() {
        best.params.clone()
    } else {
        polish_free(&model, fine, &best.params, &lens, polish_iterations)
    };
    let fit = match model.layout().end_glow {
        Some(glow) => polish_with_end_glow(&model, fine, &from, glow, polish_iterations),
        None => levenberg_marquardt(&from, &model.bounds(), polish_iterations, |q| {
            residuals(&model, fine, q)
        }),
    };
    EmptyFit {
        model,
        params: fit.params.clone(),
        fit,
        starts,
        only: None,
    }
}

/// The LEDs' glow at a shell's end fitted alone over the start's light (`--fit glow`): every
/// other value held at the start's, each evaluation on the light kept before the end's
/// scale. `None` when the model does not fit a glow (the start's end sets no spread).
pub fn fit_end_glow(model: &Model, samples: &Samples, iterations: usize) -> Option<EmptyFit> {
    let glow = model.layout().end_glow?;
    let from = model.initial(0.0);
    let cache = GlowCache {
        model,
        samples,
        glow: glow.clone(),
        kept: std::sync::RwLock::new(None),
    };
    let expand = |q: &[f64]| {
        let mut full = from.clone();
        full[glow.clone()].copy_from_slice(q);
        full
    };
    let bounds = model.bounds();
    let fit = levenberg_marquardt(
        &from[glow.clone()],
        &bounds[glow.clone()],
        iterations,
        |q| cache.residuals(&expand(q)),
    );
    let params = expand(&fit.params);
    Some(EmptyFit {
        model: model.clone(),
        starts: vec![Start {
            leds: model.leds,
            rotation_deg: 0.0,
            cost: fit.cost,
            params: params.clone(),
        }],
        params,
        fit,
        only: Some(glow),
    })
}

/// A coarse fit from the LEDs rotated by `rotation`: their places, spreads and fall-offs,
/// the shine, vignetting and finger length searched (the camera and the lens held); the
/// colours and the ambient light following them by linear least squares (variable
/// projection), which keeps a start out of the valleys where an LED's brightness and its
/// distance trade off.
fn coarse_start(model: &Model, coarse: &Samples, rotation: f64) -> Start {
    let mut held = colour_slots(model);
    // The camera stays at the start's until the polish: the linear colours assume it. So
    // does the lens, a small correction the starts need not search.
    if let Some(i) = model.layout().camera {
        held.extend(i..i + 9);
    }
    held.extend(lens_slots(model));
    let (fit, params) = fit_held(model, coarse, &model.initial(rotation), &held, 40, |p| {
        linear_colours(model, coarse, p)
    });
    Start {
        leds: model.leds,
        rotation_deg: rotation,
        cost: fit.cost,
        params,
    }
}

/// The polish where the LEDs glow at a shell's end (`glow`, their values), all values
/// together. The glow only scales the light there, so a forward difference in it reuses the
/// light before that scale, kept from the last full evaluation ([`GlowCache`]): its columns
/// cost a fraction of the others'.
fn polish_with_end_glow(
    model: &Model,
    samples: &Samples,
    from: &[f64],
    glow: std::ops::Range<usize>,
    iterations: usize,
) -> Fit {
    let cache = GlowCache {
        model,
        samples,
        glow,
        kept: std::sync::RwLock::new(None),
    };
    levenberg_marquardt(from, &model.bounds(), iterations, |q| cache.residuals(q))
}

/// At each sample: the light before a shell end's scale, its vignetting gain and its ray;
/// and each LED's weight in its glow there ([`leds::end_glow_weights`]), for `spread`.
struct BareLight {
    samples: Vec<Option<(DVec3, f64, DVec3)>>,
    weights: Vec<f64>,
    spread: Option<f64>,
}

/// Residuals of the model, keeping the light before the shell end's scale at the last
/// parameters evaluated in full (a trial step's: they differ from the kept ones in more than
/// one value outside `glow`; a forward difference moves one). Parameters that differ from
/// the kept ones only at `glow` are evaluated on the kept light, exactly as in full.
struct GlowCache<'a> {
    model: &'a Model,
    samples: &'a Samples,
    glow: std::ops::Range<usize>,
    kept: std::sync::RwLock<Option<(Vec<f64>, std::sync::Arc<BareLight>)>>,
}

impl GlowCache<'_> {
    fn residuals(&self, q: &[f64]) -> Vec<f64> {
        let differ = |kept: &[f64]| {
            kept.iter()
                .zip(q)
                .enumerate()
                .filter(|(i, (a, b))| !self.glow.contains(i) && a != b)
                .count()
        };
        let kept = self.kept.read().ok().and_then(|k| k.clone());
        let bare = match &kept {
            Some((at, bare)) if differ(at) == 0 => bare.clone(),
            _ => {
                let bare = std::sync::Arc::new(self.bare_light(q));
                if kept.as_ref().is_none_or(|(at, _)| differ(at) > 1) {
                    if let Ok(mut k) = self.kept.write() {
                        *k = Some((q.to_vec(), bare.clone()));
                    }
                }
                bare
            }
        };
        robust(&self.predict(q, &bare), &self.samples.observed)
    }

    fn bare_light(&self, q: &[f64]) -> BareLight {
        let (model, d) = (self.model, self.model.decode(q));
        let paint = model.paint(&d);
        let bare = Lighting {
            shell_end: None,
            ..d.lighting.clone()
        };
        let spread = d.lighting.shell_end.and_then(|e| e.led_glow_deg);
        let mut weights = Vec::with_capacity(self.samples.len() * d.lighting.leds.len());
        let samples = (0..self.samples.len())
            .map(|i| match model.hit(&d, self.samples, i) {
                (Some((hit, place)), x) => {
                    if let Some(spread) = spread {
                        weights.extend(leds::end_glow_weights(&d.lighting.leds, spread, hit.ray));
                    }
                    Some((
                        leds::shade_at(&bare, &paint, &hit, Some(&place)),
                        d.lighting.vignette(x),
                        hit.ray,
                    ))
                }
                (None, _) => None,
            })
            .collect();
        BareLight {
            samples,
            weights,
            spread,
        }
    }

    /// [`Model::predict`] from the light before the shell end's scale.
    fn predict(&self, q: &[f64], bare: &BareLight) -> Vec<[f64; 3]> {
        let d = self.model.decode(q);
        let camera = d.lighting.camera;
        let leds = &d.lighting.leds;
        let mut weights = bare.weights.chunks_exact(leds.len().max(1));
        bare.samples
            .iter()
            .map(|b| {
                let Some((light, gain, ray)) = b else {
                    return [0.0; 3];
                };
                let kept = match bare.spread {
                    Some(_) => weights.next(),
                    None => None,
                };
                let light = match &d.lighting.shell_end {
                    Some(end) => {
                        let glow = end.led_glow_deg.map(|spread| match kept {
                            Some(w) if bare.spread == Some(spread) => {
                                leds::weighted_end_glow(leds, w.iter().copied())
                            }
                            _ => leds::end_glow(leds, spread, *ray),
                        });
                        let (scale, beyond) = leds::shell_end_parts_glowing(end, glow, *ray);
                        *light * scale + DVec3::from_array(end.tip_colour) * beyond
                    }
                    None => *light,
                };
                recorded(&camera, light * *gain)
            })
            .collect()
    }
}

/// Where the lens's values (principal point, focal length) sit in a parameter vector.
fn lens_slots(model: &Model) -> Vec<usize> {
    let l = model.layout();
    let mut slots: Vec<usize> = l.principal.map(|i| vec![i, i + 1]).unwrap_or_default();
    slots.extend(l.focal);
    slots
}

/// `p` polished on `samples` with the values at `held` kept as they are.
fn polish_free(
    model: &Model,
    samples: &Samples,
    p: &[f64],
    held: &[usize],
    iterations: usize,
) -> Vec<f64> {
    fit_held(model, samples, p, held, iterations, |_| {}).1
}

/// Levenberg-Marquardt on `samples` over the values of `p` not at `held` (those keep `p`'s),
/// `fill` setting whatever follows from the free ones before each evaluation: the fit and
/// the whole parameter vector it ends at.
fn fit_held(
    model: &Model,
    samples: &Samples,
    p: &[f64],
    held: &[usize],
    iterations: usize,
    fill: impl Fn(&mut [f64]) + Sync,
) -> (Fit, Vec<f64>) {
    let free: Vec<usize> = (0..p.len()).filter(|i| !held.contains(i)).collect();
    let bounds = model.bounds();
    let reduced_bounds: Vec<_> = free.iter().map(|&i| bounds[i]).collect();
    let expand = |q: &[f64]| {
        let mut full = p.to_vec();
        for (&i, &v) in free.iter().zip(q) {
            full[i] = v;
        }
        fill(&mut full);
        full
    };
    let reduced: Vec<f64> = free.iter().map(|&i| p[i]).collect();
    let fit = levenberg_marquardt(&reduced, &reduced_bounds, iterations, |q| {
        residuals(model, samples, &expand(q))
    });
    let params = expand(&fit.params);
    (fit, params)
}

/// Where the LED colours and the ambient light sit in a parameter vector.
fn colour_slots(model: &Model) -> Vec<usize> {
    let l = model.layout();
    let mut slots: Vec<usize> = (0..model.leds)
        .flat_map(|k| (0..3).map(move |c| k * l.per_led + l.colour + c))
        .collect();
    slots.extend((0..3).map(|c| l.ambient + c));
    slots
}

/// Sets the LED colours and the ambient light of `p` to the linear least-squares fit of the
/// frame's linear light (gamma undone), for the LEDs' places, spreads and fall-offs in `p`:
/// the light is linear in them, so this puts each start near its best colours at once.
pub fn linear_colours(model: &Model, samples: &Samples, p: &mut [f64]) {
    let d = model.decode(p);
    let paint = model.paint(&d);
    let n = model.leds + 1;
    let gamma = d.lighting.camera.gamma;
    let l = model.layout();
    // Each LED alone, white and of intensity 1, with no ambient light and no shell's end:
    // past one, every LED's light and the ambient's pass through the same scale, found once
    // with all the LEDs (their glow there tints it), and the tip's own light is added once.
    let alone: Vec<Lighting> = d
        .lighting
        .leds
        .iter()
        .map(|led| Lighting {
            leds: vec![crate::sensor::Led {
                colour: DVec3::ONE,
                ..*led
            }],
            ambient: DVec3::ZERO,
            paint_colour: DVec3::ONE,
            shell_end: None,
            ..d.lighting.clone()
        })
        .collect();
    // Each LED's light alone and the ambient's at every sample, per channel (the vignetting's
    // gain and the shell end's scale), with the tip's own light (linear RGB, vignetted) it
    // adds.
    let basis: Vec<(Vec<DVec3>, DVec3)> = (0..samples.len())
        .map(|i| {
            let (hit, x) = model.hit(&d, samples, i);
            let gain = d.lighting.vignette(x);
            let Some((hit, place)) = hit else {
                return (vec![DVec3::ZERO; n], DVec3::ZERO);
            };
            let (scale, tip) = match &d.lighting.shell_end {
                Some(end) => {
                    let (scale, beyond) = leds::shell_end_parts(end, &d.lighting.leds, hit.ray);
                    (scale, DVec3::from_array(end.tip_colour) * beyond)
                }
                None => (DVec3::ONE, DVec3::ZERO),
            };
            let mut row: Vec<DVec3> = alone
                .iter()
                .map(|light| {
                    DVec3::splat(leds::shade_at(light, &paint, &hit, Some(&place)).x) * scale * gain
                })
                .collect();
            row.push(gain * scale);
            (row, tip * gain)
        })
        .collect();
    // The light the camera mixed: each sample's levels with the gamma undone and the colour
    // matrix's mixing undone, so that each channel's light is linear in that channel's
    // colours alone. A clipped value says only "at least full scale": taken as full scale
    // here, the fit that follows lets it rise. The tip's own light is held.
    let camera = &d.lighting.camera;
    let unmix = (!camera.has_default_response())
        .then(|| invert(&camera.colour_matrix.concat(), 3))
        .flatten();
    let light: Vec<[f64; 3]> = samples
        .observed
        .iter()
        .zip(&basis)
        .map(|(obs, (_, tip))| {
            let y: [f64; 3] = std::array::from_fn(|c| (obs[c].min(255.0) / 255.0).powf(gamma[c]));
            let x: [f64; 3] = match &unmix {
                Some(m) => std::array::from_fn(|k| (0..3).map(|c| m[k * 3 + c] * y[c]).sum()),
                None => y,
            };
            std::array::from_fn(|k| x[k] - tip[k])
        })
        .collect();
    for c in 0..3 {
        let mut ata = vec![0.0; n * n];
        let mut atb = vec![0.0; n];
        for (((row, _), obs), y) in basis.iter().zip(&samples.observed).zip(&light) {
            // Dark values say little about a channel's light (and mixed, about any).
            let dark = match unmix {
                Some(_) => obs.iter().any(|&v| v <= 0.5),
                None => obs[c] <= 0.5,
            };
            if dark {
                continue;
            }
            let y = y[c];
            for i in 0..n {
                for j in 0..n {
                    ata[i * n + j] += row[i][c] * row[j][c];
                }
                atb[i] += row[i][c] * y;
            }
        }
        for i in 0..n {
            ata[i * n + i] += 1e-9;
        }
        if let Some(x) = solve_dense(&ata, &atb, n) {
            for k in 0..model.leds {
                p[k * l.per_led + l.colour + c] = x[k].max(0.0);
            }
            p[l.ambient + c] = x[model.leds].max(0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::{LedKindName, Leds, Sensor};
    use glam::DVec2;

    /// The cached light gives the residuals a full evaluation gives, bit for bit, wherever
    /// it is used (the glow moved alone) and wherever it is not (anything else moved).
    #[test]
    fn the_glow_cache_evaluates_exactly_as_the_model_does() {
        let mut c = Sensor::preset("allsight").unwrap().config;
        if let Some(end) = c.shell_end.as_mut() {
            end.led_glow_deg = Some(25.0);
        }
        if let Leds::List(list) = &mut c.leds {
            list[2].end_glow = [0.4, -0.2, 0.1];
        }
        let sensor = Sensor::from_config("glow", c).unwrap();
        let pixels: Vec<(DVec2, [f64; 3])> = (0..400)
            .map(|i| {
                let (x, y) = (40.0 + (i % 20) as f64 * 20.0, 40.0 + (i / 20) as f64 * 20.0);
                (DVec2::new(x, y), [90.0, 60.0 + (i % 7) as f64, 120.0])
            })
            .collect();
        let samples = Samples::new(&sensor, &pixels);
        let model = Model {
            leds: 9,
            kind: LedKindName::Gel,
            camera: true,
            ..Model::point(sensor, 9)
        };
        let glow = model.layout().end_glow.expect("the glow is fitted");
        let g = glow.start;
        let cache = GlowCache {
            model: &model,
            samples: &samples,
            glow,
            kept: std::sync::RwLock::new(None),
        };
        let p = model.initial(0.0);
        assert_eq!(cache.residuals(&p), residuals(&model, &samples, &p));
        let mut trial = p.clone();
        for v in trial.iter_mut().take(g) {
            *v *= 1.001;
        }
        assert_eq!(cache.residuals(&trial), residuals(&model, &samples, &trial));
        for (i, step) in [(g + 4, 0.3), (g + 3 * model.leds, 5.0), (1, 0.05)] {
            let mut q = trial.clone();
            q[i] += step;
            let full = residuals(&model, &samples, &q);
            assert_eq!(cache.residuals(&q), full, "value {i}");
            assert_ne!(
                full,
                residuals(&model, &samples, &trial),
                "value {i} moves nothing"
            );
        }
    }
}
