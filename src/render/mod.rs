//! The renderer: "this object pressed this deep at this place" -> the image the GelTip
//! camera would see. Four stages, each a WGSL file in `shaders/` and a Rust module here with
//! a CPU mirror under the same names, so tests can compare them:
//! 1. [`contact`]: penetration of the object along the surface normal, on the heightfield;
//! 2. [`elastomer`]: the gel's blend of that penetration, capped at the shell thickness;
//! 3. [`camera`]: each pixel's lens ray meets the deformed skin inside the shell;
//! 4. [`leds`]: three LEDs at the base light the painted skin.
//!
//! The heightfield lives on the unrolled disc (see [`crate::finger`]); only the object's
//! footprint on it, and the pixels that can see that footprint, are computed per contact:
//! the rest of every frame is the no-contact reference, rendered once per sensor.

pub mod camera;
pub mod contact;
pub mod cpu;
pub mod elastomer;
pub mod gpu;
pub mod leds;
pub mod touched;
pub mod uniforms;

use crate::error::{GeltipError, Result};
use crate::finger::{Region, SurfaceCoord};
use crate::object::Object;
use crate::sensor::Sensor;
use glam::{DMat3, DVec2, DVec3};
use std::sync::Arc;

/// Where on the finger a contact is placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Place {
    /// The paper's rotation about the tip, in degrees: 0 = the tip, 90 = the junction.
    Rotation(f64),
    /// The paper's translation along the side, in mm below the junction.
    Translation(f64),
    /// Arc length from the tip along a meridian, in mm.
    ArcLength(f64),
}

impl Place {
    /// Parses the CLI's `rotation=<deg>`, `translation=<mm>` or `s=<mm>`.
    pub fn parse(text: &str) -> Result<Place> {
        let bad = |reason: &str| GeltipError::input(format!("--at {text}"), reason.to_string());
        let (key, value) = text
            .split_once('=')
            .ok_or_else(|| bad("expected rotation=<deg>, translation=<mm> or s=<mm>"))?;
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| bad("the value is not a number"))?;
        if !v.is_finite() {
            return Err(bad("the value is not a finite number"));
        }
        match key.trim() {
            "rotation" => Ok(Place::Rotation(v)),
            "translation" => Ok(Place::Translation(v)),
            "s" => Ok(Place::ArcLength(v)),
            _ => Err(bad("expected rotation=<deg>, translation=<mm> or s=<mm>")),
        }
    }

    /// Arc length from the tip on `sensor`'s finger.
    pub fn arc_length(self, sensor: &Sensor) -> f64 {
        let f = &sensor.finger;
        match self {
            Place::Rotation(deg) => f.s_of_rotation(deg.to_radians()),
            Place::Translation(mm) => f.s_of_translation(mm),
            Place::ArcLength(s) => s,
        }
    }

    /// Human-readable label, as the experiment's tables use.
    pub fn label(self) -> String {
        match self {
            Place::Rotation(d) => format!("rotation {d} deg"),
            Place::Translation(mm) => format!("translation {mm} mm"),
            Place::ArcLength(s) => format!("s {s} mm"),
        }
    }
}

/// One object pressed into the finger.
#[derive(Debug, Clone)]
pub struct Contact {
    pub object: Arc<Object>,
    pub place: Place,
    /// Azimuth of the contact about the finger's axis, degrees (0 = image +x).
    pub azimuth_deg: f64,
    /// The object's own rotation about the contact normal, degrees.
    pub spin_deg: f64,
    /// How far the object is pressed in along the normal, mm.
    pub depth_mm: f64,
}

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
    /// the object lies beyond its first touch along its own +z axis.
    Pose {
        world_from_object: DMat3,
        origin: DVec3,
    },
}

/// One object held against the finger, in any pose: the general form of [`Contact`]
/// (which is a `Press` with no tilt).
#[derive(Debug, Clone)]
pub struct Press {
    pub object: Arc<Object>,
    pub hold: Hold,
}

