//! The image circle: the disc of an empty frame that the lens lights, against the black
//! beyond its field of view. Found from the frame alone: a brightness threshold between the
//! two (Otsu's), the disc's boundary where each row and column crosses it, and a circle
//! fitted to the boundary points that do not lie on the image's own edge (a circle clipped
//! by the image, as on a GelTip, is fitted to its visible arcs).

use super::frames::EmptyFrame;
use crate::error::{GeltipError, Result};
use glam::DVec2;

/// A circle in pixel coordinates (OpenCV convention: integer coordinates at pixel centres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageCircle {
    pub centre: DVec2,
    pub radius: f64,
    /// Root-mean-square distance (px) of the boundary points from the fitted circle.
    pub rms_px: f64,
    /// Boundary points the fit used.
    pub points: usize,
}

impl ImageCircle {
    /// Whether pixel `(x, y)`'s centre lies at least `margin` px inside the circle.
    pub fn contains(&self, x: u32, y: u32, margin: f64) -> bool {
        (DVec2::new(x as f64, y as f64) - self.centre).length() <= self.radius - margin
    }
}

/// The fewest boundary points a circle is fitted to.
const MIN_POINTS: usize = 24;

/// Finds the image circle of `frame`.
pub fn find(frame: &EmptyFrame) -> Result<ImageCircle> {
    let (w, h) = (frame.width, frame.height);
    let luma: Vec<f64> = frame
        .pixels
        .iter()
        .map(|p| p.iter().sum::<f64>() / 3.0)
        .collect();
    let threshold = otsu(&luma);
    let bright = |x: u32, y: u32| luma[(y * w + x) as usize] > threshold;
    let lit = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| bright(x, y))
        .count();
    let share = lit as f64 / (w * h) as f64;
    if !(0.05..=0.995).contains(&share) {
        return Err(GeltipError::InvalidImage {
            path: frame.path.clone(),
            reason: format!(
                "no image circle: {:.1}% of the frame is lit (a GelTip frame shows a bright disc on black)",
                100.0 * share
            ),
        });
    }
    let points = boundary_points(w, h, bright);
    if points.len() < MIN_POINTS {
        return Err(GeltipError::InvalidImage {
            path: frame.path.clone(),
            reason: format!(
                "no image circle: its visible edge has {} points, at least {MIN_POINTS} are needed",
                points.len()
            ),
        });
    }
    let circle = fit_robust(&points).ok_or_else(|| GeltipError::InvalidImage {
        path: frame.path.clone(),
        reason: "no image circle: the lit region's edge is not a circle".into(),
    })?;
    // Specks and a ragged edge leave boundary points off the circle, which the robust fit
    // drops; a lit region of another shape leaves lit pixels outside the circle or dark ones
    // inside it.
    let (mut outside, mut inside) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            let d = (DVec2::new(x as f64, y as f64) - circle.centre).length() - circle.radius;
            if d > 2.0 && bright(x, y) {
                outside += 1;
            } else if d < -2.0 && !bright(x, y) {
                inside += 1;
            }
        }
    }
    let mismatch = (outside + inside) as f64 / lit as f64;
    if circle.rms_px > 3.0 || mismatch > 0.02 {
        return Err(GeltipError::InvalidImage {
            path: frame.path.clone(),
            reason: format!(
                "no image circle: the lit region is not a disc ({:.1}% of it off the best circle, edge {:.1} px rms from it)",
                100.0 * mismatch,
                circle.rms_px
            ),
        });
    }
    Ok(circle)
}

/// Otsu's threshold of values in 0..=255: the level that best splits them in two classes.
pub fn otsu(values: &[f64]) -> f64 {
    let mut hist = [0u64; 256];
    for &v in values {
        hist[v.round().clamp(0.0, 255.0) as usize] += 1;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist
        .iter()
        .enumerate()
        .map(|(i, &n)| i as f64 * n as f64)
        .sum();
    let (mut below, mut sum_below) = (0.0, 0.0);
    let (mut best, mut best_level) = (-1.0, 0.0);
    for (i, &n) in hist.iter().enumerate() {
        below += n as f64;
        sum_below += i as f64 * n as f64;
        let above = total - below;
        if below == 0.0 || above == 0.0 {
            continue;
        }
        let m0 = sum_below / below;
        let m1 = (sum_all - sum_below) / above;
        let between = below * above * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            best_level = i as f64 + 0.5;
        }
    }
    best_level
}

/// Where the lit region's outermost pixels meet the dark, along every row and column: half
/// way between the last dark and the first lit pixel. Crossings at the image's own edge are
/// left out (the circle goes on beyond it).
fn boundary_points(w: u32, h: u32, bright: impl Fn(u32, u32) -> bool) -> Vec<DVec2> {
    let mut points = Vec::new();
    for y in 0..h {
        let first = (0..w).find(|&x| bright(x, y));
        let last = (0..w).rev().find(|&x| bright(x, y));
        if let (Some(a), Some(b)) = (first, last) {
            if a > 0 {
                points.push(DVec2::new(a as f64 - 0.5, y as f64));
            }
            if b + 1 < w {
                points.push(DVec2::new(b as f64 + 0.5, y as f64));
            }
        }
    }
    for x in 0..w {
        let first = (0..h).find(|&y| bright(x, y));
        let last = (0..h).rev().find(|&y| bright(x, y));
        if let (Some(a), Some(b)) = (first, last) {
            if a > 0 {
                points.push(DVec2::new(x as f64, a as f64 - 0.5));
            }
            if b + 1 < h {
                points.push(DVec2::new(x as f64, b as f64 + 0.5));
            }
        }
    }
    points
}

