//! Contact localisers: find contacts in tactile images and map them onto the finger.
//!
//! Every detector takes the sensor, a reference frame (no contact) and a frame, all RGB
//! 8-bit images of the sensor's size, and returns a [`Detection`]: whether a contact was
//! found, its pixel, its point on the (undeformed) finger surface and a confidence.
//!
//! - [`Method::Paper`] ([`paper`]): the IROS 2020 paper's detector, step by step.
//! - [`Method::Surface`] ([`surface`]): a noise-relative, multi-scale threshold, and the
//!   contact placed at the middle of the imprint's outline measured on the finger surface
//!   instead of in the image.
//!
//! [`localise`] is the one-call entry point; a [`Localiser`] keeps the per-pixel surface
//! table that [`Method::Surface`] needs, for localising many frames of one sensor.

pub mod change;
pub mod options;
pub mod paper;
pub mod raster;
pub mod surface;

pub use options::{AreaWindow, DetectorOptions};

use crate::error::{GeltipError, Result};
use crate::finger::Region;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use image::RgbImage;
use serde_json::{json, Value};
use std::path::Path;
use std::sync::OnceLock;

/// The outcome of localising one frame. Never holds NaN: when a detector cannot place a
/// contact it says so with `detected: false` and a `note`.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    pub detected: bool,
    /// The contact's pixel (OpenCV convention).
    pub pixel: Option<DVec2>,
    /// The contact's point on the undeformed finger surface (mm).
    pub point: Option<DVec3>,
    /// The part of the finger the point lies on.
    pub region: Option<Region>,
    /// 0 (barely there) .. 1 (unmistakable); 0 when nothing was detected.
    pub confidence: f64,
    /// How many candidate regions (blobs) the detector found before choosing.
    pub regions_found: usize,
    /// Why nothing was detected, or anything else the caller should know.
    pub note: Option<String>,
}

impl Detection {
    /// Nothing detected, with the reason.
    pub fn none(regions_found: usize, note: impl Into<String>) -> Self {
        Detection {
            detected: false,
            pixel: None,
            point: None,
            region: None,
            confidence: 0.0,
            regions_found,
            note: Some(note.into()),
        }
    }

    /// A contact at `pixel`, mapped onto the finger by the sensor's map m; not detected
    /// (with a note) when the pixel is not finite or sees no part of the finger.
    pub fn at_pixel(sensor: &Sensor, pixel: DVec2, confidence: f64, regions_found: usize) -> Self {
        if !pixel.is_finite() {
            return Detection::none(regions_found, "the contact's pixel is not a finite number");
        }
        match sensor.unproject(pixel).filter(|sp| sp.point.is_finite()) {
            Some(sp) => Detection {
                detected: true,
                pixel: Some(pixel),
                point: Some(sp.point),
                region: Some(sp.region),
                confidence: finite_unit(confidence),
                regions_found,
                note: None,
            },
            None => Detection::none(
                regions_found,
                format!(
                    "the contact's pixel ({:.2}, {:.2}) sees no part of the finger",
                    pixel.x, pixel.y
                ),
            ),
        }
    }

    /// `{"detected", "pixel": [u, v] | null, "point": [x, y, z] | null, "region":
    /// "hemisphere" | "cylinder" | null, "confidence", "regions_found", "note": text | null}`.
    pub fn to_json(&self) -> Value {
        json!({
            "detected": self.detected,
            "pixel": self.pixel.filter(|p| p.is_finite()).map(|p| [p.x, p.y]),
            "point": self.point.filter(|p| p.is_finite()).map(|p| [p.x, p.y, p.z]),
            "region": self.region.map(Region::name),
            "confidence": finite_unit(self.confidence),
            "regions_found": self.regions_found,
            "note": self.note,
        })
    }
}

/// Clamps to 0..1, NaN to 0.
fn finite_unit(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0)
    }
}

/// Noise levels (grey levels) are never taken below this, so that noise-free images (a
/// renderer without sensor noise) do not make every rounding step look significant.
pub const NOISE_FLOOR: f64 = 0.25;

/// Signal-to-noise ratio at which a detector's confidence is 0.
pub const CONFIDENCE_SNR: f64 = 6.0;