impl From<&Contact> for Press {
    fn from(c: &Contact) -> Press {
        Press {
            object: c.object.clone(),
            hold: Hold::Surface {
                place: c.place,
                azimuth_deg: c.azimuth_deg,
                spin_deg: c.spin_deg,
                tilt_deg: 0.0,
                tilt_towards_deg: 0.0,
                depth_mm: c.depth_mm,
            },
        }
    }
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
    /// [`contact::FIRST_TOUCH_BAND_MM`] (a ring's circle).
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

/// Parses a rigid pose: 16 numbers (a row-major 4x4 matrix whose last row is 0 0 0 1 and
/// whose 3x3 part is orthonormal) or 7 numbers (position x y z and unit quaternion w x y z),
/// separated by commas or spaces, in the camera frame.
pub fn parse_pose(text: &str) -> Result<Hold> {
    let bad = |reason: String| GeltipError::input("--pose", reason);
    let v: Vec<f64> = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| bad(format!("'{t}' is not a number")))
        })
        .collect::<Result<_>>()?;
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
            // Orthonormal of either handedness: the frame `--at` places objects in (x along
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
            })
        }
        n => Err(bad(format!(
            "expected 16 numbers (row-major 4x4 matrix) or 7 (x y z qw qx qy qz), got {n}"
        ))),
    }
}

fn finite(what: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(GeltipError::input(
            what,
            format!("must be a finite number, got {v}"),
        ))
    }
}

impl Contact {
    /// Checks the contact's numbers and places it on `sensor`'s finger.
    pub fn pose(&self, sensor: &Sensor) -> Result<ContactPose> {
        Press::from(self).pose(sensor)
    }
}

impl Press {
    /// The object's name.
    pub fn name(&self) -> &str {
        self.object.name()
    }

