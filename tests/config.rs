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
        assert_eq!(s.width, s.config.image.width);
        assert!(s.width >= 480);
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

/// A sensor file with its LEDs listed (`[[leds]]`), its light (`[light]`), a coloured paint
/// and noise per channel: loaded and written back the same.
#[test]
fn listed_leds_light_paint_colour_and_channel_noise_load() {
    use geltip::sensor::{Leds, Noise};
    let text = paper_toml() + "\n" + include_str!("common/calibrated_light.toml");
    let s = Sensor::from_toml("listed", &text).unwrap();
    let Leds::List(list) = &s.config.leds else {
        panic!("a list: {:?}", s.config.leds);
    };
    assert_eq!(list.len(), 2);
    // The second LED takes the ring's defaults for what it leaves out.
    assert_eq!(
        (list[1].z_mm, list[1].intensity, list[1].spread),
        (-2.0, 2.0, 2.0)
    );
    let light = s.lighting();
    assert_eq!(light.leds.len(), 2);
    assert!(
        (light.leds[0].position.length() - (4.0f64.powi(2) + 1.5f64.powi(2)).sqrt()).abs() < 1e-12
    );
    assert_eq!(light.ambient.to_array(), [0.1, 0.05, 0.3]);
    assert_eq!(s.config.render.noise, Noise::Rgb([1.5, 2.0, 0.5]));
    let again = toml::to_string(&s.config).unwrap();
    assert_eq!(Sensor::from_toml("again", &again).unwrap().config, s.config);
}

/// A file that lists no LEDs lights the finger with the ring of three the presets describe,
/// and the ambient light they set.
#[test]
fn a_ring_of_leds_resolves_to_its_three_leds() {
    let paper = Sensor::preset("paper").unwrap().lighting();
    assert_eq!(paper.leds.len(), 3);
    assert_eq!(paper.ambient.to_array(), [0.06; 3]);
}

/// Listed LEDs, light, paint colour and per-channel noise out of range or of the wrong shape
/// are refused on one line naming the field.
#[test]
fn listed_leds_light_paint_colour_and_channel_noise_are_refused_by_field() {
    for (bad, field) in [
        (
            "[[leds]]\ncolour = [1.0, -0.1, 0.0]\nazimuth_deg = 0.0\n",
            "leds[0].colour[1]",
        ),
        (
            "[[leds]]\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nz_mm = 30.0\n",
            "leds[0].z_mm",
        ),
        (
            "[[leds]]\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nradius_mm = 7.5\n",
            "leds[0].radius_mm",
        ),
        (
            "[[leds]]\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nfalloff_mm = 0.0\n",
            "leds[0].falloff_mm",
        ),
        ("[[leds]]\ncolour = [1.0, 0.0]\nazimuth_deg = 0.0\n", "leds"),
        (
            "[[leds]]\ncolour = [1.0, 0.0, 0.0]\nazimuth = 0.0\n",
            "leds",
        ),
        ("[light]\nvignetting = [-1.5, 0.0]\n", "light.vignetting"),
        ("[light]\nambient = [0.1, 0.1, nan]\n", "light.ambient[2]"),
        (
            "[light]\nambient_relief = [1.0, inf, 0.0]\n",
            "light.ambient_relief[1]",
        ),
        ("[paint]\ncolour = [1.0, 1.0, -1.0]\n", "paint.colour[2]"),
        ("[render]\nnoise = [1.0, -2.0, 0.0]\n", "render.noise[1]"),
        ("[render]\nnoise = \"loud\"\n", "render.noise"),
        ("[camera]\nblur_px = -1.0\n", "camera.blur_px"),
        ("[camera]\nblur_px = nan\n", "camera.blur_px"),
        ("[camera]\nblur_px = 25.0\n", "camera.blur_px"),
        (
            "[camera]\nblur_px = 2.0\n[render]\nnoise = 2.0\n",
            "camera.blur_px",
        ),
    ] {
        let text = paper_toml() + "\n" + bad;
        let err = Sensor::from_toml("bad", &text).expect_err(bad).to_string();
        assert!(err.contains(field), "'{err}' does not name {field}");
        assert!(!err.contains('\n'), "{err:?}");
    }
    let many: String = (0..17)
        .map(|k| {
            format!(
                "[[leds]]\ncolour = [1.0, 1.0, 1.0]\nazimuth_deg = {}\n",
                20 * k
            )
        })
        .collect();
    let err = Sensor::from_toml("many", &(paper_toml() + "\n" + &many))
        .unwrap_err()
        .to_string();
    assert!(err.contains("leds") && err.contains("1 to 16"), "{err}");
}

