//! The imprint's values from frames with known contacts (an object pressed at a known place
//! and depth, as Taxim calibrates from a ball): the elastomer's blend, drape and bulge and
//! the paint's specular, fitted so that each rendered contact changes the empty picture as
//! the real one changed the real empty frame.
//!
//! A contacts file holds one JSON object a line: `"image"` (a frame's path, relative to the
//! file) and the contact as a scene file gives it (`object`, `at`, `depth`, ... or `pose`).

use super::circle::ImageCircle;
use super::frames::{load_rgb, EmptyFrames};
use super::solve::{levenberg_marquardt, Bound};
use super::Value;
use crate::error::{GeltipError, Result};
use crate::object::ObjectCache;
use crate::render::gpu::Renderer;
use crate::scene::{ContactSpec, Press};
use crate::sensor::{Sensor, SensorConfig};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// One frame with a known contact.
#[derive(Debug, Clone)]
pub struct KnownContact {
    pub image: PathBuf,
    pub spec: ContactSpec,
}

/// Reads a contacts file; each line's error names the file and the line.
pub fn read(path: &Path) -> Result<Vec<KnownContact>> {
    let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let what = format!("{} line {}", path.display(), i + 1);
        let bad = |reason: String| GeltipError::input(&what, reason);
        let mut value: serde_json::Value =
            serde_json::from_str(line).map_err(|e| bad(format!("not valid JSON: {e}")))?;
        let object = value
            .as_object_mut()
            .ok_or_else(|| bad("expected a JSON object".into()))?;
        let image = match object.remove("image") {
            Some(serde_json::Value::String(s)) => dir.join(s),
            Some(_) => return Err(bad("image: expected a path".into())),
            None => return Err(bad("image: required: the frame's path".into())),
        };
        let spec: ContactSpec = serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
        spec.hold().map_err(|e| bad(e.to_string()))?;
        if !image.is_file() {
            return Err(bad(format!("image: no such file {}", image.display())));
        }
        out.push(KnownContact { image, spec });
    }
    if out.is_empty() {
        return Err(GeltipError::input(
            path.display().to_string(),
            "holds no contacts",
        ));
    }
    Ok(out)
}

/// What the contact frames gave.
#[derive(Debug, Clone)]
pub struct ContactFit {
    /// The sensor's configuration with the fitted values.
    pub config: SensorConfig,
    pub values: Vec<Value>,
    pub frames: usize,
    /// RMS (8-bit levels) of rendered change minus real change over the compared pixels,
    /// with the start values and the fitted ones.
    pub rms_before: f64,
    pub rms_after: f64,
    pub renders: usize,
}

/// The fitted values: name, box and finite-difference step (large enough to move whole
/// levels of an 8-bit picture).
const FITTED: [(&str, f64, f64, f64); 4] = [
    ("elastomer.blend_mm", 0.05, 3.0, 0.05),
    ("elastomer.drape_mm", 0.0, 20.0, 0.1),
    ("elastomer.bulge", 0.0, 1.0, 0.05),
    ("paint.specular", 0.0, 20.0, 0.02),
];

fn get(c: &SensorConfig) -> [f64; 4] {
    [
        c.elastomer.blend_mm,
        c.elastomer.drape_mm,
        c.elastomer.bulge,
        c.paint.specular,
    ]
}

fn set(c: &mut SensorConfig, p: &[f64]) {
    c.elastomer.blend_mm = p[0];
    c.elastomer.drape_mm = p[1].max(c.finger.shell_thickness_mm);
    c.elastomer.bulge = p[2];
    c.paint.specular = p[3];
}

