//! The paper's localiser steps (difference, mean filter, threshold, regions, area filter,
//! ellipse fit, centres) on small constructed images.

use geltip::localise::paper::{
    self, area_filter, area_range, brightness, fit_ellipse, mean_filter, regions, threshold,
    weighted_centre, Blob,
};
use geltip::localise::raster::FloatImage;
use glam::DVec2;
use image::{Rgb, RgbImage};

fn gray(width: u32, height: u32, f: impl Fn(u32, u32) -> f64) -> FloatImage {
    let data = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| f(x, y))
        .collect();
    FloatImage::from_gray(width, height, data).unwrap()
}

#[test]
fn difference_is_absolute_per_channel() {
    let a = RgbImage::from_pixel(3, 2, Rgb([10, 200, 50]));
    let mut b = a.clone();
    b.put_pixel(1, 1, Rgb([30, 150, 50]));
    let d = paper::difference(&a, &b).unwrap();
    assert_eq!(d.channels, 3);
    assert_eq!(d.get(1, 1, 0), 20.0);
    assert_eq!(d.get(1, 1, 1), 50.0);
    assert_eq!(d.get(1, 1, 2), 0.0);
    assert_eq!(d.get(0, 0, 1), 0.0);
    let err = paper::difference(&a, &RgbImage::new(2, 3))
        .unwrap_err()
        .to_string();
    assert!(err.contains("2x3") && err.contains("3x2"), "{err}");
}

#[test]
fn mean_filter_keeps_a_constant_image_constant() {
    let img = gray(40, 30, |_, _| 7.25);
    let out = mean_filter(&img, 15);
    for v in &out.data {
        assert!((v - 7.25).abs() < 1e-12, "{v}");
    }
}

#[test]
fn mean_filter_spreads_an_impulse_over_a_15x15_box() {
    let (w, h) = (50u32, 40u32);
    let k = 1.0 / 225.0;
    // Inside: a 15x15 box of 1/225 centred on the impulse, zero elsewhere.
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 20 && y == 18)), 15);
    for y in 0..h {
        for x in 0..w {
            let inside = (13..=27).contains(&x) && (11..=25).contains(&y);
            let want = if inside { k } else { 0.0 };
            assert!((out.get(x, y, 0) - want).abs() < 1e-15, "({x}, {y})");
        }
    }
    // Borders are BORDER_REFLECT_101 (OpenCV's default for blur): the edge pixel is not
    // repeated, so an impulse on the corner is counted once (the sum is not preserved)...
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 0 && y == 0)), 15);
    assert!((out.get(0, 0, 0) - k).abs() < 1e-15);
    assert!((out.get(7, 7, 0) - k).abs() < 1e-15);
    assert!(out.get(8, 0, 0).abs() < 1e-15);
    // ...while one pixel in from the corner is mirrored across each edge: twice per axis.
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 1 && y == 1)), 15);
    assert!((out.get(0, 0, 0) - 4.0 * k).abs() < 1e-15);
    assert!((out.get(0, 8, 0) - 2.0 * k).abs() < 1e-15);
    assert!((out.get(8, 8, 0) - k).abs() < 1e-15);
    assert!(out.get(9, 9, 0).abs() < 1e-15);
}

#[test]
fn threshold_zeroes_pixels_under_60_percent_of_the_brightest() {
    // Brightness is the mean of the channels: (90 + 120 + 90) / 3 = 100 at the peak.
    let mut diff = FloatImage::zeros(5, 1, 3);
    let pixels = [
        [90.0, 120.0, 90.0],
        [60.0, 60.0, 60.0],
        [59.0, 59.0, 59.5],
        [61.0; 3],
        [0.0; 3],
    ];
    for (x, p) in pixels.iter().enumerate() {
        for (c, &v) in p.iter().enumerate() {
            diff.set(x as u32, 0, c, v);
        }
    }
    let b = brightness(&diff);
    assert_eq!(b.data, vec![100.0, 60.0, 59.166666666666664, 61.0, 0.0]);
    let t = threshold(&b, 0.6);
    assert_eq!(t.data, vec![100.0, 60.0, 0.0, 61.0, 0.0]);
    // An all-zero image stays zero; scaling the image does not move the cut.
    assert!(threshold(&gray(4, 4, |_, _| 0.0), 0.6)
        .data
        .iter()
        .all(|&v| v == 0.0));
    let scaled = gray(5, 1, |x, _| b.data[x as usize] * 0.1);
    let t2 = threshold(&scaled, 0.6);
    for (a, b) in t2.data.iter().zip(&t.data) {
        assert!((a - b * 0.1).abs() < 1e-12);
    }
}

/// A filled disc of `radius` px centred at (cx, cy) on a 100x100 image.
fn disc(cx: f64, cy: f64, radius: f64) -> FloatImage {
    gray(100, 100, |x, y| {
        f64::from(DVec2::new(x as f64 - cx, y as f64 - cy).length() <= radius)
    })
}