    /// Checks the press's numbers and places it on `sensor`'s finger: by first touch and
    /// depth, or as posed.
    pub fn pose(&self, sensor: &Sensor) -> Result<ContactPose> {
        let f = &sensor.finger;
        let grid = HeightfieldGrid::for_sensor(sensor);
        let object = self.object.as_ref();
        let check_reach = |trace_depth: f64| {
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
        };
        // Offsets searched for the first touch: from where the object is clear of the
        // (convex) finger down to a finger's radius inside it.
        let search = (-f.radius, object.bounding_radius() + 1e-3);
        match self.hold {
            Hold::Surface {
                place,
                azimuth_deg,
                spin_deg,
                tilt_deg,
                tilt_towards_deg,
                depth_mm,
            } => {
                finite("--azimuth", azimuth_deg)?;
                finite("--spin", spin_deg)?;
                finite("--tilt", tilt_deg)?;
                finite("--tilt-towards", tilt_towards_deg)?;
                finite("--depth", depth_mm)?;
                if depth_mm < 0.0 {
                    return Err(GeltipError::input(
                        "--depth",
                        format!("a press depth cannot be negative, got {depth_mm} mm"),
                    ));
                }
                if !(0.0..90.0).contains(&tilt_deg.abs()) {
                    return Err(GeltipError::input(
                        "--tilt",
                        format!("must lie in (-90, 90) degrees, got {tilt_deg}"),
                    ));
                }
                let s = place.arc_length(sensor);
                // The finger runs from the tip down to the camera's plane (further where the
                // lens sees behind it). A contact the lens cannot see renders as the empty
                // finger, and its ground truth says why it has no pixel.
                let s_max = (heightfield_extent(sensor) - margin_mm(sensor))
                    .max(f.junction_s() + f.cylinder_length);
                if !(0.0..=s_max).contains(&s) {
                    return Err(GeltipError::input(
                        "--at",
                        format!(
                            "{} is {s:.3} mm from the tip along the surface; the finger runs 0..{s_max:.3} mm",
                            place.label()
                        ),
                    ));
                }
                let coord = SurfaceCoord {
                    s,
                    phi: azimuth_deg.to_radians(),
                };
                let sp = f.point_at(coord);
                let (e_s, e_phi) = f.tangents_at(coord);
                // Object x along the meridian (away from the tip), y along the azimuth, z
                // inward; then the object's spin about its own z; then its tilt.
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
                    world_from_object =
                        DMat3::from_axis_angle(axis, tilt_deg.to_radians()) * world_from_object;
                }
                let touch = contact::first_touch(
                    f,
                    &grid,
                    object,
                    world_from_object,
                    sp.point,
                    sp.normal,
                    search,
                )
                .ok_or_else(|| {
                    GeltipError::input(
                        format!("object {}", object.name()),
                        format!(
                            "brought along the normal at {} it never touches the finger (searched {:.1} mm in)",
                            place.label(),
                            -search.0
                        ),
                    )
                })?;
                // A top point on the normal touches at offset 0 exactly: the classic bound
                // on how deep the object reaches holds; otherwise trace the whole shell.
                let plain = touch.offset_mm == 0.0 && tilt_deg == 0.0;
                let trace_depth_mm = if plain {
                    contact::max_trace_depth(f, depth_mm)
                } else {
                    contact::max_trace_depth(f, f64::INFINITY)
                };
                check_reach(trace_depth_mm)?;
                let push = depth_mm - touch.offset_mm;
                Ok(ContactPose {
                    point: sp.point,
                    normal: sp.normal,
                    coord,
                    region: sp.region,
                    world_from_object,
                    origin: sp.point - push * sp.normal,
                    depth_mm,
                    first_touch_offset_mm: touch.offset_mm,
                    first_touch: touch.band.iter().map(|&c| f.point_at(c).point).collect(),
                    trace_depth_mm,
                })
            }
            Hold::Pose {
                world_from_object,
                origin,
            } => {
                // Backing off along the object's own -z (its +z points at the finger).
                let b = -(world_from_object * DVec3::Z).normalize();
                // Anywhere along its axis: from beyond the finger's far side to its top.
                let span = origin.length() + f.radius + f.cylinder_length + search.1;
                let search = (-span, span);
                let touch =
                    contact::first_touch(f, &grid, object, world_from_object, origin, b, search);
                let touch = match touch {
                    Some(t) if t.offset_mm >= 0.0 => t,
                    Some(t) => {
                        return Err(GeltipError::input(
                            "--pose",
                            format!(
                                "the object does not touch the finger: it is {:.3} mm short of touching along its +z axis",
                                -t.offset_mm
                            ),
                        ))
                    }
                    None => {
                        return Err(GeltipError::input(
                            "--pose",
                            "the object does not touch the finger, nor would it moving along its +z axis",
                        ))
                    }
                };
                let trace_depth_mm = contact::max_trace_depth(f, f64::INFINITY);
                check_reach(trace_depth_mm)?;
                let sp = f.point_at(touch.point);
                Ok(ContactPose {
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
                })
            }
        }
    }
}

/// One contact of a scene file (`geltip render --scene`): the `render` flags' names.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneEntry {
    object: String,
    at: Option<String>,
    #[serde(default)]
    azimuth: f64,
    #[serde(default)]
    spin: f64,
    #[serde(default)]
    tilt: f64,
    #[serde(default)]
    tilt_towards: f64,
    depth: Option<f64>,
    /// 16 numbers (row-major 4x4) or 7 (x y z qw qx qy qz), instead of at/depth.
    pose: Option<Vec<f64>>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    contacts: Vec<SceneEntry>,
}

