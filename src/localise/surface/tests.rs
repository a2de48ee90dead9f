use super::*;

/// A smooth reference and a frame with a bump (and optional extra specks) added.
fn frames(cx: f64, cy: f64, radius: f64, amp: f64, specks: &[(u32, u32)]) -> (RgbImage, RgbImage) {
    let (w, h) = (640u32, 480u32);
    let reference = RgbImage::from_fn(w, h, |u, v| {
        image::Rgb([(60 + u / 8) as u8, (80 + v / 8) as u8, 120])
    });
    let mut frame = reference.clone();
    for (u, v, p) in frame.enumerate_pixels_mut() {
        let d2 = (u as f64 - cx).powi(2) + (v as f64 - cy).powi(2);
        let bump = amp * (-d2 / (2.0 * radius * radius)).exp();
        p.0[0] = (p.0[0] as f64 + bump).round().clamp(0.0, 255.0) as u8;
        p.0[1] = (p.0[1] as f64 - 0.5 * bump).round().clamp(0.0, 255.0) as u8;
    }
    for &(u, v) in specks {
        frame.get_pixel_mut(u, v).0[2] = 200;
    }
    (reference, frame)
}

#[test]
fn the_footprint_shortcut_changes_nothing() {
    let sensor = Sensor::preset("paper").unwrap();
    let cache = SurfaceCache::new(&sensor);
    let config = SurfaceConfig::default();
    let cases = [
        (320.0, 240.0, 6.0, 40.0, vec![]),
        (100.0, 240.0, 10.0, 3.0, vec![]),
        (540.0, 30.0, 4.0, 80.0, vec![]),
        (300.0, 200.0, 5.0, 30.0, vec![(310, 215), (40, 240)]),
        (60.0, 240.0, 30.0, 1.2, vec![]),
        // The image's corner sees no finger; a bump on the border of the view.
        (320.0, 2.0, 8.0, 25.0, vec![]),
    ];
    let mut shortcut_taken = 0;
    for (cx, cy, r, amp, specks) in cases {
        let (reference, frame) = frames(cx, cy, r, amp, &specks);
        let fast = detect_with(&sensor, &cache, &config, &reference, &frame, true).unwrap();
        let full = detect_with(&sensor, &cache, &config, &reference, &frame, false).unwrap();
        assert_eq!(
            fast, full,
            "bump at ({cx}, {cy}) radius {r} amplitude {amp}"
        );
        let bbox = difference_box(reference.as_raw(), frame.as_raw(), 640).unwrap();
        if !mostly_outside(&cache, bbox.grown(12, 640, 480)) {
            continue;
        }
        shortcut_taken += 1;
        // Every scale's numbers, not only the outcome: bit for bit.
        let signed = FloatImage {
            width: 640,
            height: 480,
            channels: 3,
            data: reference
                .as_raw()
                .iter()
                .zip(frame.as_raw())
                .map(|(&a, &b)| b as f64 - a as f64)
                .collect(),
        };
        for &size in &config.scales {
            let full = analyse_scale(&signed, &cache, size, &config);
            let part = analyse_footprint(&reference, &frame, bbox, &cache, size, &config);
            assert_eq!(
                (part.sigma, part.peak),
                (full.sigma, full.peak),
                "size {size}"
            );
            let mut in_window = vec![false; full.magnitude.len()];
            for (k, m) in part.magnitude.iter().enumerate() {
                let i = part.window.image_index(k, 640);
                in_window[i] = true;
                assert_eq!(*m, full.magnitude[i], "size {size}, pixel {i}");
            }
            for (i, m) in full.magnitude.iter().enumerate() {
                assert!(in_window[i] || *m == 0.0, "size {size}, pixel {i}: {m}");
            }
        }
    }
    assert!(
        shortcut_taken >= 5,
        "the shortcut was taken {shortcut_taken} times"
    );
}

#[test]
fn difference_box_bounds_every_changed_pixel() {
    let a = vec![7u8; 3 * 10 * 4];
    let mut b = a.clone();
    assert_eq!(difference_box(&a, &b, 10), None);
    b[3 * (10 + 2) + 1] = 9; // (2, 1), green
    b[3 * (3 * 10 + 7) + 2] = 0; // (7, 3), blue
    assert_eq!(
        difference_box(&a, &b, 10),
        Some(Window {
            x0: 2,
            y0: 1,
            x1: 8,
            y1: 4
        })
    );
}
