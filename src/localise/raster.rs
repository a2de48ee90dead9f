//! Floating-point images and the filters both detectors share: a summed-area-table box
//! filter with OpenCV's default border, and a robust noise estimate.

use image::RgbImage;

/// A `width` x `height` image of `channels` interleaved `f64` samples per pixel, row-major.
/// Values are in grey levels (0..255 for 8-bit sources) and may be negative (signed
/// differences).
#[derive(Debug, Clone, PartialEq)]
pub struct FloatImage {
    pub width: u32,
    pub height: u32,
    pub channels: usize,
    pub data: Vec<f64>,
}

impl FloatImage {
    /// An image of zeros.
    pub fn zeros(width: u32, height: u32, channels: usize) -> Self {
        FloatImage {
            width,
            height,
            channels,
            data: vec![0.0; width as usize * height as usize * channels],
        }
    }

    /// A one-channel image from row-major values; `None` if the length is not `width * height`.
    pub fn from_gray(width: u32, height: u32, data: Vec<f64>) -> Option<Self> {
        (data.len() == width as usize * height as usize).then_some(FloatImage {
            width,
            height,
            channels: 1,
            data,
        })
    }

    /// The three channels of an 8-bit RGB image.
    pub fn from_rgb(image: &RgbImage) -> Self {
        FloatImage {
            width: image.width(),
            height: image.height(),
            channels: 3,
            data: image.as_raw().iter().map(|&v| v as f64).collect(),
        }
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Sample `channel` of pixel (x, y).
    pub fn get(&self, x: u32, y: u32, channel: usize) -> f64 {
        self.data[(y as usize * self.width as usize + x as usize) * self.channels + channel]
    }

    /// Sets `channel` of pixel (x, y).
    pub fn set(&mut self, x: u32, y: u32, channel: usize, value: f64) {
        let i = (y as usize * self.width as usize + x as usize) * self.channels + channel;
        self.data[i] = value;
    }

    /// The samples of pixel number `i` (row-major).
    pub fn pixel(&self, i: usize) -> &[f64] {
        &self.data[i * self.channels..(i + 1) * self.channels]
    }

    /// The largest sample (0 for an empty image).
    pub fn max(&self) -> f64 {
        self.data.iter().copied().fold(0.0, f64::max)
    }
}

/// OpenCV's `BORDER_REFLECT_101` (`gfedcb|abcdefgh|gfedcba`): the edge sample is not
/// repeated. Reflects as often as needed, so kernels larger than the image work too.
pub fn reflect_101(i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let period = 2 * n - 2;
    let mut j = i.rem_euclid(period);
    if j >= n {
        j = period - j;
    }
    j as usize
}

/// Normalised `size` x `size` box (mean) filter of every channel, like OpenCV's
/// `blur(src, (size, size))`: each output sample is the mean of the `size * size` samples
/// centred on it, and samples beyond the image are taken from the mirror image without
/// repeating the edge (`BORDER_REFLECT_101`, OpenCV's default). Computed with one
/// summed-area table per channel over the padded image, so the cost does not grow with
/// `size`. `size` must be odd; an even size is rounded up.
pub fn mean_filter(image: &FloatImage, size: usize) -> FloatImage {
    let size = size.max(1) | 1;
    let k = size / 2;
    let (w, h, ch) = (image.width as usize, image.height as usize, image.channels);
    let mut out = FloatImage::zeros(image.width, image.height, ch);
    if w == 0 || h == 0 {
        return out;
    }
    let (pw, ph) = (w + 2 * k, h + 2 * k);
    let cols: Vec<usize> = (0..pw)
        .map(|x| reflect_101(x as isize - k as isize, w))
        .collect();
    let rows: Vec<usize> = (0..ph)
        .map(|y| reflect_101(y as isize - k as isize, h))
        .collect();
    // sat[(y) * (pw + 1) + x] = sum of padded samples with row < y and column < x.
    let stride = pw + 1;
    let mut sat = vec![0.0f64; stride * (ph + 1)];
    let norm = 1.0 / (size * size) as f64;
    for c in 0..ch {
        for (py, &sy) in rows.iter().enumerate() {
            let mut row_sum = 0.0;
            let src_row = sy * w;
            for (px, &sx) in cols.iter().enumerate() {
                row_sum += image.data[(src_row + sx) * ch + c];
                sat[(py + 1) * stride + px + 1] = sat[py * stride + px + 1] + row_sum;
            }
        }
        for y in 0..h {
            let (y0, y1) = (y * stride, (y + size) * stride);
            for x in 0..w {
                let sum = sat[y1 + x + size] - sat[y0 + x + size] - sat[y1 + x] + sat[y0 + x];
                out.data[(y * w + x) * ch + c] = sum * norm;
            }
        }
    }
    out
}

/// Neighbour offsets, clockwise on screen (v down), starting west.
pub const NEIGHBOURS_8: [(i32, i32); 8] = [
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
];

/// The 8-connected components of the set pixels of a `width` x `height` row-major mask,
/// each as its pixel indices in raster order, the components in raster order of their
/// first pixel. Also returns the label of every pixel (`u32::MAX` for unset pixels).
pub fn components(mask: &[bool], width: u32, height: u32) -> (Vec<Vec<usize>>, Vec<u32>) {
    let (w, h) = (width as usize, height as usize);
    debug_assert_eq!(mask.len(), w * h);
    let mut label = vec![u32::MAX; w * h];
    let mut comps: Vec<Vec<usize>> = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if label[start] != u32::MAX || !mask[start] {
            continue;
        }
        let id = comps.len() as u32;
        label[start] = id;
        stack.push(start);
        let mut pixels = Vec::new();
        while let Some(i) = stack.pop() {
            pixels.push(i);
            let (x, y) = ((i % w) as i32, (i / w) as i32);
            for (dx, dy) in NEIGHBOURS_8 {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if label[j] == u32::MAX && mask[j] {
                    label[j] = id;
                    stack.push(j);
                }
            }
        }
        pixels.sort_unstable();
        comps.push(pixels);
    }
    (comps, label)
}

