//! The sensor-design jobs: preview numbers against hand computations, the stability sweep's
//! invariants, and the tradeoff's Pareto front.

mod common;

use geltip::jobs::{preview, stability, tradeoff};
use geltip::localise::Method;
use geltip::sensor::Sensor;
use geltip::LensModel;
use std::f64::consts::FRAC_PI_2;

fn gpu_env() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
}

/// The paper's finger behind a pinhole lens of `fov` degrees on an image large enough that
/// the lens, not the image, limits the view.
fn pinhole(fov: f64) -> Sensor {
    let mut c = common::paper_config();
    c.lens.model = LensModel::Pinhole;
    c.lens.fov_deg = fov;
    c.lens.focal_px = 400.0;
    c.image.width = 4000;
    c.image.height = 4000;
    c.lens.cx = 2000.0;
    c.lens.cy = 2000.0;
    Sensor::from_config(format!("pinhole{fov}"), c).unwrap()
}

#[test]
fn pinhole_sees_down_to_r_over_tan_half_fov() {
    for fov in [50.0f64, 70.0, 100.0] {
        let s = pinhole(fov);
        let (r, d) = (7.5, 20.0);
        let z_min = r / (0.5 * fov.to_radians()).tan();
        let p = preview::analyse(&s).unwrap();
        // All round: the lens is round and the image does not crop.
        assert!(
            (p.lowest_z - z_min).abs() < 1e-6,
            "fov {fov}: {} vs {z_min}",
            p.lowest_z
        );
        assert!((p.lowest_z_all_round - z_min).abs() < 1e-6);
        let s_hand = FRAC_PI_2 * r + (d - z_min);
        assert!((p.visible_s_max - s_hand).abs() < 1e-6);
        // Area: the hemisphere and the cylinder down to z_min.
        let area = 2.0 * std::f64::consts::PI * r * (r + (d - z_min));
        assert!(
            (p.visible_area_mm2 - area).abs() < 1e-6 * area,
            "{} vs {area}",
            p.visible_area_mm2
        );
        let total = 2.0 * std::f64::consts::PI * r * (r + d);
        assert!((p.visible_area_pct - 100.0 * area / total).abs() < 1e-6);
    }
}

#[test]
fn image_rectangle_crops_the_webcam() {
    // 70° pinhole, alpha 571.3 px: along +x the 320 px half-width is reached at
    // theta = atan(320 / 571.3), so the side is seen down to z = r / tan(theta) there.
    let s = Sensor::preset("webcam70").unwrap();
    let z_x = 7.5 / (320.0f64 / 571.3).atan().tan();
    let extent = preview::visible_extent(&s, 0.0);
    let hand = FRAC_PI_2 * 7.5 + (20.0 - z_x);
    // The last pixel centre's edge is at u = 639.5, half a pixel further than 320.
    assert!((extent - hand).abs() < 0.05, "{extent} vs {hand}");
}

#[test]
fn fisheye_resolution_matches_the_derivative_of_theta() {
    let s = Sensor::preset("paper").unwrap();
    let (f, r, d) = (180.0, 7.5, 20.0);
    // At the tip: theta = atan2(r sin b, d + r cos b), d theta / d s = 1 / (d + r) at b = 0.
    let (m, p) = preview::px_per_mm(&s, 0.0, 0.0).unwrap();
    let tip = f / (d + r);
    assert!((m - tip).abs() < 1e-3 * tip, "{m} vs {tip}");
    assert!((p - tip).abs() < 1e-3 * tip);
    // On the hemisphere at beta = 0.5 rad: d theta / d beta = r (r + d cos b) / |q|^2 with
    // q = (r sin b, d + r cos b); parallel: rho(theta) / (r sin b).
    let b: f64 = 0.5;
    let q2 = (r * b.sin()).powi(2) + (d + r * b.cos()).powi(2);
    let meridian = f * r * (r + d * b.cos()) / q2 / r;
    let theta = (r * b.sin()).atan2(d + r * b.cos());
    let parallel = f * theta / (r * b.sin());
    let (m, p) = preview::px_per_mm(&s, b * r, 0.3).unwrap();
    assert!((m - meridian).abs() < 1e-3 * meridian, "{m} vs {meridian}");
    assert!((p - parallel).abs() < 1e-3 * parallel, "{p} vs {parallel}");
    // On the cylinder at height z: theta = atan(r / z), d theta / d s = r / (r^2 + z^2).
    let z: f64 = 10.0;
    let (m, p) = preview::px_per_mm(&s, FRAC_PI_2 * r + (d - z), 1.0).unwrap();
    let hand = f * r / (r * r + z * z);
    assert!((m - hand).abs() < 1e-3 * hand, "{m} vs {hand}");
    assert!((p - f * (r / z).atan() / r).abs() < 1e-3 * p);
}

