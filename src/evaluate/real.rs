//! Real labelled frames: frames from a real sensor with whatever their labels say (a pixel,
//! an azimuth about a centre, a point in mm, a region, or "no contact"), each against its own
//! reference, scored with the metrics each kind of label allows.
//!
//! The set is a JSON-lines file, one frame a line, paths relative to the file:
//! `{"image": "a.jpg", "reference": "a0.jpg", "contact": true, "pixel": [u, v],
//! "azimuth_deg": 101.4, "centre": [240, 240], "point_mm": [x, y, z], "region": "cylinder",
//! "group": "s1 push 2"}`; only `image`, `reference` and `contact` are required, and a
//! no-contact frame carries no place. [`RealSet::from_allsight`] converts the AllSight
//! set's `labels.json` (its contact frames, and each press's t = 0 frame against the
//! session's first as a no-contact pair).

use super::detections::Found;
use super::metrics::ErrorStats;
use super::truth::region_of;
use super::{Detector, Needs, Picture, Sample, SampleTruth};
use crate::error::{GeltipError, Result};
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Frames handed to a detector at once ([`Detector::detect_all`]).
const REAL_CHUNK: usize = 32;

/// A detection this near the labelled azimuth (degrees, about the label's centre) is at it.
pub const AZIMUTH_TOLERANCE_DEG: f64 = 15.0;

/// Region labels beyond the finger's own four ([`super::REGIONS`]): each names the regions
/// it takes in.
pub const COARSE_REGIONS: [(&str, [&str; 2]); 2] = [
    ("cylinder", ["junction", "side"]),
    ("dome", ["tip", "hemisphere"]),
];

/// What a real frame's label says; a contact frame may say any part of its place or none.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealLabel {
    pub contact: bool,
    pub pixel: Option<DVec2>,
    /// The contact's direction from `centre` in the image (0 = +x, 90 = +y, degrees).
    pub azimuth_deg: Option<f64>,
    pub centre: Option<DVec2>,
    /// The contact's point on the finger (mm, the sensor's camera frame).
    pub point_mm: Option<DVec3>,
    /// One of the finger's regions ([`super::REGIONS`]) or a coarse one ([`COARSE_REGIONS`]).
    pub region: Option<String>,
}

/// One labelled frame of a real set.
#[derive(Debug, Clone, PartialEq)]
pub struct RealFrame {
    pub image: PathBuf,
    pub reference: PathBuf,
    pub label: RealLabel,
    /// Where the tables put it (a session and push point, say); "all" if unnamed.
    pub group: String,
}

/// A set of real labelled frames.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealSet {
    pub frames: Vec<RealFrame>,
}

/// One frame's score: what the detector said and how far it was from each label it has.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealScore {
    /// The detector reported a contact.
    pub found: bool,
    pub confidence: f64,
    /// The surest detection's pixel and point.
    pub pixel: Option<DVec2>,
    pub point: Option<DVec3>,
    pub pixel_error_px: Option<f64>,
    pub azimuth_error_deg: Option<f64>,
    pub point_error_mm: Option<f64>,
    pub region_ok: Option<bool>,
}

/// A group's (or the whole set's) figures.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealRow {
    pub group: String,
    /// Contact frames, and those the detector found.
    pub contacts: usize,
    pub found: usize,
    /// Of the contact frames labelled with an azimuth: how many, and how many found within
    /// [`AZIMUTH_TOLERANCE_DEG`].
    pub with_azimuth: usize,
    pub at_azimuth: usize,
    pub median_azimuth_error_deg: Option<f64>,
    pub median_pixel_error_px: Option<f64>,
    pub median_point_error_mm: Option<f64>,
    /// Of the contact frames labelled with a region: how many, and how many found there.
    pub with_region: usize,
    pub region_right: usize,
    /// No-contact frames, and those the detector called a contact.
    pub empty: usize,
    pub false_contacts: usize,
}