/// Median of `values` (reorders them); 0 for an empty slice.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Robust standard deviation: 1.4826 times the median absolute deviation, which equals the
/// standard deviation for Gaussian noise and ignores a contact covering under half the
/// samples. Reorders `values`.
pub fn robust_sigma(values: &mut [f64]) -> f64 {
    let m = median(values);
    for v in values.iter_mut() {
        *v = (*v - m).abs();
    }
    1.4826 * median(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_101_mirrors_without_repeating_the_edge() {
        let got: Vec<usize> = (-3..8).map(|i| reflect_101(i, 5)).collect();
        assert_eq!(got, vec![3, 2, 1, 0, 1, 2, 3, 4, 3, 2, 1]);
        assert_eq!(reflect_101(-7, 1), 0);
        assert_eq!(reflect_101(9, 3), 1);
    }

    #[test]
    fn mean_filter_matches_brute_force() {
        let (w, h) = (9u32, 6u32);
        let data: Vec<f64> = (0..w * h * 2).map(|i| ((i * 37) % 11) as f64).collect();
        let img = FloatImage {
            width: w,
            height: h,
            channels: 2,
            data,
        };
        for size in [1usize, 3, 5, 15] {
            let out = mean_filter(&img, size);
            let k = (size / 2) as isize;
            for y in 0..h {
                for x in 0..w {
                    for c in 0..2 {
                        let mut sum = 0.0;
                        for dy in -k..=k {
                            for dx in -k..=k {
                                let sx = reflect_101(x as isize + dx, w as usize) as u32;
                                let sy = reflect_101(y as isize + dy, h as usize) as u32;
                                sum += img.get(sx, sy, c);
                            }
                        }
                        let want = sum / (size * size) as f64;
                        assert!((out.get(x, y, c) - want).abs() < 1e-9, "size {size}");
                    }
                }
            }
        }
    }

    #[test]
    fn robust_sigma_ignores_outliers() {
        // -1, 0, 1 in equal numbers: median 0, median absolute deviation 1.
        let mut v: Vec<f64> = (0..999).map(|i| (i % 3) as f64 - 1.0).collect();
        v.extend([1e6; 50]);
        let s = robust_sigma(&mut v);
        assert!((s - 1.4826).abs() < 1e-9, "{s}");
    }
}
