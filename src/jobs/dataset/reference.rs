//! A set's empty frame (`reference.png`): the empty finger with the set's look (background,
//! sensor noise; no per-sample jitter), what detectors subtract from the set's images.

use super::look::Look;
use super::spec::Spec;
use super::store::MANIFEST;
use crate::error::{GeltipError, Result};
use crate::render::background::load_background;
use crate::render::gpu::Renderer;
use crate::sensor::{Noise, Sensor};
use image::RgbImage;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The empty frame's file in a set.
pub const REFERENCE: &str = "reference.png";

/// The set's empty frame, from the rendered empty finger (noise-free) `rendered`.
pub(super) fn reference_image(
    spec: &Spec,
    rendered: &crate::render::Frame,
    background: Option<Vec<u8>>,
) -> RgbImage {
    match Look::new(spec, rendered, background) {
        Some(look) => {
            let rgb = look.reference(spec.seed);
            RgbImage::from_raw(rendered.width, rendered.height, rgb)
                .unwrap_or_else(|| rendered.to_rgb())
        }
        None => rendered.to_rgb(),
    }
}

/// The empty frame of the set in `dir`, rendered from its `dataset.json`: for a set that
/// holds no `reference.png` (one made by an older geltip, or whose file was removed), the
/// manifest alone says how its empty frame looks.
pub fn reference_of_set(dir: &Path) -> Result<RgbImage> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| GeltipError::io(&path, e))?;
    let what = path.display().to_string();
    let manifest: Value = serde_json::from_str(&text)
        .map_err(|e| GeltipError::input(&what, format!("not valid JSON: {e}")))?;
    let o = &manifest["options"];
    let config = serde_json::from_value(o["sensor_config"].clone())
        .map_err(|e| GeltipError::input(&what, format!("options.sensor_config: {e}")))?;
    let name = o["sensor"].as_str().unwrap_or("dataset sensor");
    let mut sensor_config: crate::sensor::SensorConfig = config;
    sensor_config.render.noise = Noise::NONE;
    let sensor = Sensor::from_config(name, sensor_config)?;
    let number = |key: &str| o[key].as_f64().unwrap_or(0.0);
    let mut spec = Spec::new(name, sensor.clone(), 1, o["seed"].as_u64().unwrap_or(0));
    spec.noise = serde_json::from_value(o["noise"].clone()).unwrap_or(Noise::NONE);
    spec.light_jitter = number("light_jitter");
    spec.paint_jitter = number("paint_jitter");
    spec.background = o["background"]["path"].as_str().map(PathBuf::from);
    let background = spec
        .background
        .as_ref()
        .map(|p| load_background(p, &sensor).map(|b| b.image.into_raw()))
        .transpose()?;
    let mut renderer = Renderer::new(&sensor)?;
    let rendered = renderer.render_empty()?;
    Ok(reference_image(&spec, &rendered, background))
}
