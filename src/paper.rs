//! The paper's closed-form map m for the pinhole lens (Eq. "function_f" in
//! `geltip-iros2020.tex`), kept twice: as printed, and as derived here.
//!
//! For a pixel at squared distance q = (x' - cx)^2 + (y' - cy)^2 from the principal point,
//! the ray is x = ((x' - cx) / alpha) z, y = ((y' - cy) / alpha) z. Then:
//! - cylinder, x^2 + y^2 = r^2:   q z^2 / alpha^2 = r^2, so z = r alpha / sqrt(q).
//!   This is part of the finger only while z <= d, that is q >= (r alpha / d)^2.
//!   Printed: the branch is taken when q < (r alpha / d)^2 -- the inequality is reversed.
//! - hemisphere, x^2 + y^2 + (z - d)^2 = r^2:
//!   (q + alpha^2) z^2 - 2 d alpha^2 z + (d^2 - r^2) alpha^2 = 0, so
//!   z = (2 d alpha^2 + sqrt(4 d^2 alpha^4 - 4 (q + alpha^2)(d^2 - r^2) alpha^2)) / (2 (q + alpha^2)).
//!   Printed: the discriminant's second factor is \[q\] instead of \[q + alpha^2\], and the
//!   sign is "+-" where only "+" (the far root) lies on the hemisphere z > d.
//!
//! `tests/paper_formula.rs` shows where the printed form disagrees with the exact map.

/// What the paper's equation gives for z, exactly as printed (with its "+-" read as `sign`).
pub fn printed_z(q: f64, alpha: f64, r: f64, d: f64, sign: f64) -> f64 {
    if q < (r * alpha / d).powi(2) {
        ((r * alpha).powi(2) / q).sqrt()
    } else {
        let a2 = alpha * alpha;
        let disc = (-a2 * 2.0 * d).powi(2) - 4.0 * q * ((d * d - r * r) * a2);
        (a2 * 2.0 * d + sign * disc.sqrt()) / (2.0 * (q + a2))
    }
}

/// z of the surface point the pixel sees, derived above (pinhole lens).
pub fn derived_z(q: f64, alpha: f64, r: f64, d: f64) -> f64 {
    if q >= (r * alpha / d).powi(2) {
        r * alpha / q.sqrt()
    } else {
        let a2 = alpha * alpha;
        let disc = 4.0 * d * d * a2 * a2 - 4.0 * (q + a2) * (d * d - r * r) * a2;
        (2.0 * d * a2 + disc.max(0.0).sqrt()) / (2.0 * (q + a2))
    }
}

/// The full derived map for a pixel offset (dx, dy) = (x' - cx, y' - cy): (x, y, z).
pub fn derived_point(dx: f64, dy: f64, alpha: f64, r: f64, d: f64) -> [f64; 3] {
    let z = derived_z(dx * dx + dy * dy, alpha, r, d);
    [dx / alpha * z, dy / alpha * z, z]
}
