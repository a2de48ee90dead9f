//! Bad sensor configurations are refused with a one-line error that names the field.

mod common;

use geltip::sensor::{Sensor, SensorConfig, PRESETS};

fn assert_refused(config: SensorConfig, field: &str) {
    let err = Sensor::from_config("test", config)
        .expect_err("config should be refused")
        .to_string();
    assert!(err.contains(field), "error '{err}' does not name '{field}'");
    assert!(!err.contains('\n'), "error is not one line: {err:?}");
}

fn paper_toml() -> String {
    PRESETS
        .iter()
        .find(|(n, _)| *n == "paper")
        .unwrap()
        .1
        .to_string()
}

#[test]
fn presets_load_and_validate() {
    for (name, _) in PRESETS {
        let s = Sensor::load(name).unwrap();
        assert_eq!(s.width, 640);
        assert!(!s.config.description.is_empty());
    }
}

#[test]
fn non_positive_radius() {
    for r in [0.0, -7.5] {
        let mut c = common::paper_config();
        c.finger.radius_mm = r;
        assert_refused(c, "finger.radius_mm");
    }
}

#[test]
fn a_finger_too_big_to_compute_with() {
    for r in [1e308, 2e245, 1001.0] {
        let mut c = common::paper_config();
        c.finger.radius_mm = r;
        assert_refused(c, "finger.radius_mm: must be at most 1000 mm");
        let mut c = common::paper_config();
        c.finger.cylinder_length_mm = r;
        assert_refused(c, "finger.cylinder_length_mm: must be at most 1000 mm");
    }
}

#[test]
fn nan_and_infinite_fields() {
    let mut c = common::paper_config();
    c.finger.radius_mm = f64::NAN;
    assert_refused(c, "finger.radius_mm");
    let mut c = common::paper_config();
    c.finger.cylinder_length_mm = f64::INFINITY;
    assert_refused(c, "finger.cylinder_length_mm");
    let mut c = common::paper_config();
    c.lens.focal_px = f64::NAN;
    assert_refused(c, "lens.focal_px");
    let mut c = common::paper_config();
    c.lens.cx = f64::NAN;
    assert_refused(c, "lens.cx");
    let mut c = common::paper_config();
    c.lens.model = geltip::LensModel::KannalaBrandt;
    c.lens.k[2] = f64::NAN;
    assert_refused(c, "lens.k[2]");
    // NaN written in the TOML itself.
    let text = paper_toml().replace("radius_mm = 7.5", "radius_mm = nan");
    let err = Sensor::from_toml("nan.toml", &text)
        .unwrap_err()
        .to_string();
    assert!(err.contains("finger.radius_mm"), "{err}");
}

#[test]
fn pinhole_cannot_pass_180_degrees() {
    for fov in [180.0, 190.0] {
        let mut c = common::paper_config();
        c.lens.model = geltip::LensModel::Pinhole;
        c.lens.fov_deg = fov;
        assert_refused(c, "lens.fov_deg");
    }
    let mut c = common::paper_config();
    c.lens.fov_deg = 360.0;
    assert_refused(c, "lens.fov_deg");
}

#[test]
fn principal_point_outside_the_image() {
    let mut c = common::paper_config();
    c.lens.cx = 700.0;
    assert_refused(c, "lens.cx");
    let mut c = common::paper_config();
    c.lens.cy = -1.0;
    assert_refused(c, "lens.cy");
}

#[test]
fn other_impossible_values() {
    let mut c = common::paper_config();
    c.finger.shell_thickness_mm = 8.0;
    assert_refused(c, "finger.shell_thickness_mm");
    let mut c = common::paper_config();
    c.image.width = 0;
    assert_refused(c, "image.width");
    let mut c = common::paper_config();
    c.lens.k = [0.1, 0.0, 0.0, 0.0];
    assert_refused(c, "lens.k");
    let mut c = common::paper_config();
    c.lens.model = geltip::LensModel::KannalaBrandt;
    c.lens.k = [-0.4, 0.0, 0.0, 0.0];
    assert_refused(c, "lens.k");
    for spacing in [0.0, -1.0, f64::NAN, 6.5] {
        let mut c = common::paper_config();
        c.render.blend_tap_spacing = spacing;
        assert_refused(c, "render.blend_tap_spacing");
    }
}

#[test]
fn parse_errors_name_the_key() {
    let cases = [
        (
            paper_toml().replace("\"equidistant\"", "\"fisheye\""),
            "lens.model",
        ),
        (
            paper_toml().replace("radius_mm = 7.5", "radius_mm = \"big\""),
            "finger.radius_mm",
        ),
        (
            paper_toml().replace("width = 640", "width = -640"),
            "image.width",
        ),
        (
            paper_toml().replace("focal_px = 180.0", "focal_pix = 180.0"),
            "focal_pix",
        ),
        (paper_toml().replace("cx = 320.0\n", ""), "cx"),
        ("[finger".to_string(), "line 1"),
    ];
    for (text, field) in cases {
        let err = Sensor::from_toml("bad.toml", &text)
            .unwrap_err()
            .to_string();
        assert!(err.contains(field), "error '{err}' does not name '{field}'");
        assert!(
            err.contains("bad.toml"),
            "error '{err}' does not name the file"
        );
        assert!(!err.contains('\n'), "error is not one line: {err:?}");
    }
}

#[test]
fn unknown_sensor_lists_presets() {
    let err = Sensor::load("no-such-sensor").unwrap_err().to_string();
    assert!(
        err.contains("no-such-sensor") && err.contains("paper"),
        "{err}"
    );
}

#[test]
fn config_round_trips_through_toml() {
    let c = common::paper_config();
    let text = toml::to_string(&c).unwrap();
    assert_eq!(SensorConfig::from_toml(&text, "x").unwrap(), c);
}
