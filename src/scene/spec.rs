//! One contact as data: the fields the command line's flags, scene files and the Python
//! package share ([`ContactSpec`]), checked on one path ([`ContactSpec::press`]); and scene
//! files, lists of them ([`load_scene`]).

use super::{Hold, Place, Press, PLACE_KEYS};
use crate::error::{GeltipError, Result};
use crate::object::{ObjectCache, Solid};
use crate::sensor::Sensor;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// One contact: an object and either a place and a press depth (with optional azimuth,
/// spin and tilt) or a rigid pose. Errors about it name these fields (`depth: ...`), which
/// front ends turn into their own flags or arguments.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// A built-in solid's name or a mesh file (.obj, .gltf, .glb).
    pub object: String,
    /// Where on the finger: `"rotation=30"` or a table such as `{rotation = 30}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<At>,
    /// Azimuth about the finger's axis, degrees (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub azimuth: Option<f64>,
    /// The object's rotation about the contact normal, degrees (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin: Option<f64>,
    /// Tilt of the object's axis away from the normal, degrees (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tilt: Option<f64>,
    /// Direction the tilt leans to, degrees from the meridian (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tilt_towards: Option<f64>,
    /// Press depth beyond the first touch, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// A rigid pose instead of a place and depth: 16 numbers (row-major 4x4 matrix) or 7
    /// (x y z qw qx qy qz), in the camera frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<Vec<f64>>,
    /// With a pose: the direction (3 numbers, camera frame) the object moves in to press the
    /// finger, along which its depth is measured (default: the object's +z axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach: Option<Vec<f64>>,
}

/// A place as given: the text `rotation=<deg>`, `translation=<mm>` or `s=<mm>`, or a table of
/// one of those keys and its number.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "'rotation=<deg>', 'translation=<mm>' or 's=<mm>', or a table such as {rotation = 30}"
)]
pub enum At {
    Text(String),
    Table(BTreeMap<String, f64>),
}

impl At {
    /// The place, checked (errors name the field `at`).
    pub fn place(&self) -> Result<Place> {
        match self {
            At::Text(text) => Place::parse(text),
            At::Table(table) => match table.iter().next() {
                Some((key, &value)) if table.len() == 1 => Place::from_key(key, value),
                _ => Err(GeltipError::contact(
                    "at",
                    format!(
                        "expected one key of {}, got {}",
                        PLACE_KEYS.join(", "),
                        if table.is_empty() {
                            "none".to_string()
                        } else {
                            table.keys().cloned().collect::<Vec<_>>().join(", ")
                        }
                    ),
                )),
            },
        }
    }
}

impl From<Place> for At {
    fn from(place: Place) -> At {
        let (key, value) = place.key_value();
        At::Table(BTreeMap::from([(key.to_string(), value)]))
    }
}

impl ContactSpec {
    /// The spec of `hold` pressing the object `object` names: the inverse of
    /// [`ContactSpec::hold`] (a place as a table, a pose as its 16 numbers).
    pub fn new(object: impl Into<String>, hold: &Hold) -> ContactSpec {
        let mut spec = ContactSpec {
            object: object.into(),
            ..ContactSpec::default()
        };
        match *hold {
            Hold::Surface {
                place,
                azimuth_deg,
                spin_deg,
                tilt_deg,
                tilt_towards_deg,
                depth_mm,
            } => {
                spec.at = Some(place.into());
                spec.azimuth = Some(azimuth_deg);
                spec.spin = Some(spin_deg);
                spec.tilt = Some(tilt_deg);
                spec.tilt_towards = Some(tilt_towards_deg);
                spec.depth = Some(depth_mm);
            }
            Hold::Pose {
                world_from_object: r,
                origin: o,
                approach,
            } => {
                let rows = r.transpose().to_cols_array();
                spec.pose = Some(vec![
                    rows[0], rows[1], rows[2], o.x, rows[3], rows[4], rows[5], o.y, rows[6],
                    rows[7], rows[8], o.z, 0.0, 0.0, 0.0, 1.0,
                ]);
                spec.approach = approach.map(|a| a.to_array().to_vec());
            }
        }
        spec
    }

