//! The localiser's interface: size errors, method names, detection JSON, image files.

mod imprints;

use geltip::finger::SurfaceCoord;
use geltip::localise::{load_frame, load_image, localise, Detection, Method};
use geltip::GeltipError;
use glam::DVec2;
use image::RgbImage;
use imprints::*;

#[test]
fn wrong_sizes_are_errors_naming_both_sizes() {
    let small = RgbImage::new(320, 240);
    let big = RgbImage::new(640, 480);
    for method in Method::ALL {
        let err = localise(sensor(), &small, &small, method).unwrap_err();
        assert!(matches!(err, GeltipError::InvalidInput { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
        assert!(!msg.contains('\n'));
        let msg = localise(sensor(), &big, &small, method)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
        let msg = localise(sensor(), &small, &big, method)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
    }
}

#[test]
fn method_names_round_trip() {
    assert_eq!(Method::ALL.len(), 2);
    for m in Method::ALL {
        assert_eq!(Method::from_name(m.name()).unwrap(), m);
    }
    let msg = Method::from_name("sobel").unwrap_err().to_string();
    assert!(
        msg.contains("sobel") && msg.contains("paper") && msg.contains("surface"),
        "{msg}"
    );
}

#[test]
fn detection_json_has_every_field_and_no_nan() {
    let f = sensor().finger;
    let truth = f.point_at(SurfaceCoord { s: 4.0, phi: 1.0 }).point;
    let frame = paint(
        gradient_reference(),
        truth,
        Paint::Blob { sigma_mm: 0.6 },
        60.0,
    );
    let d = localiser()
        .localise(gradient_reference(), &frame, Method::Surface)
        .unwrap();
    let j = d.to_json();
    assert_eq!(j["detected"], true);
    assert_eq!(j["pixel"].as_array().unwrap().len(), 2);
    let p = j["point"].as_array().unwrap();
    assert_eq!(p.len(), 3);
    assert!((p[2].as_f64().unwrap() - d.point.unwrap().z).abs() < 1e-12);
    assert_eq!(j["region"], "hemisphere");
    assert!(j["confidence"].as_f64().unwrap() > 0.5);
    assert_eq!(j["regions_found"], 1);
    assert!(j["note"].is_null());
    // A pixel that sees no part of the finger (the image corner, outside the lens circle)
    // is "not detected" with a note, never NaN.
    let d = Detection::at_pixel(sensor(), DVec2::new(0.0, 0.0), 0.7, 2);
    assert_not_detected(&d, "corner");
    assert_eq!(d.regions_found, 2);
    let j = d.to_json();
    assert!(j["pixel"].is_null() && j["point"].is_null() && j["region"].is_null());
    let d = Detection::at_pixel(sensor(), DVec2::new(f64::NAN, 3.0), f64::NAN, 0);
    assert_not_detected(&d, "NaN pixel");
}

#[test]
fn images_load_and_bad_files_are_one_line_errors() {
    let dir = std::env::temp_dir().join(format!("geltip-localise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("frame.png");
    gradient_reference().save(&good).unwrap();
    let img = load_image(&good).unwrap();
    assert_eq!(&img, gradient_reference());
    assert_eq!(&load_frame(sensor(), &good).unwrap(), gradient_reference());

    let small = dir.join("small.png");
    RgbImage::new(32, 24).save(&small).unwrap();
    let err = load_frame(sensor(), &small).unwrap_err();
    assert!(matches!(err, GeltipError::InvalidImage { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("32x24") && msg.contains("640x480") && msg.contains("small.png"),
        "{msg}"
    );

    let garbage = dir.join("garbage.png");
    std::fs::write(&garbage, b"not a png\nat all").unwrap();
    for path in [garbage, dir.join("missing.png")] {
        let err = load_image(&path).unwrap_err();
        assert!(matches!(err, GeltipError::InvalidImage { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(
            msg.contains(path.file_name().unwrap().to_str().unwrap()),
            "{msg}"
        );
        assert!(!msg.contains('\n'), "{msg}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
