//! Fitting the model to an empty frame: robust residuals in 8-bit levels (saturated values
//! only ask the model to reach 255; seams and specks are damped by a soft-L1 loss), LED
//! colours started by linear least squares, several starting rotations of the LEDs tried on
//! a coarse sample, the best polished on a fine one.

use super::frames::SATURATED;
use super::model::{Model, Samples, PER_LED};
use super::solve::{levenberg_marquardt, solve_dense, Fit};
use crate::render::camera::SkinHit;
use crate::render::leds;
use crate::sensor::Lighting;
use glam::DVec3;
use rayon::prelude::*;

/// Residuals past this many levels count less and less (soft L1): a seam or a speck is a
/// few such values, a wrong light many.
pub const ROBUST_SCALE: f64 = 6.0;

/// How a fit went.
#[derive(Debug, Clone)]
pub struct EmptyFit {
    pub params: Vec<f64>,
    pub fit: Fit,
    /// The starting rotations tried and the cost each reached on the coarse sample.
    pub starts: Vec<(f64, f64)>,
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
fn soft_l1(r: f64) -> f64 {
    let c = ROBUST_SCALE;
    let q = r / c;
    r.signum() * c * (2.0 * ((1.0 + q * q).sqrt() - 1.0)).sqrt()
}

/// Fits `model` to the frame: `coarse` samples for the starts, `fine` ones for the polish.
pub fn fit_empty(
    model: &Model,
    coarse: &Samples,
    fine: &Samples,
    start_rotations: &[f64],
    polish_iterations: usize,
) -> EmptyFit {
    let bounds = model.bounds();
    // The starts search the LEDs' places, spreads and fall-offs, the shine, vignetting and
    // finger length alone; the colours and the ambient light follow them by linear least
    // squares (variable projection), which keeps the starts away from the valleys where an
    // LED's brightness and its distance trade off.
    let colour_slots = colour_slots(model);
    let free: Vec<usize> = (0..model.len())
        .filter(|i| !colour_slots.contains(i))
        .collect();
    let reduced_bounds: Vec<_> = free.iter().map(|&i| bounds[i]).collect();
    let tried: Vec<(f64, Fit)> = start_rotations
        .par_iter()
        .map(|&rotation| {
            let full = model.initial(rotation);
            let expand = |q: &[f64]| {
                let mut p = full.clone();
                for (&i, &v) in free.iter().zip(q) {
                    p[i] = v;
                }
                linear_colours(model, coarse, &mut p);
                p
            };
            let reduced: Vec<f64> = free.iter().map(|&i| full[i]).collect();
            let fit = levenberg_marquardt(&reduced, &reduced_bounds, 40, |q| {
                residuals(model, coarse, &expand(q))
            });
            let params = expand(&fit.params);
            (rotation, Fit { params, ..fit })
        })
        .collect();
    let starts: Vec<(f64, f64)> = tried.iter().map(|(r, f)| (*r, f.cost)).collect();
    let best = tried
        .into_iter()
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        .expect("at least one start");
    let fit = levenberg_marquardt(&best.1.params, &bounds, polish_iterations, |q| {
        residuals(model, fine, q)
    });
    EmptyFit {
        params: fit.params.clone(),
        fit,
        starts,
    }
}

/// Where the LED colours and the ambient light sit in a parameter vector.
fn colour_slots(model: &Model) -> Vec<usize> {
    let mut slots: Vec<usize> = (0..model.leds)
        .flat_map(|k| (3..6).map(move |c| k * PER_LED + c))
        .collect();
    slots.extend((0..3).map(|c| model.leds * PER_LED + c));
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
    // Each LED's light alone (white, intensity 1) and the ambient's, at every sample.
    let basis: Vec<Vec<f64>> = samples
        .rays
        .iter()
        .zip(&samples.radial)
        .map(|(&ray, &x)| {
            let gain = d.lighting.vignette(x);
            let Some(s) = d.finger.surface_along(ray) else {
                return vec![0.0; n];
            };
            let hit = SkinHit {
                point: s.point,
                normal: s.normal,
                indentation: 0.0,
                ray,
            };
            let mut row: Vec<f64> = d
                .lighting
                .leds
                .iter()
                .map(|led| {
                    let alone = Lighting {
                        leds: vec![crate::sensor::Led {
                            colour: DVec3::ONE,
                            ..*led
                        }],
                        ambient: DVec3::ZERO,
                        paint_colour: DVec3::ONE,
                        vignetting: d.lighting.vignetting,
                    };
                    leds::shade_with(&alone, &paint, &hit).x * gain
                })
                .collect();
            row.push(gain);
            row
        })
        .collect();
    for c in 0..3 {
        let mut ata = vec![0.0; n * n];
        let mut atb = vec![0.0; n];
        for (row, obs) in basis.iter().zip(&samples.observed) {
            if obs[c] <= 0.5 {
                continue;
            }
            // A clipped value says only "at least full scale": taken as full scale here,
            // the fit that follows lets it rise.
            let y = (obs[c].min(255.0) / 255.0).powf(2.2);
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
                p[k * PER_LED + 3 + c] = x[k].max(0.0);
            }
            p[model.leds * PER_LED + c] = x[model.leds].max(0.0);
        }
    }
}
