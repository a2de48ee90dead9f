//! The paper's contact detector (Gomes et al., IROS 2020, "Contact localisation"), step by
//! step, with each step a public function so that it can be checked on its own:
//!
//! 1. [`difference`]: absolute difference between the frame and the reference, per channel.
//! 2. [`mean_filter`]: 15 x 15 mean convolution (OpenCV `blur`, `BORDER_REFLECT_101`).
//! 3. [`brightness`] then [`threshold`]: "pixels with a brightness intensity lower than 60%
//!    are set to zero".
//! 4. [`regions`]: OpenCV `findContours`: 8-connected regions and their outer contours.
//! 5. [`area_filter`]: keep regions whose area is between 0.012% and 0.04% of the picture
//!    (or, where [`AreaLimit::Finger`] is asked for, within a window on the finger in mm^2:
//!    the paper's window is in its own sensor's pixels, a prior on its objects' size).
//! 6. [`fit_ellipse`]: OpenCV `fitEllipse` on each kept contour; its centre is the region's.
//! 7. [`weighted_centre`]: the weighted average of the centres (weights: region areas).
//! 8. The map m ([`Sensor::unproject`]) turns that pixel into a point on the finger.
//!
//! Where the paper is ambiguous the choice is documented on the function that makes it.

pub use super::raster::mean_filter;
use super::raster::{components, FloatImage, NEIGHBOURS_8 as DIRS};
use super::{check_sizes, AreaWindow, Detection};
use crate::error::Result;
use crate::sensor::Sensor;
use glam::DVec2;
use image::RgbImage;

/// Side of the mean filter's square kernel (px).
pub const KERNEL: usize = 15;
/// Pixels below this fraction of the brightest filtered pixel are set to zero.
pub const THRESHOLD_FRACTION: f64 = 0.6;
/// Smallest region area kept, as a fraction of the picture's area (0.012%).
pub const MIN_AREA_FRACTION: f64 = 0.012e-2;
/// Largest region area kept, as a fraction of the picture's area (0.04%).
pub const MAX_AREA_FRACTION: f64 = 0.04e-2;

/// Step 1: `|frame - reference|` for each channel, like OpenCV's `absdiff`. The two images
/// must have the same size.
pub fn difference(reference: &RgbImage, frame: &RgbImage) -> Result<FloatImage> {
    check_sizes(reference, frame, None)?;
    Ok(FloatImage {
        width: frame.width(),
        height: frame.height(),
        channels: 3,
        data: reference
            .as_raw()
            .iter()
            .zip(frame.as_raw())
            .map(|(&a, &b)| (a as f64 - b as f64).abs())
            .collect(),
    })
}

/// Brightness of each pixel: the mean of its channels (one channel out).
///
/// The paper does not say how "brightness" is measured. The plain mean is used rather than
/// OpenCV's luma (0.299 R + 0.587 G + 0.114 B) because the three LEDs light the finger in
/// red, green and blue from different sides: a contact shaded mostly by the blue LED must
/// count as much as one shaded by the green LED.
pub fn brightness(image: &FloatImage) -> FloatImage {
    let n = image.channels.max(1) as f64;
    FloatImage {
        width: image.width,
        height: image.height,
        channels: 1,
        data: (0..image.pixel_count())
            .map(|i| image.pixel(i).iter().sum::<f64>() / n)
            .collect(),
    }
}

/// Step 3: sets to zero every pixel of the one-channel `brightness` image below
/// `fraction` (0.6 in the paper) of the image's brightest pixel; the rest keep their value.
///
/// The paper's "pixels with a brightness intensity lower than 60% are set to zero" does not
/// say 60% of what. Of the full 8-bit scale (153 of 255) is impossible for a mean-filtered
/// difference, which rarely exceeds a few tens of grey levels, so no contact would ever be
/// seen; the threshold is therefore relative to the brightest pixel of this difference
/// image (equivalent to normalising the image to 0..255 and thresholding at 153). Pixels
/// exactly at the threshold are kept. An all-zero image stays all zero.
pub fn threshold(brightness: &FloatImage, fraction: f64) -> FloatImage {
    let limit = fraction * brightness.max();
    let mut out = brightness.clone();
    for v in &mut out.data {
        if *v < limit || *v <= 0.0 {
            *v = 0.0;
        }
    }
    out
}

