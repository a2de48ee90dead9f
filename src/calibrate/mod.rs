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
pub mod imprint;
pub mod model;
pub mod quality;
pub mod solve;

use crate::error::{GeltipError, Result};
use crate::sensor::{LedKindName, Noise, Sensor, SensorConfig};
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
    /// Rotations of the LEDs' starting ring tried (evenly spaced over 360 degrees; one when
    /// the start sensor lists the LEDs fitted).
    pub starts: usize,
    /// What is fitted; the rest is held at the start sensor's values.
    pub fit: FitSet,
    /// Which kind of LED to fit; by default the start sensor's listed LEDs' kind (point
    /// LEDs for the ring).
    pub led_kind: Option<LedKindName>,
}

/// What calibration fits (`--fit`): each part is fitted or held at the start sensor's
/// values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FitSet {
    /// The lens from the image circle (its centre and the focal length that puts the field
    /// of view on its edge), the circle held as the image's mask.
    pub lens: bool,
    /// The lens's principal point fitted to the light: where the circle is a mask, its
    /// centre need not be the lens's.
    pub principal: bool,
    /// The focal length fitted to the light: where the circle is a mask, the field of view
    /// it implies is a guess (contact frames pin the lens better where there are some).
    pub focal: bool,
    /// LEDs, ambient light, paint shine, vignetting.
    pub light: bool,
    /// The camera's colour matrix and gamma (held by default).
    pub camera: bool,
    /// The finger's length (the cylinder's).
    pub geometry: bool,
    /// The imprint's elastomer values, from the frames with known contacts.
    pub imprint: bool,
    /// The LEDs' glow at a clear shell's open end alone, over the start's light (its
    /// `[shell_end]` must set `led_glow_deg`; the light fit fits the glow with the rest).
    pub glow: bool,
}

impl Default for FitSet {
    /// Lens, light and imprint; the geometry and the camera the sensor file states are held
    /// (a camera's response is the camera's: fitted once, on the frame that shows it best).
    fn default() -> Self {
        FitSet {
            lens: true,
            principal: false,
            focal: false,
            light: true,
            camera: false,
            geometry: false,
            imprint: true,
            glow: false,
        }
    }
}

impl FitSet {
    pub const PARTS: [&'static str; 8] = [
        "lens",
        "principal",
        "focal",
        "light",
        "camera",
        "geometry",
        "imprint",
        "glow",
    ];

    /// Nothing fitted.
    pub const NONE: FitSet = FitSet {
        lens: false,
        principal: false,
        focal: false,
        light: false,
        camera: false,
        geometry: false,
        imprint: false,
        glow: false,
    };