/// Gel LEDs (light carried up the gel) and a camera with its own colour matrix and gamma:
/// loaded, resolved and written back the same; the `allsight` preset has nine such LEDs.
#[test]
fn gel_leds_and_a_camera_response_load_and_round_trip() {
    use geltip::sensor::{LedKind, Leds};
    let text = paper_toml()
        + "\n[[leds]]\nkind = \"gel\"\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 30.0\nwidth_mm = 2.5\n"
        + "[[leds]]\ncolour = [0.0, 1.0, 0.0]\nazimuth_deg = 150.0\n"
        + "[camera]\ncolour_matrix = [[1.0, -0.2, 0.0], [0.0, 1.0, 0.0], [0.0, -0.1, 1.0]]\ngamma = [2.4, 2.2, 3.0]\n";
    let s = Sensor::from_toml("gel", &text).unwrap();
    let light = s.lighting();
    let LedKind::Gel(band) = light.leds[0].kind else {
        panic!("a gel LED: {:?}", light.leds[0]);
    };
    assert_eq!(band.width_mm, 2.5);
    assert_eq!(band.widening, geltip::sensor::GelSpread::DEFAULT.widening);
    assert_eq!(light.leds[1].kind, LedKind::Point);
    assert_eq!(light.camera.gamma, [2.4, 2.2, 3.0]);
    let again = toml::to_string(&s.config).unwrap();
    assert_eq!(Sensor::from_toml("again", &again).unwrap().config, s.config);
    // A sensor without [camera] writes none.
    assert!(!toml::to_string(&common::paper_config())
        .unwrap()
        .contains("camera"));
    let allsight = Sensor::preset("allsight").unwrap();
    let Leds::List(list) = &allsight.config.leds else {
        panic!("listed LEDs");
    };
    assert_eq!(list.len(), 9);
    assert!(allsight
        .lighting()
        .leds
        .iter()
        .all(|l| matches!(l.kind, LedKind::Gel(_))));
}

/// A gel LED's band, and the camera, out of range are refused naming the field; a point LED
/// given a band is refused too.
/// A `[shell_end]` table whose keys are sound but for `bad` (a key = value line replacing
/// that key's).
fn shell_end(bad: &str) -> String {
    let key = bad.split(' ').next().unwrap();
    [
        "z_mm = 20.0",
        "inner_radius_mm = 5.0",
        "tip_colour = [0.1, 0.1, 0.2]",
        "tip_transmit = 0.3",
        "rim_glow = 0.4",
        "rim_width_mm = 2.0",
    ]
    .iter()
    .map(|line| if line.starts_with(key) { bad } else { line })
    .fold("[shell_end]\n".to_string(), |text, line| text + line + "\n")
}