/// Reads a scene: a JSON (`.json`) or TOML file with a list `contacts`, each an `object`
/// and either `at` + `depth` (with optional `azimuth`, `spin`, `tilt`, `tilt_towards`) or a
/// `pose`. The same object named twice is loaded once.
pub fn load_scene(path: &std::path::Path) -> Result<Vec<Press>> {
    let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
    let what = format!("scene {}", path.display());
    let file: SceneFile = if path.extension().is_some_and(|e| e == "json") {
        serde_json::from_str(&text).map_err(|e| GeltipError::input(&what, e.to_string()))?
    } else {
        toml::from_str(&text).map_err(|e| GeltipError::input(&what, e.message().to_string()))?
    };
    if file.contacts.is_empty() {
        return Err(GeltipError::input(what, "lists no contacts"));
    }
    let mut objects: std::collections::HashMap<String, Arc<Object>> = Default::default();
    let mut presses = Vec::with_capacity(file.contacts.len());
    for (k, c) in file.contacts.into_iter().enumerate() {
        let here = |reason: &str| {
            GeltipError::input(format!("{what}: contact {}", k + 1), reason.to_string())
        };
        let object = match objects.get(&c.object) {
            Some(o) => o.clone(),
            None => {
                let o = Arc::new(Object::from_arg(&c.object)?);
                objects.insert(c.object.clone(), o.clone());
                o
            }
        };
        let hold = match (c.pose, c.at, c.depth) {
            (Some(pose), None, None) => {
                let text: Vec<String> = pose.iter().map(|v| v.to_string()).collect();
                parse_pose(&text.join(","))?
            }
            (None, Some(at), Some(depth)) => Hold::Surface {
                place: Place::parse(&at)?,
                azimuth_deg: c.azimuth,
                spin_deg: c.spin,
                tilt_deg: c.tilt,
                tilt_towards_deg: c.tilt_towards,
                depth_mm: depth,
            },
            (Some(_), _, _) => return Err(here("give either a pose or at and depth, not both")),
            _ => return Err(here("needs at and depth (or a pose)")),
        };
        presses.push(Press { object, hold });
    }
    Ok(presses)
}

/// Ground truth of one rendered contact.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    pub object: String,
    pub place: String,
    pub point: DVec3,
    /// The contact point's pixel, or `None` with the reason when the camera cannot see it.
    pub pixel: std::result::Result<DVec2, String>,
    pub normal: DVec3,
    pub depth_mm: f64,
    pub region: Region,
    pub s_mm: f64,
    pub azimuth_deg: f64,
    pub spin_deg: f64,
    /// Pixels whose skin is pressed in by more than [`MASK_THRESHOLD_MM`].
    pub mask_pixels: u64,
    /// Bounding box of those pixels: [u0, v0, u1, v1] inclusive.
    pub mask_bbox: Option<[u32; 4]>,
    /// Whether the object pushed the gel against the rigid shell (penetration > thickness).
    pub over_pressed: bool,
    /// How far the skin is pushed in at the contact point itself (mm): the press depth for
    /// a solid top, 0 in a tube's hole.
    pub contact_indentation_mm: f64,
    /// The object's tilt away from the normal and its direction (degrees; 0 for a rigid pose).
    pub tilt_deg: f64,
    pub tilt_towards_deg: f64,
    /// The object's pose: camera-frame point = M (object point, 1), M row-major.
    pub pose: [f64; 16],
    /// How far from its top's place on the normal the object first touched (mm, outward
    /// positive; 0 for a top point on the normal, -1 for the torus at the tip).
    pub first_touch_offset_mm: f64,
    /// Surface points touched first (a ring's circle), the refined first point first.
    pub first_touch: Vec<DVec3>,
    /// The deepest penetration of the object into the undeformed skin (mm), and where.
    pub indentation_reached_mm: f64,
    pub deepest_point: Option<DVec3>,
    /// Centroid of the indented area on the surface (weighted by indentation): **the label
    /// detectors are scored against** (see [`GroundTruth::scoring_point`]).
    pub contact_centre: Option<DVec3>,
    /// Surface area of the indented region (mm²).
    pub indented_area_mm2: f64,
}

/// Indentation (mm) above which a pixel belongs to the contact mask.
pub const MASK_THRESHOLD_MM: f64 = 0.01;

impl GroundTruth {
    /// The point a contact detector should be scored against: the centre of the indented
    /// region on the surface ([`GroundTruth::contact_centre`]), or the contact point when
    /// nothing is indented. For a single-point top pressed along the normal of a smooth
    /// finger it lies at the contact point up to the imprint's asymmetry.
    pub fn scoring_point(&self) -> DVec3 {
        self.contact_centre.unwrap_or(self.point)
    }