/// Confidence from a signal-to-noise ratio: `1 - 6 / snr`, clamped to 0..1 (0 at 6 noise
/// deviations, 0.5 at 12, 0.9 at 60).
pub fn snr_confidence(snr: f64) -> f64 {
    finite_unit(1.0 - CONFIDENCE_SNR / snr)
}

/// The detectors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// The paper's detector ([`paper`]).
    Paper,
    /// Noise-relative threshold and surface averaging ([`surface`]).
    Surface,
    /// A change model that absorbs the LEDs' drift, sub-pixel shifts and clipped channels,
    /// for real sensors' frames ([`change`]).
    Change,
}

impl Method {
    /// The methods the paper's experiment and the stability sweep compare, in the order
    /// reports list them.
    pub const ALL: [Method; 2] = [Method::Paper, Method::Surface];
    /// Every method a name selects.
    pub const NAMED: [Method; 3] = [Method::Paper, Method::Surface, Method::Change];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::Paper => "paper",
            Method::Surface => "surface",
            Method::Change => "change",
        }
    }

    /// The method with this name.
    pub fn from_name(name: &str) -> Result<Self> {
        Method::NAMED
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Method::NAMED.iter().map(|m| m.name()).collect();
                GeltipError::input(
                    "method",
                    format!("unknown '{name}', expected one of {}", names.join(", ")),
                )
            })
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Checks that `reference` and `frame` have the same size, and the sensor's if given.
pub fn check_sizes(reference: &RgbImage, frame: &RgbImage, sensor: Option<&Sensor>) -> Result<()> {
    let size = |i: &RgbImage| format!("{}x{}", i.width(), i.height());
    if reference.dimensions() != frame.dimensions() {
        return Err(GeltipError::input(
            "frame",
            format!(
                "is {} but the reference is {}; both must have the same size",
                size(frame),
                size(reference)
            ),
        ));
    }
    if let Some(s) = sensor {
        if frame.dimensions() != (s.width, s.height) {
            return Err(GeltipError::input(
                "frame",
                format!(
                    "images are {} but sensor '{}' makes {}x{} images",
                    size(frame),
                    s.name,
                    s.width,
                    s.height
                ),
            ));
        }
    }
    Ok(())
}

/// Reads an image file (PNG or JPEG) as 8-bit RGB; other pixel formats are converted (alpha dropped,
/// 16-bit scaled). An unreadable file is an `InvalidImage` error.
pub fn load_image(path: impl AsRef<Path>) -> Result<RgbImage> {
    let path = path.as_ref();
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| invalid_image(path, e.to_string()))?
        .decode()
        .map_err(|e| invalid_image(path, e.to_string()))?;
    Ok(img.to_rgb8())
}

/// [`load_image`], also requiring the sensor's image size.
pub fn load_frame(sensor: &Sensor, path: impl AsRef<Path>) -> Result<RgbImage> {
    let path = path.as_ref();
    let img = load_image(path)?;
    if img.dimensions() != (sensor.width, sensor.height) {
        return Err(invalid_image(
            path,
            format!(
                "is {}x{} but sensor '{}' makes {}x{} images",
                img.width(),
                img.height(),
                sensor.name,
                sensor.width,
                sensor.height
            ),
        ));
    }
    Ok(img)
}

fn invalid_image(path: &Path, reason: String) -> GeltipError {
    GeltipError::InvalidImage {
        path: path.to_path_buf(),
        reason: reason.split_whitespace().collect::<Vec<_>>().join(" "),
    }
}

/// Localises frames of one sensor, building the per-pixel surface table of
/// [`Method::Surface`] once, on first use.
#[derive(Debug)]
pub struct Localiser {
    pub sensor: Sensor,
    pub surface: surface::SurfaceConfig,
    cache: OnceLock<surface::SurfaceCache>,
}

impl Localiser {
    /// A localiser with the default settings.
    pub fn new(sensor: &Sensor) -> Self {
        Localiser::with_config(sensor, surface::SurfaceConfig::default())
    }

    /// A localiser with the given settings for [`Method::Surface`].
    pub fn with_config(sensor: &Sensor, surface: surface::SurfaceConfig) -> Self {
        Localiser {
            sensor: sensor.clone(),
            surface,
            cache: OnceLock::new(),
        }
    }