#[test]
fn gel_leds_the_camera_and_a_shell_end_are_refused_by_field() {
    // The shell's end the bad cases below spoil one key of loads as it is,
    // and is written back the same.
    let sound = Sensor::from_toml("sound", &(paper_toml() + "\n" + &shell_end("z_mm = 20.0")))
        .unwrap()
        .config;
    assert_eq!(sound.shell_end.map(|e| e.z_mm), Some(20.0));
    let text = toml::to_string(&sound).unwrap();
    assert_eq!(SensorConfig::from_toml(&text, "written").unwrap(), sound);
    for (bad, field) in [
        (
            "[[leds]]\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nwidth_mm = 2.0\n",
            "leds[0].width_mm",
        ),
        (
            "[[leds]]\nkind = \"gel\"\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nwidth_mm = 0.0\n",
            "leds[0].width_mm",
        ),
        (
            "[[leds]]\nkind = \"gel\"\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\nattenuation_mm = -1.0\n",
            "leds[0].attenuation_mm",
        ),
        (
            "[[leds]]\nkind = \"glow\"\ncolour = [1.0, 0.0, 0.0]\nazimuth_deg = 0.0\n",
            "leds",
        ),
        ("[camera]\ngamma = [2.2, 0.0, 2.2]\n", "camera.gamma[1]"),
        ("[camera]\ngamma = [2.2, 2.2, 9.0]\n", "camera.gamma[2]"),
        (
            "[camera]\ncolour_matrix = [[1.0, 0.0, 0.0], [0.0, nan, 0.0], [0.0, 0.0, 1.0]]\n",
            "camera.colour_matrix[1][1]",
        ),
        ("[shell_end]\nz_mm = 20.0\ninner_radius_mm = 5.0\n", "shell_end"),
    ]
    .map(|(bad, field)| (bad.to_string(), field))
    .into_iter()
    .chain([
        (shell_end("inner_radius_mm = 30.0"), "shell_end.inner_radius_mm"),
        (shell_end("z_mm = 0.0"), "shell_end.z_mm"),
        (shell_end("tip_colour = [0.1, -0.1, 0.1]"), "shell_end.tip_colour[1]"),
        (shell_end("rim_glow = -2.0"), "shell_end.rim_glow"),
        (shell_end("rim_width_mm = inf"), "shell_end.rim_width_mm"),
        (
            shell_end("rim_width_mm = 2.0") + "led_glow_deg = 0.0\n",
            "shell_end.led_glow_deg",
        ),
    ]) {
        let bad = bad.as_str();
        let text = paper_toml() + "\n" + bad;
        let err = Sensor::from_toml("bad", &text).expect_err(bad).to_string();
        assert!(err.contains(field), "'{err}' does not name {field}");
        assert!(!err.contains('\n'), "{err:?}");
    }
}