#[test]
fn regions_are_8_connected_with_outer_contours_and_opencv_areas() {
    // A filled 10x6 rectangle: contour through the border pixel centres, area 9 x 5.
    let img = gray(30, 20, |x, y| {
        f64::from((5..15).contains(&x) && (3..9).contains(&y))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].pixel_count(), 60);
    assert_eq!(r[0].area, 45.0);
    assert_eq!(r[0].contour.len(), 2 * (9 + 5));
    assert_eq!(r[0].contour[0], DVec2::new(5.0, 3.0));
    // Diagonal neighbours join; a gap splits; a lone pixel has area 0.
    let img = gray(10, 10, |x, y| {
        f64::from((x == 1 && y == 1) || (x == 2 && y == 2) || (x == 6 && y == 6))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 2);
    assert_eq!(r[0].pixel_count(), 2);
    assert_eq!(r[1].pixel_count(), 1);
    assert_eq!(r[1].area, 0.0);
    // A ring is one region; its hole is not a region of its own.
    let img = gray(40, 40, |x, y| {
        let d = DVec2::new(x as f64 - 20.0, y as f64 - 20.0).length();
        f64::from((5.0..9.0).contains(&d))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    assert!(r[0].area > 200.0, "outer contour area {}", r[0].area);
}

#[test]
fn area_filter_keeps_80_px_and_rejects_20_and_300_px() {
    let picture = 640.0 * 480.0;
    let (lo, hi) = area_range(picture);
    assert!((lo - 36.864).abs() < 1e-9 && (hi - 122.88).abs() < 1e-9);
    let img = {
        let a = disc(15.0, 15.0, 2.6);
        let b = disc(50.0, 20.0, 5.1);
        let c = disc(50.0, 65.0, 9.8);
        gray(100, 100, |x, y| {
            a.get(x, y, 0) + b.get(x, y, 0) + c.get(x, y, 0)
        })
    };
    let r = regions(&img);
    let counts: Vec<usize> = r.iter().map(Blob::pixel_count).collect();
    assert_eq!(r.len(), 3, "{counts:?}");
    for (n, want) in counts.iter().zip([21usize, 81, 301]) {
        assert!(n.abs_diff(want) <= 12, "pixel counts {counts:?}");
    }
    let kept = area_filter(r, picture);
    assert_eq!(
        kept.len(),
        1,
        "kept {:?}",
        kept.iter().map(|b| b.area).collect::<Vec<_>>()
    );
    assert!(kept[0].pixel_count().abs_diff(81) <= 12);
    assert!((lo..=hi).contains(&kept[0].area));
}

#[test]
fn ellipse_fit_recovers_centre_axes_and_angle() {
    // Points exactly on an ellipse: exact recovery.
    let (c, a, b, t) = (DVec2::new(40.3, 27.8), 12.0, 5.0, 0.5f64);
    let rot = DVec2::from_angle(t);
    let pts: Vec<DVec2> = (0..40)
        .map(|i| {
            let u = i as f64 * std::f64::consts::TAU / 40.0;
            c + rot.rotate(DVec2::new(a * u.cos(), b * u.sin()))
        })
        .collect();
    let e = fit_ellipse(&pts).expect("fit");
    assert!((e.centre - c).length() < 1e-9, "centre {}", e.centre);
    assert!(
        (e.semi_axes - DVec2::new(a, b)).length() < 1e-9,
        "{}",
        e.semi_axes
    );
    assert!((e.angle - t).abs() < 1e-9, "angle {}", e.angle);
    // A rasterised ellipse: its contour runs through border pixel centres, about half a
    // pixel inside the true outline.
    let img = gray(100, 70, |x, y| {
        let q = DVec2::from_angle(-t).rotate(DVec2::new(x as f64, y as f64) - c);
        f64::from((q.x / a).powi(2) + (q.y / b).powi(2) <= 1.0)
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    let e = fit_ellipse(&r[0].contour).expect("fit");
    assert!((e.centre - c).length() < 0.2, "centre {} vs {c}", e.centre);
    assert!((e.semi_axes.x - a).abs() < 1.0, "major {}", e.semi_axes.x);
    assert!((e.semi_axes.y - b).abs() < 1.0, "minor {}", e.semi_axes.y);
    assert!((e.angle - t).abs() < 0.05, "angle {}", e.angle);
    // Too few or collinear points: no fit (the detector falls back to the centroid).
    assert!(fit_ellipse(&pts[..4]).is_none());
    let line: Vec<DVec2> = (0..10)
        .map(|i| DVec2::new(i as f64, 2.0 * i as f64))
        .collect();
    assert!(fit_ellipse(&line).is_none());
    let mut with_nan = pts.clone();
    with_nan[3] = DVec2::NAN;
    assert!(fit_ellipse(&with_nan).is_none());
}

#[test]
fn centres_are_averaged_by_area() {
    let img = {
        let a = disc(20.0, 20.0, 5.0);
        let b = disc(70.0, 60.0, 3.0);
        gray(100, 100, |x, y| a.get(x, y, 0) + b.get(x, y, 0))
    };
    let r = regions(&img);
    assert_eq!(r.len(), 2);
    let (wa, wb) = (r[0].area, r[1].area);
    let want = (wa * DVec2::new(20.0, 20.0) + wb * DVec2::new(70.0, 60.0)) / (wa + wb);
    let got = weighted_centre(&r).unwrap();
    assert!((got - want).length() < 1e-6, "{got} vs {want}");
    assert!(weighted_centre(&[]).is_none());
}
