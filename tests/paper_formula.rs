//! The paper's printed closed form of m (pinhole lens) against the exact map: where the
//! printed equation goes wrong, shown by numbers rather than a comment.

use geltip::paper::{derived_point, derived_z, printed_z};
use geltip::sensor::Sensor;
use glam::DVec2;

/// The webcam preset is the paper's pinhole model of the 15 mm finger.
fn webcam() -> Sensor {
    Sensor::preset("webcam70").unwrap()
}

#[test]
fn derived_closed_form_is_the_exact_map() {
    let s = webcam();
    let (alpha, r, d) = (s.lens.focal_px, s.finger.radius, s.finger.cylinder_length);
    for v in (0..480).step_by(7) {
        for u in (0..640).step_by(7) {
            let px = DVec2::new(u as f64, v as f64);
            let Some(sp) = s.unproject(px) else { continue };
            let off = px - s.principal;
            let p = derived_point(off.x, off.y, alpha, r, d);
            let err = (glam::DVec3::from_array(p) - sp.point).length();
            assert!(err < 1e-9, "derived form is {err} mm off at {px}");
        }
    }
}

#[test]
fn printed_condition_is_reversed() {
    let s = webcam();
    let (alpha, r, d) = (s.lens.focal_px, s.finger.radius, s.finger.cylinder_length);
    let q_junction = (r * alpha / d).powi(2);
    // A pixel near the centre sees the hemisphere (the tip at the very centre)...
    let q_centre = 1.0;
    let exact = derived_z(q_centre, alpha, r, d);
    assert!(
        (exact - (d + r)).abs() < 1e-3,
        "centre sees the tip at z = d + r"
    );
    // ...but the printed equation sends it to the cylinder branch: z = r alpha / sqrt(q),
    // thousands of millimetres away.
    let printed = printed_z(q_centre, alpha, r, d, 1.0);
    assert!(printed > 1000.0, "printed gives z = {printed}");
    // On the junction ring both agree: the branches meet there.
    let at_ring = printed_z(q_junction * (1.0 - 1e-12), alpha, r, d, 1.0);
    assert!((at_ring - derived_z(q_junction, alpha, r, d)).abs() < 1e-6);
}

#[test]
fn printed_discriminant_misses_alpha_squared_and_sign_must_be_plus() {
    let s = webcam();
    let (alpha, r, d) = (s.lens.focal_px, s.finger.radius, s.finger.cylinder_length);
    let q_junction = (r * alpha / d).powi(2);
    // Take the printed sphere branch where the printed condition applies it (the cylinder
    // side of the ring): it cannot be fixed by choosing + or -, since the discriminant
    // itself is wrong. Fix the discriminant and use "+", and the sphere is right.
    let mut worst = 0.0f64;
    for i in 1..=50 {
        let q = q_junction * (1.0 + i as f64 * 0.2);
        let exact_sphere = sphere_far_root(q, alpha, r, d);
        for sign in [1.0, -1.0] {
            let printed = printed_z(q, alpha, r, d, sign);
            if printed.is_finite() {
                worst = worst.max(
                    (printed - exact_sphere)
                        .abs()
                        .min((printed - derived_z(q, alpha, r, d)).abs()),
                );
            }
        }
    }
    assert!(
        worst > 0.5,
        "printed sphere root is within {worst} mm of both exact answers"
    );
    // The near root of the corrected quadratic lies below the hemisphere (z <= d).
    for i in 0..50 {
        let q = q_junction * i as f64 / 50.0;
        let a2 = alpha * alpha;
        let disc = 4.0 * d * d * a2 * a2 - 4.0 * (q + a2) * (d * d - r * r) * a2;
        let near = (2.0 * d * a2 - disc.sqrt()) / (2.0 * (q + a2));
        assert!(
            near <= d + 1e-9,
            "the '-' root z = {near} is on the hemisphere"
        );
        assert!((sphere_far_root(q, alpha, r, d) - derived_z(q, alpha, r, d)).abs() < 1e-9);
    }
}

/// Far intersection of the pinhole ray with the full sphere, solved numerically (bisection on
/// the squared distance along the ray), independent of any closed form.
fn sphere_far_root(q: f64, alpha: f64, r: f64, d: f64) -> f64 {
    let slope2 = q / (alpha * alpha);
    let f = |z: f64| slope2 * z * z + (z - d) * (z - d) - r * r;
    // Outside the sphere beyond z = d + r; inside at the sphere's centre height when the ray
    // passes within r of it, else the far root is the tangent-free minimum.
    let (mut lo, mut hi) = (d / (1.0 + slope2), d + r);
    if f(lo) > 0.0 {
        return f64::NAN;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn where_the_printed_formula_disagrees_over_the_image() {
    // Map the whole webcam image: the printed equation is right only next to the junction
    // ring, wrong by millimetres on both the hemisphere and the cylinder.
    let s = webcam();
    let (alpha, r, d) = (s.lens.focal_px, s.finger.radius, s.finger.cylinder_length);
    let rho_ring = r * alpha / d;
    let mut errors = [Vec::new(), Vec::new()];
    let mut farthest_agreement = 0.0f64;
    for v in (0..480).step_by(4) {
        for u in (0..640).step_by(4) {
            let px = DVec2::new(u as f64, v as f64);
            let Some(sp) = s.unproject(px) else { continue };
            let off = px - s.principal;
            let printed = printed_z(off.length_squared(), alpha, r, d, 1.0);
            let err = (printed - sp.point.z).abs();
            errors[(sp.region == geltip::Region::Cylinder) as usize].push(err);
            if err < 0.01 {
                farthest_agreement = farthest_agreement.max((off.length() - rho_ring).abs());
            }
        }
    }
    for (name, errs) in ["hemisphere", "cylinder"].iter().zip(errors.iter_mut()) {
        errs.sort_by(f64::total_cmp);
        let median = errs[errs.len() / 2];
        assert!(
            errs.len() > 1000 && median > 1.0,
            "{name}: median printed error {median} mm over {} px",
            errs.len()
        );
    }
    assert!(
        farthest_agreement < 15.0,
        "printed form agrees {farthest_agreement} px from the ring"
    );
}