/// A detector's scores over a real set.
#[derive(Debug, Clone, PartialEq)]
pub struct RealReport {
    pub detector: String,
    pub scores: Vec<RealScore>,
    /// Per group, in the order groups first appear, then the whole set ("all").
    pub rows: Vec<RealRow>,
}

fn bad(what: impl Into<String>, reason: impl Into<String>) -> GeltipError {
    GeltipError::input(what, reason)
}

fn number(v: &Value, what: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| bad(what, format!("must be a finite number, got {v}")))
}

fn numbers<const N: usize>(v: &Value, what: &str) -> Result<[f64; N]> {
    let list = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| bad(what, format!("must be {N} numbers, got {v}")))?;
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(list) {
        *o = number(x, what)?;
    }
    Ok(out)
}

/// Whether `label` (a region label) takes in the finger's region `found`.
pub fn region_matches(label: &str, found: &str) -> bool {
    label == found
        || COARSE_REGIONS
            .iter()
            .any(|(name, parts)| *name == label && parts.contains(&found))
}

fn known_region(name: &str) -> bool {
    super::REGIONS.contains(&name) || COARSE_REGIONS.iter().any(|(n, _)| *n == name)
}

impl RealFrame {
    /// A frame from one line of a set (`what` names it in errors); paths relative to `dir`.
    pub fn from_json(line: &Value, dir: &Path, what: &str) -> Result<RealFrame> {
        let obj = line
            .as_object()
            .ok_or_else(|| bad(what, "must be a JSON object"))?;
        const KNOWN: [&str; 9] = [
            "image",
            "reference",
            "contact",
            "pixel",
            "azimuth_deg",
            "centre",
            "point_mm",
            "region",
            "group",
        ];
        if let Some(k) = obj.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(bad(
                format!("{what}.{k}"),
                format!("unknown field (known: {})", KNOWN.join(", ")),
            ));
        }
        let field = |k: &str| obj.get(k).filter(|v| !v.is_null());
        let path = |k: &str| -> Result<PathBuf> {
            let v = field(k).ok_or_else(|| bad(format!("{what}.{k}"), "missing"))?;
            let s = v
                .as_str()
                .filter(|s| !s.is_empty())
                .ok_or_else(|| bad(format!("{what}.{k}"), "must be a file name"))?;
            Ok(dir.join(s))
        };
        let name = |k: &str| format!("{what}.{k}");
        let contact = field("contact")
            .ok_or_else(|| bad(name("contact"), "missing (true or false)"))?
            .as_bool()
            .ok_or_else(|| bad(name("contact"), "must be true or false"))?;
        let pixel = field("pixel")
            .map(|v| numbers::<2>(v, &name("pixel")).map(DVec2::from))
            .transpose()?;
        let azimuth_deg = field("azimuth_deg")
            .map(|v| number(v, &name("azimuth_deg")))
            .transpose()?;
        let centre = field("centre")
            .map(|v| numbers::<2>(v, &name("centre")).map(DVec2::from))
            .transpose()?;
        let point_mm = field("point_mm")
            .map(|v| numbers::<3>(v, &name("point_mm")).map(DVec3::from))
            .transpose()?;
        let region = match field("region") {
            None => None,
            Some(v) => {
                let r = v.as_str().filter(|r| known_region(r)).ok_or_else(|| {
                    bad(
                        name("region"),
                        format!(
                            "must be tip, hemisphere, junction, side, cylinder or dome, got {v}"
                        ),
                    )
                })?;
                Some(r.to_string())
            }
        };
        let group = match field("group") {
            None => "all".to_string(),
            Some(v) => v
                .as_str()
                .ok_or_else(|| bad(name("group"), "must be a string"))?
                .to_string(),
        };
        let label = RealLabel {
            contact,
            pixel,
            azimuth_deg,
            centre,
            point_mm,
            region,
        };
        let placed = label.pixel.is_some()
            || label.azimuth_deg.is_some()
            || label.point_mm.is_some()
            || label.region.is_some();
        if !contact && placed {
            return Err(bad(
                what,
                "a no-contact frame has no place (pixel, azimuth, point or region)",
            ));
        }
        if label.centre.is_some() && label.azimuth_deg.is_none() {
            return Err(bad(
                name("centre"),
                "is the centre of azimuth_deg, which is missing",
            ));
        }
        Ok(RealFrame {
            image: path("image")?,
            reference: path("reference")?,
            label,
            group,
        })
    }

    /// The frame as a line of a set, paths relative to `dir` where they lie under it.
    pub fn to_json(&self, dir: &Path) -> Value {
        let rel = |p: &Path| {
            p.strip_prefix(dir)
                .unwrap_or(p)
                .to_string_lossy()
                .into_owned()
        };
        let l = &self.label;
        let mut obj = Map::new();
        obj.insert("image".into(), json!(rel(&self.image)));
        obj.insert("reference".into(), json!(rel(&self.reference)));
        obj.insert("contact".into(), json!(l.contact));
        if let Some(p) = l.pixel {
            obj.insert("pixel".into(), json!([p.x, p.y]));
        }
        if let Some(a) = l.azimuth_deg {
            obj.insert("azimuth_deg".into(), json!(a));
        }
        if let Some(c) = l.centre {
            obj.insert("centre".into(), json!([c.x, c.y]));
        }
        if let Some(p) = l.point_mm {
            obj.insert("point_mm".into(), json!([p.x, p.y, p.z]));
        }
        if let Some(r) = &l.region {
            obj.insert("region".into(), json!(r));
        }
        obj.insert("group".into(), json!(self.group));
        Value::Object(obj)
    }
}

