//! An evaluation's files: `summary.json`, `per_sample.jsonl`, `tables.md` and the charts, with
//! a second detector's results beside them when compared.

use super::charts;
use super::metrics::{depth_bins, group_names};
use super::truth::REGIONS;
use super::{Evaluation, Summary};
use crate::error::{GeltipError, Result};
use crate::output;
use crate::sensor::Sensor;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;

/// The run an evaluation came from, as reports state it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunInfo {
    /// `dataset <dir>` or `suite <name>`.
    pub source: String,
    pub sensor: String,
    pub gate_mm: Option<f64>,
    pub seconds: f64,
}

/// `summary.json`: the summary's fields and the run's.
pub fn summary_json(summary: &Summary, run: &RunInfo) -> Value {
    let mut v = summary.to_json();
    if let Value::Object(m) = &mut v {
        m.insert("source".into(), json!(run.source));
        m.insert("sensor".into(), json!(run.sensor));
        m.insert("gate_mm".into(), json!(run.gate_mm));
        m.insert("seconds".into(), json!(run.seconds));
        m.insert("geltip_version".into(), json!(env!("CARGO_PKG_VERSION")));
    }
    v
}

/// `per_sample.jsonl`: per frame, what matched (with its errors), what was missed and the
/// false positives; one line of [`per_sample`] each.
pub fn per_sample_jsonl(eval: &Evaluation) -> String {
    let mut text = String::new();
    for line in per_sample(eval) {
        let _ = writeln!(text, "{line}");
    }
    text
}

/// Per frame, what matched (with its errors), what was missed and the false positives.
pub fn per_sample(eval: &Evaluation) -> Vec<Value> {
    eval.frames
        .iter()
        .map(|f| {
            let point = |j: usize| f.found[j].point.map(|p| p.to_array());
            json!({
                "sample": f.truth.index,
                "contacts": f.truth.contacts.len(),
                "visible": f.truth.visible(),
                "detections": f.found.len(),
                "matched": f.score.matches.iter().map(|m| json!({
                    "contact": m.contact,
                    "detection": m.detection,
                    "error_mm": m.error_mm,
                    "error_px": m.error_px,
                    "confidence": f.found[m.detection].confidence,
                })).collect::<Vec<_>>(),
                "missed": f.score.missed,
                "false_positives": f.score.false_positives.iter()
                    .map(|&j| json!({"detection": j, "point": point(j)})).collect::<Vec<_>>(),
                "ignored": f.score.ignored,
            })
        })
        .collect()
}

/// A number with `digits` decimals, or "–" for null.
fn num(v: &Value, digits: usize) -> String {
    v.as_f64()
        .map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

/// "mean / median / p95 / max" of an error object.
fn errors(v: &Value) -> String {
    ["mean", "median", "p95", "max"]
        .iter()
        .map(|k| num(&v[k], 2))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// "detected of visible (recall %)".
fn found(v: &Value) -> String {
    let recall = v["recall"]
        .as_f64()
        .map(|r| format!(" ({:.1}%)", 100.0 * r))
        .unwrap_or_default();
    format!("{} of {}{recall}", v["detected"], v["visible"])
}

/// A table cell made from a summary.
type Cell = dyn Fn(&Value) -> String;

/// `tables.md`: the headline table, then recall and error by region, depth and object; a
/// column per summary (ours first, then the one compared).
pub fn tables_markdown(summaries: &[Value]) -> String {
    let first = &summaries[0];
    let mut md = format!(
        "# Detector evaluation\n\n{}, sensor `{}`, {} frames; a detection matches a visible contact within {} on the finger (one to one, Hungarian assignment).\n\n",
        first["source"].as_str().unwrap_or("?"),
        first["sensor"].as_str().unwrap_or("?"),
        first["samples"],
        match first["gate_mm"].as_f64() {
            Some(g) => format!("{g} mm"),
            None => "any distance".into(),
        },
    );
    let names: Vec<String> = summaries
        .iter()
        .map(|s| format!("`{}`", s["detector"].as_str().unwrap_or("?")))
        .collect();
    let _ = writeln!(md, "| | {} |", names.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(summaries.len()));
    let rows: [(&str, &Cell); 7] = [
        ("contacts found (recall)", &found),
        ("empty frames", &|s| s["empty_frames"].to_string()),
        ("false positives (on empty frames)", &|s| {
            format!(
                "{} ({})",
                s["false_positives"], s["false_positives_on_empty_frames"]
            )
        }),
        ("error, mm: mean / median / p95 / max", &|s| {
            errors(&s["error_mm"])
        }),
        ("error, px: mean / median / p95 / max", &|s| {
            errors(&s["error_px"])
        }),
        ("average precision", &|s| num(&s["average_precision"], 3)),
        ("seconds", &|s| num(&s["seconds"], 1)),
    ];
    for (label, cell) in rows {
        let cells: Vec<String> = summaries.iter().map(cell).collect();
        let _ = writeln!(md, "| {label} | {} |", cells.join(" | "));
    }
    for (key, title, order) in [
        ("by_region", "region", REGIONS.map(String::from).to_vec()),
        ("by_depth", "press depth (mm)", depth_bins()),
        ("by_object", "object", Vec::new()),
    ] {
        let _ = write!(md, "\n## By {title}\n\n| {title} |");
        for n in &names {
            let _ = write!(md, " {n}: found | {n}: error mm, mean / p95 |");
        }
        let _ = writeln!(md, "\n|---|{}", "---|---|".repeat(summaries.len()));
        for group in group_names(summaries, key, &order) {
            let _ = write!(md, "| {group} |");
            for s in summaries {
                let g = &s[key][&group];
                if g.is_null() {
                    let _ = write!(md, " – | – |");
                } else {
                    let e = &g["error_mm"];
                    let _ = write!(
                        md,
                        " {} | {} / {} |",
                        found(g),
                        num(&e["mean"], 2),
                        num(&e["p95"], 2)
                    );
                }
            }
            md.push('\n');
        }
    }
    md
}

/// Reads a compared run's `summary.json` from its output directory.
pub fn read_summary(dir: &Path) -> Result<Value> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| GeltipError::io(&path, e))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| {
        GeltipError::input(path.display().to_string(), format!("not valid JSON: {e}"))
    })?;
    for key in [
        "detector",
        "samples",
        "by_region",
        "by_depth",
        "by_object",
        "error_mm",
    ] {
        if v.get(key).is_none() {
            return Err(GeltipError::input(
                path.display().to_string(),
                format!("{key}: missing; is this a geltip evaluate summary?"),
            ));
        }
    }
    summary_numbers(&v).map_err(|why| {
        GeltipError::input(
            path.display().to_string(),
            format!("{why}; is this a geltip evaluate summary?"),
        )
    })?;
    Ok(v)
}