    /// The hold the spec describes, its numbers checked ([`Hold::check`]); no object is
    /// loaded. Errors name the spec's fields.
    pub fn hold(&self) -> Result<Hold> {
        let hold = match &self.pose {
            Some(pose) => {
                for (field, given) in [
                    ("at", self.at.is_some()),
                    ("azimuth", self.azimuth.is_some()),
                    ("spin", self.spin.is_some()),
                    ("tilt", self.tilt.is_some()),
                    ("tilt_towards", self.tilt_towards.is_some()),
                    ("depth", self.depth.is_some()),
                ] {
                    if given {
                        return Err(GeltipError::contact(
                            field,
                            "cannot be combined with pose (the pose fixes it)",
                        ));
                    }
                }
                let hold = Hold::from_pose(pose)?;
                match &self.approach {
                    Some(approach) => hold.approaching(approach)?,
                    None => hold,
                }
            }
            None => {
                if self.approach.is_some() {
                    return Err(GeltipError::contact(
                        "approach",
                        "is for a pose (a place presses along the surface normal)",
                    ));
                }
                let at = self.at.as_ref().ok_or_else(|| {
                    GeltipError::contact(
                        "at",
                        "required: rotation=<deg>, translation=<mm> or s=<mm> (or a pose)",
                    )
                })?;
                let place = at.place()?;
                let depth_mm = self.depth.ok_or_else(|| {
                    GeltipError::contact("depth", "required: the press depth in mm (or a pose)")
                })?;
                Hold::Surface {
                    place,
                    azimuth_deg: self.azimuth.unwrap_or(0.0),
                    spin_deg: self.spin.unwrap_or(0.0),
                    tilt_deg: self.tilt.unwrap_or(0.0),
                    tilt_towards_deg: self.tilt_towards.unwrap_or(0.0),
                    depth_mm,
                }
            }
        };
        hold.check()?;
        Ok(hold)
    }