/// A connected region of non-zero pixels, as OpenCV's `findContours` sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct Blob {
    /// Every pixel of the region, in raster order.
    pub pixels: Vec<(u32, u32)>,
    /// The outer contour: the centres of the region's border pixels, in order (clockwise on
    /// screen), starting at the top-most, left-most pixel; no point is repeated at the end.
    /// Like `findContours` with `RETR_EXTERNAL` and `CHAIN_APPROX_NONE`.
    pub contour: Vec<DVec2>,
    /// Area enclosed by the contour polygon (shoelace formula), which is what OpenCV's
    /// `contourArea` returns: less than the pixel count, because the polygon runs through
    /// the border pixels' centres (a filled w x h rectangle has area (w - 1)(h - 1); a
    /// one-pixel-wide line has area 0).
    pub area: f64,
}

impl Blob {
    /// Number of pixels in the region.
    pub fn pixel_count(&self) -> usize {
        self.pixels.len()
    }

    /// Mean position of the region's pixels.
    pub fn centroid(&self) -> DVec2 {
        let sum = self.pixels.iter().fold(DVec2::ZERO, |acc, &(x, y)| {
            acc + DVec2::new(x as f64, y as f64)
        });
        sum / self.pixels.len().max(1) as f64
    }
}

fn dir_index(dx: i32, dy: i32) -> usize {
    DIRS.iter()
        .position(|&d| d == (dx, dy))
        .expect("neighbour offset")
}

/// Step 4: the 8-connected regions of non-zero pixels of an image (a pixel is set when any
/// channel is non-zero), in raster order of their first pixel, each with its outer contour
/// (traced by Moore-neighbour tracing with OpenCV's stopping rule) and contour area. Holes
/// are not reported as regions of their own (`RETR_EXTERNAL`).
pub fn regions(image: &FloatImage) -> Vec<Blob> {
    let w = image.width as usize;
    let mask: Vec<bool> = (0..image.pixel_count())
        .map(|i| image.pixel(i).iter().any(|&v| v != 0.0))
        .collect();
    let (comps, label) = components(&mask, image.width, image.height);
    comps
        .into_iter()
        .enumerate()
        .map(|(id, pixels)| {
            let pixels: Vec<(u32, u32)> = pixels
                .into_iter()
                .map(|i| ((i % w) as u32, (i / w) as u32))
                .collect();
            let inside = |x: i32, y: i32| {
                x >= 0
                    && y >= 0
                    && x < image.width as i32
                    && y < image.height as i32
                    && label[y as usize * w + x as usize] == id as u32
            };
            let contour = trace_contour(pixels[0], pixels.len(), inside);
            Blob {
                area: polygon_area(&contour),
                contour,
                pixels,
            }
        })
        .collect()
}

/// Moore-neighbour tracing of the outer border of the region containing `start`, which
/// must be its first pixel in raster order (so its west neighbour is outside).
fn trace_contour(
    start: (u32, u32),
    pixel_count: usize,
    inside: impl Fn(i32, i32) -> bool,
) -> Vec<DVec2> {
    let s = (start.0 as i32, start.1 as i32);
    let mut path = vec![s];
    let (mut c, mut back) = (s, 0usize);
    // Each border pixel is entered at most once from each of its 8 neighbours.
    for _ in 0..8 * pixel_count + 8 {
        let next = (1..=8).map(|i| (back + i) % 8).find_map(|k| {
            let n = (c.0 + DIRS[k].0, c.1 + DIRS[k].1);
            inside(n.0, n.1).then_some((k, n))
        });
        let Some((k, n)) = next else { break };
        // OpenCV's rule: stop when the start pixel is left again towards the second pixel.
        if c == s && path.len() >= 2 && n == path[1] {
            break;
        }
        let (bx, by) = DIRS[(k + 7) % 8];
        back = dir_index(c.0 + bx - n.0, c.1 + by - n.1);
        path.push(n);
        c = n;
    }
    if path.len() > 1 && path.last() == path.first() {
        path.pop();
    }
    path.into_iter()
        .map(|(x, y)| DVec2::new(x as f64, y as f64))
        .collect()
}

/// Area of the closed polygon through `points` (absolute value of the shoelace sum).
pub fn polygon_area(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n < 3 {
        return 0.0;
    }
    let twice: f64 = (0..n)
        .map(|i| points[i].perp_dot(points[(i + 1) % n]))
        .sum();
    0.5 * twice.abs()
}

/// The kept-area range in px^2 for a picture of `picture_area` px: 0.012%..0.04% of it
/// (36.9..122.9 for 640 x 480).
pub fn area_range(picture_area: f64) -> (f64, f64) {
    (
        MIN_AREA_FRACTION * picture_area,
        MAX_AREA_FRACTION * picture_area,
    )
}