impl RealSet {
    /// Reads a set: a JSON-lines file in the format above, or the AllSight set's
    /// `labels.json` (converted by [`RealSet::from_allsight`]).
    pub fn read(path: &Path) -> Result<RealSet> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad("real set", format!("cannot read {}: {e}", path.display())))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        if let Ok(Value::Object(whole)) = serde_json::from_str::<Value>(&text) {
            if whole.contains_key("frames") {
                return RealSet::from_allsight(&Value::Object(whole), dir);
            }
        }
        let mut frames = Vec::new();
        for (k, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let what = format!("{} line {}", path.display(), k + 1);
            let value: Value = serde_json::from_str(line)
                .map_err(|e| bad(what.clone(), format!("not JSON: {e}")))?;
            frames.push(RealFrame::from_json(&value, dir, &what)?);
        }
        if frames.is_empty() {
            return Err(bad(
                "real set",
                format!("{} holds no frames", path.display()),
            ));
        }
        Ok(RealSet { frames })
    }

    /// The AllSight set's `labels.json` (`../shared/real/README.md`): each contact frame
    /// against its press's t = 0 frame, labelled with the authors' pixel, the azimuth about
    /// the image centre (240, 240; none at the tip, push point 11, where it means nothing)
    /// and the push point's region (cylinder or dome); then each press's t = 0 frame against
    /// the session's first frame, no contact. Groups: session and push point, and each
    /// session's drift pairs.
    pub fn from_allsight(labels: &Value, dir: &Path) -> Result<RealSet> {
        let what = "labels.json";
        let list = labels
            .get("frames")
            .and_then(Value::as_array)
            .ok_or_else(|| bad(what, "has no frames list"))?;
        let text = |f: &Value, k: &str, n: usize| -> Result<String> {
            f.get(k)
                .and_then(Value::as_str)
                .map(str::to_string)
                .ok_or_else(|| bad(format!("{what} frames[{n}].{k}"), "missing"))
        };
        let mut frames = Vec::new();
        let mut drift: BTreeMap<String, (String, String)> = BTreeMap::new();
        for (n, f) in list.iter().enumerate() {
            let image = text(f, "image", n)?;
            let session = image.split('_').next().unwrap_or("s").to_string();
            let press = text(f, "reference_press", n)?;
            let first = text(f, "reference_session", n)?;
            let num = f.get("num").and_then(Value::as_u64).unwrap_or(0);
            let field = |k: &str| f.get(k).filter(|v| !v.is_null());
            let name = |k: &str| format!("{what} frames[{n}].{k}");
            let pixel = field("contact_px_authors_formula")
                .map(|v| numbers::<2>(v, &name("contact_px_authors_formula")).map(DVec2::from))
                .transpose()?;
            let azimuth_deg = match num {
                11 => None,
                _ => field("image_azimuth_deg")
                    .map(|v| number(v, &name("image_azimuth_deg")))
                    .transpose()?,
            };
            let region = match field("push_point_region").and_then(Value::as_str) {
                Some("cylinder") => Some("cylinder".to_string()),
                Some("hemisphere") => Some("dome".to_string()),
                _ => None,
            };
            frames.push(RealFrame {
                image: dir.join(&image),
                reference: dir.join(&press),
                label: RealLabel {
                    contact: true,
                    pixel,
                    centre: azimuth_deg.map(|_| DVec2::new(240.0, 240.0)),
                    azimuth_deg,
                    point_mm: None,
                    region,
                },
                group: format!("{session} push {num}"),
            });
            drift.entry(press).or_insert((first, session));
        }
        for (press, (first, session)) in drift {
            frames.push(RealFrame {
                image: dir.join(press),
                reference: dir.join(first),
                label: RealLabel::default(),
                group: format!("{session} drift"),
            });
        }
        Ok(RealSet { frames })
    }

    /// The set as JSON lines, paths relative to `dir` (the file's folder).
    pub fn to_jsonl(&self, dir: &Path) -> String {
        self.frames
            .iter()
            .map(|f| format!("{}\n", f.to_json(dir)))
            .collect()
    }
}

