//! A real sensor's empty frames: loaded, checked, averaged, and their noise measured.

use crate::error::{GeltipError, Result};
use std::path::{Path, PathBuf};

/// An empty frame (the mean of several, when several were given), 8-bit levels as f64.
#[derive(Debug, Clone, PartialEq)]
pub struct EmptyFrame {
    /// The first frame's path, for messages.
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// RGB by pixel, row by row.
    pub pixels: Vec<[f64; 3]>,
}

/// A level this close to 255 counts as saturated: the camera clipped it.
pub const SATURATED: f64 = 254.5;

/// Loads an RGB frame (PNG, or any format the `image` crate reads).
pub fn load_rgb(path: &Path) -> Result<image::RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| GeltipError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|e| GeltipError::InvalidImage {
        path: path.to_path_buf(),
        reason: format!("not an image: {e}"),
    })?;
    Ok(img.to_rgb8())
}

/// Empty frames loaded together: their mean and, from two or more, the noise.
#[derive(Debug, Clone)]
pub struct EmptyFrames {
    pub mean: EmptyFrame,
    /// How many frames were averaged.
    pub count: usize,
    frames: Vec<image::RgbImage>,
}

impl EmptyFrames {
    /// Loads `paths` (at least one); every frame must have the first one's size and show
    /// something (an all-black frame is refused).
    pub fn load(paths: &[PathBuf]) -> Result<EmptyFrames> {
        let first = paths
            .first()
            .ok_or_else(|| GeltipError::input("empty frames", "at least one is needed"))?;
        let mut frames = Vec::with_capacity(paths.len());
        for path in paths {
            let img = load_rgb(path)?;
            if let Some(f) = frames.first() {
                let f: &image::RgbImage = f;
                if img.dimensions() != f.dimensions() {
                    return Err(GeltipError::InvalidImage {
                        path: path.clone(),
                        reason: format!(
                            "is {}x{} but {} is {}x{}: empty frames come from one camera",
                            img.width(),
                            img.height(),
                            first.display(),
                            f.width(),
                            f.height()
                        ),
                    });
                }
            }
            let brightest = img.pixels().flat_map(|p| p.0).max().unwrap_or(0);
            if brightest < 16 {
                return Err(GeltipError::InvalidImage {
                    path: path.clone(),
                    reason: format!(
                        "is black (no level above {brightest}): the LEDs were off or the lens covered"
                    ),
                });
            }
            frames.push(img);
        }
        let (w, h) = frames[0].dimensions();
        let n = frames.len() as f64;
        let pixels = (0..(w * h) as usize)
            .map(|i| {
                std::array::from_fn(|c| {
                    frames
                        .iter()
                        .map(|f| f.as_raw()[i * 3 + c] as f64)
                        .sum::<f64>()
                        / n
                })
            })
            .collect();
        Ok(EmptyFrames {
            mean: EmptyFrame {
                path: first.clone(),
                width: w,
                height: h,
                pixels,
            },
            count: frames.len(),
            frames,
        })
    }

    /// The noise's standard deviation in each channel (8-bit levels), from the spread of the
    /// frames about their mean over the pixels `inside` selects (saturated or black values
    /// left out: clipping hides the noise there). `None` from a single frame.
    pub fn noise(&self, inside: impl Fn(u32, u32) -> bool) -> Option<[f64; 3]> {
        if self.frames.len() < 2 {
            return None;
        }
        let (w, h) = (self.mean.width, self.mean.height);
        let mut sum = [0.0f64; 3];
        let mut count = [0usize; 3];
        for y in 0..h {
            for x in 0..w {
                if !inside(x, y) {
                    continue;
                }
                let i = (y * w + x) as usize;
                for c in 0..3 {
                    let values: Vec<f64> = self
                        .frames
                        .iter()
                        .map(|f| f.as_raw()[i * 3 + c] as f64)
                        .collect();
                    if values.iter().any(|&v| v >= SATURATED || v <= 0.5) {
                        continue;
                    }
                    let m = self.mean.pixels[i][c];
                    sum[c] += values.iter().map(|v| (v - m).powi(2)).sum::<f64>();
                    count[c] += values.len() - 1;
                }
            }
        }
        // The 8-bit rounding of each frame adds 1/12 level^2 of variance of its own.
        Some(std::array::from_fn(|c| {
            if count[c] == 0 {
                0.0
            } else {
                (sum[c] / count[c] as f64 - 1.0 / 12.0).max(0.0).sqrt()
            }
        }))
    }
}