/// Step 5: keeps the regions whose contour area ([`Blob::area`], OpenCV's `contourArea`)
/// lies between 0.012% and 0.04% of `picture_area` (both ends included).
pub fn area_filter(blobs: Vec<Blob>, picture_area: f64) -> Vec<Blob> {
    split_by_area(blobs, &AreaLimit::Picture, picture_area, 0).0
}

/// How step 5 bounds a region's area.
#[derive(Debug, Clone, Copy)]
pub enum AreaLimit<'a> {
    /// The paper's: the contour area within 0.012%..0.04% of the picture, px.
    Picture,
    /// On the finger: the region's pixels' areas summed (`areas`: mm^2 per pixel,
    /// row-major, as [`super::surface::SurfaceCache::areas`]) within `window`.
    Finger {
        areas: &'a [f64],
        window: AreaWindow,
    },
}

impl Blob {
    /// The finger's area the region's pixels see, mm^2 (`areas` as [`AreaLimit::Finger`]).
    pub fn area_on_finger(&self, areas: &[f64], width: u32) -> f64 {
        self.pixels
            .iter()
            .map(|&(x, y)| {
                areas
                    .get(y as usize * width as usize + x as usize)
                    .copied()
                    .unwrap_or(0.0)
            })
            .sum()
    }
}

impl AreaLimit<'_> {
    /// A region's area under this limit: px for `Picture`, mm^2 for `Finger` (`width`: the
    /// picture's).
    pub fn measure(&self, blob: &Blob, width: u32) -> f64 {
        match self {
            AreaLimit::Picture => blob.area,
            AreaLimit::Finger { areas, .. } => blob.area_on_finger(areas, width),
        }
    }

    /// The smallest and largest area a region may have, in [`Self::measure`]'s unit, for a
    /// picture of `picture_area` px.
    pub fn window(&self, picture_area: f64) -> (f64, f64) {
        match self {
            AreaLimit::Picture => area_range(picture_area),
            AreaLimit::Finger { window, .. } => (window.min_mm2, window.max_mm2),
        }
    }

    fn unit(&self) -> &'static str {
        match self {
            AreaLimit::Picture => "px",
            AreaLimit::Finger { .. } => "mm^2 on the finger",
        }
    }
}

/// Step 5 under `limit`: the regions whose area lies in its window (both ends included),
/// and the others (`width`: the picture's).
pub fn split_by_area(
    blobs: Vec<Blob>,
    limit: &AreaLimit,
    picture_area: f64,
    width: u32,
) -> (Vec<Blob>, Vec<Blob>) {
    let (lo, hi) = limit.window(picture_area);
    blobs.into_iter().partition(|b| {
        let area = limit.measure(b, width);
        area >= lo && area <= hi
    })
}

/// An ellipse in pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    pub centre: DVec2,
    /// Semi-axes (px): major, then minor. (OpenCV's `RotatedRect` holds full axes.)
    pub semi_axes: DVec2,
    /// Angle of the major axis from +u towards +v (radians, in (-pi/2, pi/2]).
    pub angle: f64,
}

/// Step 6: the direct least-squares ellipse fit of Fitzgibbon, Pilu and Fisher (1999), in
/// the numerically stable form of Halir and Flusser (1998), on points normalised to zero
/// mean and unit spread. OpenCV's `fitEllipse` is also an algebraic least-squares conic fit
/// to the contour points; on clean contours the centres agree to a fraction of a pixel.
///
/// `None` (the caller falls back to the region's centroid) when there are fewer than 5
/// points, the points are (nearly) collinear, no ellipse-shaped solution exists, or the
/// centre falls outside the points' bounding box grown by one pixel (a fit that wild says
/// the contour is not elliptical, where OpenCV would return a meaningless centre).
pub fn fit_ellipse(points: &[DVec2]) -> Option<Ellipse> {
    if points.len() < 5 || points.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let n = points.len() as f64;
    let mean = points.iter().copied().sum::<DVec2>() / n;
    let spread = (points
        .iter()
        .map(|p| (*p - mean).length_squared())
        .sum::<f64>()
        / (2.0 * n))
        .sqrt();
    if spread <= 0.0 {
        return None;
    }
    // Scatter matrices of D1 = [x^2, xy, y^2] and D2 = [x, y, 1].
    let (mut s1, mut s2, mut s3) = ([[0.0f64; 3]; 3], [[0.0f64; 3]; 3], [[0.0f64; 3]; 3]);
    for p in points {
        let q = (*p - mean) / spread;
        let d1 = [q.x * q.x, q.x * q.y, q.y * q.y];
        let d2 = [q.x, q.y, 1.0];
        for i in 0..3 {
            for j in 0..3 {
                s1[i][j] += d1[i] * d1[j];
                s2[i][j] += d1[i] * d2[j];
                s3[i][j] += d2[i] * d2[j];
            }
        }
    }
    let s3_inv = invert3(s3)?;
    // T = -S3^-1 S2^T, so that a2 = T a1.
    let t = mul3(s3_inv, transpose3(s2)).map(|r| r.map(|v| -v));
    let m = add3(s1, mul3(s2, t));
    // Premultiply by C1^-1 for the constraint 4ac - b^2 = 1.
    let m = [
        m[2].map(|v| v / 2.0),
        m[1].map(|v| -v),
        m[0].map(|v| v / 2.0),
    ];
    let a1 = eigenvectors3(m)
        .into_iter()
        .filter_map(|v| {
            let cond = 4.0 * v[0] * v[2] - v[1] * v[1];
            let norm2 = v.iter().map(|x| x * x).sum::<f64>();
            (cond > 0.0).then_some((cond / norm2, v))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))?
        .1;
    let a2 = mul3v(t, a1);
    let conic = [a1[0], a1[1], a1[2], a2[0], a2[1], a2[2]];
    let e = conic_to_ellipse(conic)?;
    let centre = mean + spread * e.centre;
    let (lo, hi) = points.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let inside = centre.cmpge(lo - 1.0).all() && centre.cmple(hi + 1.0).all();
    (inside && centre.is_finite()).then_some(Ellipse {
        centre,
        semi_axes: spread * e.semi_axes,
        angle: e.angle,
    })
}

