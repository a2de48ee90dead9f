//! One object held against the finger ([`Press`]) and where that puts it
//! ([`Press::pose`]): at a place, brought along the normal to its first touch and pressed
//! on, or as a rigid pose.

use super::first_touch::{first_touch, touching_offset, FirstTouch};
use super::{Hold, Place};
use crate::error::{GeltipError, Result};
use crate::finger::{Finger, Region, SurfaceCoord, SurfacePoint};
use crate::object::Object;
use crate::render::contact::max_trace_depth;
use crate::render::{heightfield_extent, margin_mm, HeightfieldGrid};
use crate::sensor::Sensor;
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// Where a rigid pose puts its object against the finger ([`Press::pose_if_touching`]'s
/// answer, before it becomes a pose or an error).
enum Rigid {
    Touching(Box<ContactPose>),
    /// Short of touching by this much along its approach.
    Short(f64),
    /// Not touching, nor would it moving along its approach.
    Never,
}

/// One object held against the finger, in any pose: what every render call takes.
#[derive(Debug, Clone)]
pub struct Press {
    pub object: Arc<Object>,
    pub hold: Hold,
}

/// Where a contact sits and how its object is oriented, in the camera frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPose {
    /// Contact point on the undeformed surface: the place asked for, or for a rigid pose the
    /// point it touches first.
    pub point: DVec3,
    /// Outward surface normal there.
    pub normal: DVec3,
    pub coord: SurfaceCoord,
    pub region: Region,
    /// Rotation taking object-local vectors to the camera frame. Object-local +z points into
    /// the finger (along -normal when untilted): objects stand on their base with their top
    /// at the origin.
    pub world_from_object: DMat3,
    /// The object's origin (its top) in the camera frame.
    pub origin: DVec3,
    /// How far the object is pressed beyond its first touch (mm): asked for, or implied by a
    /// rigid pose.
    pub depth_mm: f64,
    /// How far from its top's place on the normal the object first touches the undeformed
    /// finger (mm, outward positive): 0 for a top point on the normal, negative when the
    /// object had to come closer (a ring's hole).
    pub first_touch_offset_mm: f64,
    /// Surface points touched first: the refined point, then the coarse samples within
    /// [`super::first_touch::FIRST_TOUCH_BAND_MM`] (a ring's circle).
    pub first_touch: Vec<DVec3>,
    /// Deepest inward distance the contact stage traces from (mm).
    pub trace_depth_mm: f64,
}

impl ContactPose {
    /// Object-local coordinates of a camera-frame point.
    pub fn to_object(&self, p: DVec3) -> DVec3 {
        self.world_from_object.transpose() * (p - self.origin)
    }

    /// The pose as a 4x4 matrix (row-major: camera-frame point = M (object point, 1)).
    pub fn matrix_row_major(&self) -> [f64; 16] {
        let m = glam::DMat4::from_cols(
            self.world_from_object.x_axis.extend(0.0),
            self.world_from_object.y_axis.extend(0.0),
            self.world_from_object.z_axis.extend(0.0),
            self.origin.extend(1.0),
        );
        m.transpose().to_cols_array()
    }
}

impl Press {
    /// `object` pressed `depth_mm` into the finger at `place`, `azimuth_deg` about the
    /// finger's axis (0 = image +x), its axis along the inward normal: the paper's taps.
    pub fn at(object: Arc<Object>, place: Place, azimuth_deg: f64, depth_mm: f64) -> Press {
        Press {
            object,
            hold: Hold::Surface {
                place,
                azimuth_deg,
                spin_deg: 0.0,
                tilt_deg: 0.0,
                tilt_towards_deg: 0.0,
                depth_mm,
            },
        }
    }

    /// The same press with the object turned `spin_deg` about the contact normal (a pose
    /// has no spin to set and is returned as it is).
    pub fn spun(mut self, spin_deg: f64) -> Press {
        if let Hold::Surface { spin_deg: s, .. } = &mut self.hold {
            *s = spin_deg;
        }
        self
    }