    /// The labels file: one JSON object.
    pub fn to_json(&self) -> serde_json::Value {
        let v = |p: &DVec3| p.to_array();
        // A ring's first-touch band can hold hundreds of samples: at most 64, evenly spread.
        let stride = self.first_touch.len().div_ceil(64).max(1);
        let first_touch: Vec<[f64; 3]> = self.first_touch.iter().step_by(stride).map(v).collect();
        let (pixel, reason) = match &self.pixel {
            Ok(px) => (serde_json::json!([px.x, px.y]), serde_json::Value::Null),
            Err(why) => (serde_json::Value::Null, serde_json::json!(why)),
        };
        serde_json::json!({
            "object": self.object,
            "place": self.place,
            "point": self.point.to_array(),
            "pixel": pixel,
            "pixel_reason": reason,
            "normal": self.normal.to_array(),
            "depth_mm": self.depth_mm,
            "region": self.region.name(),
            "s_mm": self.s_mm,
            "azimuth_deg": self.azimuth_deg,
            "spin_deg": self.spin_deg,
            "mask_pixels": self.mask_pixels,
            "mask_bbox": self.mask_bbox,
            "over_pressed": self.over_pressed,
            "contact_indentation_mm": self.contact_indentation_mm,
            "tilt_deg": self.tilt_deg,
            "tilt_towards_deg": self.tilt_towards_deg,
            "pose": self.pose,
            "first_touch_offset_mm": self.first_touch_offset_mm,
            "first_touch_point": self.first_touch.first().map(v),
            "first_touch": first_touch,
            "indentation_reached_mm": self.indentation_reached_mm,
            "deepest_point": self.deepest_point.as_ref().map(v),
            "contact_centre": self.contact_centre.as_ref().map(v),
            "indented_area_mm2": self.indented_area_mm2,
            "score_against": "contact_centre",
        })
    }
}

/// A rendered frame: RGBA8 pixels (row-major, tightly packed) and the indentation (mm)
/// each pixel sees.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub indentation: Vec<f32>,
}

impl Frame {
    /// The RGB image (alpha dropped), as the localiser and PNG files use.
    pub fn to_rgb(&self) -> image::RgbImage {
        let rgb = self
            .rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        image::RgbImage::from_raw(self.width, self.height, rgb)
            .expect("frame size matches its pixels")
    }

    /// Pixel count and bounding box of the contact mask inside `rect`.
    pub fn mask_in(&self, rect: Rect) -> (u64, Option<[u32; 4]>) {
        let pressed = |d: &f32| *d as f64 > MASK_THRESHOLD_MM;
        let (u0, u1) = (rect.x.min(self.width), (rect.x + rect.w).min(self.width));
        let mut count = 0;
        let mut bbox: Option<[u32; 4]> = None;
        // Row by row: a count and the first and last pressed pixel (loops the compiler
        // vectorises; this runs on every rendered frame).
        for v in rect.y..(rect.y + rect.h).min(self.height) {
            let start = (v * self.width) as usize;
            let row = &self.indentation[start + u0 as usize..start + u1 as usize];
            let Some(first) = row.iter().position(pressed) else {
                continue;
            };
            let last = row.iter().rposition(pressed).unwrap_or(first);
            count += row[first..=last].iter().filter(|d| pressed(d)).count() as u64;
            let (a, b) = (u0 + first as u32, u0 + last as u32);
            bbox = Some(match bbox {
                None => [a, v, b, v],
                Some([x0, y0, x1, _]) => [x0.min(a), y0, x1.max(b), v],
            });
        }
        (count, bbox)
    }

    /// Pixel count and bounding box of the contact mask.
    pub fn mask(&self) -> (u64, Option<[u32; 4]>) {
        self.mask_in(Rect {
            x: 0,
            y: 0,
            w: self.width,
            h: self.height,
        })
    }
}

/// Extra arc length (mm) the heightfield covers beyond what the lens sees.
pub fn margin_mm(sensor: &Sensor) -> f64 {
    1.0 + 4.0 * sensor.config.elastomer.blend_mm
}