/// A thick gel needs no hand-set drape: a file that gives none gets the gel's thickness (2 mm
/// for thinner gels, as before); a drape given thinner than the gel is still refused.
#[test]
fn a_thick_gel_gets_a_drape_of_its_thickness() {
    let thick = paper_toml().replace("shell_thickness_mm = 1.5", "shell_thickness_mm = 3.5");
    assert_ne!(thick, paper_toml());
    let s = Sensor::from_toml("thick", &thick).unwrap();
    assert_eq!(s.config.elastomer.drape_mm, 3.5);
    assert_eq!(
        Sensor::preset("paper").unwrap().config.elastomer.drape_mm,
        2.0
    );
    assert_eq!(
        Sensor::preset("allsight")
            .unwrap()
            .config
            .elastomer
            .drape_mm,
        3.5
    );
    let err = Sensor::from_toml("thin drape", &(thick + "\n[elastomer]\ndrape_mm = 2.0\n"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("elastomer.drape_mm"), "{err}");
}

/// An image circle cut by the camera (`image.circle`): loaded and written back the same,
/// and refused on one line naming the field when it is not a circle on the image.
#[test]
fn an_image_circle_mask_loads_round_trips_and_is_refused_by_field() {
    let text = paper_toml().replace("[image]\n", "[image]\ncircle = [318.5, 241.0, 230.0]\n");
    let c = SensorConfig::from_toml(&text, "masked").unwrap();
    assert_eq!(c.image.circle, Some([318.5, 241.0, 230.0]));
    let written = toml::to_string(&c).unwrap();
    assert_eq!(SensorConfig::from_toml(&written, "x").unwrap(), c);
    // Without one, nothing is written: the presets' files stay as they were.
    let plain = common::paper_config();
    assert!(!toml::to_string(&plain).unwrap().contains("circle"));

    for (circle, field) in [
        ([f64::NAN, 240.0, 200.0], "image.circle[0]"),
        ([320.0, f64::INFINITY, 200.0], "image.circle[1]"),
        ([320.0, 240.0, 0.0], "image.circle[2]"),
        ([320.0, 240.0, -5.0], "image.circle[2]"),
        (
            [-1.0, 240.0, 200.0],
            "image.circle: centre (-1, 240) is outside the image",
        ),
        (
            [320.0, 481.0, 200.0],
            "image.circle: centre (320, 481) is outside the image",
        ),
    ] {
        let mut bad = plain.clone();
        bad.image.circle = Some(circle);
        assert_refused(bad, field);
    }
}

/// `camera.blur_px` loads, writes back and round-trips (alone in its table); left out it is
/// 0 and not written.
#[test]
fn a_camera_blur_round_trips_and_is_left_out_when_none() {
    let sharp = Sensor::from_toml("sharp", &paper_toml()).unwrap();
    assert_eq!(sharp.config.camera.blur_px, 0.0);
    assert!(!toml::to_string(&sharp.config).unwrap().contains("blur_px"));
    let s = Sensor::from_toml("soft", &(paper_toml() + "\n[camera]\nblur_px = 2.5\n")).unwrap();
    assert_eq!(s.config.camera.blur_px, 2.5);
    assert!(s.config.camera.has_default_response());
    let written = toml::to_string(&s.config).unwrap();
    assert!(written.contains("blur_px = 2.5"), "{written}");
    assert_eq!(
        Sensor::from_toml("back", &written).unwrap().config,
        s.config
    );
}

/// `light.ambient_relief` loads, writes back and round-trips; left out it is flat and not
/// written, so a file without it is the same file.
#[test]
fn an_ambient_that_shades_with_tilt_round_trips_and_is_left_out_when_flat() {
    let flat = Sensor::from_toml("flat", &paper_toml()).unwrap();
    assert_eq!(flat.config.light.ambient_relief, [0.0; 3]);
    assert!(!toml::to_string(&flat.config)
        .unwrap()
        .contains("ambient_relief"));
    let text =
        paper_toml() + "\n[light]\nambient = [0.1, 0.1, 0.1]\nambient_relief = [1.5, -0.5, 0.0]\n";
    let s = Sensor::from_toml("tilted", &text).unwrap();
    assert_eq!(s.config.light.ambient_relief, [1.5, -0.5, 0.0]);
    let written = toml::to_string(&s.config).unwrap();
    assert!(written.contains("ambient_relief"), "{written}");
    let back = Sensor::from_toml("back", &written).unwrap();
    assert_eq!(back.config, s.config);
}

/// An LED's glow at a shell's end (`end_glow`) needs the end's `led_glow_deg`, and each of
/// its channels above -1; with both it loads, writes and loads back the same.
#[test]
fn an_leds_end_glow_needs_the_ends_spread_and_is_refused_on_one_line() {
    // The `allsight` preset glows; the checks start from it without its glow.
    let glows = Sensor::preset("allsight").unwrap().lighting();
    assert!(glows.shell_end.and_then(|e| e.led_glow_deg).is_some());
    assert!(glows
        .leds
        .iter()
        .any(|l| l.end_glow.abs().max_element() > 0.1));
    let preset: String = include_str!("../assets/sensors/allsight.toml")
        .lines()
        .filter(|l| !l.starts_with("end_glow = ") && !l.starts_with("led_glow_deg = "))
        .map(|l| format!("{l}\n"))
        .collect();
    let first_led = "[[leds]]\nkind = \"gel\"\n";
    assert!(preset.contains(first_led));
    let glowing =
        |glow: &str| preset.replacen(first_led, &format!("{first_led}end_glow = {glow}\n"), 1);
    let spread =
        |text: String| text.replacen("[shell_end]\n", "[shell_end]\nled_glow_deg = 25.0\n", 1);
    for (text, field) in [
        (glowing("[0.5, 0.0, 0.2]"), "leds[0].end_glow"),
        (spread(glowing("[-1.5, 0.0, 0.2]")), "leds[0].end_glow[0]"),
        (spread(glowing("[0.5, nan, 0.2]")), "leds[0].end_glow[1]"),
    ] {
        let err = Sensor::from_toml("bad", &text)
            .expect_err(field)
            .to_string();
        assert!(err.contains(field), "'{err}' does not name {field}");
        assert!(!err.contains('\n'), "{err:?}");
    }
    let sensor = Sensor::from_toml("glow", &spread(glowing("[0.5, 0.0, 0.2]"))).unwrap();
    assert_eq!(
        sensor.lighting().leds[0].end_glow.to_array(),
        [0.5, 0.0, 0.2]
    );
    let written = toml::to_string(&sensor.config).unwrap();
    let again = Sensor::from_toml("again", &written).unwrap();
    assert_eq!(again.config, sensor.config);
}
