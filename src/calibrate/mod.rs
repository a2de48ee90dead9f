//! Calibration to a real sensor from its own frames: the lens from the image circle of an
//! empty frame ([`circle`]), the light (LEDs, ambient, paint shine, vignetting) and the
//! finger's length by fitting the renderer's light model to the frame ([`model`], [`fit`]),
//! the noise from several empty frames ([`frames`]), and the imprint's elastomer values from
//! frames with known contacts ([`contacts`]). [`quality`] scores a render against a frame.
//!
//! The result is a sensor configuration: physical values only, no per-pixel image.

pub mod circle;
pub mod contacts;
pub mod fit;
pub mod frames;
pub mod model;
pub mod quality;
pub mod solve;

use crate::error::{GeltipError, Result};
use crate::sensor::{Noise, Sensor, SensorConfig};
use circle::ImageCircle;
use frames::EmptyFrames;
use glam::DVec2;
use model::{Model, Samples};
use std::path::PathBuf;

/// What to calibrate from.
#[derive(Debug, Clone)]
pub struct Options {
    /// The sensor to start from: its finger, lens model and field of view, and every value
    /// calibration does not fit.
    pub start: Sensor,
    /// Frames of the empty finger (one or more, the same camera).
    pub empty: Vec<PathBuf>,
    /// Frames with known contacts (a JSON-lines file), to fit the elastomer's values.
    pub contacts: Option<PathBuf>,
    /// How many LEDs to fit; 0 tries [`AUTO_LEDS`] and keeps the fewest that explain the
    /// frame about as well as more would ([`fit::EXTRA_LED_GAIN`]).
    pub leds: usize,
    /// Pixels the polish compares (the starts compare a fifth as many).
    pub samples: usize,
    /// Rotations of the LEDs' starting ring tried (evenly spaced over 360 degrees).
    pub starts: usize,
}

impl Options {
    pub fn new(start: Sensor, empty: Vec<PathBuf>) -> Options {
        Options {
            start,
            empty,
            contacts: None,
            leds: 0,
            samples: 16_000,
            starts: DEFAULT_STARTS,
        }
    }
}

/// Starting rotations of the LEDs tried for each LED count.
pub const DEFAULT_STARTS: usize = 6;

/// The LED counts tried when the count is not given.
pub const AUTO_LEDS: std::ops::RangeInclusive<usize> = 3..=6;

/// A fitted value and its standard error.
#[derive(Debug, Clone, PartialEq)]
pub struct Value {
    pub name: String,
    pub value: f64,
    /// Infinite when the frames do not constrain it.
    pub std_error: f64,
}

/// What calibration found.
#[derive(Debug, Clone)]
pub struct Calibration {
    /// The calibrated sensor's configuration (complete: every command takes it).
    pub config: SensorConfig,
    pub circle: ImageCircle,
    /// Every fitted value (lens, light, finger, noise, elastomer) with its uncertainty.
    pub values: Vec<Value>,
    /// What the frames could not tell, each with why.
    pub unconstrained: Vec<String>,
    /// The empty frames' mean (RGB, 8-bit levels rounded), what renders are compared with.
    pub empty: image::RgbImage,
    pub frames: usize,
    /// Robust cost at the end of each fit stage, and LM iterations.
    pub fit_cost: f64,
    pub fit_iterations: usize,
    /// LEDs fitted.
    pub leds: usize,
    /// Every start tried (LED count, rotation) and the coarse cost it reached.
    pub starts: Vec<fit::Start>,
    pub contacts: Option<contacts::ContactFit>,
}

