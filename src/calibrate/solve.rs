//! Least squares for the calibration: a dense linear solve and Levenberg-Marquardt with a
//! forward-difference Jacobian, box bounds and the parameters' standard errors.

use rayon::prelude::*;
use std::ops::Range;

/// Solves the n x n system `a x = b` (row-major); `None` when it is singular. By
/// [`gaussian_elimination`]; with the `nalgebra-solve` feature by nalgebra's LU, for paired
/// runs (`cargo bench --bench solve --features nalgebra-solve` compares the two).
pub fn solve_dense(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    #[cfg(feature = "nalgebra-solve")]
    return nalgebra_lu(a, b, n);
    #[cfg(not(feature = "nalgebra-solve"))]
    return gaussian_elimination(a, b, n);
}

/// [`solve_dense`] by nalgebra's LU with partial pivoting.
#[cfg(feature = "nalgebra-solve")]
pub fn nalgebra_lu(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let m = nalgebra::DMatrix::from_row_slice(n, n, a);
    let x = m.lu().solve(&nalgebra::DVector::from_column_slice(b))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.as_slice().to_vec())
}

/// Solves the n x n system `a x = b` (row-major) by Gaussian elimination with partial
/// pivoting; `None` when it is singular.
pub fn gaussian_elimination(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut m: Vec<f64> = a.to_vec();
    let mut x: Vec<f64> = b.to_vec();
    for col in 0..n {
        let pivot =
            (col..n).max_by(|&i, &j| m[i * n + col].abs().total_cmp(&m[j * n + col].abs()))?;
        if m[pivot * n + col].abs() < 1e-300 {
            return None;
        }
        if pivot != col {
            for k in 0..n {
                m.swap(pivot * n + k, col * n + k);
            }
            x.swap(pivot, col);
        }
        for row in col + 1..n {
            let f = m[row * n + col] / m[col * n + col];
            if f != 0.0 {
                for k in col..n {
                    m[row * n + k] -= f * m[col * n + k];
                }
                x[row] -= f * x[col];
            }
        }
    }
    for col in (0..n).rev() {
        let s: f64 = (col + 1..n).map(|k| m[col * n + k] * x[k]).sum();
        x[col] = (x[col] - s) / m[col * n + col];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The inverse of an n x n matrix (row-major), column by column; `None` when singular.
pub fn invert(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut inv = vec![0.0; n * n];
    for j in 0..n {
        let e: Vec<f64> = (0..n).map(|i| if i == j { 1.0 } else { 0.0 }).collect();
        let col = solve_dense(a, &e, n)?;
        for i in 0..n {
            inv[i * n + j] = col[i];
        }
    }
    Some(inv)
}

/// A parameter's box: the solver keeps it within `[lo, hi]`; `step` is its finite-difference
/// step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub lo: f64,
    pub hi: f64,
    pub step: f64,
}

/// What [`levenberg_marquardt`] ends with.
#[derive(Debug, Clone)]
pub struct Fit {
    pub params: Vec<f64>,
    /// Half the sum of squared residuals.
    pub cost: f64,
    pub iterations: usize,
    /// J^T J at the solution (row-major), for the parameters' uncertainty.
    pub jtj: Vec<f64>,
    pub residuals: usize,
}

impl Fit {
    /// Each parameter's standard error: sqrt(diag((J^T J)^-1) s^2), s^2 the residual
    /// variance; infinite for a parameter the residuals do not depend on.
    pub fn standard_errors(&self) -> Vec<f64> {
        let n = self.params.len();
        let dof = self.residuals.saturating_sub(n).max(1) as f64;
        let s2 = 2.0 * self.cost / dof;
        // Columns the residuals do not move leave J^T J singular: those parameters are
        // unconstrained; the others' errors come from the rest of the matrix.
        let free: Vec<usize> = (0..n).filter(|&i| self.jtj[i * n + i] > 1e-12).collect();
        let m = free.len();
        let sub: Vec<f64> = free
            .iter()
            .flat_map(|&i| free.iter().map(move |&j| (i, j)))
            .map(|(i, j)| self.jtj[i * n + j])
            .collect();
        let mut errors = vec![f64::INFINITY; n];
        if let Some(inv) = invert(&sub, m) {
            for (k, &i) in free.iter().enumerate() {
                errors[i] = (inv[k * m + k].max(0.0) * s2).sqrt();
            }
        }
        errors
    }
}

/// Levenberg-Marquardt: minimises half the sum of squares of `residuals(params)` within
/// `bounds`, for at most `max_iterations` accepted or rejected steps. The Jacobian's columns
/// are forward differences, computed in parallel.
pub fn levenberg_marquardt<F>(
    start: &[f64],
    bounds: &[Bound],
    max_iterations: usize,
    residuals: F,
) -> Fit
where
    F: Fn(&[f64]) -> Vec<f64> + Sync,
{
    let sweeps = Sweeps::dense(start.len());
    levenberg_marquardt_sweeps(start, bounds, max_iterations, &sweeps, residuals)
}

/// Which parameters a forward difference moves at once. Parameters that move disjoint
/// residuals (each frame's own depth, say) share a sweep: one evaluation of the residuals
/// gives all their columns, each read from its own range and zero elsewhere.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweeps(pub Vec<Vec<(usize, Option<Range<usize>>)>>);

impl Sweeps {
    /// Every parameter alone, over every residual.
    pub fn dense(n: usize) -> Sweeps {
        Sweeps((0..n).map(|i| vec![(i, None)]).collect())
    }
}

/// [`levenberg_marquardt`] with the Jacobian found by `sweeps`, which must name every
/// parameter once.
pub fn levenberg_marquardt_sweeps<F>(
    start: &[f64],
    bounds: &[Bound],
    max_iterations: usize,
    sweeps: &Sweeps,
    residuals: F,
) -> Fit
where
    F: Fn(&[f64]) -> Vec<f64> + Sync,
{
    let n = start.len();
    let clamp = |p: &mut [f64]| {
        for (v, b) in p.iter_mut().zip(bounds) {
            *v = v.clamp(b.lo, b.hi);
        }
    };
    let mut params = start.to_vec();
    clamp(&mut params);
    let mut r = residuals(&params);
    let m = r.len();
    let mut cost = half_squares(&r);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut jtj = vec![0.0; n * n];
    let mut fresh_jacobian = true;
    let mut g = vec![0.0; n];
    let mut small_gains = 0;
    while iterations < max_iterations {
        if fresh_jacobian {
            let columns = jacobian(&params, &r, bounds, sweeps, &residuals);
            normal_equations(&columns, &r, &mut jtj, &mut g);
            fresh_jacobian = false;
        }
        iterations += 1;
        let Some(step) = damped_step(&jtj, &g, &params, bounds, lambda) else {
            lambda *= 10.0;
            continue;
        };
        let mut trial: Vec<f64> = params.iter().zip(&step).map(|(p, s)| p + s).collect();
        clamp(&mut trial);
        let tr = residuals(&trial);
        let tc = half_squares(&tr);
        if tc.is_finite() && tc < cost {
            let gain = (cost - tc) / cost.max(1e-300);
            params = trial;
            r = tr;
            cost = tc;
            lambda = (lambda / 3.0).max(1e-9);
            fresh_jacobian = true;
            // Converged when steps keep gaining next to nothing; one small gain alone may be
            // a short step taken after rejections (a large lambda), not the bottom.
            small_gains = if gain < 1e-7 { small_gains + 1 } else { 0 };
            if small_gains >= 3 {
                break;
            }
        } else {
            lambda *= 4.0;
            if lambda > 1e12 {
                break;
            }
        }
    }
    if fresh_jacobian {
        let columns = jacobian(&params, &r, bounds, sweeps, &residuals);
        normal_equations(&columns, &r, &mut jtj, &mut g);
    }
    Fit {
        params,
        cost,
        iterations,
        jtj,
        residuals: m,
    }
}

/// One step of Levenberg-Marquardt from `params`: the normal equations `jtj`, `g` with their
/// diagonal damped by `lambda`, solved; `None` when singular. Parameters held at a bound by
/// the descent direction stay there this step (their rows and columns are taken out), so
/// that the others' step is not bent by clamping.
fn damped_step(
    jtj: &[f64],
    g: &[f64],
    params: &[f64],
    bounds: &[Bound],
    lambda: f64,
) -> Option<Vec<f64>> {
    let n = params.len();
    let held: Vec<bool> = (0..n)
        .map(|i| {
            (params[i] <= bounds[i].lo && g[i] < 0.0) || (params[i] >= bounds[i].hi && g[i] > 0.0)
        })
        .collect();
    let mut a = jtj.to_vec();
    let mut rhs = g.to_vec();
    for i in 0..n {
        a[i * n + i] += lambda * jtj[i * n + i].max(1e-12);
        if held[i] {
            for k in 0..n {
                a[i * n + k] = 0.0;
                a[k * n + i] = 0.0;
            }
            a[i * n + i] = 1.0;
            rhs[i] = 0.0;
        }
    }
    solve_dense(&a, &rhs, n)
}

fn half_squares(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

/// A Jacobian column: its values over the residuals from `start` on, zero elsewhere.
struct Column {
    start: usize,
    values: Vec<f64>,
}

impl Column {
    fn range(&self) -> Range<usize> {
        self.start..self.start + self.values.len()
    }
}

/// Forward-difference columns of the Jacobian, one sweep per task; a step that would leave
/// the box goes backwards.
fn jacobian<F>(
    params: &[f64],
    r: &[f64],
    bounds: &[Bound],
    sweeps: &Sweeps,
    residuals: &F,
) -> Vec<Column>
where
    F: Fn(&[f64]) -> Vec<f64> + Sync,
{
    let per_sweep: Vec<Vec<(usize, Column)>> = sweeps
        .0
        .par_iter()
        .map(|sweep| {
            let mut p = params.to_vec();
            let steps: Vec<f64> = sweep
                .iter()
                .map(|&(i, _)| {
                    let b = bounds[i];
                    let h = if p[i] + b.step <= b.hi {
                        b.step
                    } else {
                        -b.step
                    };
                    p[i] += h;
                    h
                })
                .collect();
            let rp = residuals(&p);
            sweep
                .iter()
                .zip(steps)
                .map(|((i, range), h)| {
                    let range = range.clone().unwrap_or(0..r.len());
                    let values = range.clone().map(|k| (rp[k] - r[k]) / h).collect();
                    (
                        *i,
                        Column {
                            start: range.start,
                            values,
                        },
                    )
                })
                .collect()
        })
        .collect();
    let mut columns: Vec<Option<Column>> = (0..params.len()).map(|_| None).collect();
    for (i, c) in per_sweep.into_iter().flatten() {
        columns[i] = Some(c);
    }
    columns
        .into_iter()
        .map(|c| {
            c.unwrap_or(Column {
                start: 0,
                values: Vec::new(),
            })
        })
        .collect()
}

fn normal_equations(columns: &[Column], r: &[f64], jtj: &mut [f64], g: &mut [f64]) {
    let n = columns.len();
    for i in 0..n {
        let a = &columns[i];
        for j in i..n {
            let b = &columns[j];
            let (ra, rb) = (a.range(), b.range());
            let overlap = ra.start.max(rb.start)..ra.end.min(rb.end);
            let v: f64 = overlap
                .map(|k| a.values[k - a.start] * b.values[k - b.start])
                .sum();
            jtj[i * n + j] = v;
            jtj[j * n + i] = v;
        }
        g[i] = -a.range().map(|k| a.values[k - a.start] * r[k]).sum::<f64>();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_system_solves_and_a_singular_one_does_not() {
        let a = [4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        let x = solve_dense(&a, &[1.0, 2.0, 3.0], 3).unwrap();
        let back: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum())
            .collect();
        for (b, want) in back.iter().zip([1.0, 2.0, 3.0]) {
            assert!((b - want).abs() < 1e-12);
        }
        assert!(solve_dense(&[1.0, 2.0, 2.0, 4.0], &[1.0, 1.0], 2).is_none());
    }

    #[test]
    fn lm_fits_an_exponential_and_reports_its_errors() {
        // y = a exp(-b t) + noise-free; then a parameter the data cannot see.
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let truth = [2.5, 1.3];
        let y: Vec<f64> = t.iter().map(|t| truth[0] * (-truth[1] * t).exp()).collect();
        let bounds = [Bound {
            lo: 0.0,
            hi: 10.0,
            step: 1e-6,
        }; 3];
        let fit = levenberg_marquardt(&[1.0, 0.5, 3.0], &bounds, 200, |p| {
            t.iter()
                .zip(&y)
                .map(|(t, y)| p[0] * (-p[1] * t).exp() - y)
                .collect()
        });
        assert!((fit.params[0] - truth[0]).abs() < 1e-6, "{:?}", fit.params);
        assert!((fit.params[1] - truth[1]).abs() < 1e-6, "{:?}", fit.params);
        let errors = fit.standard_errors();
        assert!(errors[0].is_finite() && errors[1].is_finite());
        assert!(errors[2].is_infinite(), "{errors:?}");
    }

    #[test]
    fn sweeps_over_disjoint_residuals_fit_as_the_dense_jacobian_does() {
        // Two curves a exp(-b_k t): a shared, each b_k moving only its own curve's residuals.
        let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
        let truth: [f64; 3] = [2.0, 0.7, 1.6];
        let y: Vec<f64> = [truth[1], truth[2]]
            .iter()
            .flat_map(|&b| t.iter().map(move |&t| truth[0] * (-b * t).exp()))
            .collect();
        let residuals = |p: &[f64]| -> Vec<f64> {
            [p[1], p[2]]
                .iter()
                .flat_map(|&b: &f64| t.iter().map(move |&t| p[0] * (-b * t).exp()))
                .zip(&y)
                .map(|(m, y)| m - y)
                .collect()
        };
        let bounds = [Bound {
            lo: 0.0,
            hi: 10.0,
            step: 1e-6,
        }; 3];
        let start = [1.0, 0.3, 0.3];
        let sweeps = Sweeps(vec![
            vec![(0, None)],
            vec![(1, Some(0..30)), (2, Some(30..60))],
        ]);
        let sparse = levenberg_marquardt_sweeps(&start, &bounds, 200, &sweeps, residuals);
        let dense = levenberg_marquardt(&start, &bounds, 200, residuals);
        for ((s, d), t) in sparse.params.iter().zip(&dense.params).zip(truth) {
            assert!((s - t).abs() < 1e-6, "{:?}", sparse.params);
            assert!((s - d).abs() < 1e-6);
        }
        for (a, b) in sparse.jtj.iter().zip(&dense.jtj) {
            assert!(
                (a - b).abs() < 1e-3 * (1.0 + b.abs()),
                "{:?} {:?}",
                sparse.jtj,
                dense.jtj
            );
        }
    }
}
