//! Fitting the model to an empty frame: robust residuals in 8-bit levels (saturated values
//! only ask the model to reach 255; seams and specks are damped by a soft-L1 loss), LED
//! colours started by linear least squares, several starting rotations of the LEDs tried on
//! a coarse sample, the best polished on a fine one.

use super::frames::SATURATED;
use super::model::{Model, Samples};
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
}

/// The residuals of `p` on `samples`, soft-L1 damped.
pub fn residuals(model: &Model, samples: &Samples, p: &[f64]) -> Vec<f64> {
    let predicted = model.predict(p, samples);
    let mut out = Vec::with_capacity(samples.len() * 3);
    for (pred, obs) in predicted.iter().zip(&samples.observed) {
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
    let fit = levenberg_marquardt(&from, &model.bounds(), polish_iterations, |q| {
        residuals(&model, fine, q)
    });
    EmptyFit {
        model,
        params: fit.params.clone(),
        fit,
        starts,
    }
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
    let mut paint = model.start.config.paint.clone();
    paint.specular = d.specular;
    paint.shininess = d.shininess;
    let n = model.leds + 1;
    let gamma = d.lighting.camera.gamma;
    let l = model.layout();
    // Each LED alone, white and of intensity 1, with no ambient light (and past a shell's
    // end, none of the tip's own: it is added once, below).
    let alone_end = d.lighting.shell_end.map(|e| crate::sensor::ShellEndConfig {
        tip_colour: [0.0; 3],
        ..e
    });
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
            shell_end: alone_end,
            ..d.lighting.clone()
        })
        .collect();
    // Each LED's light alone and the ambient's at every sample (the vignetting's gain, and
    // past a shell's end the scale every LED's and the ambient's light pass through), with
    // the tip's own light (linear RGB, vignetted) it adds.
    let basis: Vec<(Vec<f64>, DVec3)> = (0..samples.len())
        .map(|i| {
            let (hit, x) = model.hit(&d, samples, i);
            let gain = d.lighting.vignette(x);
            let Some((hit, place)) = hit else {
                return (vec![0.0; n], DVec3::ZERO);
            };
            let (scale, tip) = match &d.lighting.shell_end {
                Some(end) => {
                    let (scale, beyond) = leds::shell_end_parts(end, hit.ray);
                    (scale, DVec3::from_array(end.tip_colour) * beyond)
                }
                None => (1.0, DVec3::ZERO),
            };
            let mut row: Vec<f64> = alone
                .iter()
                .map(|light| leds::shade_at(light, &paint, &hit, Some(&place)).x * gain)
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
                    ata[i * n + j] += row[i] * row[j];
                }
                atb[i] += row[i] * y;
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