#[test]
fn paper_comparisons_come_out() {
    let names = ["tube13", "paper", "tube21", "webcam70"];
    let designs: Vec<Sensor> = names.iter().map(|n| Sensor::preset(n).unwrap()).collect();
    let report = preview::run(&designs, &[120.0, 160.0, 200.0], None, false, |_| {}).unwrap();
    let area = |i: usize| report.designs[i].1.visible_area_mm2;
    // A larger tube has more surface to see; the webcam sees far less of the same finger.
    assert!(area(0) < area(1) && area(1) < area(2));
    assert!(area(3) < 0.6 * area(1));
    // A wider lens reaches further down and resolves less at the tip.
    let sweep = &report.sweep;
    assert!(sweep[0].1.visible_s_max < sweep[2].1.visible_s_max);
    let tip = |k: usize| sweep[k].1.curve[0].meridian;
    assert!(tip(0) > tip(1) && tip(1) > tip(2));
    assert!(report.best_sweep().is_some());
}

#[test]
fn bad_sweep_ranges_are_one_line_errors() {
    for bad in [
        "120:200",
        "a:b:c",
        "200:120:10",
        "120:200:0",
        "0:100000:0.1",
    ] {
        let e = preview::parse_range(bad).unwrap_err().to_string();
        // The library names its own argument; the command line names its flag.
        assert!(
            e.starts_with(&format!("sweep_fovs {bad}: ")) && !e.contains('\n'),
            "{e}"
        );
    }
    assert_eq!(
        preview::parse_range("120:200:40").unwrap(),
        vec![120.0, 160.0, 200.0]
    );
}

#[test]
fn pareto_front_of_constructed_points() {
    // (speed, error): b dominates a; c and d trade off; e is dominated by d; f is NaN.
    let pts = [
        (10.0, 2.0),
        (12.0, 1.0),
        (20.0, 3.0),
        (5.0, 0.5),
        (4.0, 0.6),
        (f64::NAN, 0.0),
        (12.0, 1.0),
    ];
    let front = tradeoff::pareto_front(&pts);
    assert_eq!(front, vec![false, true, true, true, false, false, true]);
    // Within the ties, 2% faster and 0.005 better is no evidence; 10% faster at the same
    // error is; and with two errors, a point must not be worse beyond the tie on either.
    let tol = tradeoff::Tolerance {
        speed: 0.05,
        errors: vec![0.01, 0.01],
    };
    let two = |a: (f64, f64, f64)| (a.0, vec![a.1, a.2]);
    let pts = [
        two((100.0, 0.50, 0.50)),
        two((102.0, 0.495, 0.50)),
        two((60.0, 0.40, 0.60)),
    ];
    assert_eq!(
        tradeoff::pareto_front_within(&pts, &tol),
        vec![true, true, true]
    );
    let pts = [two((100.0, 0.50, 0.50)), two((110.0, 0.50, 0.505))];
    assert_eq!(tradeoff::pareto_front_within(&pts, &tol), vec![false, true]);
    let pts = [two((100.0, 0.50, 0.50)), two((110.0, 0.50, 0.60))];
    assert_eq!(tradeoff::pareto_front_within(&pts, &tol), vec![true, true]);
}

#[test]
fn stability_invariants_on_the_webcam() {
    gpu_env();
    // The webcam sees less than half the finger: hidden contacts that leave the image
    // untouched must never be localised.
    let s = Sensor::preset("webcam70").unwrap();
    let sweep = stability::Sweep {
        positions: 2,
        azimuths: 1,
        depths: vec![0.01, 1.0],
        noise: 0.0,
        hidden_offset_mm: 12.0,
        empty_frames: 0,
        methods: vec![Method::Surface],
    };
    let report = stability::run(&s, &sweep, None, |_, _| {}).unwrap();
    assert_eq!(report.non_finite, 0);
    let hidden: Vec<_> = report.trials.iter().filter(|t| !t.visible).collect();
    assert!(hidden.iter().any(|t| !t.image_changed));
    for t in &hidden {
        if !t.image_changed {
            assert!(!t.detected, "hidden contact localised: {t:?}");
        }
    }
    // Detection is monotone enough in depth: deeper is found at least as often.
    let shallow = report.rate(false, Method::Surface, 0.01, None);
    let deep = report.rate(false, Method::Surface, 1.0, None);
    assert!(deep >= shallow && deep >= 0.75, "{shallow} -> {deep}");
    for t in report.trials.iter().filter(|t| t.detected) {
        assert!(t.error_mm.is_some_and(f64::is_finite));
    }
    // Two contacts rendered as one scene (here two places on one meridian): the surface
    // detector reports a point within a few mm of one of them (2.2 mm on this coarse lens).
    let &(method, pairs, found, distance) = report.two_contacts.first().expect("pairs");
    assert_eq!(method, Method::Surface);
    assert!(pairs >= 1 && found == pairs, "{pairs} pairs, {found} found");
    assert!(
        distance.is_some_and(|d| d.is_finite() && d < 4.0),
        "{distance:?}"
    );
    assert!(report.markdown().contains("| surface | no noise |"));
}

