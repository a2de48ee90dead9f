//! Lens models: the map between the angle theta off the optical axis and the image radius rho
//! (pixels from the principal point), and its exact inverse.

use serde::{Deserialize, Serialize};

/// Which projection a lens follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LensModel {
    /// rho = alpha tan(theta): the paper's model; cannot reach 90 degrees.
    Pinhole,
    /// rho = f theta.
    Equidistant,
    /// rho = 2 f sin(theta / 2).
    Equisolid,
    /// rho = f theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), OpenCV's fisheye.
    KannalaBrandt,
}

impl LensModel {
    /// The name used in TOML files.
    pub fn name(self) -> &'static str {
        match self {
            LensModel::Pinhole => "pinhole",
            LensModel::Equidistant => "equidistant",
            LensModel::Equisolid => "equisolid",
            LensModel::KannalaBrandt => "kannala-brandt",
        }
    }

    /// Every model, in the order the docs list them.
    pub const ALL: [LensModel; 4] = [
        LensModel::Pinhole,
        LensModel::Equidistant,
        LensModel::Equisolid,
        LensModel::KannalaBrandt,
    ];
}

/// A lens: its model, focal length in pixels, distortion coefficients and field of view.
/// Construct through [`crate::sensor::SensorConfig`] validation, which guarantees that
/// `project` is strictly increasing on `[0, max_theta]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    pub model: LensModel,
    /// alpha for the pinhole, f for the fisheye models.
    pub focal_px: f64,
    /// Kannala-Brandt k1..k4 (zero for the other models).
    pub k: [f64; 4],
    /// Half the full cone the lens passes, in radians.
    pub max_theta: f64,
}

impl Lens {
    /// Image radius (px) of a ray at angle `theta` (radians) off the axis.
    pub fn project(&self, theta: f64) -> f64 {
        let f = self.focal_px;
        match self.model {
            LensModel::Pinhole => f * theta.tan(),
            LensModel::Equidistant => f * theta,
            LensModel::Equisolid => 2.0 * f * (0.5 * theta).sin(),
            LensModel::KannalaBrandt => {
                let t2 = theta * theta;
                let [k1, k2, k3, k4] = self.k;
                f * theta * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
            }
        }
    }

    /// d rho / d theta, used by the Kannala-Brandt inverse and its monotonicity check.
    pub fn project_derivative(&self, theta: f64) -> f64 {
        let f = self.focal_px;
        match self.model {
            LensModel::Pinhole => f / (theta.cos() * theta.cos()),
            LensModel::Equidistant => f,
            LensModel::Equisolid => f * (0.5 * theta).cos(),
            LensModel::KannalaBrandt => {
                let t2 = theta * theta;
                let [k1, k2, k3, k4] = self.k;
                f * (1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4))))
            }
        }
    }

    /// Image radius of the edge of the field of view.
    pub fn max_rho(&self) -> f64 {
        self.project(self.max_theta)
    }

    /// Angle off the axis (radians) of the ray that lands `rho` pixels from the principal
    /// point, or `None` when rho is beyond the edge of the lens's field of view.
    pub fn unproject(&self, rho: f64) -> Option<f64> {
        let max_rho = self.max_rho();
        if rho.is_nan() || rho < 0.0 || rho > max_rho * (1.0 + 1e-12) {
            return None;
        }
        let f = self.focal_px;
        let theta = match self.model {
            LensModel::Pinhole => (rho / f).atan(),
            LensModel::Equidistant => rho / f,
            LensModel::Equisolid => 2.0 * (rho / (2.0 * f)).min(1.0).asin(),
            LensModel::KannalaBrandt => self.unproject_polynomial(rho),
        };
        Some(theta.min(self.max_theta))
    }

    /// Unit direction (camera frame, z the axis) of the ray that lands at `offset` px from
    /// the principal point, or `None` beyond the field of view.
    pub fn ray(&self, offset: glam::DVec2) -> Option<glam::DVec3> {
        let rho = offset.length();
        let theta = self.unproject(rho)?;
        if rho == 0.0 {
            return Some(glam::DVec3::Z);
        }
        let (sin_t, cos_t) = theta.sin_cos();
        Some(glam::DVec3::new(
            sin_t * offset.x / rho,
            sin_t * offset.y / rho,
            cos_t,
        ))
    }

    /// Safeguarded Newton on rho(theta) = rho over [0, max_theta], where rho is increasing.
    fn unproject_polynomial(&self, rho: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, self.max_theta);
        let mut theta = (rho / self.focal_px).clamp(lo, hi);
        for _ in 0..100 {
            let err = self.project(theta) - rho;
            if err > 0.0 {
                hi = theta;
            } else {
                lo = theta;
            }
            let step = err / self.project_derivative(theta);
            let mut next = theta - step;
            if next.is_nan() || next <= lo || next >= hi {
                next = 0.5 * (lo + hi);
            }
            if (next - theta).abs() <= 1e-16 * theta.max(1e-300) || hi - lo <= f64::EPSILON * hi {
                return next;
            }
            theta = next;
        }
        theta
    }

    /// Where on [0, max_theta] the projection stops increasing, if it does (checked on a
    /// fine grid: a lens whose rho(theta) folds back cannot be inverted).
    pub fn first_non_increasing_theta(&self) -> Option<f64> {
        const STEPS: usize = 4096;
        (0..=STEPS)
            .map(|i| self.max_theta * i as f64 / STEPS as f64)
            .find(|&t| {
                self.project_derivative(t).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(model: LensModel, k: [f64; 4]) -> Lens {
        Lens {
            model,
            focal_px: 180.0,
            k,
            max_theta: if model == LensModel::Pinhole {
                1.2
            } else {
                85f64.to_radians()
            },
        }
    }

    #[test]
    fn each_model_inverts_exactly() {
        for model in LensModel::ALL {
            let l = lens(model, [0.02, -0.01, 0.003, -0.0005]);
            for i in 0..=1000 {
                let theta = l.max_theta * i as f64 / 1000.0;
                let back = l.unproject(l.project(theta)).unwrap();
                assert!(
                    (back - theta).abs() < 1e-13,
                    "{model:?} theta={theta} back={back}"
                );
            }
        }
    }

    #[test]
    fn beyond_the_edge_is_none() {
        for model in LensModel::ALL {
            let l = lens(model, [0.0; 4]);
            assert!(l.unproject(l.max_rho() * 1.001).is_none());
            assert!(l.unproject(-1.0).is_none());
            assert!(l.unproject(f64::NAN).is_none());
            assert!(l.unproject(l.max_rho()).is_some());
        }
    }

    #[test]
    fn folding_polynomial_is_detected() {
        let l = lens(LensModel::KannalaBrandt, [-0.5, 0.0, 0.0, 0.0]);
        assert!(l.first_non_increasing_theta().is_some());
        assert!(lens(LensModel::KannalaBrandt, [0.0; 4])
            .first_non_increasing_theta()
            .is_none());
    }
}
