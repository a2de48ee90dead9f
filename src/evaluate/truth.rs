//! What a sample holds: its labelled contacts, taken from the renderer's ground truth or read
//! back from a labels line (`geltip render --labels`, a dataset's `labels.jsonl`, a scene's
//! labels).

use crate::error::{GeltipError, Result};
use crate::render::GroundTruth;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use serde_json::Value;

/// Which point of a contact a detection is scored against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// The indented area's centre on the surface (`contact_centre`; the contact point when
    /// nothing is indented): what the labels say detectors are scored against.
    ContactCentre,
    /// The point the object was pressed at (`point`).
    ContactPoint,
}

/// The parts of the finger results are broken down by, in report order.
pub const REGIONS: [&str; 4] = ["tip", "hemisphere", "junction", "side"];

/// The part of the finger at arc length `s` (mm) from the tip: the tip (the first quarter
/// of the hemisphere's arc), the rest of the hemisphere, the junction (from 0.5 mm above it
/// to 2 mm below), the cylinder's side below that.
pub fn region_of(sensor: &Sensor, s: f64) -> &'static str {
    let sj = sensor.finger.junction_s();
    if s < 0.25 * sj {
        "tip"
    } else if s < sj - 0.5 {
        "hemisphere"
    } else if s <= sj + 2.0 {
        "junction"
    } else {
        "side"
    }
}

/// Press-depth bins (mm) results are broken down by: `[edge_k, edge_k+1)`, the last open.
pub const DEPTH_EDGES: [f64; 8] = [0.0, 0.05, 0.1, 0.2, 0.4, 0.7, 1.0, 1.5];

/// The label of the depth bin holding `depth` (mm).
pub fn depth_bin(depth: f64) -> String {
    let k = DEPTH_EDGES.iter().rposition(|&e| depth >= e).unwrap_or(0);
    match DEPTH_EDGES.get(k + 1) {
        Some(hi) => format!("{}-{}", DEPTH_EDGES[k], hi),
        None => format!(">={}", DEPTH_EDGES[k]),
    }
}

/// One labelled contact of a sample.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledContact {
    /// The point detections are scored against (mm, camera frame).
    pub target: DVec3,
    /// The target's pixel (the contact point's when the target projects nowhere); `None`
    /// when the lens cannot see the contact.
    pub pixel: Option<DVec2>,
    /// The lens sees the contact: only visible contacts count as misses when not found.
    pub visible: bool,
    pub object: String,
    pub depth_mm: f64,
    /// Arc length from the tip (mm) and azimuth (degrees) of the contact point.
    pub s_mm: f64,
    pub azimuth_deg: f64,
    /// [`region_of`] the contact point.
    pub region: &'static str,
}

impl LabelledContact {
    /// A rendered contact's labels.
    pub fn from_truth(sensor: &Sensor, truth: &GroundTruth, target: Target) -> LabelledContact {
        let point = match target {
            Target::ContactCentre => truth.scoring_point(),
            Target::ContactPoint => truth.point,
        };
        LabelledContact::new(
            sensor,
            point,
            truth.pixel.as_ref().ok().copied(),
            truth.object.clone(),
            truth.depth_mm,
            (truth.s_mm, truth.azimuth_deg),
        )
    }

    fn new(
        sensor: &Sensor,
        target: DVec3,
        point_pixel: Option<DVec2>,
        object: String,
        depth_mm: f64,
        (s_mm, azimuth_deg): (f64, f64),
    ) -> LabelledContact {
        let visible = point_pixel.is_some();
        let pixel = if visible {
            sensor.project(target).ok().or(point_pixel)
        } else {
            None
        };
        LabelledContact {
            target,
            pixel,
            visible,
            object,
            depth_mm,
            s_mm,
            azimuth_deg,
            region: region_of(sensor, s_mm),
        }
    }

    /// One contact's object in a labels file (what [`GroundTruth::to_json`] writes); `what`
    /// names it in errors.
    pub fn from_json(sensor: &Sensor, v: &Value, target: Target, what: &str) -> Result<Self> {
        let point =
            vec3(v, "point", what)?.ok_or_else(|| GeltipError::input(what, "point: required"))?;
        let target = match target {
            Target::ContactCentre => vec3(v, "contact_centre", what)?.unwrap_or(point),
            Target::ContactPoint => point,
        };
        let pixel = match v.get("pixel") {
            None | Some(Value::Null) => None,
            Some(p) => Some(pixel_of(p).ok_or_else(|| {
                GeltipError::input(what, "pixel: expected [u, v] (finite numbers) or null")
            })?),
        };
        let object = match v.get("object") {
            Some(Value::String(s)) => s.clone(),
            _ => return Err(GeltipError::input(what, "object: required, a name")),
        };
        let number = |key: &str| -> Result<f64> {
            v.get(key)
                .and_then(Value::as_f64)
                .filter(|x| x.is_finite())
                .ok_or_else(|| GeltipError::input(what, format!("{key}: required, a number")))
        };
        Ok(LabelledContact::new(
            sensor,
            target,
            pixel,
            object,
            number("depth_mm")?,
            (number("s_mm")?, number("azimuth_deg")?),
        ))
    }
}

