//! `geltip.calibrate`: a sensor fitted to a real GelTip's own frames by the library's
//! `geltip calibrate` job, returned as a `geltip.Sensor` that carries the job's report
//! (report.json's content); with `out`, the job's files are written there too.

use crate::convert::{count, path_or_str, repr};
use crate::errors::{bad, detached};
use crate::sensor::Sensor;
use geltip::calibrate::{FitSet, Options};
use geltip::jobs::calibrate as job;
use geltip::sensor::LedKindName;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A sensor fitted to a real GelTip's own frames, as `geltip calibrate`: `empty` is a frame
/// of the empty finger (an image file) or a list of several from the same camera; `sensor`
/// the one to start from (a `Sensor`, a preset name or a TOML path; default "paper").
/// `contacts`: a JSON-lines file of frames with known contacts (fits the imprint). `out`: a
/// directory for sensor.toml, report.json and the pictures (None: no file is kept).
/// `leds`, `samples`, `starts`: None for the command's defaults. `fit`: what is fitted, as
/// `--fit` ("lens,light,imprint" by default; add "camera" for the colour matrix and gamma,
/// "geometry" for the finger's length, "principal" and "focal" for the lens's principal point
/// and focal length fitted to the light where the circle is a mask);
/// `led_kind`: "point" or "gel" (default: the start sensor's). Returns the calibrated
/// `Sensor`, whose `calibration` is the report.
#[pyfunction]
#[pyo3(signature = (empty, sensor = None, *, contacts = None, out = None, leds = None, samples = None, starts = None, fit = None, led_kind = None))]
#[allow(clippy::too_many_arguments)] // The keyword arguments of geltip.calibrate, one each.
pub fn calibrate(
    py: Python<'_>,
    empty: &Bound<'_, PyAny>,
    sensor: Option<&Bound<'_, PyAny>>,
    contacts: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    leds: Option<&Bound<'_, PyAny>>,
    samples: Option<&Bound<'_, PyAny>>,
    starts: Option<&Bound<'_, PyAny>>,
    fit: Option<&str>,
    led_kind: Option<&str>,
) -> PyResult<Sensor> {
    let start = Sensor::of(py, sensor)?.get().inner.clone();
    let mut options = Options::new(start, paths(empty)?);
    options.contacts = contacts
        .map(|c| path_or_str("contacts", c).map(PathBuf::from))
        .transpose()?;
    let out = out
        .map(|o| path_or_str("out", o).map(PathBuf::from))
        .transpose()?;
    for (field, value, slot) in [
        ("leds", leds, &mut options.leds),
        ("samples", samples, &mut options.samples),
        ("starts", starts, &mut options.starts),
    ] {
        if let Some(v) = value {
            *slot = count(field, v)?;
        }
    }
    if let Some(f) = fit {
        options.fit = crate::errors::lib(FitSet::parse(f))?;
    }
    if let Some(k) = led_kind {
        options.led_kind = Some(crate::errors::lib(LedKindName::from_name(k))?);
    }
    let (sensor, report) = detached(py, "calibrating", || {
        let judged = job::judge(&options, &|_| {})?;
        if let Some(dir) = &out {
            job::write(&judged, dir)?;
        }
        Ok((judged.sensor, judged.report.to_string()))
    })?;
    Ok(Sensor::calibrated(sensor, report))
}

/// `empty`: one path, or a sequence of them (a `str` is one path, not its characters).
fn paths(empty: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    if let Ok(one) = path_or_str("empty", empty) {
        return Ok(vec![PathBuf::from(one)]);
    }
    let items = empty.try_iter().map_err(|_| {
        bad(
            "empty",
            format!("expected a path or a list of paths, got {}", repr(empty)),
        )
    })?;
    items
        .enumerate()
        .map(|(k, item)| path_or_str(&format!("empty[{k}]"), &item?).map(PathBuf::from))
        .collect()
}
