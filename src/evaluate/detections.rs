//! What a detector reports for a frame: a list of detections, each a pixel or a point on the
//! finger with a confidence, as JSON (`{"pixel": [u, v], "confidence": c}` or
//! `{"point": [x, y, z], ...}`) or from a built-in localiser.

use crate::error::{GeltipError, Result};
use crate::localise::Detection;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use serde_json::Value;

/// One detection, placed on the finger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Found {
    /// The detected contact on the finger (mm, camera frame): given, or the given pixel's
    /// surface point through the sensor's map m. `None`: the pixel sees no part of the
    /// finger, so the detection cannot match a contact.
    pub point: Option<DVec3>,
    /// The detection's pixel: given, or the pixel that sees the given point.
    pub pixel: Option<DVec2>,
    /// Larger is surer; only the order matters (precision-recall thresholds).
    pub confidence: f64,
}

impl Found {
    /// A detection at a pixel, placed on the finger by the map m.
    pub fn at_pixel(sensor: &Sensor, pixel: DVec2, confidence: f64) -> Found {
        Found {
            point: sensor.unproject(pixel).map(|sp| sp.point),
            pixel: Some(pixel),
            confidence,
        }
    }

    /// A detection at a point: its pixel is the one whose lens ray points at it.
    pub fn at_point(sensor: &Sensor, point: DVec3, confidence: f64) -> Found {
        let pixel = sensor
            .finger
            .surface_along(point.normalize_or_zero())
            .and_then(|sp| sensor.project(sp.point).ok());
        Found {
            point: Some(point),
            pixel,
            confidence,
        }
    }

    /// A built-in localiser's result: one detection, or none.
    pub fn from_detection(d: &Detection) -> Vec<Found> {
        match (d.detected, d.point) {
            (true, Some(point)) => vec![Found {
                point: Some(point),
                pixel: d.pixel,
                confidence: d.confidence,
            }],
            _ => Vec::new(),
        }
    }

    /// A detection's JSON object; `what` names it in errors.
    pub fn from_json(sensor: &Sensor, v: &Value, what: &str) -> Result<Found> {
        let Value::Object(fields) = v else {
            return Err(GeltipError::input(what, "expected an object"));
        };
        let numbers = |key: &str, expected: &str| -> Result<Option<Vec<f64>>> {
            let Some(v) = fields.get(key) else {
                return Ok(None);
            };
            v.as_array()
                .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
                .map(Some)
                .ok_or_else(|| {
                    GeltipError::input(what, format!("{key}: expected {expected}, got {v}"))
                })
        };
        let confidence = match fields.get("confidence") {
            None => None,
            Some(c) => Some(c.as_f64().ok_or_else(|| {
                GeltipError::input(
                    what,
                    format!("confidence: expected a finite number, got {c}"),
                )
            })?),
        };
        let given = Given {
            pixel: numbers("pixel", PIXEL)?,
            point: numbers("point", POINT)?,
            confidence,
        };
        Found::from_given(sensor, &given, what)
    }

    /// A detection as a front end gives it, checked: a point of three finite numbers (mm;
    /// its pixel, if given too, must lie on the image), else a pixel of two on the image; a
    /// finite confidence (1 if none). `what` names it in errors.
    pub fn from_given(sensor: &Sensor, given: &Given, what: &str) -> Result<Found> {
        let bad = |reason: String| GeltipError::input(what, reason);
        let confidence = match given.confidence {
            None => 1.0,
            Some(c) if c.is_finite() => c,
            Some(c) => {
                return Err(bad(format!(
                    "confidence: expected a finite number, got {c}"
                )))
            }
        };
        let finite = |v: &[f64], n: usize| v.len() == n && v.iter().all(|x| x.is_finite());
        let pixel = |v: &Vec<f64>| -> Result<DVec2> {
            if !finite(v, 2) {
                return Err(bad(format!("pixel: expected {PIXEL}, got {v:?}")));
            }
            let pixel = DVec2::new(v[0], v[1]);
            if !sensor.in_image(pixel) {
                return Err(bad(format!(
                    "pixel: ({}, {}) is outside the {}x{} image",
                    pixel.x, pixel.y, sensor.width, sensor.height
                )));
            }
            Ok(pixel)
        };
        if let Some(p) = &given.point {
            if !finite(p, 3) {
                return Err(bad(format!("point: expected {POINT}, got {p:?}")));
            }
            let mut found = Found::at_point(sensor, DVec3::new(p[0], p[1], p[2]), confidence);
            if let Some(px) = &given.pixel {
                found.pixel = Some(pixel(px)?);
            }
            return Ok(found);
        }
        match &given.pixel {
            Some(px) => Ok(Found::at_pixel(sensor, pixel(px)?, confidence)),
            None => Err(bad("needs \"pixel\": [u, v] or \"point\": [x, y, z]".into())),
        }
    }
}

/// How errors say what a pixel and a point must be.
const PIXEL: &str = "[u, v] (finite numbers)";
const POINT: &str = "[x, y, z] in mm";

/// A detection as a detector gives it, before it is checked ([`Found::from_given`]): what a
/// front end (a JSON line, a Python dict) converts its own values into, and nothing more.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Given {
    pub pixel: Option<Vec<f64>>,
    pub point: Option<Vec<f64>>,
    pub confidence: Option<f64>,
}