    /// The object's name.
    pub fn name(&self) -> &str {
        self.object.name()
    }

    /// Checks the press's numbers and places it on `sensor`'s finger: by first touch and
    /// depth, or as posed. A press deeper than the gel is thick is an over-press (the
    /// renderer labels it); one so deep that the object has gone through the gel it is
    /// traced in is refused.
    pub fn pose(&self, sensor: &Sensor) -> Result<ContactPose> {
        self.hold.check()?;
        match self.hold {
            Hold::Surface {
                place,
                azimuth_deg,
                spin_deg,
                tilt_deg,
                tilt_towards_deg,
                depth_mm,
            } => {
                let hold = (azimuth_deg, spin_deg, tilt_deg, tilt_towards_deg);
                self.surface_pose(sensor, place, hold, depth_mm)
            }
            Hold::Pose {
                world_from_object,
                origin,
                approach,
            } => {
                let along = match approach {
                    Some(_) => "its approach",
                    None => "its +z axis",
                };
                match self.rigid_pose(sensor, world_from_object, origin, approach)? {
                    Rigid::Touching(pose) => Ok(*pose),
                    Rigid::Short(mm) => Err(GeltipError::contact(
                        "pose",
                        format!(
                            "the object does not touch the finger: it is {mm:.3} mm short of touching along {along}"
                        ),
                    )),
                    Rigid::Never => Err(GeltipError::contact(
                        "pose",
                        format!(
                            "the object does not touch the finger, nor would it moving along {along}"
                        ),
                    )),
                }
            }
        }
    }

    /// The pose of a hold at `place`: `(azimuth, spin, tilt, tilt towards)` in degrees,
    /// brought along the normal to its first touch and pressed `depth_mm` further.
    fn surface_pose(
        &self,
        sensor: &Sensor,
        place: Place,
        (azimuth_deg, spin_deg, tilt_deg, tilt_towards_deg): (f64, f64, f64, f64),
        depth_mm: f64,
    ) -> Result<ContactPose> {
        let f = &sensor.finger;
        let coord = coord_of(sensor, place, azimuth_deg)?;
        let sp = f.point_at(coord);
        let frame = object_frame(f, coord, &sp, spin_deg, tilt_deg, tilt_towards_deg);
        let touch = self.touch_on_normal(sensor, frame, &sp, place)?;
        // A top point on the normal touches at offset 0 exactly: the classic bound on how
        // deep the object reaches holds; otherwise trace the whole shell.
        let plain = touch.offset_mm == 0.0 && tilt_deg == 0.0;
        let trace_depth_mm = if plain {
            max_trace_depth(f, depth_mm)
        } else {
            max_trace_depth(f, f64::INFINITY)
        };
        check_reach(sensor, &self.object, trace_depth_mm)?;
        let push = depth_mm - touch.offset_mm;
        let pose = ContactPose {
            point: sp.point,
            normal: sp.normal,
            coord,
            region: sp.region,
            world_from_object: frame,
            origin: sp.point - push * sp.normal,
            depth_mm,
            first_touch_offset_mm: touch.offset_mm,
            first_touch: touch.band.iter().map(|&c| f.point_at(c).point).collect(),
            trace_depth_mm,
        };
        check_not_through(sensor, &self.object, &pose, -sp.normal).map_err(|most| {
            GeltipError::contact(
                "depth",
                format!(
                    "the {} pressed {depth_mm} mm deep at {} {most}",
                    self.name(),
                    place.label()
                ),
            )
        })?;
        Ok(pose)
    }

