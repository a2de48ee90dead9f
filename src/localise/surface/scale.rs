//! The signed difference at one smoothing scale: its magnitude per pixel, its noise and its
//! peak, over the whole frame or, for a noise-free frame, over the difference's footprint.

use super::{SurfaceCache, SurfaceConfig};
use crate::localise::paper::mean_filter;
use crate::localise::raster::{robust_sigma, FloatImage};
use crate::localise::NOISE_FLOOR;
use image::RgbImage;

/// A rectangle of pixels, `[x0, x1) x [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Window {
    pub(super) x0: usize,
    pub(super) y0: usize,
    pub(super) x1: usize,
    pub(super) y1: usize,
}

impl Window {
    pub(super) fn width(&self) -> usize {
        self.x1 - self.x0
    }

    pub(super) fn height(&self) -> usize {
        self.y1 - self.y0
    }

    /// Grown by `by` pixels on every side, clipped to a `w` x `h` image.
    pub(super) fn grown(&self, by: usize, w: usize, h: usize) -> Window {
        Window {
            x0: self.x0.saturating_sub(by),
            y0: self.y0.saturating_sub(by),
            x1: (self.x1 + by).min(w),
            y1: (self.y1 + by).min(h),
        }
    }

    /// The image index of the `i`-th pixel of the window (row-major in the window).
    pub(super) fn image_index(&self, i: usize, image_width: usize) -> usize {
        (self.y0 + i / self.width()) * image_width + self.x0 + i % self.width()
    }
}

/// The bounding box of the pixels where `frame` differs from `reference` (RGB8, `w` wide),
/// or `None` when they are identical.
pub(super) fn difference_box(reference: &[u8], frame: &[u8], w: usize) -> Option<Window> {
    let row_bytes = 3 * w;
    let mut bbox: Option<Window> = None;
    for (y, (a, b)) in reference
        .chunks_exact(row_bytes)
        .zip(frame.chunks_exact(row_bytes))
        .enumerate()
    {
        if a == b {
            continue;
        }
        let first = a.iter().zip(b).position(|(p, q)| p != q).unwrap_or(0) / 3;
        let last = a.iter().zip(b).rposition(|(p, q)| p != q).unwrap_or(0) / 3;
        bbox = Some(match bbox {
            None => Window {
                x0: first,
                y0: y,
                x1: last + 1,
                y1: y + 1,
            },
            Some(r) => Window {
                x0: r.x0.min(first),
                y0: r.y0,
                x1: r.x1.max(last + 1),
                y1: y + 1,
            },
        });
    }
    bbox
}

/// The difference seen at one smoothing scale, over `window` (zero outside it).
pub(super) struct Scale {
    pub(super) size: usize,
    pub(super) window: Window,
    /// Row-major (in the window) norm of the smoothed signed difference (0 where the pixel
    /// sees no finger).
    pub(super) magnitude: Vec<f64>,
    /// RMS of that norm under noise alone.
    pub(super) sigma: f64,
    pub(super) peak: f64,
    pub(super) detect_level: f64,
}

/// Over the whole frame: the noise estimated from every pixel that sees the finger.
pub(super) fn analyse_scale(
    signed: &FloatImage,
    cache: &SurfaceCache,
    size: usize,
    config: &SurfaceConfig,
) -> Scale {
    let smooth = mean_filter(signed, size);
    let mut sigma2 = 0.0;
    let mut values = vec![0.0; cache.valid.len()];
    for c in 0..3 {
        for (v, &i) in values.iter_mut().zip(&cache.valid) {
            *v = smooth.data[3 * i + c];
        }
        sigma2 += robust_sigma(&mut values).powi(2);
    }
    let sigma = sigma2.sqrt().max(NOISE_FLOOR);
    let mut magnitude = vec![0.0; cache.areas.len()];
    let mut peak = 0.0f64;
    for &i in &cache.valid {
        let m = smooth.pixel(i).iter().map(|v| v * v).sum::<f64>().sqrt();
        magnitude[i] = m;
        peak = peak.max(m);
    }
    Scale {
        size,
        window: Window {
            x0: 0,
            y0: 0,
            x1: signed.width as usize,
            y1: signed.height as usize,
        },
        magnitude,
        sigma,
        peak,
        detect_level: (config.detect_snr * sigma).max(config.min_peak),
    }
}

/// Over the difference's footprint only, for a frame that equals the reference outside
/// `bbox` (no sensor noise): the same numbers as [`analyse_scale`], at a fraction of the
/// cost. The smoothed difference is exactly 0 farther than `size / 2` from `bbox` (the
/// differences are whole grey levels, so the box sums are exact), so only the window
/// `bbox` grown by `size / 2` can be non-zero; it is filtered from a crop grown by `size`
/// (whose edges are the image's wherever the window's window reaches them, so the mirrored
/// border samples are the same). When more than half of the pixels that see the finger lie
/// outside the window, the median of each channel and of its absolute deviations is 0, so
/// the robust noise is 0 and `sigma` is the floor. The caller checks that condition.
pub(super) fn analyse_footprint(
    reference: &RgbImage,
    frame: &RgbImage,
    bbox: Window,
    cache: &SurfaceCache,
    size: usize,
    config: &SurfaceConfig,
) -> Scale {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    let half = (size.max(1) | 1) / 2;
    let window = bbox.grown(half, w, h);
    let crop = bbox.grown(2 * half, w, h);
    let (a, b) = (reference.as_raw(), frame.as_raw());
    let mut data = Vec::with_capacity(crop.width() * crop.height() * 3);
    for y in crop.y0..crop.y1 {
        let row = (y * w + crop.x0) * 3..(y * w + crop.x1) * 3;
        data.extend(
            a[row.clone()]
                .iter()
                .zip(&b[row])
                .map(|(&p, &q)| q as f64 - p as f64),
        );
    }
    let signed = FloatImage {
        width: crop.width() as u32,
        height: crop.height() as u32,
        channels: 3,
        data,
    };
    let smooth = mean_filter(&signed, size);
    let sigma = NOISE_FLOOR;
    let mut magnitude = vec![0.0; window.width() * window.height()];
    let mut peak = 0.0f64;
    for (k, m) in magnitude.iter_mut().enumerate() {
        let i = window.image_index(k, w);
        if cache.areas[i] <= 0.0 {
            continue;
        }
        let (x, y) = (
            window.x0 + k % window.width(),
            window.y0 + k / window.width(),
        );
        let c = (y - crop.y0) * crop.width() + (x - crop.x0);
        *m = smooth.pixel(c).iter().map(|v| v * v).sum::<f64>().sqrt();
        peak = peak.max(*m);
    }
    Scale {
        size,
        window,
        magnitude,
        sigma,
        peak,
        detect_level: (config.detect_snr * sigma).max(config.min_peak),
    }
}

/// Whether more than half of the pixels that see the finger lie outside `window`.
pub(super) fn mostly_outside(cache: &SurfaceCache, window: Window) -> bool {
    let w = cache.width as usize;
    let inside: usize = (window.y0..window.y1)
        .map(|y| {
            cache.areas[y * w + window.x0..y * w + window.x1]
                .iter()
                .filter(|&&a| a > 0.0)
                .count()
        })
        .sum();
    2 * (cache.valid.len() - inside) > cache.valid.len()
}