/// Fits the imprint values of `sensor` (already calibrated to the empty frames) to the
/// frames the contacts file at `path` lists.
pub fn fit(
    sensor: &Sensor,
    empty: &EmptyFrames,
    circle: &ImageCircle,
    path: &Path,
) -> Result<ContactFit> {
    let (presses, changes) = known_frames(sensor, empty, path)?;
    let (w, h) = (empty.mean.width, empty.mean.height);
    let inside: Vec<usize> = (0..(w * h) as usize)
        .filter(|&i| circle.contains(i as u32 % w, i as u32 / w, 3.0))
        .collect();
    let renders = Mutex::new(0usize);
    let first_error: Mutex<Option<GeltipError>> = Mutex::new(None);
    let residuals = |p: &[f64]| -> Vec<f64> {
        let mut c = sensor.config.clone();
        set(&mut c, p);
        match rendered_changes(&sensor.name, c, &presses) {
            Ok(rendered) => {
                *renders.lock().unwrap() += 1;
                rendered
                    .iter()
                    .zip(&changes)
                    .flat_map(|(r, real)| {
                        inside.iter().flat_map(move |&i| {
                            (0..3).map(move |ch| r[i * 3 + ch] - real[i * 3 + ch])
                        })
                    })
                    .collect()
            }
            Err(e) => {
                first_error.lock().unwrap().get_or_insert(e);
                vec![f64::INFINITY; inside.len() * 3 * presses.len()]
            }
        }
    };
    let start = get(&sensor.config);
    let before = residuals(&start);
    if let Some(e) = first_error.lock().unwrap().take() {
        return Err(e);
    }
    let bounds: Vec<Bound> = FITTED
        .iter()
        .map(|&(_, lo, hi, step)| Bound { lo, hi, step })
        .collect();
    let fit = levenberg_marquardt(&start, &bounds, 30, residuals);
    if let Some(e) = first_error.lock().unwrap().take() {
        return Err(e);
    }
    let errors = fit.standard_errors();
    let mut config = sensor.config.clone();
    set(&mut config, &fit.params);
    let rms = |r: &[f64]| (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
    Ok(ContactFit {
        config,
        values: FITTED
            .iter()
            .zip(&fit.params)
            .zip(errors)
            .map(|((f, v), e)| Value {
                name: f.0.to_string(),
                value: *v,
                std_error: e,
            })
            .collect(),
        frames: presses.len(),
        rms_before: rms(&before),
        rms_after: (2.0 * fit.cost / fit.residuals as f64).sqrt(),
        renders: renders.into_inner().unwrap(),
    })
}

/// Each known frame's press and its change from the empty frames' mean (RGB, 8-bit levels).
type KnownFrames = (Vec<Press>, Vec<Vec<f64>>);

/// Reads the frames the contacts file at `path` lists: each press, checked on `sensor`'s
/// finger, and each frame's change from `empty`'s mean.
fn known_frames(sensor: &Sensor, empty: &EmptyFrames, path: &Path) -> Result<KnownFrames> {
    let known = read(path)?;
    let (w, h) = (empty.mean.width, empty.mean.height);
    let mut objects = ObjectCache::default();
    let mut presses: Vec<Press> = Vec::with_capacity(known.len());
    let mut changes: Vec<Vec<f64>> = Vec::with_capacity(known.len());
    for (i, k) in known.iter().enumerate() {
        let img = load_rgb(&k.image)?;
        if img.dimensions() != (w, h) {
            return Err(GeltipError::InvalidImage {
                path: k.image.clone(),
                reason: format!(
                    "is {}x{} but the empty frames are {w}x{h}",
                    img.width(),
                    img.height()
                ),
            });
        }
        let press = k.spec.press(&mut objects).map_err(|e| {
            GeltipError::input(format!("{} line {}", path.display(), i + 1), e.to_string())
        })?;
        press.pose(sensor).map_err(|e| {
            GeltipError::input(
                format!("{} contact {}", path.display(), i + 1),
                e.to_string(),
            )
        })?;
        presses.push(press);
        changes.push(
            img.as_raw()
                .iter()
                .zip(empty.mean.pixels.iter().flatten())
                .map(|(&v, &e)| v as f64 - e)
                .collect(),
        );
    }
    Ok((presses, changes))
}

/// Each press rendered with `config`, less the rendered empty finger (RGB, 8-bit levels).
fn rendered_changes(name: &str, config: SensorConfig, presses: &[Press]) -> Result<Vec<Vec<f64>>> {
    let sensor = Sensor::from_config(name, config)?;
    let mut renderer = Renderer::new(&sensor)?;
    let reference = renderer.reference().to_rgb().into_raw();
    presses
        .iter()
        .map(|p| {
            let (frame, _) = renderer.render(p)?;
            Ok(frame
                .to_rgb()
                .into_raw()
                .iter()
                .zip(&reference)
                .map(|(&a, &b)| a as f64 - b as f64)
                .collect())
        })
        .collect()
}