    /// As [`Press::pose`], but a rigid pose that does not touch the finger (short of it, or
    /// never touching along its approach) is `None` rather than an error: for callers that
    /// hold objects wherever a simulation puts them and render whichever touch.
    pub fn pose_if_touching(&self, sensor: &Sensor) -> Result<Option<ContactPose>> {
        self.hold.check()?;
        match self.hold {
            Hold::Pose {
                world_from_object,
                origin,
                approach,
            } => Ok(
                match self.rigid_pose(sensor, world_from_object, origin, approach)? {
                    Rigid::Touching(pose) => Some(*pose),
                    Rigid::Short(_) | Rigid::Never => None,
                },
            ),
            Hold::Surface { .. } => self.pose(sensor).map(Some),
        }
    }

    /// Where the object, held in `frame` with its top on the normal at `sp`, first touches
    /// the finger when brought along that normal: offsets searched from where it is clear of
    /// the (convex) finger down to a finger's radius inside it.
    fn touch_on_normal(
        &self,
        sensor: &Sensor,
        frame: DMat3,
        sp: &SurfacePoint,
        place: Place,
    ) -> Result<FirstTouch> {
        let f = &sensor.finger;
        let object = self.object.as_ref();
        let search = (-f.radius, object.bounding_radius() + 1e-3);
        let grid = HeightfieldGrid::for_sensor(sensor);
        first_touch(f, &grid, object, frame, sp.point, sp.normal, search).ok_or_else(|| {
            GeltipError::input(
                format!("object {}", object.name()),
                format!(
                    "brought along the normal at {} it never touches the finger (searched {:.1} mm in)",
                    place.label(),
                    -search.0
                ),
            )
        })
    }

    /// Where a rigid hold puts the object: touching (its depth is how far the object lies
    /// beyond its first touch moving along `approach`, or its own +z axis), short of
    /// touching, or never touching.
    fn rigid_pose(
        &self,
        sensor: &Sensor,
        world_from_object: DMat3,
        origin: DVec3,
        approach: Option<DVec3>,
    ) -> Result<Rigid> {
        let f = &sensor.finger;
        let grid = HeightfieldGrid::for_sensor(sensor);
        let object = self.object.as_ref();
        // Backing off: against the approach (the object's +z points at the finger).
        let b = -approach.unwrap_or_else(|| (world_from_object * DVec3::Z).normalize());
        // Anywhere along its axis: from beyond the finger's far side to its top.
        let clear = object.bounding_radius() + 1e-3;
        let span = origin.length() + f.radius + f.cylinder_length + clear;
        let touch = match first_touch(
            f,
            &grid,
            object,
            world_from_object,
            origin,
            b,
            (-span, span),
        ) {
            Some(t) if t.offset_mm >= 0.0 => t,
            Some(t) => return Ok(Rigid::Short(-t.offset_mm)),
            None => return Ok(Rigid::Never),
        };
        let trace_depth_mm = max_trace_depth(f, f64::INFINITY);
        check_reach(sensor, object, trace_depth_mm)?;
        let sp = f.point_at(touch.point);
        let pose = ContactPose {
            point: sp.point,
            normal: sp.normal,
            coord: touch.point,
            region: sp.region,
            world_from_object,
            origin,
            depth_mm: touch.offset_mm,
            first_touch_offset_mm: 0.0,
            first_touch: touch.band.iter().map(|&c| f.point_at(c).point).collect(),
            trace_depth_mm,
        };
        check_not_through(sensor, object, &pose, -b).map_err(|most| {
            GeltipError::contact(
                "pose",
                format!(
                    "the {} posed {:.3} mm beyond its first touch {most}",
                    self.name(),
                    pose.depth_mm
                ),
            )
        })?;
        Ok(Rigid::Touching(Box::new(pose)))
    }
}

/// The surface coordinate of `place` at `azimuth_deg`: the finger runs from the tip down to
/// the camera's plane (further where the lens sees behind it). A contact the lens cannot see
/// renders as the empty finger, and its ground truth says why it has no pixel.
fn coord_of(sensor: &Sensor, place: Place, azimuth_deg: f64) -> Result<SurfaceCoord> {
    let f = &sensor.finger;
    let s = place.arc_length(sensor);
    let s_max =
        (heightfield_extent(sensor) - margin_mm(sensor)).max(f.junction_s() + f.cylinder_length);
    if !(0.0..=s_max).contains(&s) {
        return Err(GeltipError::contact(
            "at",
            format!(
                "{} is {s:.3} mm from the tip along the surface; the finger runs 0..{s_max:.3} mm",
                place.label()
            ),
        ));
    }
    Ok(SurfaceCoord {
        s,
        phi: azimuth_deg.to_radians(),
    })
}