/// Centre, semi-axes and angle of the conic `a x^2 + b xy + c y^2 + d x + e y + f = 0`, if it
/// is a real ellipse.
fn conic_to_ellipse([a, b, c, d, e, f]: [f64; 6]) -> Option<Ellipse> {
    let det = 4.0 * a * c - b * b;
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let x0 = (b * e - 2.0 * c * d) / det;
    let y0 = (b * d - 2.0 * a * e) / det;
    let fc = a * x0 * x0 + b * x0 * y0 + c * y0 * y0 + d * x0 + e * y0 + f;
    // Eigenvalues of the quadratic form [[a, b/2], [b/2, c]].
    let mean = 0.5 * (a + c);
    let r = (0.25 * (a - c) * (a - c) + 0.25 * b * b).sqrt();
    let (l_small, l_big) = (mean - r, mean + r);
    let (ax_major, ax_minor) = ((-fc / l_small).sqrt(), (-fc / l_big).sqrt());
    if !(ax_major.is_finite() && ax_minor.is_finite() && ax_minor > 0.0) {
        return None;
    }
    // The major axis is along the eigenvector of the smaller eigenvalue.
    let angle = if b == 0.0 && a <= c {
        0.0
    } else if b == 0.0 {
        std::f64::consts::FRAC_PI_2
    } else {
        (l_small - a).atan2(0.5 * b)
    };
    let angle = if angle <= -std::f64::consts::FRAC_PI_2 {
        angle + std::f64::consts::PI
    } else if angle > std::f64::consts::FRAC_PI_2 {
        angle - std::f64::consts::PI
    } else {
        angle
    };
    Some(Ellipse {
        centre: DVec2::new(x0, y0),
        semi_axes: DVec2::new(ax_major, ax_minor),
        angle,
    })
}

type M3 = [[f64; 3]; 3];

fn transpose3(m: M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

fn mul3(a: M3, b: M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn mul3v(a: M3, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn add3(a: M3, b: M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] + b[i][j]))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn det3(m: M3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse of a 3x3 matrix, `None` if it is (nearly) singular.
fn invert3(m: M3) -> Option<M3> {
    let det = det3(m);
    let scale = m.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
    if det.is_nan() || det.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let cof = [cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1])];
    // The inverse is the transposed cofactor matrix over the determinant.
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| cof[j][i] / det)
    }))
}

/// Eigenvectors of the real eigenvalues of a 3x3 matrix (not normalised).
fn eigenvectors3(m: M3) -> Vec<[f64; 3]> {
    // Characteristic polynomial: l^3 - tr l^2 + c1 l - det.
    let tr = m[0][0] + m[1][1] + m[2][2];
    let c1 = m[0][0] * m[1][1] - m[0][1] * m[1][0] + m[0][0] * m[2][2] - m[0][2] * m[2][0]
        + m[1][1] * m[2][2]
        - m[1][2] * m[2][1];
    let det = det3(m);
    real_cubic_roots(-tr, c1, -det)
        .into_iter()
        .filter_map(|l| {
            let a: M3 = std::array::from_fn(|i| {
                std::array::from_fn(|j| m[i][j] - if i == j { l } else { 0.0 })
            });
            // The null vector is the largest cross product of two rows.
            [cross(a[0], a[1]), cross(a[0], a[2]), cross(a[1], a[2])]
                .into_iter()
                .map(|v| (v.iter().map(|x| x * x).sum::<f64>(), v))
                .max_by(|x, y| x.0.total_cmp(&y.0))
                .filter(|(n2, _)| *n2 > 0.0 && n2.is_finite())
                .map(|(_, v)| v)
        })
        .collect()
}