/// Half the side of the heightfield's square on the unrolled disc (mm): the arc length of the
/// farthest surface point the lens can see, plus a margin for the elastomer's blend.
pub fn heightfield_extent(sensor: &Sensor) -> f64 {
    let t = sensor.lens.max_theta;
    let f = &sensor.finger;
    let edge = f
        .surface_along(DVec3::new(t.sin(), 0.0, t.cos()))
        .map(|sp| f.coord_of(sp.point).s)
        .unwrap_or(f.junction_s());
    // The inner skin (pressed to the full thickness) is seen a little further out.
    let inner = edge + f.shell_thickness;
    inner + margin_mm(sensor)
}

/// The heightfield grid: `texels` x `texels` square on the unrolled disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightfieldGrid {
    pub texels: u32,
    pub half_size_mm: f64,
}

impl HeightfieldGrid {
    pub fn for_sensor(sensor: &Sensor) -> Self {
        HeightfieldGrid {
            texels: sensor.config.render.heightfield_texels,
            half_size_mm: heightfield_extent(sensor),
        }
    }

    /// Size of one texel on the disc, mm.
    pub fn texel_mm(&self) -> f64 {
        2.0 * self.half_size_mm / self.texels as f64
    }

    /// Disc coordinates of texel (i, j)'s centre.
    pub fn texel_centre(&self, i: u32, j: u32) -> DVec2 {
        DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * self.texel_mm()
            - DVec2::splat(self.half_size_mm)
    }

    /// Continuous texel coordinates of a disc point (texel centres at integer + 0.5).
    pub fn texel_of(&self, disc: DVec2) -> DVec2 {
        (disc + DVec2::splat(self.half_size_mm)) / self.texel_mm()
    }
}