/// Calibrates `options.start` to the frames; `progress` hears each stage's name.
pub fn calibrate(options: &Options, progress: &dyn Fn(&str)) -> Result<Calibration> {
    if options.leds > crate::sensor::MAX_LEDS {
        return Err(GeltipError::option(
            "leds",
            format!(
                "fits 1 to {} LEDs (0: choose), got {}",
                crate::sensor::MAX_LEDS,
                options.leds
            ),
        ));
    }
    progress("loading the empty frames");
    let frames = EmptyFrames::load(&options.empty)?;
    progress("finding the image circle");
    let circle = circle::find(&frames.mean)?;
    let lensed = with_lens(&options.start, &frames, &circle)?;
    progress("fitting the light");
    let fitted = fit_light(options, &lensed, &frames, &circle)?;
    let model = &fitted.model;
    let mut config = model.config(&fitted.params);
    let mut values = lens_values(&model.start, &circle);
    values.extend(light_values(&fitted));
    let mut unconstrained = unconstrained_values(&values);
    unconstrained.push(
        "paint.colour, paint.diffuse: an empty frame shows the LEDs' light times the paint's; \
         the product is fitted as the LEDs' colours"
            .to_string(),
    );
    match noise_values(&frames, &circle) {
        Some((noise, noise_values)) => {
            config.render.noise = Noise::Rgb(noise);
            values.extend(noise_values);
        }
        None => unconstrained.push(
            "render.noise: one empty frame shows no noise; give several empty frames".to_string(),
        ),
    }
    let contacts = match &options.contacts {
        Some(path) => {
            progress("fitting the imprint to the frames with contacts");
            let sensor = Sensor::from_config(options.start.name.clone(), config.clone())?;
            let fit = contacts::fit(&sensor, &frames, &circle, path)?;
            config = fit.config.clone();
            values.extend(fit.values.iter().cloned());
            Some(fit)
        }
        None => {
            unconstrained.push(
                "elastomer.blend_mm, elastomer.drape_mm, elastomer.bulge: empty frames show no \
                 imprint; give frames with known contacts"
                    .to_string(),
            );
            None
        }
    };
    config.description = format!(
        "Calibrated from {} ({} frame{}) starting from {}",
        frames.mean.path.display(),
        frames.count,
        if frames.count == 1 { "" } else { "s" },
        options.start.name
    );
    config.validate()?;
    Ok(Calibration {
        config,
        circle,
        values,
        unconstrained,
        empty: mean_image(&frames),
        frames: frames.count,
        fit_cost: fitted.fit.cost,
        fit_iterations: fitted.fit.iterations,
        leds: model.leds,
        starts: fitted.starts,
        contacts,
    })
}

/// The light fitted to the empty frames' pixels inside the circle: every LED count asked
/// for (`options.leds`, or [`AUTO_LEDS`]) from `options.starts` rotations, on a coarse
/// sample and then a fine one, from the `lensed` sensor.
fn fit_light(
    options: &Options,
    lensed: &Sensor,
    frames: &EmptyFrames,
    circle: &ImageCircle,
) -> Result<fit::EmptyFit> {
    let counts: Vec<usize> = if options.leds == 0 {
        AUTO_LEDS.collect()
    } else {
        vec![options.leds]
    };
    let models: Vec<Model> = counts
        .iter()
        .map(|&leds| Model {
            start: lensed.clone(),
            leds,
        })
        .collect();
    let fine = sample(lensed, frames, circle, options.samples);
    let coarse = sample(lensed, frames, circle, (options.samples / 5).max(500));
    let most = models.iter().map(Model::len).max().unwrap_or(0);
    if coarse.len() < 4 * most {
        return Err(GeltipError::InvalidImage {
            path: frames.mean.path.clone(),
            reason: format!(
                "the image circle holds {} usable pixels, too few to fit {most} values",
                fine.len(),
            ),
        });
    }
    let rotations: Vec<f64> = (0..options.starts.max(1))
        .map(|i| 360.0 * i as f64 / options.starts.max(1) as f64)
        .collect();
    Ok(fit::fit_empty(&models, &coarse, &fine, &rotations, 200))
}

/// The light's fitted values, named as the model names them, with their standard errors.
fn light_values(fitted: &fit::EmptyFit) -> Vec<Value> {
    let errors = fitted.fit.standard_errors();
    model::names(fitted.model.leds)
        .into_iter()
        .zip(&fitted.params)
        .zip(errors)
        .map(|((name, value), std_error)| Value {
            name,
            value: *value,
            std_error,
        })
        .collect()
}