/// The angle from `a` to `b`, degrees, in [0, 180].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// How far (degrees, 0 to 180) `pixel`'s direction from `centre` is from `azimuth_deg`
/// (0 = +x, 90 = +y): what "at the labelled azimuth" is judged by.
pub fn azimuth_error_deg(pixel: DVec2, centre: DVec2, azimuth_deg: f64) -> f64 {
    let d = pixel - centre;
    angle_between(d.y.atan2(d.x).to_degrees(), azimuth_deg)
}

/// Scores `found` (a frame's detections) against `frame`'s label.
pub fn score_frame(sensor: &Sensor, frame: &RealFrame, found: &[Found]) -> RealScore {
    let best = found
        .iter()
        .max_by(|a, b| a.confidence.total_cmp(&b.confidence));
    let l = &frame.label;
    let pixel = best.and_then(|f| f.pixel);
    let point = best.and_then(|f| f.point);
    let mut score = RealScore {
        found: best.is_some(),
        confidence: best.map_or(0.0, |f| f.confidence),
        pixel,
        point,
        ..RealScore::default()
    };
    if !l.contact {
        return score;
    }
    score.pixel_error_px = pixel.zip(l.pixel).map(|(a, b)| a.distance(b));
    if let (Some(p), Some(azimuth)) = (pixel, l.azimuth_deg) {
        let c = l.centre.unwrap_or(DVec2::new(
            sensor.width as f64 / 2.0,
            sensor.height as f64 / 2.0,
        ));
        score.azimuth_error_deg = Some(azimuth_error_deg(p, c, azimuth));
    }
    score.point_error_mm = point.zip(l.point_mm).map(|(a, b)| a.distance(b));
    if let Some(region) = &l.region {
        let found_region = point.map(|p| region_of(sensor, sensor.finger.coord_of(p).s));
        score.region_ok = Some(found_region.is_some_and(|r| region_matches(region, r)));
    }
    score
}

/// The median of `v` ([`ErrorStats`]'s); `None` when empty.
fn median(v: Vec<f64>) -> Option<f64> {
    ErrorStats::of(v).map(|s| s.median)
}