/// A rectangle of texels or pixels: origin and size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl Rect {
    /// The rectangle covering continuous coordinates [lo, hi], grown by `pad` cells (x, y)
    /// and clipped to a `size.0` x `size.1` grid; `None` when nothing is left.
    pub fn covering(lo: DVec2, hi: DVec2, pad: DVec2, size: (u32, u32)) -> Option<Rect> {
        let x0 = (lo.x - pad.x).floor().max(0.0);
        let y0 = (lo.y - pad.y).floor().max(0.0);
        let x1 = (hi.x + pad.x).ceil().min(size.0 as f64);
        let y1 = (hi.y + pad.y).ceil().min(size.1 as f64);
        if !(x1 > x0 && y1 > y0) {
            return None;
        }
        Some(Rect {
            x: x0 as u32,
            y: y0 as u32,
            w: (x1 - x0) as u32,
            h: (y1 - y0) as u32,
        })
    }

    pub fn area(&self) -> u64 {
        self.w as u64 * self.h as u64
    }

    /// The smallest rectangle covering both.
    pub fn union(&self, other: &Rect) -> Rect {
        let (x0, y0) = (self.x.min(other.x), self.y.min(other.y));
        let x1 = (self.x + self.w).max(other.x + other.w);
        let y1 = (self.y + self.h).max(other.y + other.h);
        Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        }
    }

    /// `self` grown by `cells` each side, clipped to `within`; `None` when they do not meet.
    pub fn grown_within(&self, cells: u32, within: Rect) -> Option<Rect> {
        let x0 = self.x.saturating_sub(cells).max(within.x);
        let y0 = self.y.saturating_sub(cells).max(within.y);
        let x1 = (self.x + self.w + cells).min(within.x + within.w);
        let y1 = (self.y + self.h + cells).min(within.y + within.h);
        (x1 > x0 && y1 > y0).then_some(Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        })
    }

    /// The part of `self` outside `other`, as up to four disjoint rectangles.
    pub fn minus(self, other: Rect) -> Vec<Rect> {
        let (ax1, ay1) = (self.x + self.w, self.y + self.h);
        let (bx1, by1) = (other.x + other.w, other.y + other.h);
        let (ix0, iy0) = (self.x.max(other.x), self.y.max(other.y));
        let (ix1, iy1) = (ax1.min(bx1), ay1.min(by1));
        if ix0 >= ix1 || iy0 >= iy1 {
            return vec![self];
        }
        let mut out = Vec::new();
        let mut push = |x0: u32, y0: u32, x1: u32, y1: u32| {
            if x1 > x0 && y1 > y0 {
                out.push(Rect {
                    x: x0,
                    y: y0,
                    w: x1 - x0,
                    h: y1 - y0,
                });
            }
        };
        push(self.x, self.y, ax1, iy0); // above
        push(self.x, iy1, ax1, ay1); // below
        push(self.x, iy0, ix0, iy1); // left
        push(ix1, iy0, ax1, iy1); // right
        out
    }

    /// The union of `rects` as disjoint rectangles (each cell covered once).
    pub fn disjoint(rects: impl IntoIterator<Item = Rect>) -> Vec<Rect> {
        let mut out: Vec<Rect> = Vec::new();
        for r in rects {
            let mut pieces = vec![r];
            for q in &out {
                pieces = pieces.into_iter().flat_map(|p| p.minus(*q)).collect();
            }
            out.extend(pieces);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(pressed: &[(u32, u32, f32)]) -> Frame {
        let (width, height) = (7, 5);
        let mut indentation = vec![0.0; (width * height) as usize];
        for &(x, y, d) in pressed {
            indentation[(y * width + x) as usize] = d;
        }
        Frame {
            width,
            height,
            rgba: vec![0; (width * height * 4) as usize],
            indentation,
        }
    }

    #[test]
    fn disjoint_rects_cover_the_union_once() {
        let rects = [
            Rect {
                x: 0,
                y: 0,
                w: 10,
                h: 8,
            },
            Rect {
                x: 5,
                y: 4,
                w: 10,
                h: 10,
            },
            Rect {
                x: 30,
                y: 30,
                w: 3,
                h: 3,
            },
            Rect {
                x: 2,
                y: 2,
                w: 3,
                h: 3,
            },
        ];
        let pieces = Rect::disjoint(rects);
        let mut cover = vec![0u32; 40 * 40];
        for p in &pieces {
            for y in p.y..p.y + p.h {
                for x in p.x..p.x + p.w {
                    cover[y as usize * 40 + x as usize] += 1;
                }
            }
        }
        for y in 0..40u32 {
            for x in 0..40u32 {
                let inside = rects
                    .iter()
                    .any(|r| (r.x..r.x + r.w).contains(&x) && (r.y..r.y + r.h).contains(&y));
                assert_eq!(cover[(y * 40 + x) as usize], inside as u32, "cell {x},{y}");
            }
        }
        let area: u64 = pieces.iter().map(|p| p.area()).sum();
        // The second overlaps the first by 5 x 4; the fourth lies inside the first.
        assert_eq!(area, 80 + 100 - 20 + 9);
    }

    #[test]
    fn mask_counts_pressed_pixels_and_bounds_them() {
        assert_eq!(frame(&[]).mask(), (0, None));
        // At the threshold is not pressed; just past it is.
        assert_eq!(frame(&[(3, 2, MASK_THRESHOLD_MM as f32)]).mask(), (0, None));
        assert_eq!(frame(&[(3, 2, 0.02)]).mask(), (1, Some([3, 2, 3, 2])));
        // First and last pixels of the frame, a bump out (negative) ignored, in between.
        let f = frame(&[
            (0, 0, 0.5),
            (6, 4, 0.3),
            (5, 1, -0.4),
            (2, 3, 0.2),
            (6, 0, 0.1),
        ]);
        assert_eq!(f.mask(), (4, Some([0, 0, 6, 4])));
        let f = frame(&[(4, 1, 0.5), (1, 3, 0.3), (5, 2, 0.2)]);
        assert_eq!(f.mask(), (3, Some([1, 1, 5, 3])));
        // Inside a rect: pixels outside it do not count; a rect past the frame is clipped.
        let rect = |x, y, w, h| Rect { x, y, w, h };
        assert_eq!(f.mask_in(rect(2, 0, 10, 3)), (2, Some([4, 1, 5, 2])));
        assert_eq!(f.mask_in(rect(0, 3, 2, 1)), (1, Some([1, 3, 1, 3])));
        assert_eq!(f.mask_in(rect(0, 0, 1, 9)), (0, None));
    }
}