/// A finite `[x, y, z]` under `key`, `None` when absent or null.
fn vec3(v: &Value, key: &str, what: &str) -> Result<Option<DVec3>> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Array(a)) if a.len() == 3 => {
            let xyz: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
            if xyz.len() == 3 && xyz.iter().all(|x| x.is_finite()) {
                Ok(Some(DVec3::new(xyz[0], xyz[1], xyz[2])))
            } else {
                Err(GeltipError::input(
                    what,
                    format!("{key}: expected three finite numbers"),
                ))
            }
        }
        Some(_) => Err(GeltipError::input(
            what,
            format!("{key}: expected [x, y, z] or null"),
        )),
    }
}

/// A finite `[u, v]`.
pub(super) fn pixel_of(v: &Value) -> Option<DVec2> {
    let a = v.as_array().filter(|a| a.len() == 2)?;
    let (u, w) = (a[0].as_f64()?, a[1].as_f64()?);
    (u.is_finite() && w.is_finite()).then(|| DVec2::new(u, w))
}

/// A sample's labelled contacts (none: an empty frame).
#[derive(Debug, Clone, PartialEq)]
pub struct SampleTruth {
    /// The sample's index in its set or suite: what predictions name it by.
    pub index: u64,
    pub contacts: Vec<LabelledContact>,
}

impl SampleTruth {
    /// A rendered frame's truth: its contacts' ground truths (none for an empty frame).
    pub fn from_truths(
        sensor: &Sensor,
        index: u64,
        truths: &[GroundTruth],
        target: Target,
    ) -> SampleTruth {
        SampleTruth {
            index,
            contacts: truths
                .iter()
                .map(|t| LabelledContact::from_truth(sensor, t, target))
                .collect(),
        }
    }

    /// A labels object: one contact (`geltip render --labels`, a single-contact dataset's
    /// line) or a scene's `{"contacts": [...]}` (empty for an empty frame). `what` names
    /// the line in errors.
    pub fn from_json(
        sensor: &Sensor,
        index: u64,
        v: &Value,
        target: Target,
        what: &str,
    ) -> Result<SampleTruth> {
        let contacts = match v.get("contacts") {
            Some(Value::Array(list)) => list
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    LabelledContact::from_json(sensor, c, target, &format!("{what}: contacts[{i}]"))
                })
                .collect::<Result<Vec<_>>>()?,
            Some(_) => {
                return Err(GeltipError::input(what, "contacts: expected a list"));
            }
            None => vec![LabelledContact::from_json(sensor, v, target, what)?],
        };
        Ok(SampleTruth { index, contacts })
    }

    /// Contacts the lens sees.
    pub fn visible(&self) -> usize {
        self.contacts.iter().filter(|c| c.visible).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn depth_bins_cover_every_depth_once() {
        assert_eq!(depth_bin(0.0), "0-0.05");
        assert_eq!(depth_bin(0.05), "0.05-0.1");
        assert_eq!(depth_bin(0.99), "0.7-1");
        assert_eq!(depth_bin(1.5), ">=1.5");
        assert_eq!(depth_bin(7.0), ">=1.5");
    }

    #[test]
    fn labels_lines_read_back_one_contact_or_a_scene() {
        let sensor = Sensor::preset("paper").unwrap();
        let one = json!({"object": "sphere", "point": [7.5, 0.0, 15.0], "pixel": [400.0, 240.0],
            "contact_centre": [7.5, 0.1, 15.0], "depth_mm": 1.0, "s_mm": 12.0, "azimuth_deg": 0.0});
        let t = SampleTruth::from_json(&sensor, 3, &one, Target::ContactCentre, "line 4").unwrap();
        assert_eq!(t.contacts.len(), 1);
        assert_eq!(t.contacts[0].target, DVec3::new(7.5, 0.1, 15.0));
        assert!(t.contacts[0].visible);
        let p = SampleTruth::from_json(&sensor, 3, &one, Target::ContactPoint, "l").unwrap();
        assert_eq!(p.contacts[0].target, DVec3::new(7.5, 0.0, 15.0));
        let scene = json!({"contacts": [one.clone(), one], "mask_pixels": 3});
        let t = SampleTruth::from_json(&sensor, 0, &scene, Target::ContactCentre, "l").unwrap();
        assert_eq!(t.visible(), 2);
        let empty = json!({"contacts": []});
        let t = SampleTruth::from_json(&sensor, 0, &empty, Target::ContactCentre, "l").unwrap();
        assert!(t.contacts.is_empty());
        let bad = json!({"contacts": [{"object": "sphere", "point": [1.0, f64::NAN, 2.0]}]});
        let e = SampleTruth::from_json(&sensor, 0, &bad, Target::ContactCentre, "line 9")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 9: contacts[0]: point"), "{e}");
    }
}
