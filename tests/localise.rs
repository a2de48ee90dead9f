//! The contact localisers on constructed images: where they find painted and shaded
//! imprints (tests/imprints), and that no contact is no detection.
//!
//! Tolerances are stated in every assert; the measured errors are printed (`--nocapture`).

mod imprints;

use geltip::finger::SurfaceCoord;
use geltip::localise::paper::{self, area_range, brightness, mean_filter, regions, threshold};
use geltip::localise::{localise, Localiser, Method};
use glam::DVec3;
use image::RgbImage;
use imprints::*;

// ---------------------------------------------------------------------------------------
// A single clear contact on the hemisphere, at the junction and on the cylinder
// ---------------------------------------------------------------------------------------

/// `shape(mm_per_px)` painted at every position and azimuth, located by `method`.
fn painted_errors(method: Method, shape: impl Fn(f64) -> Paint) -> Vec<(String, f64)> {
    let f = sensor().finger;
    let mut out = Vec::new();
    for (name, s) in positions() {
        for phi in AZIMUTHS {
            let truth = f.point_at(SurfaceCoord { s, phi }).point;
            let frame = paint(gradient_reference(), truth, shape(mm_per_px(truth)), 60.0);
            let d = localiser()
                .localise(gradient_reference(), &frame, method)
                .unwrap();
            let what = format!("{} at {name}, phi {phi}", method.name());
            let e = error_mm(&d, truth, &what);
            if let Some(want) = expected_region(s) {
                assert_eq!(d.region, Some(want), "{what}: wrong region");
            }
            out.push((what, e));
        }
    }
    out
}

#[test]
fn paper_finds_a_ring_imprint_on_hemisphere_junction_and_cylinder() {
    // A thin ring 4.5 px in radius: after the 15x15 filter its brightest part is a small
    // peak, and the part above 60% of it is one region of 90..120 px, inside the area
    // filter (37..123 px). Smooth blobs never are (see the next test).
    let errors = painted_errors(Method::Paper, |mm| Paint::Ring {
        radius_mm: 4.5 * mm,
        width_mm: 0.45 * mm,
    });
    let (mean, worst) = report("paper, painted rings", &errors);
    assert!(mean < 0.1, "paper: mean error {mean:.3} mm, allowed 0.1 mm");
    assert!(
        worst < 0.3,
        "paper: worst error {worst:.3} mm, allowed 0.3 mm"
    );
}

#[test]
fn paper_area_filter_rejects_every_single_smooth_blob() {
    // After the 15x15 mean filter, the part of a lone blob above 60% of its peak is never
    // smaller than about 118 px (contour area): a small blob becomes the kernel's 15x15
    // square, a large one stays large. So the paper's detector only ever keeps fragments,
    // rings and secondary peaks, never one clean blob; this is the paper's algorithm, not
    // a bug here.
    let truth = sensor().finger.tip();
    let (lo, hi) = area_range(640.0 * 480.0);
    for sigma_px in [0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0] {
        let shape = Paint::Blob {
            sigma_mm: sigma_px * mm_per_px(truth),
        };
        let frame = paint(gradient_reference(), truth, shape, 60.0);
        let diff = paper::difference(gradient_reference(), &frame).unwrap();
        let b = threshold(&brightness(&mean_filter(&diff, paper::KERNEL)), 0.6);
        let r = regions(&b);
        assert_eq!(r.len(), 1, "blob {sigma_px} px: {} regions", r.len());
        assert!(
            r[0].area > hi,
            "blob {sigma_px} px: area {} inside {lo}..{hi}",
            r[0].area
        );
        let d = localiser()
            .localise(gradient_reference(), &frame, Method::Paper)
            .unwrap();
        assert!(!d.detected, "blob {sigma_px} px detected");
        let note = d.note.unwrap();
        assert!(note.contains("area filter"), "note: {note}");
        assert_eq!(d.regions_found, 1);
    }
}