/// A circle through `points`: the algebraic (Kasa) fit, refined geometrically, refitted
/// without the points more than 3 px (or 3 rms) off it.
pub fn fit_robust(points: &[DVec2]) -> Option<ImageCircle> {
    let mut kept: Vec<DVec2> = points.to_vec();
    let mut circle = fit_geometric(&kept, fit_algebraic(&kept)?)?;
    for _ in 0..3 {
        let cut = (3.0 * circle.rms_px).max(1.5);
        let next: Vec<DVec2> = points
            .iter()
            .copied()
            .filter(|p| ((*p - circle.centre).length() - circle.radius).abs() <= cut)
            .collect();
        if next.len() < MIN_POINTS || next.len() == kept.len() {
            break;
        }
        kept = next;
        circle = fit_geometric(&kept, circle)?;
    }
    Some(circle)
}

/// Kasa's fit: least squares on x^2 + y^2 + D x + E y + F = 0.
fn fit_algebraic(points: &[DVec2]) -> Option<ImageCircle> {
    // Centred for conditioning.
    let mean = points.iter().copied().sum::<DVec2>() / points.len() as f64;
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for p in points {
        let q = *p - mean;
        let row = [q.x, q.y, 1.0];
        let rhs = -(q.x * q.x + q.y * q.y);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * rhs;
        }
    }
    let s = super::solve::solve_dense(&a.iter().flatten().copied().collect::<Vec<_>>(), &b, 3)?;
    let centre = DVec2::new(-s[0] / 2.0, -s[1] / 2.0);
    let r2 = centre.length_squared() - s[2];
    (r2 > 0.0).then(|| ImageCircle {
        centre: centre + mean,
        radius: r2.sqrt(),
        rms_px: f64::INFINITY,
        points: points.len(),
    })
}

/// Gauss-Newton on the points' distances from the circle, from `start`.
fn fit_geometric(points: &[DVec2], start: ImageCircle) -> Option<ImageCircle> {
    let (mut c, mut r) = (start.centre, start.radius);
    for _ in 0..50 {
        let mut a = [0.0f64; 9];
        let mut g = [0.0f64; 3];
        for p in points {
            let d = *p - c;
            let len = d.length().max(1e-12);
            let res = len - r;
            let j = [-d.x / len, -d.y / len, -1.0];
            for i in 0..3 {
                for k in 0..3 {
                    a[i * 3 + k] += j[i] * j[k];
                }
                g[i] -= j[i] * res;
            }
        }
        let step = super::solve::solve_dense(&a, &g, 3)?;
        c += DVec2::new(step[0], step[1]);
        r += step[2];
        if step.iter().all(|s| s.abs() < 1e-9) {
            break;
        }
    }
    let ms = points
        .iter()
        .map(|p| ((*p - c).length() - r).powi(2))
        .sum::<f64>()
        / points.len() as f64;
    (r.is_finite() && r > 0.0 && c.is_finite()).then(|| ImageCircle {
        centre: c,
        radius: r,
        rms_px: ms.sqrt(),
        points: points.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: u32, h: u32, c: DVec2, r: f64) -> EmptyFrame {
        let pixels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let inside = (DVec2::new(x as f64, y as f64) - c).length() <= r;
                if inside {
                    [150.0, 120.0, 200.0]
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        EmptyFrame {
            path: "disc.png".into(),
            width: w,
            height: h,
            pixels,
        }
    }

    #[test]
    fn a_clipped_disc_is_found_to_a_fraction_of_a_pixel() {
        for (c, r) in [
            (DVec2::new(320.0, 240.0), 240.0),
            (DVec2::new(327.3, 233.6), 267.0),
            (DVec2::new(300.5, 250.25), 180.0),
        ] {
            let found = find(&disc(640, 480, c, r)).unwrap();
            assert!((found.centre - c).length() < 0.2, "{found:?} vs {c} {r}");
            assert!((found.radius - r).abs() < 0.3, "{found:?} vs {c} {r}");
        }
    }

    #[test]
    fn frames_without_a_disc_are_refused() {
        let black = disc(64, 48, DVec2::ZERO, 0.0);
        let err = find(&black).unwrap_err().to_string();
        assert!(err.contains("no image circle"), "{err}");
        let mut square = disc(64, 48, DVec2::ZERO, 0.0);
        for (i, p) in square.pixels.iter_mut().enumerate() {
            let (x, y) = (i % 64, i / 64);
            if (10..60).contains(&x) && (10..30).contains(&y) {
                *p = [200.0; 3];
            }
        }
        let err = find(&square).unwrap_err().to_string();
        assert!(
            err.contains("not a circle") || err.contains("not a disc"),
            "{err}"
        );
    }
}