#[test]
fn stability_refuses_depths_beyond_the_shell() {
    let s = Sensor::preset("paper").unwrap();
    let mut sweep = stability::Sweep::default_for(&s);
    sweep.depths = vec![0.1, 2.0];
    let e = stability::positions(&s, &sweep).unwrap_err().to_string();
    assert!(e.starts_with("depths: ") && e.contains("shell"), "{e}");
}

/// A camera that blurs would blur the noisy pass's noise: its default sweep has none, and
/// noise asked for is refused on one line that says how to sweep without it, before anything
/// is rendered; without the noise it sweeps.
#[test]
fn stability_refuses_noise_on_a_soft_camera_and_sweeps_without_it() {
    gpu_env();
    let s = Sensor::preset("allsight").unwrap();
    assert!(s.config.camera.blur_px > 0.0);
    assert_eq!(stability::Sweep::default_for(&s).noise, 0.0);
    let paper = Sensor::preset("paper").unwrap();
    assert_eq!(stability::Sweep::default_for(&paper).noise, 2.0);
    let mut sweep = stability::Sweep {
        positions: 2,
        azimuths: 1,
        depths: vec![0.5],
        noise: 2.0,
        hidden_offset_mm: 12.0,
        empty_frames: 0,
        methods: vec![Method::Surface],
    };
    let e = stability::suite(&s, &sweep).unwrap_err().to_string();
    assert!(
        e.contains("blur_px") && e.contains("--noise 0") && !e.contains('\n'),
        "{e}"
    );
    sweep.noise = 0.0;
    let report = stability::run(&s, &sweep, None, |_, _| {}).unwrap();
    assert!(!report.trials.is_empty());
}

#[test]
fn tradeoff_marks_the_front_and_the_default() {
    gpu_env();
    let s = Sensor::preset("paper").unwrap();
    let d = tradeoff::Knobs::default_for(&s);
    let configs = [
        d,
        tradeoff::Knobs {
            texels: 64,
            ray_steps: 2,
            ..d
        },
    ];
    let contacts = &tradeoff::contacts(false)[..1];
    let dir = std::env::temp_dir().join(format!("geltip-tradeoff-{}", std::process::id()));
    let report = tradeoff::run(&s, &configs, contacts, 1, Some(&dir), |_| {}).unwrap();
    assert_eq!(report.rows.len(), 2);
    assert!(report.rows[0].is_default && !report.rows[1].is_default);
    // The front as the report reads it: fps within SPEED_TIE and image errors within
    // IMAGE_TIE are ties (the two configurations' fps can land that close on a busy host,
    // where an exact front would call the slower one dominated).
    let pts: Vec<(f64, Vec<f64>)> = report
        .rows
        .iter()
        .map(|r| (r.fps, vec![r.image_error]))
        .collect();
    let front = tradeoff::pareto_front_within(
        &pts,
        &tradeoff::Tolerance {
            speed: tradeoff::SPEED_TIE,
            errors: vec![tradeoff::IMAGE_TIE],
        },
    );
    for (r, f) in report.rows.iter().zip(front) {
        assert_eq!(r.on_front_image, f);
        assert!(r.fps.is_finite() && r.fps > 0.0 && r.image_error.is_finite());
    }
    // The coarse configuration is further from the reference than the default.
    assert!(report.rows[1].image_error > report.rows[0].image_error);
    let md = std::fs::read_to_string(dir.join("tradeoff.md")).unwrap();
    assert!(md.contains("(default)") && md.contains("front"));
    assert!(std::fs::read_to_string(dir.join("tradeoff.svg"))
        .unwrap()
        .contains("Pareto front"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stability sweep's tables on the paper sensor, as the command printed them when they
/// were last checked by hand (tests/reference/): the sweep scores through the evaluate
/// module, and any change to a detector, the renderer or the scoring that moves a figure
/// shows here; the reference is then regenerated on purpose.
#[test]
fn stability_tables_on_the_paper_sensor() {
    gpu_env();
    let s = Sensor::preset("paper").unwrap();
    let report = stability::run(&s, &stability::Sweep::default_for(&s), None, |_, _| {}).unwrap();
    assert_eq!(
        report.markdown(),
        include_str!("reference/stability_paper.md"),
        "the stability tables changed"
    );
}