#[test]
fn surface_finds_painted_blobs_and_rings_on_hemisphere_junction_and_cylinder() {
    for (label, shape) in [
        ("blob 2.5 px", Paint::Blob { sigma_mm: 2.5 }),
        ("blob 6 px", Paint::Blob { sigma_mm: 6.0 }),
        (
            "ring 4.5 px",
            Paint::Ring {
                radius_mm: 4.5,
                width_mm: 0.45,
            },
        ),
    ] {
        let errors = painted_errors(Method::Surface, |mm| match shape {
            Paint::Blob { sigma_mm } => Paint::Blob {
                sigma_mm: sigma_mm * mm,
            },
            Paint::Ring {
                radius_mm,
                width_mm,
            } => Paint::Ring {
                radius_mm: radius_mm * mm,
                width_mm: width_mm * mm,
            },
        });
        let (mean, worst) = report(&format!("surface, painted {label}"), &errors);
        // The outline is found to the pixel (up to 0.3 mm per pixel where the finger is
        // seen obliquely) and measured on the tangent plane, which near the junction is
        // not quite symmetric (sphere on one side, cylinder on the other): ~0.1 mm.
        assert!(
            mean < 0.06,
            "{label}: mean error {mean:.3} mm, allowed 0.06"
        );
        assert!(
            worst < 0.15,
            "{label}: worst error {worst:.3} mm, allowed 0.15"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Object-shaped imprints, shaded
// ---------------------------------------------------------------------------------------

const OBJECTS: [&str; 7] = [
    "sphere", "cone", "cylinder", "edge", "tube", "slab", "gaussian",
];

struct Case {
    what: String,
    truth: DVec3,
    reference: RgbImage,
    frame: RgbImage,
}

/// Every object at every position (56 taps like the paper's experiment, azimuths varied),
/// pressed 1 mm; `every` > 1 keeps one case in `every`.
fn object_cases(noise: Option<f64>, lighting: Lighting, every: usize) -> Vec<Case> {
    let f = sensor().finger;
    let reference = match lighting {
        Lighting::Leds => rendered_reference().clone(),
        Lighting::Headlight => render(None, None, lighting),
    };
    let mut cases = Vec::new();
    for (i, (name, s)) in positions().into_iter().enumerate() {
        for (j, obj) in OBJECTS.iter().enumerate() {
            let k = i * OBJECTS.len() + j;
            if !k.is_multiple_of(every) {
                continue;
            }
            let phi = AZIMUTHS[(i + j) % AZIMUTHS.len()];
            let coord = SurfaceCoord { s, phi };
            let dimple = if *obj == "gaussian" {
                Dimple::new(coord, 1.5, 1.5, 1.0)
            } else {
                Dimple::with_profile(coord, object_profile(obj, 1.0, s > f.junction_s()))
            };
            let seed = k as u64 + 1;
            let reference = match noise {
                Some(n) => render(None, Some((n, 1000 + seed)), lighting),
                None => reference.clone(),
            };
            let frame = render(Some(&dimple), noise.map(|n| (n, seed)), lighting);
            cases.push(Case {
                what: format!("{obj} at {name}, phi {phi}"),
                truth: dimple.p,
                reference,
                frame,
            });
        }
    }
    cases
}

/// Errors of `method` on `cases`, and the cases it missed.
fn case_errors(cases: &[Case], method: Method) -> (Vec<(String, f64)>, Vec<String>) {
    let mut errors = Vec::new();
    let mut missed = Vec::new();
    for c in cases {
        let d = localiser()
            .localise(&c.reference, &c.frame, method)
            .unwrap();
        if d.detected {
            let what = format!("{} {}", method.name(), c.what);
            errors.push((what.clone(), error_mm(&d, c.truth, &what)));
        } else {
            missed.push(format!("{}: {}", c.what, d.note.unwrap_or_default()));
        }
    }
    (errors, missed)
}

#[test]
fn object_imprints_surface_within_half_a_millimetre_and_better_than_paper() {
    let cases = object_cases(None, Lighting::Leds, 1);
    assert_eq!(cases.len(), 56);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects", &errors);
    assert!(
        mean < 0.3,
        "surface: mean error {mean:.3} mm, allowed 0.3 mm"
    );
    assert!(
        worst < 1.0,
        "surface: worst error {worst:.3} mm, allowed 1.0 mm"
    );

    let (paper_errors, paper_missed) = case_errors(&cases, Method::Paper);
    eprintln!("paper missed {} of 56", paper_missed.len());
    let paper_mean = if paper_errors.is_empty() {
        f64::INFINITY
    } else {
        report("paper, shaded objects (detected ones)", &paper_errors).0
    };
    assert!(
        mean < paper_mean,
        "surface mean {mean:.3} mm is not below paper's {paper_mean:.3} mm"
    );
}

#[test]
fn object_imprints_in_sensor_noise() {
    // Gaussian noise of 2 grey levels in every channel of both frames.
    let cases = object_cases(Some(2.0), Lighting::Leds, 2);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects, noise 2", &errors);
    assert!(
        mean < 0.35,
        "surface: mean error {mean:.3} mm, allowed 0.35 mm"
    );
    assert!(
        worst < 1.0,
        "surface: worst error {worst:.3} mm, allowed 1.0 mm"
    );
}

#[test]
fn object_imprints_under_other_lighting() {
    let cases = object_cases(None, Lighting::Headlight, 2);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects, headlight", &errors);
    assert!(
        mean < 0.35,
        "surface: mean error {mean:.3} mm, allowed 0.35 mm"
    );
    assert!(
        worst < 1.2,
        "surface: worst error {worst:.3} mm, allowed 1.2 mm"
    );
}

// ---------------------------------------------------------------------------------------
// No contact
// ---------------------------------------------------------------------------------------

#[test]
fn a_frame_identical_to_the_reference_is_no_contact() {
    for reference in [gradient_reference(), rendered_reference()] {
        for method in Method::ALL {
            let d = localise(sensor(), reference, reference, method).unwrap();
            assert_not_detected(&d, method.name());
            assert!(d.note.unwrap().contains("does not differ"));
        }
    }
}

#[test]
fn noise_alone_is_no_contact_for_the_surface_detector() {
    for (sigma, seed) in [(1.0, 1u64), (2.0, 2), (5.0, 3), (5.0, 4)] {
        let reference = render(None, Some((sigma, seed)), Lighting::Leds);
        let frame = render(None, Some((sigma, seed + 100)), Lighting::Leds);
        let d = localiser()
            .localise(&reference, &frame, Method::Surface)
            .unwrap();
        assert_not_detected(&d, &format!("noise {sigma}"));
        assert!(d.note.unwrap().contains("below the detection level"));
    }
}

#[test]
fn a_weak_contact_is_found_at_a_coarser_scale() {
    // A shallow dimple (0.1 mm deep, 1.5 mm wide) under noise of 5 grey levels: too faint
    // for the 5x5 scale, found at 9x9.
    let f = sensor().finger;
    let coord = SurfaceCoord {
        s: f.s_of_translation(5.0),
        phi: 0.4,
    };
    let dimple = Dimple::new(coord, 1.5, 1.5, 0.1);
    let reference = render(None, Some((5.0, 11)), Lighting::Leds);
    let frame = render(Some(&dimple), Some((5.0, 12)), Lighting::Leds);
    let fine = Localiser::with_config(
        sensor(),
        geltip::localise::surface::SurfaceConfig {
            scales: vec![5],
            ..Default::default()
        },
    );
    let d = fine.localise(&reference, &frame, Method::Surface).unwrap();
    assert!(
        !d.detected,
        "the 5x5 scale alone should miss it: {:?}",
        d.point
    );
    let d = localiser()
        .localise(&reference, &frame, Method::Surface)
        .unwrap();
    let e = error_mm(&d, dimple.p, "weak contact");
    eprintln!("weak contact: {e:.3} mm, confidence {:.2}", d.confidence);
    assert!(e < 1.0, "weak contact: error {e:.3} mm, allowed 1.0 mm");
}
