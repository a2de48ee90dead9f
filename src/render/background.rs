//! A real sensor's empty frame under rendered images: a render's change from the rendered
//! empty finger, added to the real frame, so that a synthetic contact shows on that sensor's
//! own light, paint and blemishes (`geltip render --background`, `geltip dataset
//! --background`). One formula for both: [`compose`], of which [`composite`] is the plain
//! case.

use crate::error::{GeltipError, Result};
use crate::render::Frame;
use crate::sensor::Sensor;
use image::RgbImage;
use std::fs;
use std::path::Path;

/// 64-bit FNV-1a of `bytes` (identifies a background image in `dataset.json`).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A loaded background: an RGB frame of the sensor's size, and the hash of its file's bytes.
#[derive(Debug, Clone)]
pub struct Background {
    pub image: RgbImage,
    pub fnv1a64: u64,
}

/// Loads a background image: an image file (any format the image reader knows) of
/// `sensor`'s size, as RGB. An unreadable file, a file that is not an image and an image of
/// another size are refused on one line naming the file.
pub fn load_background(path: &Path, sensor: &Sensor) -> Result<Background> {
    let bytes = fs::read(path).map_err(|e| GeltipError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|e| GeltipError::InvalidImage {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    if (img.width(), img.height()) != (sensor.width, sensor.height) {
        return Err(GeltipError::InvalidImage {
            path: path.to_path_buf(),
            reason: format!(
                "is {}x{}, the sensor's images are {}x{}",
                img.width(),
                img.height(),
                sensor.width,
                sensor.height
            ),
        });
    }
    Ok(Background {
        image: img.to_rgb8(),
        fnv1a64: fnv1a64(&bytes),
    })
}

/// Backgrounds for a dataset: one image file, or every PNG and JPEG of a folder (sorted by
/// name; one is drawn per sample). Each has the sensor's size.
#[derive(Debug, Clone)]
pub struct Backgrounds {
    /// Each image's file name.
    pub names: Vec<String>,
    pub images: Vec<RgbImage>,
    /// The file's FNV-1a hash for one file; for a folder, the hash of each name and its
    /// file's hash in turn.
    pub fnv1a64: u64,
}

impl Backgrounds {
    /// Whether each sample draws its own (a folder of several).
    pub fn many(&self) -> bool {
        self.images.len() > 1
    }
}

/// The file-name extensions read as images from a folder of backgrounds.
pub const BACKGROUND_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// Loads `path`: an image file ([`load_background`]) or a folder of them. A folder without
/// images, two of its images whose names differ only by extension, and any image
/// [`load_background`] refuses are refused on one line naming the file.
pub fn load_backgrounds(path: &Path, sensor: &Sensor) -> Result<Backgrounds> {
    if !path.is_dir() {
        let one = load_background(path, sensor)?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        return Ok(Backgrounds {
            names: vec![name],
            images: vec![one.image],
            fnv1a64: one.fnv1a64,
        });
    }
    let mut names: Vec<String> = fs::read_dir(path)
        .map_err(|e| GeltipError::io(path, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            let ext = n.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
            ext.is_some_and(|e| BACKGROUND_EXTENSIONS.contains(&e.as_str()))
        })
        .collect();
    names.sort();
    if names.is_empty() {
        return Err(GeltipError::input(
            path.display().to_string(),
            "holds no PNG or JPEG images to use as backgrounds",
        ));
    }
    let mut stems = std::collections::BTreeSet::new();
    let mut images = Vec::with_capacity(names.len());
    let mut hash_bytes = Vec::new();
    for name in &names {
        if !stems.insert(background_stem(name)) {
            return Err(GeltipError::input(
                path.join(name).display().to_string(),
                "another background has the same name but for its extension",
            ));
        }
        let one = load_background(&path.join(name), sensor)?;
        hash_bytes.extend(name.as_bytes());
        hash_bytes.extend(one.fnv1a64.to_le_bytes());
        images.push(one.image);
    }
    Ok(Backgrounds {
        names,
        images,
        fnv1a64: fnv1a64(&hash_bytes),
    })
}

/// A background's name without its extension: what its reference in a dataset is named by.
pub fn background_stem(name: &str) -> &str {
    name.rsplit_once('.').map_or(name, |(stem, _)| stem)
}

/// `background` plus the change of `rendered` from `reference` (the empty finger as the same
/// renderer draws it, noise-free), each value rounded and clamped to 0..=255. Whatever the
/// renderer added to `rendered` beyond the contact (its sensor noise) is part of the change,
/// so a noisy sensor's empty frame gives the background plus that noise. Images of different
/// sizes are refused naming the background.
pub fn composite(background: &RgbImage, rendered: &Frame, reference: &Frame) -> Result<RgbImage> {
    let (w, h) = (rendered.width, rendered.height);
    if background.dimensions() != (w, h) || (reference.width, reference.height) != (w, h) {
        return Err(GeltipError::input(
            "background",
            format!(
                "is {}x{}, the rendered frame {}x{} and its reference {}x{}",
                background.width(),
                background.height(),
                w,
                h,
                reference.width,
                reference.height
            ),
        ));
    }
    let reference = reference.to_rgb().into_raw();
    let rgb = compose(
        background.as_raw(),
        rgb_values(rendered),
        &reference,
        1.0,
        [1.0; 3],
        None::<fn(usize) -> f64>,
    );
    Ok(RgbImage::from_raw(w, h, rgb).expect("one value per channel of each pixel"))
}

/// A frame's RGB values (its alpha dropped), in order.
pub fn rgb_values(frame: &Frame) -> impl Iterator<Item = u8> + '_ {
    frame
        .rgba
        .chunks_exact(4)
        .flat_map(|px| [px[0], px[1], px[2]])
}

/// The general composite (`geltip dataset`'s look): each RGB value
/// `(base + contrast * (rendered - reference)) * gains[channel] + noise(channel)`, rounded
/// and clamped to 0..=255. `base` and `reference` hold one value per value of `rendered`
/// (extra ones are ignored); `noise` draws one value per output value, in order.
pub fn compose<N: FnMut(usize) -> f64>(
    base: &[u8],
    rendered: impl Iterator<Item = u8>,
    reference: &[u8],
    contrast: f64,
    gains: [f64; 3],
    noise: Option<N>,
) -> Vec<u8> {
    compose_drifted(base, rendered, reference, contrast, gains, noise, None)
}

/// [`compose`] with the light drifted before the noise: value `i` (pixel `i / 3`, channel
/// `i % 3`) becomes `v * gain + offset` for `drift(i) = [gain, offset]`.
pub fn compose_drifted<N: FnMut(usize) -> f64>(
    base: &[u8],
    rendered: impl Iterator<Item = u8>,
    reference: &[u8],
    contrast: f64,
    gains: [f64; 3],
    mut noise: Option<N>,
    drift: Option<&dyn Fn(usize) -> [f64; 2]>,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(base.len());
    for ((value, &base), &reference) in rendered.zip(base).zip(reference) {
        let c = out.len() % 3;
        let change = value as f64 - reference as f64;
        let mut v = (base as f64 + contrast * change) * gains[c];
        if let Some(drift) = drift {
            let [gain, offset] = drift(out.len());
            v = v * gain + offset;
        }
        if let Some(noise) = noise.as_mut() {
            v += noise(c);
        }
        out.push(v.round().clamp(0.0, 255.0) as u8);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(rgb: &[[u8; 3]]) -> Frame {
        Frame {
            width: rgb.len() as u32,
            height: 1,
            rgba: rgb.iter().flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
            indentation: vec![0.0; rgb.len()],
        }
    }

    #[test]
    fn the_change_lands_on_the_background_clamped() {
        let reference = frame(&[[100, 100, 100], [10, 20, 30]]);
        let rendered = frame(&[[120, 90, 100], [0, 250, 30]]);
        let background = RgbImage::from_raw(2, 1, vec![50, 60, 70, 5, 200, 255]).unwrap();
        let out = composite(&background, &rendered, &reference).unwrap();
        assert_eq!(out.as_raw(), &[70, 50, 70, 0, 255, 255]);
    }

    #[test]
    fn the_reference_itself_gives_the_background() {
        let reference = frame(&[[100, 0, 255], [7, 8, 9]]);
        let background = RgbImage::from_raw(2, 1, vec![1, 2, 3, 4, 5, 6]).unwrap();
        let out = composite(&background, &reference, &reference).unwrap();
        assert_eq!(out, background);
    }

    #[test]
    fn sizes_that_differ_are_refused_naming_the_background() {
        let reference = frame(&[[0; 3], [0; 3]]);
        let background = RgbImage::new(3, 1);
        let e = composite(&background, &reference, &reference).unwrap_err();
        assert_eq!(
            e.to_string(),
            "background: is 3x1, the rendered frame 2x1 and its reference 2x1"
        );
    }

    #[test]
    fn contrast_gains_and_noise_apply_per_channel() {
        let noise = |c: usize| [0.25, -0.25, 1.0][c];
        let out = compose(
            &[10, 10, 10],
            [20u8, 20, 20].into_iter(),
            &[10, 10, 10],
            0.5,
            [1.0, 2.0, 0.5],
            Some(noise),
        );
        // (10 + 0.5 * 10) * gain + noise: 15.25, 29.75, 8.5.
        assert_eq!(out, vec![15, 30, 9]);
    }
}