/// The noise of each colour channel inside the circle and its values (`render.noise[c]`),
/// when there are several empty frames to measure it from.
fn noise_values(frames: &EmptyFrames, circle: &ImageCircle) -> Option<([f64; 3], Vec<Value>)> {
    let inside = |x: u32, y: u32| circle.contains(x, y, 3.0);
    let noise = frames.noise(inside)?;
    let values = noise
        .iter()
        .enumerate()
        .map(|(c, sigma)| Value {
            name: format!("render.noise[{c}]"),
            value: *sigma,
            std_error: sigma / (2.0 * (frames.count as f64 - 1.0)).sqrt(),
        })
        .collect();
    Some((noise, values))
}

/// The start sensor with the frame's size and the lens the circle implies: the principal
/// point at its centre, the focal length that puts the edge of the field of view on it.
pub fn with_lens(start: &Sensor, frames: &EmptyFrames, circle: &ImageCircle) -> Result<Sensor> {
    let mut c = start.config.clone();
    c.image.width = frames.mean.width;
    c.image.height = frames.mean.height;
    c.lens.cx = circle.centre.x;
    c.lens.cy = circle.centre.y;
    // rho(theta_max) scales with the focal length for every model.
    let unit = start.lens.max_rho() / start.lens.focal_px;
    c.lens.focal_px = circle.radius / unit;
    Sensor::from_config(start.name.clone(), c).map_err(|e| GeltipError::InvalidImage {
        path: frames.mean.path.clone(),
        reason: format!("the image circle gives a lens the sensor cannot have: {e}"),
    })
}

/// The circle's values and the lens they set, each with the circle fit's uncertainty.
fn lens_values(sensor: &Sensor, circle: &ImageCircle) -> Vec<Value> {
    // A circle fitted to n points with rms scatter s: centre and radius to about s/sqrt(n/2).
    let e = circle.rms_px.max(0.29) / (circle.points as f64 / 2.0).sqrt();
    let unit = sensor.lens.max_rho() / sensor.lens.focal_px;
    let v = |name: &str, value: f64, std_error: f64| Value {
        name: name.to_string(),
        value,
        std_error,
    };
    vec![
        v("image_circle.cx", circle.centre.x, e),
        v("image_circle.cy", circle.centre.y, e),
        v("image_circle.radius", circle.radius, e),
        v("lens.cx", sensor.config.lens.cx, e),
        v("lens.cy", sensor.config.lens.cy, e),
        v("lens.focal_px", sensor.config.lens.focal_px, e / unit),
    ]
}

/// The fitted values the frames leave loose: an infinite error, or one larger than the
/// value's own size (or than 1 for a value near 0).
fn unconstrained_values(values: &[Value]) -> Vec<String> {
    values
        .iter()
        .filter(|v| !v.std_error.is_finite() || v.std_error > v.value.abs().max(1.0))
        .map(|v| {
            format!(
                "{}: the frames leave it loose ({} = {:.4}, standard error {})",
                v.name,
                v.name,
                v.value,
                if v.std_error.is_finite() {
                    format!("{:.3}", v.std_error)
                } else {
                    "unbounded".to_string()
                }
            )
        })
        .collect()
}

/// Pixels inside the circle (3 px from its edge), about `target` of them on a regular grid.
fn sample(sensor: &Sensor, frames: &EmptyFrames, circle: &ImageCircle, target: usize) -> Samples {
    let f = &frames.mean;
    let inside: Vec<(u32, u32)> = (0..f.height)
        .flat_map(|y| (0..f.width).map(move |x| (x, y)))
        .filter(|&(x, y)| circle.contains(x, y, 3.0))
        .collect();
    let stride = ((inside.len() as f64 / target.max(1) as f64).sqrt().floor() as u32).max(1);
    let chosen: Vec<(DVec2, [f64; 3])> = inside
        .into_iter()
        .filter(|&(x, y)| x % stride == 0 && y % stride == 0)
        .map(|(x, y)| {
            (
                DVec2::new(x as f64, y as f64),
                f.pixels[(y * f.width + x) as usize],
            )
        })
        .collect();
    Samples::new(sensor, &chosen)
}

fn mean_image(frames: &EmptyFrames) -> image::RgbImage {
    let f = &frames.mean;
    let raw = f
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| v.round().clamp(0.0, 255.0) as u8))
        .collect();
    image::RgbImage::from_raw(f.width, f.height, raw).expect("the frame's own size")
}