/// Refuses the numbers no summary holds, which the tables and charts would compute with:
/// a share (recall, precision, average precision) outside [0, 1], a negative error.
fn summary_numbers(v: &Value) -> std::result::Result<(), String> {
    // Far from 1, in exponent form: no line of hundreds of digits.
    let shown = |x: f64| match x.abs() >= 1e9 {
        true => format!("{x:e}"),
        false => format!("{x}"),
    };
    let share = |at: String, x: &Value| match x.as_f64() {
        Some(x) if !(0.0..=1.0).contains(&x) => {
            Err(format!("{at}: {} is not a share in [0, 1]", shown(x)))
        }
        _ => Ok(()),
    };
    let errors = |at: &str, e: &Value| {
        for stat in ["mean", "median", "p95", "max"] {
            if let Some(x) = e[stat].as_f64().filter(|x| *x < 0.0) {
                return Err(format!(
                    "{at}.{stat}: {} is not an error, which is >= 0",
                    shown(x)
                ));
            }
        }
        Ok(())
    };
    share("recall".into(), &v["recall"])?;
    share("average_precision".into(), &v["average_precision"])?;
    errors("error_mm", &v["error_mm"])?;
    errors("error_px", &v["error_px"])?;
    for (i, point) in v["precision_recall"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
    {
        // [threshold, precision, recall]
        share(format!("precision_recall[{i}][1]"), &point[1])?;
        share(format!("precision_recall[{i}][2]"), &point[2])?;
    }
    for key in ["by_region", "by_depth", "by_object"] {
        for (name, g) in v[key].as_object().into_iter().flatten() {
            share(format!("{key}.{name}.recall"), &g["recall"])?;
            errors(&format!("{key}.{name}.error_mm"), &g["error_mm"])?;
        }
    }
    Ok(())
}

/// The files of an evaluation, in memory: (name, bytes).
pub fn files(
    eval: &Evaluation,
    run: &RunInfo,
    sensor: &Sensor,
    compare: Option<&Value>,
) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let summary = summary_json(&eval.summary(), run);
    let mut summaries = vec![summary.clone()];
    summaries.extend(compare.cloned());
    let pretty = serde_json::to_string_pretty(&summary)
        .map_err(|e| GeltipError::input("summary.json", e.to_string()))?;
    Ok(vec![
        ("summary.json", (pretty + "\n").into_bytes()),
        ("per_sample.jsonl", per_sample_jsonl(eval).into_bytes()),
        ("tables.md", tables_markdown(&summaries).into_bytes()),
        (
            "by_depth.svg",
            charts::by_group(&summaries, "by_depth", &depth_bins())?.into_bytes(),
        ),
        (
            "by_region.svg",
            charts::by_group(&summaries, "by_region", &REGIONS.map(String::from))?.into_bytes(),
        ),
        (
            "failure_map.svg",
            charts::failure_map(eval, sensor)?.into_bytes(),
        ),
        (
            "precision_recall.svg",
            charts::precision_recall(&summaries)?.into_bytes(),
        ),
    ])
}

/// Writes an evaluation's files into `out` (each whole or not at all); returns their names.
pub fn write(
    out: &Path,
    eval: &Evaluation,
    run: &RunInfo,
    sensor: &Sensor,
    compare: Option<&Value>,
) -> Result<Vec<&'static str>> {
    // Everything is made before anything is written: a failure leaves no partial report.
    let files = files(eval, run, sensor, compare)?;
    std::fs::create_dir_all(out).map_err(|e| GeltipError::io(out, e))?;
    for (name, bytes) in &files {
        output::write_atomic(out.join(name), bytes)?;
    }
    Ok(files.into_iter().map(|(n, _)| n).collect())
}