/// The object's frame at surface point `sp` (at `coord`): x along the meridian (away from
/// the tip), y along the azimuth, z inward; then the object's spin about its own z; then its
/// tilt.
fn object_frame(
    f: &Finger,
    coord: SurfaceCoord,
    sp: &SurfacePoint,
    spin_deg: f64,
    tilt_deg: f64,
    tilt_towards_deg: f64,
) -> DMat3 {
    let (e_s, e_phi) = f.tangents_at(coord);
    let (sin, cos) = spin_deg.to_radians().sin_cos();
    let x = cos * e_s + sin * e_phi;
    let y = -sin * e_s + cos * e_phi;
    let z = -sp.normal;
    let mut world_from_object = DMat3::from_cols(x, y, z);
    if tilt_deg != 0.0 {
        // The object's outward axis (+normal when untilted) leans towards t.
        let (ts, tc) = tilt_towards_deg.to_radians().sin_cos();
        let t = tc * e_s + ts * e_phi;
        let axis = sp.normal.cross(t).normalize();
        world_from_object = DMat3::from_axis_angle(axis, tilt_deg.to_radians()) * world_from_object;
    }
    world_from_object
}

/// Refuses an object whose baked SDF is not exact as far out as the contact stage traces it.
fn check_reach(sensor: &Sensor, object: &Object, trace_depth: f64) -> Result<()> {
    let reach = trace_depth + sensor.config.elastomer.drape_mm;
    if object.exact_reach_mm() < reach {
        return Err(GeltipError::input(
            format!("object {}", object.name()),
            format!(
                "its baked SDF is exact only {:.2} mm around it; this sensor's drape and press need {reach:.2} mm",
                object.exact_reach_mm()
            ),
        ));
    }
    Ok(())
}

/// The deepest `pose`'s object can be pressed (mm beyond its first touch, moving along unit
/// `into`) while it still reaches the gel the contact stage traces: while it holds the
/// point the trace depth beyond its first-touch point. Deeper, the object has gone through
/// the gel (and the rigid shell under it), and the frame would show nothing of it.
fn deepest_press(object: &Object, pose: &ContactPose, into: DVec3) -> f64 {
    let depth = pose.trace_depth_mm;
    let Some(&touched) = pose.first_touch.first() else {
        return depth;
    };
    let origin_at_touch = pose.origin - pose.depth_mm * into;
    let object_from_world = pose.world_from_object.transpose();
    // The object lies within its bounding radius of its origin.
    let last = depth + 2.0 * object.bounding_radius() + 1.0;
    touching_offset(
        object,
        object_from_world,
        touched + depth * into - origin_at_touch,
        object_from_world * into,
        last,
        0.0,
    )
    .map_or(depth, |t| t.max(depth))
}

/// Refuses a press deeper than the gel that has gone through it ([`deepest_press`]); the
/// error's tail says how deep it can go.
fn check_not_through(
    sensor: &Sensor,
    object: &Object,
    pose: &ContactPose,
    into: DVec3,
) -> std::result::Result<(), String> {
    let thickness = sensor.finger.shell_thickness;
    if pose.depth_mm <= thickness {
        return Ok(());
    }
    let most = deepest_press(object, pose, into);
    if pose.depth_mm <= most {
        return Ok(());
    }
    Err(format!(
        "has gone through the {thickness} mm gel and the shell under it: it reaches the gel only up to {most:.3} mm deep (beyond {thickness} mm a press is an over-press)"
    ))
}