/// A detections list: `[{...}, ...]`.
pub fn detections_from_json(sensor: &Sensor, v: &Value, what: &str) -> Result<Vec<Found>> {
    let Value::Array(list) = v else {
        return Err(GeltipError::input(
            what,
            format!("detections: expected a list, got {}", kind(v)),
        ));
    };
    list.iter()
        .enumerate()
        .map(|(j, d)| Found::from_json(sensor, d, &format!("{what}: detections[{j}]")))
        .collect()
}

/// A JSON value's kind, for errors.
pub(super) fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// One line of a predictions file or a detector's answer, parsed: the sample it names (if
/// it names one) and its detections. `what` names the line in errors.
pub fn parse_line(sensor: &Sensor, line: &str, what: &str) -> Result<(Option<u64>, Vec<Found>)> {
    let v: Value = serde_json::from_str(line)
        .map_err(|e| GeltipError::input(what, format!("not valid JSON: {e}")))?;
    let Value::Object(fields) = &v else {
        return Err(GeltipError::input(
            what,
            format!("expected a JSON object, got {}", kind(&v)),
        ));
    };
    let sample = match fields.get("sample") {
        None => None,
        Some(s) => Some(s.as_u64().ok_or_else(|| {
            GeltipError::input(
                what,
                format!("sample: expected the sample's index (an integer >= 0), got {s}"),
            )
        })?),
    };
    let list = fields
        .get("detections")
        .ok_or_else(|| GeltipError::input(what, "detections: required (a list, maybe empty)"))?;
    Ok((sample, detections_from_json(sensor, list, what)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> Sensor {
        Sensor::preset("paper").unwrap()
    }

    #[test]
    fn a_pixel_goes_through_the_map_and_a_point_back_to_its_pixel() {
        let s = paper();
        let (k, found) = parse_line(
            &s,
            r#"{"sample": 4, "detections": [{"pixel": [400, 240], "confidence": 0.5}, {"point": [7.5, 0, 15.748976162659282]}]}"#,
            "line 1",
        )
        .unwrap();
        assert_eq!(k, Some(4));
        assert!(
            (found[0].point.unwrap() - DVec3::new(7.5, 0.0, 15.748976162659282)).length() < 1e-9
        );
        assert_eq!(found[0].confidence, 0.5);
        assert!((found[1].pixel.unwrap() - DVec2::new(400.0, 240.0)).length() < 1e-6);
        assert_eq!(found[1].confidence, 1.0);
        // A pixel in the image's dark corner sees no part of the finger.
        let (_, corner) = parse_line(&s, r#"{"detections": [{"pixel": [1, 1]}]}"#, "l").unwrap();
        assert_eq!(corner[0].point, None);
    }

    /// What a front end hands over unchecked (a Python dict: NaN and infinities included)
    /// is checked by the library, naming the field.
    #[test]
    fn given_values_are_checked_by_the_library() {
        let s = paper();
        let given = |pixel: Option<Vec<f64>>, point: Option<Vec<f64>>, confidence| Given {
            pixel,
            point,
            confidence,
        };
        let ok = Found::from_given(&s, &given(Some(vec![400.0, 240.0]), None, None), "d").unwrap();
        assert_eq!(
            (ok.pixel, ok.confidence),
            (Some(DVec2::new(400.0, 240.0)), 1.0)
        );
        for (g, says) in [
            (
                given(Some(vec![f64::NAN, 3.0]), None, None),
                "d: pixel: expected",
            ),
            (given(Some(vec![1.0]), None, None), "d: pixel: expected"),
            (
                given(None, Some(vec![1.0, f64::INFINITY, 2.0]), None),
                "d: point: expected",
            ),
            (
                given(Some(vec![1.0, 2.0]), None, Some(f64::NAN)),
                "d: confidence: expected a finite",
            ),
            (given(None, None, Some(0.5)), "d: needs"),
        ] {
            let e = Found::from_given(&s, &g, "d").unwrap_err().to_string();
            assert!(e.starts_with(says), "{g:?}: {e}");
        }
    }

    #[test]
    fn bad_lines_name_the_line_and_the_field() {
        let s = paper();
        for (line, says) in [
            ("{", "line 7: not valid JSON"),
            ("[1]", "line 7: expected a JSON object, got a list"),
            (r#"{"sample": -1, "detections": []}"#, "line 7: sample:"),
            (r#"{"sample": 1.5, "detections": []}"#, "line 7: sample:"),
            (r#"{"sample": 1}"#, "line 7: detections: required"),
            (
                r#"{"detections": {}}"#,
                "line 7: detections: expected a list",
            ),
            (r#"{"detections": [{}]}"#, "line 7: detections[0]: needs"),
            (
                r#"{"detections": [{"pixel": [700, 10]}]}"#,
                "line 7: detections[0]: pixel: (700, 10) is outside",
            ),
            (
                r#"{"detections": [{"pixel": [1, "a"]}]}"#,
                "line 7: detections[0]: pixel: expected",
            ),
            (
                r#"{"detections": [{"point": [1, 2]}]}"#,
                "line 7: detections[0]: point: expected",
            ),
            (
                r#"{"detections": [{"pixel": [1, 2], "confidence": "high"}]}"#,
                "line 7: detections[0]: confidence:",
            ),
            (
                r#"{"detections": [{"pixel": [1e999, 2]}]}"#,
                "line 7: not valid JSON",
            ),
            (
                r#"{"detections": [{"pixel": [NaN, 2]}]}"#,
                "line 7: not valid JSON",
            ),
        ] {
            let e = parse_line(&s, line, "line 7").unwrap_err().to_string();
            assert!(e.starts_with(says), "{line}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
