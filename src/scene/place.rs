//! Where on the finger a contact is placed: the paper's rotation about the tip, its
//! translation along the side, or arc length from the tip.

use crate::error::{quoted, GeltipError, Result};
use crate::sensor::Sensor;

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

/// The keys a place is given by, in its text (`rotation=30`) and table (`{rotation = 30}`)
/// forms.
pub const PLACE_KEYS: [&str; 3] = ["rotation", "translation", "s"];

const EXPECTED: &str = "expected rotation=<deg>, translation=<mm> or s=<mm>";

impl Place {
    /// Parses the text form `rotation=<deg>`, `translation=<mm>` or `s=<mm>`. Errors name the
    /// contact field `at`.
    pub fn parse(text: &str) -> Result<Place> {
        let (key, value) = text.split_once('=').ok_or_else(|| {
            GeltipError::contact("at", format!("{EXPECTED}, got {}", quoted(text)))
        })?;
        let v: f64 = value.trim().parse().map_err(|_| {
            GeltipError::contact(
                "at",
                format!("the value of {} is not a number", quoted(text)),
            )
        })?;
        if !PLACE_KEYS.contains(&key.trim()) {
            return Err(GeltipError::contact(
                "at",
                format!("{EXPECTED}, got {}", quoted(text)),
            ));
        }
        Place::from_key(key.trim(), v)
    }

    /// The place `key` (one of [`PLACE_KEYS`]) = `value`; the value must be finite.
    pub fn from_key(key: &str, value: f64) -> Result<Place> {
        crate::checks::finite(value)
            .map_err(|reason| GeltipError::contact("at", format!("{key} {reason}")))?;
        match key {
            "rotation" => Ok(Place::Rotation(value)),
            "translation" => Ok(Place::Translation(value)),
            "s" => Ok(Place::ArcLength(value)),
            _ => Err(GeltipError::contact(
                "at",
                format!(
                    "unknown place {}, expected rotation, translation or s",
                    quoted(key)
                ),
            )),
        }
    }

    /// The place's key (one of [`PLACE_KEYS`]) and value.
    pub fn key_value(self) -> (&'static str, f64) {
        match self {
            Place::Rotation(v) => ("rotation", v),
            Place::Translation(v) => ("translation", v),
            Place::ArcLength(v) => ("s", v),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_places_parse_and_bad_ones_name_the_field() {
        assert_eq!(Place::parse("rotation=30").unwrap(), Place::Rotation(30.0));
        assert_eq!(
            Place::parse(" translation = 5 ").unwrap(),
            Place::Translation(5.0)
        );
        assert_eq!(Place::parse("s=12.5").unwrap(), Place::ArcLength(12.5));
        for (bad, says) in [
            ("rotation", "expected rotation=<deg>"),
            ("elevation=3", "got 'elevation=3'"),
            (
                "rotation=abc",
                "the value of 'rotation=abc' is not a number",
            ),
            ("s=inf", "s must be a finite number, got inf"),
            ("rotation=NaN", "rotation must be a finite number"),
            // Text echoed on one line, shortened.
            ("s=12.5\ns=12.5", "the value of 's=12.5\\ns=12.5' is not"),
            (
                "rotation=1".repeat(100).as_str(),
                "the value of 'rotation=1rotation=1",
            ),
        ] {
            let e = Place::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("at: ") && e.contains(says), "{bad}: {e}");
            assert!(!e.contains('\n') && e.len() < 200, "{bad}: {e}");
        }
        for p in [
            Place::Rotation(-3.5),
            Place::Translation(8.0),
            Place::ArcLength(0.0),
        ] {
            let (k, v) = p.key_value();
            assert_eq!(Place::from_key(k, v).unwrap(), p);
        }
    }
}
