//! How an object is held against the finger ([`Hold`]): at a place, or as a rigid pose;
//! and the numbers a pose is given as ([`pose_numbers`], [`Hold::from_pose`]). Where a hold
//! puts the object on a sensor's finger is [`super::Press::pose`]'s to say.

use super::Place;
use crate::error::{quoted, GeltipError, Result};
use glam::{DMat3, DVec3};

/// How an object is held against the finger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hold {
    /// At a place on the surface: the object's axis along the inward normal, spun about it,
    /// tilted `tilt_deg` away from it towards the tangent direction `tilt_towards_deg`
    /// (measured from the meridian away from the tip, towards increasing azimuth), then
    /// brought along the normal until it first touches the undeformed finger and pressed
    /// `depth_mm` further.
    Surface {
        place: Place,
        azimuth_deg: f64,
        spin_deg: f64,
        tilt_deg: f64,
        tilt_towards_deg: f64,
        depth_mm: f64,
    },
    /// A rigid pose in the camera frame: object-local points p map to
    /// `world_from_object * p + origin`. The press depth is whatever the pose implies: how far
    /// the object lies beyond its first touch moving along `approach` (a unit vector in the
    /// camera frame: the way it moves to press the finger), or its own +z axis without one.
    Pose {
        world_from_object: DMat3,
        origin: DVec3,
        approach: Option<DVec3>,
    },
}

/// The numbers of a pose given as text (`--pose`, or a string in Python): separated by
/// commas or whitespace. Errors name the contact field `pose`; [`Hold::from_pose`] checks
/// how many there are and what they describe.
pub fn pose_numbers(text: &str) -> Result<Vec<f64>> {
    numbers("pose", text)
}

/// The numbers of the contact field `field` given as text, separated by commas or
/// whitespace (`--pose`, `--approach`); errors name the field.
pub fn numbers(field: &str, text: &str) -> Result<Vec<f64>> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| GeltipError::contact(field, format!("{} is not a number", quoted(t))))
        })
        .collect()
}

impl Hold {
    /// A rigid pose from 16 numbers (a row-major 4x4 matrix whose last row is 0 0 0 1 and
    /// whose 3x3 part is orthonormal) or 7 (position x y z and unit quaternion w x y z), in
    /// the camera frame. Errors name the contact field `pose`.
    pub fn from_pose(v: &[f64]) -> Result<Hold> {
        let bad = |reason: String| GeltipError::contact("pose", reason);
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(bad(format!("{x} is not a finite number")));
        }
        match v.len() {
            16 => {
                let r = DMat3::from_cols(
                    DVec3::new(v[0], v[4], v[8]),
                    DVec3::new(v[1], v[5], v[9]),
                    DVec3::new(v[2], v[6], v[10]),
                );
                if (v[12], v[13], v[14], v[15]) != (0.0, 0.0, 0.0, 1.0) {
                    return Err(bad("the matrix's last row must be 0 0 0 1".into()));
                }
                let err = (r.transpose() * r - DMat3::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, x| m.max(x.abs()));
                // Orthonormal of either handedness: the frame `at` places objects in (x along
                // the meridian, y along the azimuth, z inward) is left-handed, and its labels'
                // matrices must load back as the same pose.
                if err > 1e-6 {
                    return Err(bad(format!(
                        "the matrix's 3x3 part is not a rotation (orthonormal to {err:.2e}, not 1e-6)"
                    )));
                }
                Ok(Hold::Pose {
                    world_from_object: r,
                    origin: DVec3::new(v[3], v[7], v[11]),
                    approach: None,
                })
            }
            7 => {
                let q = glam::DQuat::from_xyzw(v[4], v[5], v[6], v[3]);
                if (q.length() - 1.0).abs() > 1e-6 {
                    return Err(bad(format!(
                        "the quaternion w x y z must have length 1, got {:.6}",
                        q.length()
                    )));
                }
                Ok(Hold::Pose {
                    world_from_object: DMat3::from_quat(q),
                    origin: DVec3::new(v[0], v[1], v[2]),
                    approach: None,
                })
            }
            n => Err(bad(format!(
                "expected 16 numbers (row-major 4x4 matrix) or 7 (x y z qw qx qy qz), got {n}"
            ))),
        }
    }

    /// Checks the hold's numbers, whatever the sensor: finite, a press depth that is not
    /// negative, a tilt inside (-90, 90) degrees. Errors name the contact's fields.
    pub fn check(&self) -> Result<()> {
        let finite = |field: &str, v: f64| {
            crate::checks::finite(v).map_err(|reason| GeltipError::contact(field, reason))
        };
        match *self {
            Hold::Surface {
                place: _,
                azimuth_deg,
                spin_deg,
                tilt_deg,
                tilt_towards_deg,
                depth_mm,
            } => {
                finite("azimuth", azimuth_deg)?;
                finite("spin", spin_deg)?;
                finite("tilt", tilt_deg)?;
                finite("tilt_towards", tilt_towards_deg)?;
                finite("depth", depth_mm)?;
                if depth_mm < 0.0 {
                    return Err(GeltipError::contact(
                        "depth",
                        format!("a press depth cannot be negative, got {depth_mm} mm"),
                    ));
                }
                if !(0.0..90.0).contains(&tilt_deg.abs()) {
                    return Err(GeltipError::contact(
                        "tilt",
                        format!("must lie in (-90, 90) degrees, got {tilt_deg}"),
                    ));
                }
                Ok(())
            }
            Hold::Pose {
                world_from_object,
                origin,
                approach,
            } => {
                if !(world_from_object.is_finite() && origin.is_finite()) {
                    return Err(GeltipError::contact("pose", "must be finite numbers"));
                }
                match approach {
                    Some(a) if !a.is_finite() || (a.length() - 1.0).abs() > 1e-9 => Err(
                        GeltipError::contact("approach", format!("must be a unit vector, got {a}")),
                    ),
                    _ => Ok(()),
                }
            }
        }
    }

    /// The same pose moving along `approach` to press (three numbers, a direction in the
    /// camera frame, normalised here); errors name the contact field `approach`. A hold at a
    /// place has its approach already (the normal) and is refused.
    pub fn approaching(self, approach: &[f64]) -> Result<Hold> {
        let bad = |reason: String| GeltipError::contact("approach", reason);
        let Hold::Pose {
            world_from_object,
            origin,
            ..
        } = self
        else {
            return Err(bad(
                "is for a pose (a place presses along the surface normal)".into(),
            ));
        };
        let [x, y, z] = approach else {
            return Err(bad(format!(
                "expected 3 numbers (a direction in the camera frame), got {}",
                approach.len()
            )));
        };
        let a = DVec3::new(*x, *y, *z);
        if !a.is_finite() {
            return Err(bad(format!("{a} is not a finite direction")));
        }
        let length = a.length();
        if !length.is_finite() || length < 1e-9 {
            return Err(bad(format!(
                "{a} has no direction (its length is under 1e-9)"
            )));
        }
        Ok(Hold::Pose {
            world_from_object,
            origin,
            approach: Some(a / length),
        })
    }
}
