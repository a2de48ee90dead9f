//! A contact from Python, `render`'s keyword arguments or a dict of the same keys, as the
//! library's [`ContactSpec`]. Only types are converted here; what the values may be is the
//! library's to check ([`ContactSpec::hold`]), and its errors name these same keys.

use crate::convert::{number, path_or_str, repr};
use crate::errors::{bad, lib};
use geltip::scene::{naming_contact, numbers, At, ContactSpec};
use numpy::{AllowTypeChange, PyArrayLikeDyn};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

/// The keys a contact accepts (keyword arguments of `render`, keys of the dicts of
/// `render_batch` and `render_scene`): the spec's fields, and `rotation`, `translation` and
/// `s` as shorthands for `at`.
pub const CONTACT_KEYS: [&str; 12] = [
    "object",
    "at",
    "rotation",
    "translation",
    "s",
    "azimuth",
    "spin",
    "tilt",
    "tilt_towards",
    "depth",
    "pose",
    "approach",
];

/// The places, in the order `at` and its shorthands are named in messages.
const PLACE_ARGS: [&str; 4] = ["at", "rotation", "translation", "s"];

/// A contact's arguments as given (keys of [`CONTACT_KEYS`], `None` values left out), and
/// its index when it is one of a list.
pub struct ContactArgs<'py> {
    given: Vec<(&'static str, Bound<'py, PyAny>)>,
    index: Option<usize>,
}