impl RealRow {
    fn of<'a>(
        group: &str,
        frames: impl Iterator<Item = (&'a RealFrame, &'a RealScore)>,
    ) -> RealRow {
        let mut row = RealRow {
            group: group.to_string(),
            ..RealRow::default()
        };
        let (mut az, mut px, mut pt) = (Vec::new(), Vec::new(), Vec::new());
        for (f, s) in frames {
            if !f.label.contact {
                row.empty += 1;
                row.false_contacts += s.found as usize;
                continue;
            }
            row.contacts += 1;
            row.found += s.found as usize;
            if f.label.azimuth_deg.is_some() {
                row.with_azimuth += 1;
                if let Some(e) = s.azimuth_error_deg {
                    row.at_azimuth += (e <= AZIMUTH_TOLERANCE_DEG) as usize;
                    az.push(e);
                }
            }
            if f.label.region.is_some() {
                row.with_region += 1;
                row.region_right += (s.region_ok == Some(true)) as usize;
            }
            px.extend(s.pixel_error_px);
            pt.extend(s.point_error_mm);
        }
        row.median_azimuth_error_deg = median(az);
        row.median_pixel_error_px = median(px);
        row.median_point_error_mm = median(pt);
        row
    }

    fn to_json(&self) -> Value {
        json!({
            "group": self.group,
            "contacts": self.contacts,
            "found": self.found,
            "with_azimuth": self.with_azimuth,
            "at_azimuth": self.at_azimuth,
            "median_azimuth_error_deg": self.median_azimuth_error_deg,
            "median_pixel_error_px": self.median_pixel_error_px,
            "median_point_error_mm": self.median_point_error_mm,
            "with_region": self.with_region,
            "region_right": self.region_right,
            "no_contact_frames": self.empty,
            "false_contacts": self.false_contacts,
        })
    }
}

impl RealReport {
    /// The whole set's row.
    pub fn total(&self) -> &RealRow {
        &self.rows[self.rows.len() - 1]
    }

    /// The tables, as markdown: a row per group, then the whole set.
    pub fn tables(&self) -> String {
        let pct = |a: usize, n: usize| match n {
            0 => "-".to_string(),
            _ => format!("{a}/{n} ({:.1}%)", 100.0 * a as f64 / n as f64),
        };
        let opt = |v: Option<f64>, d: usize| v.map_or("-".into(), |x| format!("{x:.d$}"));
        let mut out = format!(
            "{} on real frames (at the azimuth: within {AZIMUTH_TOLERANCE_DEG}° about the label's centre)\n\n\
             | group | found | at the azimuth | azimuth error ° (median) | pixel error px (median) | region right | false contacts |\n\
             |---|---|---|---|---|---|---|\n",
            self.detector
        );
        for r in &self.rows {
            out += &format!(
                "| {} | {} | {} | {} | {} | {} | {} |\n",
                r.group,
                pct(r.found, r.contacts),
                pct(r.at_azimuth, r.with_azimuth),
                opt(r.median_azimuth_error_deg, 1),
                opt(r.median_pixel_error_px, 1),
                pct(r.region_right, r.with_region),
                pct(r.false_contacts, r.empty),
            );
        }
        out
    }

    /// `summary.json`'s object: the detector, the azimuth tolerance and the rows.
    pub fn summary(&self) -> Value {
        json!({
            "detector": self.detector,
            "azimuth_tolerance_deg": AZIMUTH_TOLERANCE_DEG,
            "rows": self.rows.iter().map(RealRow::to_json).collect::<Vec<_>>(),
        })
    }