/// Real roots of `x^3 + a x^2 + b x + c`.
fn real_cubic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    let shift = a / 3.0;
    if r * r < q * q * q {
        let theta = (r / q.powf(1.5)).clamp(-1.0, 1.0).acos();
        let k = -2.0 * q.sqrt();
        (0..3)
            .map(|i| k * ((theta + 2.0 * std::f64::consts::PI * i as f64) / 3.0).cos() - shift)
            .collect()
    } else {
        let big = -r.signum() * (r.abs() + (r * r - q * q * q).max(0.0).sqrt()).cbrt();
        let small = if big == 0.0 { 0.0 } else { q / big };
        vec![big + small - shift]
    }
}

/// A region's centre: the centre of the ellipse fitted to its contour, or the centroid of
/// its pixels when the fit fails (see [`fit_ellipse`]).
pub fn region_centre(blob: &Blob) -> DVec2 {
    fit_ellipse(&blob.contour)
        .map(|e| e.centre)
        .unwrap_or_else(|| blob.centroid())
}

/// Step 7: the average of the regions' centres weighted by their contour areas (the paper
/// says only "weighted average"; area is the weight its regions have). Falls back to pixel
/// counts if every area is 0. `None` for no regions.
pub fn weighted_centre(blobs: &[Blob]) -> Option<DVec2> {
    if blobs.is_empty() {
        return None;
    }
    let use_area = blobs.iter().any(|b| b.area > 0.0);
    let weight = |b: &Blob| {
        if use_area {
            b.area
        } else {
            b.pixel_count() as f64
        }
    };
    let total: f64 = blobs.iter().map(weight).sum();
    let sum = blobs
        .iter()
        .fold(DVec2::ZERO, |acc, b| acc + weight(b) * region_centre(b));
    Some(sum / total)
}

/// The paper's detector from end to end, with the paper's area filter. The images must have
/// the sensor's size.
///
/// Like the original, it always predicts a contact when anything differs: noise alone
/// yields regions above 60% of the (noise) maximum. Only a frame identical to the
/// reference, no region of the right size, or a centre that sees no part of the finger
/// give "not detected". Confidence: how far the brightest filtered pixel stands above the
/// image's median, in robust noise deviations, mapped by [`super::snr_confidence`].
pub fn detect(sensor: &Sensor, reference: &RgbImage, frame: &RgbImage) -> Result<Detection> {
    detect_with(sensor, reference, frame, AreaLimit::Picture)
}

/// [`detect`] with step 5's bound on a region's area given by `limit`.
pub fn detect_with(
    sensor: &Sensor,
    reference: &RgbImage,
    frame: &RgbImage,
    limit: AreaLimit,
) -> Result<Detection> {
    check_sizes(reference, frame, Some(sensor))?;
    let diff = difference(reference, frame)?;
    let filtered = mean_filter(&diff, KERNEL);
    let bright = brightness(&filtered);
    let peak = bright.max();
    if peak <= 0.0 {
        return Ok(Detection::none(
            0,
            "the frame does not differ from the reference",
        ));
    }
    let mut values = bright.data.clone();
    let med = super::raster::median(&mut values);
    let sigma = super::raster::robust_sigma(&mut values).max(super::NOISE_FLOOR);
    let confidence = super::snr_confidence((peak - med) / sigma);
    let blobs = regions(&threshold(&bright, THRESHOLD_FRACTION));
    let found = blobs.len();
    let picture = bright.pixel_count() as f64;
    let (kept, rejected) = split_by_area(blobs, &limit, picture, bright.width);
    let Some(centre) = weighted_centre(&kept) else {
        let (min, max) = rejected
            .iter()
            .map(|b| limit.measure(b, bright.width))
            .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        let ((lo, hi), unit) = (limit.window(picture), limit.unit());
        return Ok(Detection::none(
            found,
            format!(
                "no region passed the area filter ({found} regions of area {min:.1}..{max:.1} {unit}, allowed {lo:.1}..{hi:.1} {unit})"
            ),
        ));
    };
    Ok(Detection::at_pixel(sensor, centre, confidence, found))
}