    /// The per-pixel surface table (built on first call).
    pub fn cache(&self) -> &surface::SurfaceCache {
        self.cache
            .get_or_init(|| surface::SurfaceCache::new(&self.sensor))
    }

    /// Finds the contact in `frame`. Errors if the images differ in size from each other or
    /// from the sensor's images.
    pub fn localise(
        &self,
        reference: &RgbImage,
        frame: &RgbImage,
        method: Method,
    ) -> Result<Detection> {
        check_sizes(reference, frame, Some(&self.sensor))?;
        match method {
            Method::Paper => paper::detect(&self.sensor, reference, frame),
            Method::Surface => {
                surface::detect(&self.sensor, self.cache(), &self.surface, reference, frame)
            }
            Method::Change => self.localise_change(reference, frame, &Default::default()),
        }
    }

    /// [`Localiser::localise`] with `options` (the change method's decision threshold in
    /// noise spreads and the sensor's noise in levels, each finite and > 0; the contact's
    /// area on the finger for the change and paper methods); an option the method does not
    /// take is an error.
    pub fn localise_with(
        &self,
        reference: &RgbImage,
        frame: &RgbImage,
        method: Method,
        options: &DetectorOptions,
    ) -> Result<Detection> {
        options.check(method)?;
        match (method, options.area_mm2) {
            (Method::Change, _) if options.any() => {
                self.localise_change(reference, frame, &options.change_config()?)
            }
            (Method::Paper, Some(window)) => {
                check_sizes(reference, frame, Some(&self.sensor))?;
                let limit = paper::AreaLimit::Finger {
                    areas: &self.cache().areas,
                    window,
                };
                paper::detect_with(&self.sensor, reference, frame, limit)
            }
            _ => self.localise(reference, frame, method),
        }
    }

    /// [`Method::Change`] inside the lens's image circle, with `config`'s constants (its
    /// decision threshold, say). Errors as [`Localiser::localise`].
    pub fn localise_change(
        &self,
        reference: &RgbImage,
        frame: &RgbImage,
        config: &change::ChangeConfig,
    ) -> Result<Detection> {
        check_sizes(reference, frame, Some(&self.sensor))?;
        let s = &self.sensor;
        let (centre, radius) = s.image_circle();
        let found = change::detect(
            reference,
            frame,
            centre,
            radius,
            &self.cache().areas,
            config,
        );
        // Placed on the surface as the surface method places its own contacts (a weighted
        // centroid in the image is pulled by shading and the lens's compression), or where
        // the surface method itself puts it when the two agree.
        let on_surface = found
            .detected
            .then(|| surface::region_middle(s, self.cache(), &found.region))
            .flatten();
        if let Some(sp) = on_surface {
            let fine = surface::detect(s, self.cache(), &self.surface, reference, frame)?;
            let near = |p: DVec3| (p - sp.point).length() <= config.agree_mm;
            let agreed = fine.detected && fine.point.is_some_and(near);
            let point = if agreed { fine.point } else { Some(sp.point) };
            let region = if agreed { fine.region } else { Some(sp.region) };
            return Ok(Detection {
                detected: true,
                pixel: point.and_then(|p| s.project(p).ok()),
                point,
                region,
                confidence: finite_unit(found.confidence),
                regions_found: found.regions,
                note: None,
            });
        }
        Ok(match found.pixel.filter(|_| found.detected) {
            Some(pixel) => Detection::at_pixel(s, pixel, found.confidence, found.regions),
            None => Detection::none(
                found.regions,
                format!(
                    "no change stands out: the strongest scores {:.1} noise spreads, a contact needs {}",
                    found.score, config.score_threshold
                ),
            ),
        })
    }
}

/// Finds the contact in `frame` with `method`. Errors if the images differ in size from each
/// other or from the sensor's images. [`Method::Surface`] builds its per-pixel table on
/// every call: use a [`Localiser`] for many frames.
pub fn localise(
    sensor: &Sensor,
    reference: &RgbImage,
    frame: &RgbImage,
    method: Method,
) -> Result<Detection> {
    check_sizes(reference, frame, Some(sensor))?;
    Localiser::new(sensor).localise(reference, frame, method)
}
