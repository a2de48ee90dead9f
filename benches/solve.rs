//! The calibration's dense solve, hand-written against nalgebra's LU, on systems shaped like
//! its Levenberg-Marquardt steps: `cargo bench --bench solve --features nalgebra-solve`.
//!
//! Each system is a step's damped normal equations (JᵀJ + λ diag(JᵀJ)) x = Jᵀr for a
//! Jacobian of `4n` residuals whose columns are scaled 10⁻⁴ to 10³ apart (a calibration's
//! parameters: millimetres, colours, exponents), λ = 10⁻³. Printed per size: µs a solve
//! (the median of 200 passes over 50 systems), the largest relative residual
//! ‖Ax − b‖ / ‖b‖ of each, and the largest relative difference between their solutions.
//! The paired calibrations (the whole `geltip calibrate` built with and without the
//! feature) are in docs/calibrate.md.

use geltip::calibrate::solve::{gaussian_elimination, nalgebra_lu};
use std::time::Instant;

/// xorshift64*: deterministic systems without a random-number crate.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A step's damped normal equations for `n` parameters: (row-major A, b).
fn system(rng: &mut Rng, n: usize) -> (Vec<f64>, Vec<f64>) {
    let m = 4 * n;
    let scales: Vec<f64> = (0..n)
        .map(|_| 10f64.powf(-4.0 + 7.0 * rng.uniform()))
        .collect();
    let j: Vec<f64> = (0..m * n)
        .map(|k| (rng.uniform() - 0.5) * scales[k % n])
        .collect();
    let r: Vec<f64> = (0..m).map(|_| rng.uniform() - 0.5).collect();
    let mut a = vec![0.0; n * n];
    let mut b = vec![0.0; n];
    for row in 0..m {
        let jr = &j[row * n..(row + 1) * n];
        for p in 0..n {
            b[p] += jr[p] * r[row];
            for q in 0..n {
                a[p * n + q] += jr[p] * jr[q];
            }
        }
    }
    for p in 0..n {
        a[p * n + p] *= 1.0 + 1e-3;
    }
    (a, b)
}

fn relative_residual(a: &[f64], b: &[f64], x: &[f64], n: usize) -> f64 {
    let norm = |v: &[f64]| v.iter().map(|e| e * e).sum::<f64>().sqrt();
    let ax_b: Vec<f64> = (0..n)
        .map(|p| (0..n).map(|q| a[p * n + q] * x[q]).sum::<f64>() - b[p])
        .collect();
    norm(&ax_b) / norm(b)
}

type Solver = fn(&[f64], &[f64], usize) -> Option<Vec<f64>>;

/// µs a solve: the median over `passes` passes of all `systems`.
fn time(solver: Solver, systems: &[(Vec<f64>, Vec<f64>)], n: usize, passes: usize) -> f64 {
    let mut per_pass: Vec<f64> = (0..passes)
        .map(|_| {
            let start = Instant::now();
            for (a, b) in systems {
                std::hint::black_box(solver(a, b, n));
            }
            start.elapsed().as_secs_f64() * 1e6 / systems.len() as f64
        })
        .collect();
    per_pass.sort_by(f64::total_cmp);
    per_pass[passes / 2]
}

fn main() {
    println!("| parameters | hand-written µs | nalgebra LU µs | hand-written max ‖Ax−b‖/‖b‖ | nalgebra max ‖Ax−b‖/‖b‖ | max relative difference |");
    println!("|---|---|---|---|---|---|");
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for n in [3, 6, 12, 24, 48, 96] {
        let systems: Vec<(Vec<f64>, Vec<f64>)> = (0..50).map(|_| system(&mut rng, n)).collect();
        let (mut worst, mut worst_na, mut apart) = (0f64, 0f64, 0f64);
        for (a, b) in &systems {
            let x = gaussian_elimination(a, b, n).expect("a damped system is regular");
            let y = nalgebra_lu(a, b, n).expect("a damped system is regular");
            worst = worst.max(relative_residual(a, b, &x, n));
            worst_na = worst_na.max(relative_residual(a, b, &y, n));
            for (u, v) in x.iter().zip(&y) {
                apart = apart.max((u - v).abs() / u.abs().max(v.abs()).max(1e-300));
            }
        }
        // Alternated, so that both see the same phases of a shared host.
        let (mut hand, mut na) = (Vec::new(), Vec::new());
        for _ in 0..4 {
            hand.push(time(gaussian_elimination, &systems, n, 50));
            na.push(time(nalgebra_lu, &systems, n, 50));
        }
        hand.sort_by(f64::total_cmp);
        na.sort_by(f64::total_cmp);
        println!(
            "| {n} | {:.2} | {:.2} | {worst:.1e} | {worst_na:.1e} | {apart:.1e} |",
            hand[2], na[2]
        );
    }
}
