//! A set's empty frame (`reference.png`): the empty finger with the set's look (background,
//! sensor noise; no per-sample jitter), what detectors subtract from the set's images.

use super::encode::{reference_file, rgb_of};
use super::look::Look;
use super::spec::Spec;
use super::store::MANIFEST;
use crate::error::{GeltipError, Result};
use crate::output;
use crate::render::background::{load_backgrounds, Backgrounds};
use crate::render::gpu::Renderer;
use crate::sensor::{Noise, Sensor};
use image::RgbImage;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The empty frame's file in a set.
pub const REFERENCE: &str = "reference.png";

/// The set's empty frames, from the rendered empty finger (noise-free) `rendered`: one per
/// background (the first is `reference.png`), or the finger's own.
pub(super) fn reference_images(
    spec: &Spec,
    rendered: &crate::render::Frame,
    backgrounds: Vec<Vec<u8>>,
) -> Vec<RgbImage> {
    let count = backgrounds.len().max(1);
    match Look::new(spec, rendered, backgrounds) {
        Some(look) => (0..count)
            .map(|base| {
                let rgb = look.reference(spec.seed, base);
                RgbImage::from_raw(rendered.width, rendered.height, rgb)
                    .unwrap_or_else(|| rendered.to_rgb())
            })
            .collect(),
        None => vec![rendered.to_rgb()],
    }
}

/// Writes the set's empty frames into `dir` where missing: `reference.png` and, when each
/// sample draws one of several backgrounds, `references/<stem>.png` for each.
pub(super) fn write_references(
    spec: &Spec,
    dir: &Path,
    rendered: &crate::render::Frame,
    backgrounds: Option<&Backgrounds>,
) -> Result<()> {
    let mut wanted = vec![dir.join(REFERENCE)];
    if let Some(b) = backgrounds.filter(|b| b.many()) {
        wanted.extend(b.names.iter().map(|n| dir.join(reference_file(n))));
    }
    if wanted.iter().all(|p| p.is_file()) {
        return Ok(());
    }
    let images = reference_images(spec, rendered, rgb_of(backgrounds));
    if wanted.len() > 1 {
        let folder = dir.join("references");
        std::fs::create_dir_all(&folder).map_err(|e| GeltipError::io(&folder, e))?;
    }
    for (k, path) in wanted.iter().enumerate() {
        // reference.png is the first background's.
        let img = &images[k.saturating_sub(1)];
        if !path.is_file() {
            output::write_png_rgb8(path, img.width(), img.height(), img.as_raw())?;
        }
    }
    Ok(())
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
    spec.drift = number("drift");
    spec.background = o["background"]["path"].as_str().map(PathBuf::from);
    let backgrounds = spec
        .background
        .as_ref()
        .map(|p| load_backgrounds(p, &sensor))
        .transpose()?;
    let mut renderer = Renderer::new(&sensor)?;
    let rendered = renderer.render_empty()?;
    let first: Vec<Vec<u8>> = rgb_of(backgrounds.as_ref()).into_iter().take(1).collect();
    Ok(reference_images(&spec, &rendered, first).remove(0))
}