impl<'py> ContactArgs<'py> {
    /// `render`'s keyword arguments, in the order of [`CONTACT_KEYS`].
    pub fn from_kwargs(values: [Option<&Bound<'py, PyAny>>; 12]) -> ContactArgs<'py> {
        let given = CONTACT_KEYS
            .into_iter()
            .zip(values)
            .filter_map(|(k, v)| v.filter(|v| !v.is_none()).map(|v| (k, v.clone())))
            .collect();
        ContactArgs { given, index: None }
    }

    /// Contact `k` of a list: a dict whose keys are among [`CONTACT_KEYS`].
    fn from_item(k: usize, item: &Bound<'py, PyAny>) -> PyResult<ContactArgs<'py>> {
        let field = format!("contacts[{k}]");
        let d = item
            .cast::<PyDict>()
            .map_err(|_| bad(&field, format!("expected a dict, got {}", repr(item))))?;
        let mut given = Vec::with_capacity(d.len());
        for (key, v) in d.iter() {
            let name: String = key
                .extract()
                .map_err(|_| bad(&field, format!("keys must be strings, got {}", repr(&key))))?;
            let Some(known) = CONTACT_KEYS.into_iter().find(|c| *c == name) else {
                return Err(bad(
                    format!("{field}.{name}"),
                    format!("unknown key, expected one of {}", CONTACT_KEYS.join(", ")),
                ));
            };
            if !v.is_none() {
                given.push((known, v));
            }
        }
        Ok(ContactArgs {
            given,
            index: Some(k),
        })
    }

    fn get(&self, key: &str) -> Option<&Bound<'py, PyAny>> {
        self.given.iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// The argument `key`'s name in messages: `depth`, or `contacts[3].depth` in a list.
    fn field(&self, key: &str) -> String {
        match self.index {
            Some(k) => format!("contacts[{k}].{key}"),
            None => key.to_string(),
        }
    }

    /// The contact as the library's spec. An object left out is an empty name, which the
    /// library refuses with the others it cannot press.
    pub fn spec(&self) -> PyResult<ContactSpec> {
        let object = match self.get("object") {
            Some(o) => path_or_str(&self.field("object"), o)?,
            None => String::new(),
        };
        let num = |key: &str| {
            self.get(key)
                .map(|v| number(&self.field(key), v))
                .transpose()
        };
        Ok(ContactSpec {
            object,
            at: self.at()?,
            azimuth: num("azimuth")?,
            spin: num("spin")?,
            tilt: num("tilt")?,
            tilt_towards: num("tilt_towards")?,
            depth: num("depth")?,
            pose: self
                .get("pose")
                .map(|p| self.numbers("pose", p))
                .transpose()?,
            approach: self
                .get("approach")
                .map(|a| self.numbers("approach", a))
                .transpose()?,
        })
    }

    /// `at` as text (`"rotation=30"`), a pair (`("rotation", 30)`) or a dict
    /// (`{"rotation": 30}`); or `rotation=`, `translation=` or `s=` instead. Giving two of
    /// these is refused here: only Python has the shorthands.
    fn at(&self) -> PyResult<Option<At>> {
        let given: Vec<(&str, &Bound<'py, PyAny>)> = PLACE_ARGS
            .into_iter()
            .filter_map(|k| self.get(k).map(|v| (k, v)))
            .collect();
        match given.as_slice() {
            [] => Ok(None),
            [("at", v)] => self.at_value(v).map(Some),
            [(key, v)] => Ok(Some(At::Table(BTreeMap::from([(
                key.to_string(),
                number(&self.field(key), v)?,
            )])))),
            many => {
                let names: Vec<&str> = many.iter().map(|(n, _)| *n).collect();
                Err(bad(
                    self.field(names[1]),
                    format!("give one place, not {}", names.join(" and ")),
                ))
            }
        }
    }

    fn at_value(&self, at: &Bound<'py, PyAny>) -> PyResult<At> {
        let field = self.field("at");
        if let Ok(text) = at.extract::<String>() {
            return Ok(At::Text(text));
        }
        let pairs: Option<Vec<(String, Bound<'py, PyAny>)>> = match at.cast::<PyDict>() {
            Ok(d) => d
                .iter()
                .map(|(k, v)| Some((k.extract().ok()?, v)))
                .collect(),
            Err(_) => at
                .extract::<(String, Bound<'py, PyAny>)>()
                .ok()
                .map(|p| vec![p]),
        };
        let Some(pairs) = pairs else {
            return Err(bad(
                field,
                format!(
                    "expected 'rotation=<deg>', 'translation=<mm>' or 's=<mm>' (or a pair such as ('rotation', 30)), got {}",
                    repr(at)
                ),
            ));
        };
        let mut table = BTreeMap::new();
        for (key, value) in pairs {
            let v = number(&format!("{field} {key}"), &value)?;
            table.insert(key, v);
        }
        Ok(At::Table(table))
    }

    /// `pose` or `approach` as text (the numbers separated by commas or spaces, as `--pose`)
    /// or any array-like of numbers.
    fn numbers(&self, key: &str, value: &Bound<'py, PyAny>) -> PyResult<Vec<f64>> {
        if let Ok(text) = value.extract::<String>() {
            return lib(numbers(key, &text).map_err(|e| match self.index {
                Some(k) => naming_contact(e, k),
                None => e,
            }));
        }
        let values = value.call_method0("__iter__").and_then(|_| {
            let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = value.extract()?;
            Ok(array.as_array().iter().copied().collect())
        });
        let expected = match key {
            "pose" => "16 numbers (a 4x4 matrix) or 7 (x y z qw qx qy qz)",
            _ => "3 numbers (a direction in the camera frame)",
        };
        values.map_err(|_| {
            bad(
                self.field(key),
                format!("expected {expected}, got {}", repr(value)),
            )
        })
    }
}

/// A list of contact dicts as specs.
pub fn specs_of(contacts: &Bound<'_, PyAny>) -> PyResult<Vec<ContactSpec>> {
    let iter = contacts.try_iter().map_err(|_| {
        bad(
            "contacts",
            format!("expected a list of dicts, got {}", repr(contacts)),
        )
    })?;
    let mut specs = Vec::new();
    for (k, item) in iter.enumerate() {
        specs.push(ContactArgs::from_item(k, &item?)?.spec()?);
    }
    Ok(specs)
}