    /// Parses a comma-separated list of [`FitSet::PARTS`] (`"light,lens"`).
    pub fn parse(text: &str) -> Result<FitSet> {
        let mut set = FitSet::NONE;
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part {
                "lens" => set.lens = true,
                "principal" => set.principal = true,
                "focal" => set.focal = true,
                "light" => set.light = true,
                "camera" => set.camera = true,
                "geometry" => set.geometry = true,
                "imprint" => set.imprint = true,
                "glow" => set.glow = true,
                other => {
                    return Err(GeltipError::option(
                        "fit",
                        format!(
                            "unknown part '{other}'; choose from {}",
                            FitSet::PARTS.join(", ")
                        ),
                    ))
                }
            }
        }
        set.validate()?;
        Ok(set)
    }

    /// Refuses a set that fits nothing, or the camera or the geometry without the light.
    pub fn validate(&self) -> Result<()> {
        if *self == FitSet::NONE {
            return Err(GeltipError::option(
                "fit",
                format!(
                    "names nothing to fit; choose from {}",
                    FitSet::PARTS.join(", ")
                ),
            ));
        }
        if (self.camera || self.geometry || self.principal || self.focal) && !self.light {
            return Err(GeltipError::option(
                "fit",
                "the camera, the geometry, the principal point and the focal length are fitted with the light; add light",
            ));
        }
        if self.glow && self.light {
            return Err(GeltipError::option(
                "fit",
                "the light fit fits the glow too where the start sets led_glow_deg; glow alone fits it over the start's light",
            ));
        }
        if (self.principal || self.focal) && !self.lens {
            return Err(GeltipError::option(
                "fit",
                "the principal point and the focal length are fitted with the lens; add lens",
            ));
        }
        Ok(())
    }

    /// The parts fitted, comma-separated.
    pub fn names(&self) -> String {
        let on = [
            self.lens,
            self.principal,
            self.focal,
            self.light,
            self.camera,
            self.geometry,
            self.imprint,
            self.glow,
        ];
        FitSet::PARTS
            .iter()
            .zip(on)
            .filter(|(_, on)| *on)
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// A fitted value that ended on its box's edge: the frames pushed it as far as the model
/// lets it go.
#[derive(Debug, Clone, PartialEq)]
pub struct AtBound {
    pub name: String,
    pub value: f64,
    /// "lower" or "upper".
    pub side: &'static str,
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
            fit: FitSet::default(),
            led_kind: None,
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
    /// Every fitted value that ended on a bound.
    pub at_bounds: Vec<AtBound>,
    /// What was fitted.
    pub fit: FitSet,
}

/// Calibrates `options.start` to the frames; `progress` hears each stage's name.
pub fn calibrate(options: &Options, progress: &dyn Fn(&str)) -> Result<Calibration> {
    options.fit.validate()?;
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
    let (lensed, reach) = if options.fit.lens {
        with_lens(&options.start, &frames, &circle, &options.fit)?
    } else {
        (held_lens(&options.start, &frames)?, LensReach::default())
    };
    let mut values = if options.fit.lens {
        lens_values(&lensed, &circle, &reach)
    } else {
        Vec::new()
    };
    let (mut config, leds, fit_cost, fit_iterations, starts, at_bounds) =
        if options.fit.light || options.fit.glow {
            let fitted = if options.fit.light {
                progress("fitting the light");
                fit_light(options, &lensed, &frames, &circle, reach)?
            } else {
                progress("fitting the LEDs' glow at the shell's end");
                fit_glow(options, &lensed, &frames, &circle)?
            };
            let model = &fitted.model;
            values.extend(light_values(&fitted));
            (
                model.config(&fitted.params),
                model.leds,
                fitted.fit.cost,
                fitted.fit.iterations,
                fitted.starts.clone(),
                at_bounds(&fitted),
            )
        } else {
            let leds = lensed.lighting().leds.len();
            (lensed.config.clone(), leds, 0.0, 0, Vec::new(), Vec::new())
        };
    let mut unconstrained = unconstrained_values(&values);
    unconstrained.push(
        "paint.colour, paint.diffuse: an empty frame shows the LEDs' light times the paint's; \
         the product is fitted as the LEDs' colours"
            .to_string(),
    );
    match noise_values(&frames, &circle) {
        // A soft camera blurs what it records, the renderer's noise with it: the noise
        // measured is reported, not written.
        Some((noise, noise_values)) if config.camera.blurs() => {
            values.extend(noise_values);
            unconstrained.push(format!(
                "render.noise: measured ({:.2}, {:.2}, {:.2} levels) but not written: the \
                 camera's blur_px would blur it; add it afterwards (`dataset --noise`)",
                noise[0], noise[1], noise[2]
            ));
        }
        Some((noise, noise_values)) => {
            config.render.noise = Noise::Rgb(noise);
            values.extend(noise_values);
        }
        None => unconstrained.push(
            "render.noise: one empty frame shows no noise; give several empty frames".to_string(),
        ),
    }
    let contacts = match &options.contacts {
        Some(path) if options.fit.imprint => {
            progress("fitting the imprint to the frames with contacts");
            let sensor = Sensor::from_config(options.start.name.clone(), config.clone())?;
            let fit = contacts::fit(&sensor, &frames, &circle, path)?;
            config = fit.config.clone();
            values.extend(fit.values.iter().cloned());
            Some(fit)
        }
        Some(_) => None,
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
        fit_cost,
        fit_iterations,
        leds,
        starts,
        contacts,
        at_bounds,
        fit: options.fit,
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
    reach: LensReach,
) -> Result<fit::EmptyFit> {
    let listed = listed_leds(lensed);
    let kind = options
        .led_kind
        .or(listed.map(|(kind, _)| kind))
        .unwrap_or(LedKindName::Point);
    let own = listed.filter(|&(k, _)| k == kind).map(|(_, n)| n);
    let counts: Vec<usize> = match (options.leds, own) {
        (0, Some(n)) => vec![n],
        (0, None) => AUTO_LEDS.collect(),
        (n, _) => vec![n],
    };
    let models: Vec<Model> = counts
        .iter()
        .map(|&leds| Model {
            start: lensed.clone(),
            leds,
            kind,
            camera: options.fit.camera,
            geometry: options.fit.geometry,
            principal: reach.principal_px,
            focal: reach.focal_low,
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
    // LEDs the start sensor lists start where it puts them; a ring is tried turned.
    let turns = if own.is_some_and(|n| counts == [n]) {
        1
    } else {
        options.starts.max(1)
    };
    let rotations: Vec<f64> = (0..turns)
        .map(|i| 360.0 * i as f64 / turns as f64)
        .collect();
    Ok(fit::fit_empty(&models, &coarse, &fine, &rotations, 200))
}

/// The LEDs' glow at the shell's end fitted alone over the `lensed` sensor's light
/// (`--fit glow`).
fn fit_glow(
    options: &Options,
    lensed: &Sensor,
    frames: &EmptyFrames,
    circle: &ImageCircle,
) -> Result<fit::EmptyFit> {
    let Some((kind, leds)) = listed_leds(lensed) else {
        return Err(GeltipError::option(
            "fit",
            "glow needs a start sensor that lists its LEDs ([[leds]], all of one kind)",
        ));
    };
    let model = Model {
        start: lensed.clone(),
        leds,
        kind,
        camera: false,
        geometry: false,
        principal: None,
        focal: None,
    };
    let fine = sample(lensed, frames, circle, options.samples);
    fit::fit_end_glow(&model, &fine, 200).ok_or_else(|| {
        GeltipError::option(
            "fit",
            "glow needs the start sensor's [shell_end] with led_glow_deg (how far round the end each LED's glow spreads)",
        )
    })
}

/// The kind and number of the LEDs the sensor file lists (`[[leds]]`, all of one kind), or
/// `None` for the ring or a mixed list.
fn listed_leds(sensor: &Sensor) -> Option<(LedKindName, usize)> {
    let crate::sensor::Leds::List(list) = &sensor.config.leds else {
        return None;
    };
    let kind = list.first()?.kind;
    list.iter()
        .all(|l| l.kind == kind)
        .then_some((kind, list.len()))
}

/// The fitted values that ended on their box's edge.
fn at_bounds(fitted: &fit::EmptyFit) -> Vec<AtBound> {
    let bounds = fitted.model.bounds();
    let fitted_here = |i: &usize| fitted.only.as_ref().is_none_or(|r| r.contains(i));
    fitted
        .model
        .names()
        .into_iter()
        .zip(&fitted.params)
        .zip(bounds)
        .enumerate()
        .filter(|(i, _)| fitted_here(i))
        .filter_map(|(_, ((name, &value), b))| {
            let tol = 1e-6 * (b.hi - b.lo).abs().max(1e-9);
            let side = if value <= b.lo + tol {
                "lower"
            } else if value >= b.hi - tol {
                "upper"
            } else {
                return None;
            };
            Some(AtBound { name, value, side })
        })
        .collect()
}

/// The start sensor's own lens, held: the frames must be its size.
fn held_lens(start: &Sensor, frames: &EmptyFrames) -> Result<Sensor> {
    let f = &frames.mean;
    if (f.width, f.height) != (start.width, start.height) {
        return Err(GeltipError::InvalidImage {
            path: f.path.clone(),
            reason: format!(
                "is {}x{} but the sensor's lens is held (--fit without lens) for {}x{} images",
                f.width, f.height, start.width, start.height
            ),
        });
    }
    Ok(start.clone())
}

/// The light's fitted values, named as the model names them, with their standard errors.
fn light_values(fitted: &fit::EmptyFit) -> Vec<Value> {
    let errors = fitted.fit.standard_errors();
    let range = fitted.only.clone().unwrap_or(0..fitted.params.len());
    fitted.model.names()[range.clone()]
        .iter()
        .cloned()
        .zip(&fitted.params[range])
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

/// How far from the image circle's centre the principal point may be fitted, as a fraction
/// of the circle's radius.
pub const PRINCIPAL_REACH: f64 = 0.1;

/// How far calibration may move the lens from where the image circle put it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LensReach {
    /// The principal point, px each way (`None`: held).
    pub principal_px: Option<f64>,
    /// The focal length's least fraction of the start's (`None`: held).
    pub focal_low: Option<f64>,
}

/// The start sensor with the frame's size and the lens the circle implies, the circle held
/// as the image's mask (`image.circle`). A start sensor without a mask takes the circle for
/// the lens's edge: the principal point at its centre, the focal length that puts the edge
/// of the field of view on it. One with a mask keeps its lens and its principal point's
/// offset from the mask's centre. Where `fit` frees the principal point or the focal length,
/// the field of view is widened so the lens covers the circle wherever they may go; how far
/// that is comes back.
pub fn with_lens(
    start: &Sensor,
    frames: &EmptyFrames,
    circle: &ImageCircle,
    fit: &FitSet,
) -> Result<(Sensor, LensReach)> {
    let mut c = start.config.clone();
    c.image.width = frames.mean.width;
    c.image.height = frames.mean.height;
    let offset = match start.config.image.circle {
        Some([mx, my, _]) => DVec2::new(c.lens.cx - mx, c.lens.cy - my),
        None => {
            // rho(theta_max) scales with the focal length for every model.
            let unit = start.lens.max_rho() / start.lens.focal_px;
            c.lens.focal_px = circle.radius / unit;
            DVec2::ZERO
        }
    };
    c.lens.cx = circle.centre.x + offset.x;
    c.lens.cy = circle.centre.y + offset.y;
    c.image.circle = Some([circle.centre.x, circle.centre.y, circle.radius]);
    let mut reach = LensReach::default();
    if fit.principal || fit.focal {
        let mut room = if fit.principal {
            PRINCIPAL_REACH * circle.radius
        } else {
            0.0
        };
        let shortest = if fit.focal {
            1.0 - model::FOCAL_REACH
        } else {
            1.0
        };
        let need = circle.radius + room + offset.length();
        // rho scales with the focal length for every model: a field of view that covers
        // the circle at the shortest focal length covers it at every longer one.
        if let Some(rho) = widen_fov(&mut c, need / shortest) {
            if fit.focal {
                reach.focal_low = Some((need / rho).max(shortest).min(1.0));
            } else {
                room = room.min(rho - circle.radius - offset.length());
            }
            if fit.principal && room >= 0.5 {
                reach.principal_px = Some(room);
            }
        }
    }
    let sensor =
        Sensor::from_config(start.name.clone(), c).map_err(|e| GeltipError::InvalidImage {
            path: frames.mean.path.clone(),
            reason: format!("the image circle gives a lens the sensor cannot have: {e}"),
        })?;
    Ok((sensor, reach))
}

/// Widens the lens's field of view (1 degree at a time) until it reaches `rho` px from the
/// principal point, as far as the lens model allows; the image radius it reaches, `None`
/// when no wider field of view is valid.
fn widen_fov(c: &mut SensorConfig, rho: f64) -> Option<f64> {
    let limit = if c.lens.model == crate::LensModel::Pinhole {
        179.0
    } else {
        359.0
    };
    let mut best = None;
    let mut fov = c.lens.fov_deg;
    while fov <= limit {
        let mut trial = c.clone();
        trial.lens.fov_deg = fov;
        if let Ok(sensor) = Sensor::from_config("", trial) {
            let reached = sensor.lens.max_rho();
            best = Some((fov, reached));
            if reached >= rho {
                break;
            }
        }
        fov = (fov.floor() + 1.0).min(limit + 1.0);
    }
    let (fov, reached) = best?;
    c.lens.fov_deg = fov;
    Some(reached)
}

/// The circle's values and the lens they set, each with the circle fit's uncertainty (the
/// lens's values the light fit does not fit).
fn lens_values(sensor: &Sensor, circle: &ImageCircle, reach: &LensReach) -> Vec<Value> {
    // A circle fitted to n points with rms scatter s: centre and radius to about s/sqrt(n/2).
    let e = circle.rms_px.max(0.29) / (circle.points as f64 / 2.0).sqrt();
    let unit = sensor.lens.max_rho() / sensor.lens.focal_px;
    let v = |name: &str, value: f64, std_error: f64| Value {
        name: name.to_string(),
        value,
        std_error,
    };
    let mut out = vec![
        v("image_circle.cx", circle.centre.x, e),
        v("image_circle.cy", circle.centre.y, e),
        v("image_circle.radius", circle.radius, e),
    ];
    if reach.principal_px.is_none() {
        out.push(v("lens.cx", sensor.config.lens.cx, e));
        out.push(v("lens.cy", sensor.config.lens.cy, e));
    }
    if reach.focal_low.is_none() {
        out.push(v("lens.focal_px", sensor.config.lens.focal_px, e / unit));
    }
    out
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