    /// Writes `summary.json` (the rows), `per_frame.jsonl` (each frame's label and score),
    /// `set.jsonl` (the set as scored, in the set format), `tables.md` and `by_group.svg`
    /// (the groups' shares found, at the azimuth and falsely called contacts) into `out`;
    /// the files written.
    pub fn write(&self, set: &RealSet, out: &Path) -> Result<Vec<String>> {
        std::fs::create_dir_all(out).map_err(|e| GeltipError::io(out, e))?;
        let summary = self.summary();
        let v2 = |p: Option<DVec2>| p.map(|p| json!([p.x, p.y]));
        let v3 = |p: Option<DVec3>| p.map(|p| json!([p.x, p.y, p.z]));
        let per_frame: String = set
            .frames
            .iter()
            .zip(&self.scores)
            .enumerate()
            .map(|(k, (f, s))| {
                let line = json!({
                    "sample": k,
                    "label": f.to_json(out),
                    "found": s.found,
                    "confidence": s.confidence,
                    "pixel": v2(s.pixel),
                    "point": v3(s.point),
                    "pixel_error_px": s.pixel_error_px,
                    "azimuth_error_deg": s.azimuth_error_deg,
                    "point_error_mm": s.point_error_mm,
                    "region_ok": s.region_ok,
                });
                format!("{line}\n")
            })
            .collect();
        let files = [
            ("summary.json", format!("{summary:#}\n")),
            ("per_frame.jsonl", per_frame),
            ("set.jsonl", set.to_jsonl(out)),
            ("tables.md", self.tables()),
            ("by_group.svg", super::charts::real_by_group(self)?),
        ];
        for (name, text) in &files {
            crate::output::write_atomic(out.join(name), text.as_bytes())?;
        }
        Ok(files.iter().map(|(n, _)| n.to_string()).collect())
    }
}

/// Runs `detector` on every frame of `set` (each against its own reference) for `sensor`,
/// whose image size the frames must have, and scores it; `progress(done, total)` after each
/// frame. A detector reading files gets `sensor_file` (the sensor as TOML) with each frame.
pub fn evaluate_real(
    set: &RealSet,
    sensor: &Arc<Sensor>,
    sensor_file: Option<Arc<PathBuf>>,
    detector: &mut dyn Detector,
    mut progress: impl FnMut(usize, usize),
) -> Result<RealReport> {
    if detector.needs() == Needs::Files && sensor_file.is_none() {
        return Err(bad(
            "evaluate",
            "a detector program needs the sensor as a file",
        ));
    }
    let indices: Vec<u64> = (0..set.frames.len() as u64).collect();
    detector.start(&indices)?;
    let mut references: BTreeMap<&Path, Arc<Picture>> = BTreeMap::new();
    let mut scores = Vec::with_capacity(set.frames.len());
    // A chunk of frames at a time (a detector may take them side by side), their pixels
    // dropped with the chunk.
    for (c, chunk) in set.frames.chunks(REAL_CHUNK).enumerate() {
        let first = c * REAL_CHUNK;
        let samples: Vec<Sample> = chunk
            .iter()
            .enumerate()
            .map(|(k, frame)| {
                let reference = references
                    .entry(frame.reference.as_path())
                    .or_insert_with(|| Arc::new(Picture::file(&frame.reference)))
                    .clone();
                Sample {
                    truth: SampleTruth {
                        index: (first + k) as u64,
                        contacts: Vec::new(),
                    },
                    image: Picture::file(&frame.image),
                    reference,
                    sensor: sensor.clone(),
                    sensor_file: sensor_file.clone(),
                    rendered: None,
                }
            })
            .collect();
        let found = detector.detect_all(&samples);
        for (k, (frame, found)) in chunk.iter().zip(found).enumerate() {
            let found = found.map_err(|e| {
                bad(
                    format!("frame {} ({})", first + k, frame.image.display()),
                    e.to_string(),
                )
            })?;
            scores.push(score_frame(sensor, frame, &found));
        }
        progress(scores.len(), set.frames.len());
    }
    detector.finish()?;
    let mut groups: Vec<&str> = Vec::new();
    for f in &set.frames {
        if !groups.contains(&f.group.as_str()) {
            groups.push(&f.group);
        }
    }
    let pairs = || set.frames.iter().zip(&scores);
    let mut rows: Vec<RealRow> = groups
        .iter()
        .map(|g| RealRow::of(g, pairs().filter(|(f, _)| f.group == *g)))
        .collect();
    rows.push(RealRow::of("all", pairs()));
    Ok(RealReport {
        detector: detector.name(),
        scores,
        rows,
    })
}