    /// The press: the hold checked first, then the object loaded through `objects`. Whether
    /// it fits a sensor's finger is [`Press::pose`]'s to say.
    pub fn press(&self, objects: &mut ObjectCache) -> Result<Press> {
        let hold = self.hold()?;
        if self.object.is_empty() {
            return Err(GeltipError::contact(
                "object",
                format!(
                    "required: a built-in solid ({}) or a mesh file (.obj, .gltf, .glb)",
                    Solid::ALL
                        .iter()
                        .chain(&Solid::EXTRA)
                        .map(|s| s.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        Ok(Press {
            object: objects.get(&self.object)?,
            hold,
        })
    }
}

/// The presses of a list of specs, objects loaded through `objects` (each once), each
/// placed on `sensor`'s finger when one is given ([`Press::pose`]). An error names the
/// contact (`contacts[1].depth: ...`, see [`naming_contact`]).
pub fn presses(
    specs: &[ContactSpec],
    objects: &mut ObjectCache,
    sensor: Option<&Sensor>,
) -> Result<Vec<Press>> {
    let mut presses = Vec::with_capacity(specs.len());
    for (k, spec) in specs.iter().enumerate() {
        let press = spec
            .press(objects)
            .and_then(|p| match sensor {
                Some(sensor) => p.pose(sensor).map(|_| p),
                None => Ok(p),
            })
            .map_err(|e| naming_contact(e, k))?;
        presses.push(press);
    }
    Ok(presses)
}

/// An error about contact `k` of a list, named as a list's element: a field's as
/// `contacts[k].depth: ...`, any other as `contacts[k]: ...`.
pub fn naming_contact(e: GeltipError, k: usize) -> GeltipError {
    match e {
        GeltipError::InvalidContact { field, reason } => {
            GeltipError::contact(format!("contacts[{k}].{field}"), reason)
        }
        other => GeltipError::input(format!("contacts[{k}]"), other.to_string()),
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    contacts: Vec<ContactSpec>,
}

/// Reads a scene: a JSON (`.json`) or TOML file with a list `contacts` of [`ContactSpec`]s,
/// and checks that each can be placed on `sensor`'s finger. The same object named twice is
/// loaded once. Errors name the file and the contact (`contacts[1].depth: ...`).
pub fn load_scene(path: &Path, sensor: &Sensor) -> Result<Vec<Press>> {
    let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
    let in_file = |reason: String| GeltipError::input(format!("scene {}", path.display()), reason);
    let file = parse_scene(path, &text).map_err(in_file)?;
    if file.contacts.is_empty() {
        return Err(in_file("lists no contacts".into()));
    }
    presses(&file.contacts, &mut ObjectCache::default(), Some(sensor))
        .map_err(|e| in_file(e.to_string()))
}

/// A scene file's contents, or a one-line reason naming the field (`contacts[1].at: ...`).
fn parse_scene(path: &Path, text: &str) -> std::result::Result<SceneFile, String> {
    let at = |field: String, message: String| {
        let message = message.trim().replace('\n', " ");
        if field == "." {
            message
        } else {
            format!("{field}: {message}")
        }
    };
    if path.extension().is_some_and(|e| e == "json") {
        let de = &mut serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            at(field, e.into_inner().to_string())
        })
    } else {
        let line = |e: &toml::de::Error| {
            e.span().map_or(String::new(), |s| {
                let n = text[..s.start.min(text.len())].lines().count().max(1);
                format!(" (line {n})")
            })
        };
        let de = toml::de::Deserializer::parse(text)
            .map_err(|e| format!("{}{}", e.message().trim(), line(&e)))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            let inner = e.into_inner();
            let where_ = line(&inner);
            at(field, format!("{}{where_}", inner.message()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(json: &str) -> ContactSpec {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn at_is_text_or_a_table() {
        let text = spec(r#"{"object": "sphere", "at": "rotation=30", "depth": 1}"#);
        let table = spec(r#"{"object": "sphere", "at": {"rotation": 30}, "depth": 1}"#);
        let toml: ContactSpec =
            toml::from_str("object = \"sphere\"\nat = {rotation = 30}\ndepth = 1.0").unwrap();
        for s in [&text, &table, &toml] {
            assert_eq!(
                s.hold().unwrap(),
                Hold::Surface {
                    place: Place::Rotation(30.0),
                    azimuth_deg: 0.0,
                    spin_deg: 0.0,
                    tilt_deg: 0.0,
                    tilt_towards_deg: 0.0,
                    depth_mm: 1.0,
                }
            );
        }
        let s = spec(r#"{"object": "sphere", "at": {"s": 12}, "depth": 1}"#);
        assert!(
            matches!(s.hold(), Ok(Hold::Surface { place: Place::ArcLength(v), .. }) if v == 12.0)
        );
    }

    #[test]
    fn bad_specs_name_the_field() {
        for (json, says) in [
            (
                r#"{"object": "sphere", "at": "rotation=30", "depth": -1}"#,
                "depth: a press depth cannot be negative, got -1 mm",
            ),
            (
                r#"{"object": "sphere", "at": "rotation=30"}"#,
                "depth: required",
            ),
            (r#"{"object": "sphere", "depth": 1}"#, "at: required"),
            (
                r#"{"object": "sphere", "at": "rotation=x", "depth": 1}"#,
                "at: the value of 'rotation=x' is not a number",
            ),
            (
                r#"{"object": "sphere", "at": {"rotation": 3, "s": 2}, "depth": 1}"#,
                "at: expected one key of rotation, translation, s, got rotation, s",
            ),
            (
                r#"{"object": "sphere", "at": {"height": 3}, "depth": 1}"#,
                "at: unknown place 'height'",
            ),
            (
                r#"{"object": "sphere", "at": "s=1", "depth": 1, "tilt": 95}"#,
                "tilt: must lie in (-90, 90) degrees, got 95",
            ),
            (
                r#"{"object": "sphere", "pose": [1, 2, 3]}"#,
                "pose: expected 16 numbers",
            ),
            (
                r#"{"object": "sphere", "pose": [0, 0, 0, 1, 0, 0, 0], "azimuth": 0}"#,
                "azimuth: cannot be combined with pose",
            ),
        ] {
            let e = spec(json).hold().unwrap_err();
            assert!(
                matches!(e, GeltipError::InvalidContact { .. }),
                "{json}: {e:?}"
            );
            assert!(e.to_string().starts_with(says), "{json}: {e}");
        }
        let e = toml::from_str::<ContactSpec>("object = \"sphere\"\nat = 30\ndepth = 1.0")
            .unwrap_err()
            .to_string();
        assert!(e.contains("or a table such as {rotation = 30}"), "{e}");
        assert!(serde_json::from_str::<ContactSpec>(r#"{"object": "sphere", "dpth": 1}"#).is_err());
    }

    #[test]
    fn a_list_names_the_contact_at_fault() {
        let specs = [
            spec(r#"{"object": "sphere", "at": "rotation=30", "depth": 1}"#),
            spec(r#"{"object": "sphere", "at": "rotation=30", "depth": -1}"#),
        ];
        let mut objects = ObjectCache::default();
        assert_eq!(presses(&specs[..1], &mut objects, None).unwrap().len(), 1);
        let e = presses(&specs, &mut objects, None).unwrap_err().to_string();
        assert_eq!(
            e,
            "contacts[1].depth: a press depth cannot be negative, got -1 mm"
        );
        let nameless = spec(r#"{"object": "", "at": "rotation=30", "depth": 1}"#);
        let e = presses(&[nameless], &mut objects, None)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("contacts[0].object: required"), "{e}");
        let e = presses(
            &[spec(r#"{"object": "pear", "at": "s=1", "depth": 1}"#)],
            &mut objects,
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("contacts[0]: object 'pear': not a built-in solid"),
            "{e}"
        );
    }

    #[test]
    fn pose_text_is_numbers_by_commas_or_spaces() {
        assert_eq!(
            crate::scene::pose_numbers(" 1,2  3,\t4 ").unwrap(),
            vec![1.0, 2.0, 3.0, 4.0]
        );
        let e = crate::scene::pose_numbers("1, x").unwrap_err().to_string();
        assert_eq!(e, "pose: 'x' is not a number");
    }

    #[test]
    fn specs_round_trip_through_json_and_toml() {
        let holds = [
            Hold::Surface {
                place: Place::Translation(6.5),
                azimuth_deg: 200.0,
                spin_deg: 10.0,
                tilt_deg: -25.0,
                tilt_towards_deg: 180.0,
                depth_mm: 1.2,
            },
            Hold::from_pose(&[0.5, 1.0, 28.0, 0.0, 1.0, 0.0, 0.0]).unwrap(),
        ];
        for hold in holds {
            let s = ContactSpec::new("cone", &hold);
            assert_eq!(s.hold().unwrap(), hold);
            let json: ContactSpec =
                serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
            let toml: ContactSpec = toml::from_str(&toml::to_string(&s).unwrap()).unwrap();
            assert_eq!(json, s);
            assert_eq!(toml, s);
        }
    }
}
