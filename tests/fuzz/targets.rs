//! The parsers a user feeds, as fuzz targets: a table of (name, format, seeds, feed). A feed
//! hands one input to the library the way a user's file or argument reaches it, and checks
//! an accepted value for NaN and infinity where that is cheap.

use super::seeds::{self, paper, small};
use super::{Fed, Format, Target};
use geltip::evaluate::{self, Detector, Found, Predictions};
use geltip::jobs::dataset;
use geltip::localise::{self, Localiser, Method};
use geltip::object::{Mesh, Object, Primitive};
use geltip::render::{ContactPose, Hold, Place, Press};
use geltip::scene::{load_scene, pose_numbers, At, ContactSpec};
use geltip::Sensor;
use glam::{DVec2, DVec3};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The cases `tests/fuzz.rs` runs of a target (the CI budget).
const CI: usize = 2000;

/// Every target: name, input format, seeds, feed, CI cases. One row a parser.
#[rustfmt::skip]
static TARGETS: [Target; 23] = [
    t("sensor toml", Format::Toml, seeds::sensor_tomls, sensor_toml, CI),
    t("scene json", Format::Json, seeds::scene_jsons, scene_json, CI),
    t("scene toml", Format::Toml, seeds::scene_tomls, scene_toml, CI),
    t("mesh obj", Format::Obj, seeds::objs, mesh_obj, CI),
    t("mesh gltf", Format::Json, seeds::gltfs, mesh_gltf, CI),
    t("mesh glb", Format::Glb, seeds::glbs, mesh_glb, CI),
    t("png load_image", Format::Png, seeds::pngs, png_image, CI),
    t("png localise frame", Format::Png, seeds::small_frames, png_localise, CI),
    t("png dataset background", Format::Png, seeds::small_frames, png_background, CI),
    t("pose text", Format::Words, seeds::pose_texts, pose_text, CI),
    t("place text", Format::Words, seeds::place_texts, place_text, CI),
    t("primitive text", Format::Words, seeds::primitive_texts, primitive_text, CI),
    t("resume dataset.json", Format::Json, resume_manifests, resume_manifest, CI),
    t("resume labels.jsonl", Format::JsonLines, seeds::labels_jsonl, resume_labels, CI),
    t("merge dataset.json", Format::Json, merge_manifests, merge_manifest, CI),
    t("merge first dataset.json", Format::Json, first_merge_manifests, merge_first_manifest, CI),
    t("merge labels.jsonl", Format::JsonLines, merge_labels_seeds, merge_labels, CI),
    t("evaluate predictions.jsonl", Format::JsonLines, seeds::predictions_jsonl, predictions, CI),
    t("evaluate detector answer", Format::Json, seeds::detector_answers, detector_answer, CI),
    t("calibrate contacts.jsonl", Format::JsonLines, seeds::calibrate_contacts, calibrate_contacts, CI),
    t("png calibrate empty frame", Format::Png, seeds::small_frames, png_empty_frame, CI),
    t("evaluate labels.jsonl", Format::JsonLines, seeds::evaluate_labels, evaluate_labels, CI),
    t("evaluate compare summary.json", Format::Json, seeds::evaluate_summaries, evaluate_compare, CI),
];

const fn t(
    name: &'static str,
    format: Format,
    seeds: fn() -> Vec<Vec<u8>>,
    feed: fn(&Path, &[u8]) -> Fed,
    ci_cases: usize,
) -> Target {
    Target {
        name,
        format,
        seeds,
        feed,
        ci_cases,
    }
}

/// Every target.
pub fn all() -> &'static [Target] {
    &TARGETS
}

/// The target called `name`.
pub fn by_name(name: &str) -> &'static Target {
    all()
        .iter()
        .find(|t| t.name == name)
        .unwrap_or_else(|| panic!("no fuzz target '{name}'"))
}

/// `input` written to `dir/name`.
fn file(dir: &Path, name: &str, input: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, input).expect("cannot write a fuzz case");
    path
}

/// A library result as a verdict: its error message, or `check` of its value.
fn verdict<T>(r: geltip::Result<T>, check: impl FnOnce(T) -> Result<(), String>) -> Fed {
    match r {
        Err(e) => Fed::Refused(e.to_string()),
        Ok(v) => match check(v) {
            Ok(()) => Fed::Accepted,
            Err(why) => Fed::Unsound(why),
        },
    }
}

/// Ok if every number is finite; else names the first that is not.
fn finite(what: &str, values: &[f64]) -> Result<(), String> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => Err(format!("{what} holds {v}")),
        None => Ok(()),
    }
}

fn vec3s(v: &[DVec3]) -> Vec<f64> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

fn sensor_toml(dir: &Path, input: &[u8]) -> Fed {
    let path = file(dir, "sensor.toml", input);
    verdict(Sensor::load(&path.to_string_lossy()), |s| check_sensor(&s))
}

/// Every float of the configuration, the finger and the lens finite, and the map m finite
/// where it answers.
fn check_sensor(s: &Sensor) -> Result<(), String> {
    let text = toml::to_string(&s.config).map_err(|e| format!("config does not serialise: {e}"))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| format!("config: {e}"))?;
    let mut floats = Vec::new();
    collect_floats(&toml::Value::Table(table), &mut floats);
    finite("config", &floats)?;
    let f = &s.finger;
    finite("finger", &[f.radius, f.cylinder_length, f.shell_thickness])?;
    finite("principal point", &s.principal.to_array())?;
    for px in [
        s.principal,
        DVec2::ZERO,
        DVec2::new(s.width as f64 - 1.0, 0.5 * s.height as f64),
    ] {
        if let Some(sp) = s.unproject(px) {
            finite("unproject", &vec3s(&[sp.point, sp.normal]))?;
            if let Ok(back) = s.project(sp.point) {
                finite("project", &back.to_array())?;
            }
        }
    }
    Ok(())
}

fn collect_floats(v: &toml::Value, out: &mut Vec<f64>) {
    match v {
        toml::Value::Float(x) => out.push(*x),
        toml::Value::Array(items) => items.iter().for_each(|i| collect_floats(i, out)),
        toml::Value::Table(t) => t.values().for_each(|i| collect_floats(i, out)),
        _ => {}
    }
}

fn scene(dir: &Path, name: &str, input: &[u8]) -> Fed {
    let path = file(dir, name, input);
    verdict(load_scene(&path, paper()), |presses| {
        for p in &presses {
            check_hold(&p.hold)?;
        }
        // The scene's presses placed on the finger (load_scene placed each to check it).
        match presses.first().map(|p| p.pose(paper())) {
            Some(Ok(pose)) => check_pose(&pose),
            Some(Err(e)) => Err(format!("loaded, then refused: {e}")),
            None => Err("no contacts".into()),
        }
    })
}

fn scene_json(dir: &Path, input: &[u8]) -> Fed {
    scene(dir, "scene.json", input)
}

fn scene_toml(dir: &Path, input: &[u8]) -> Fed {
    scene(dir, "scene.toml", input)
}

/// Every number of a hold finite (read through its spec: the place's value, the angles and
/// depth, or the pose's 16 numbers).
fn check_hold(hold: &Hold) -> Result<(), String> {
    let spec = ContactSpec::new("", hold);
    let mut v: Vec<f64> = [
        spec.azimuth,
        spec.spin,
        spec.tilt,
        spec.tilt_towards,
        spec.depth,
    ]
    .into_iter()
    .flatten()
    .collect();
    if let Some(At::Table(place)) = &spec.at {
        v.extend(place.values());
    }
    v.extend(spec.pose.iter().flatten());
    finite("hold", &v)
}

fn check_pose(p: &ContactPose) -> Result<(), String> {
    let mut v = vec3s(&[p.point, p.normal, p.origin]);
    v.extend(p.world_from_object.to_cols_array());
    v.extend([
        p.depth_mm,
        p.first_touch_offset_mm,
        p.trace_depth_mm,
        p.coord.s,
        p.coord.phi,
    ]);
    v.extend(vec3s(&p.first_touch));
    finite("contact pose", &v)
}

fn mesh(dir: &Path, name: &str, input: &[u8]) -> Fed {
    let path = file(dir, name, input);
    verdict(Mesh::load(&path), |m| {
        finite("vertices", &vec3s(&m.positions))?;
        let placed = m.placed_for_contact();
        finite("placed vertices", &vec3s(&placed.positions))?;
        let n = m.positions.len();
        match m.triangles.iter().flatten().find(|&&i| i as usize >= n) {
            Some(i) => Err(format!("index {i} of {n} vertices")),
            None => Ok(()),
        }
    })
}

fn mesh_obj(dir: &Path, input: &[u8]) -> Fed {
    mesh(dir, "mesh.obj", input)
}

fn mesh_gltf(dir: &Path, input: &[u8]) -> Fed {
    mesh(dir, "mesh.gltf", input)
}

fn mesh_glb(dir: &Path, input: &[u8]) -> Fed {
    mesh(dir, "mesh.glb", input)
}

fn check_image(img: &image::RgbImage) -> Result<(), String> {
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 || img.as_raw().len() != (w * h * 3) as usize {
        return Err(format!("a {w}x{h} image of {} bytes", img.as_raw().len()));
    }
    Ok(())
}

fn png_image(dir: &Path, input: &[u8]) -> Fed {
    let path = file(dir, "frame.png", input);
    verdict(localise::load_image(&path), |img| check_image(&img))
}

/// The small sensor's localiser (its surface table built once) and reference frame.
fn small_localiser() -> &'static (Localiser, image::RgbImage) {
    static L: OnceLock<(Localiser, image::RgbImage)> = OnceLock::new();
    L.get_or_init(|| {
        let reference = image::load_from_memory(&seeds::small_frames()[0])
            .expect("a seed frame")
            .to_rgb8();
        (Localiser::new(small()), reference)
    })
}

fn png_localise(dir: &Path, input: &[u8]) -> Fed {
    let path = file(dir, "frame.png", input);
    let (localiser, reference) = small_localiser();
    verdict(localise::load_frame(small(), &path), |frame| {
        check_image(&frame)?;
        for method in [Method::Paper, Method::Surface] {
            let d = localiser
                .localise(reference, &frame, method)
                .map_err(|e| format!("a frame of the sensor's size refused: {e}"))?;
            let mut v = vec![d.confidence];
            v.extend(d.pixel.map_or(vec![], |p| p.to_array().to_vec()));
            v.extend(d.point.map_or(vec![], |p| p.to_array().to_vec()));
            finite("detection", &v)?;
        }
        Ok(())
    })
}

fn png_background(dir: &Path, input: &[u8]) -> Fed {
    let path = file(dir, "background.png", input);
    let spec = seeds::empty_shard_spec(Some(path));
    verdict(dataset::run(&spec, Some(&dir.join("set")), |_| {}), |_| {
        Ok(())
    })
}

/// The sphere, shared by the pose and place targets.
fn sphere() -> Arc<geltip::object::Object> {
    static S: OnceLock<Arc<geltip::object::Object>> = OnceLock::new();
    S.get_or_init(|| Arc::new(geltip::object::Object::from_arg("sphere").expect("sphere")))
        .clone()
}

fn pose_text(_: &Path, input: &[u8]) -> Fed {
    let text = String::from_utf8_lossy(input);
    let placed = pose_numbers(&text)
        .and_then(|v| Hold::from_pose(&v))
        .and_then(|hold| {
            Press {
                object: sphere(),
                hold,
            }
            .pose(paper())
        });
    verdict(placed, |pose| check_pose(&pose))
}

fn place_text(_: &Path, input: &[u8]) -> Fed {
    let text = String::from_utf8_lossy(input);
    let placed =
        Place::parse(&text).and_then(|place| Press::at(sphere(), place, 30.0, 1.0).pose(paper()));
    verdict(placed, |pose| check_pose(&pose))
}

/// A primitive's text (`--object box:x=10,y=6,z=4`), pressed 1 mm at a place when it parses.
fn primitive_text(_: &Path, input: &[u8]) -> Fed {
    let text = String::from_utf8_lossy(input);
    let placed = Primitive::parse(&text).and_then(|p| match p {
        Some(p) => Press::at(
            Arc::new(Object::primitive(p)),
            Place::Rotation(30.0),
            45.0,
            1.0,
        )
        .pose(paper())
        .map(Some),
        None => Ok(None),
    });
    verdict(placed, |pose| pose.map_or(Ok(()), |p| check_pose(&p)))
}

fn resume_manifests() -> Vec<Vec<u8>> {
    vec![seeds::resume_manifest()]
}

/// A set directory of [`seeds::empty_shard_spec`] with `manifest` and `labels`, resumed.
fn resume(dir: &Path, manifest: &[u8], labels: &[u8]) -> Fed {
    let set = dir.join("set");
    std::fs::create_dir_all(set.join("images")).expect("a set directory");
    file(&set, dataset::MANIFEST, manifest);
    file(&set, dataset::LABELS, labels);
    std::fs::write(set.join("images/000000.png"), b"png").expect("a sample file");
    let spec = seeds::empty_shard_spec(None);
    verdict(dataset::run(&spec, Some(&set), |_| {}), |_| Ok(()))
}

fn resume_manifest(dir: &Path, input: &[u8]) -> Fed {
    resume(dir, input, &seeds::labels_jsonl()[0])
}

fn resume_labels(dir: &Path, input: &[u8]) -> Fed {
    resume(dir, &seeds::resume_manifest(), input)
}

fn merge_manifests() -> Vec<Vec<u8>> {
    vec![seeds::shard_manifest(1)]
}

fn first_merge_manifests() -> Vec<Vec<u8>> {
    vec![seeds::shard_manifest(0)]
}

fn merge_labels_seeds() -> Vec<Vec<u8>> {
    vec![
        format!("{}\n", seeds::label_line(1)).into_bytes(),
        seeds::labels_jsonl()[0].clone(),
    ]
}

/// Shards 0 and 1 of a two-sample set, shard 1 with `manifest` and `labels` (and shard 0
/// with `first`, the manifest read first), merged.
fn merge(dir: &Path, first: &[u8], manifest: &[u8], labels: &[u8]) -> Fed {
    let (a, b) = (dir.join("a"), dir.join("b"));
    let line = format!("{}\n", seeds::label_line(0));
    seeds::write_shard(&a, 0, first, line.as_bytes());
    seeds::write_shard(&b, 1, manifest, labels);
    verdict(dataset::merge(&dir.join("out"), &[a, b], &[]), |n| {
        if n == 2 {
            Ok(())
        } else {
            Err(format!("merged {n} samples of 2"))
        }
    })
}

fn merge_manifest(dir: &Path, input: &[u8]) -> Fed {
    let line = format!("{}\n", seeds::label_line(1));
    merge(dir, &seeds::shard_manifest(0), input, line.as_bytes())
}

fn merge_first_manifest(dir: &Path, input: &[u8]) -> Fed {
    let line = format!("{}\n", seeds::label_line(1));
    merge(dir, input, &seeds::shard_manifest(1), line.as_bytes())
}

fn merge_labels(dir: &Path, input: &[u8]) -> Fed {
    merge(
        dir,
        &seeds::shard_manifest(0),
        &seeds::shard_manifest(1),
        input,
    )
}

/// Every number of some detections finite.
fn check_found(found: &[Found]) -> Result<(), String> {
    let mut v: Vec<f64> = found.iter().map(|f| f.confidence).collect();
    v.extend(
        found
            .iter()
            .flat_map(|f| f.point.map(|p| p.to_array()))
            .flatten(),
    );
    v.extend(
        found
            .iter()
            .flat_map(|f| f.pixel.map(|p| p.to_array()))
            .flatten(),
    );
    finite("detections", &v)
}

/// A predictions file read and checked against a set of frames 0..4, then each frame's
/// detections looked up.
fn predictions(dir: &Path, input: &[u8]) -> Fed {
    let path = file(dir, "predictions.jsonl", input);
    let read = Predictions::read(&path, paper()).and_then(|mut p| {
        p.start(&[0, 1, 2, 3])?;
        Ok(p)
    });
    verdict(read, |p| {
        let found: Vec<Found> = (0..4).flat_map(|k| p.detections_of(k)).collect();
        check_found(&found)
    })
}

/// A calibration's contacts file, its frame `c.png` present.
fn calibrate_contacts(dir: &Path, input: &[u8]) -> Fed {
    let frame = dir.join("c.png");
    if !frame.exists() {
        image::RgbImage::new(4, 4)
            .save(&frame)
            .expect("cannot write a fuzz frame");
    }
    let path = file(dir, "contacts.jsonl", input);
    verdict(geltip::calibrate::contacts::read(&path), |known| {
        for k in &known {
            let numbers: Vec<f64> = k.spec.pose.clone().unwrap_or_default();
            finite("pose", &numbers)?;
            finite(
                "contact",
                &[k.spec.depth, k.spec.azimuth, k.spec.spin, k.spec.tilt].map(|v| v.unwrap_or(0.0)),
            )?;
        }
        Ok(())
    })
}

/// An empty frame for `geltip calibrate`: loaded, checked and its image circle found.
fn png_empty_frame(dir: &Path, input: &[u8]) -> Fed {
    use geltip::calibrate::{circle, frames::EmptyFrames};
    let path = file(dir, "empty.png", input);
    let found = EmptyFrames::load(&[path]).and_then(|f| circle::find(&f.mean));
    verdict(found, |c| {
        finite("circle", &[c.centre.x, c.centre.y, c.radius, c.rms_px])
    })
}

/// One line a detector program answers with.
fn detector_answer(_: &Path, input: &[u8]) -> Fed {
    let text = String::from_utf8_lossy(input);
    verdict(
        evaluate::parse_line(paper(), &text, "answer"),
        |(_, found)| check_found(&found),
    )
}

/// A set's `labels.jsonl` as `geltip evaluate --dataset` reads it (through the evaluate
/// source: manifest, sensor, every line checked), then scored and its report written.
fn evaluate_labels(dir: &Path, input: &[u8]) -> Fed {
    seeds::write_evaluate_set(&dir.join("set"), input);
    verdict(seeds::evaluate_run(dir, None), |(out, outcome)| {
        check_evaluation(&outcome.evaluation)?;
        check_report(&out, input)
    })
}

/// `--compare`'s `summary.json`: read, then set beside a real run's in the tables and
/// charts.
fn evaluate_compare(dir: &Path, input: &[u8]) -> Fed {
    let compared = dir.join("compared");
    std::fs::create_dir_all(&compared).expect("a compared directory");
    file(&compared, "summary.json", input);
    seeds::write_evaluate_set(&dir.join("set"), &seeds::evaluate_labels()[1]);
    verdict(seeds::evaluate_run(dir, Some(&compared)), |(out, _)| {
        check_report(&out, input)
    })
}

/// Each of the set's samples scored once, and every number an evaluation holds finite: the
/// labels read back, the matches' errors and the summary's statistics.
fn check_evaluation(e: &evaluate::Evaluation) -> Result<(), String> {
    // The set's samples 0 and 1, each scored once.
    let mut samples: Vec<u64> = e.frames.iter().map(|f| f.truth.index).collect();
    samples.sort_unstable();
    if samples != [0, 1] {
        return Err(format!(
            "a set of samples 0 and 1 scored as samples {samples:?}"
        ));
    }
    for f in &e.frames {
        for c in &f.truth.contacts {
            let mut v = c.target.to_array().to_vec();
            v.extend(c.pixel.map_or(vec![], |p| p.to_array().to_vec()));
            v.extend([c.depth_mm, c.s_mm, c.azimuth_deg]);
            finite(&format!("sample {} labels", f.truth.index), &v)?;
        }
        for m in &f.score.matches {
            finite("match", &[m.error_mm, m.error_px.unwrap_or(0.0)])?;
        }
    }
    let s = e.summary();
    let stats = |x: &Option<evaluate::metrics::ErrorStats>| {
        x.map_or(vec![], |x| vec![x.mean, x.median, x.p95, x.max])
    };
    let mut v = stats(&s.error_mm);
    v.extend(stats(&s.error_px));
    v.extend(s.average_precision);
    for p in &s.precision_recall {
        v.extend([p.threshold, p.precision, p.recall]);
    }
    for g in s.by_region.iter().chain(&s.by_depth).chain(&s.by_object) {
        v.extend(stats(&g.error_mm));
    }
    finite("summary", &v)
}

/// A report's tables and charts written, with no number that is not one: no `NaN` or `inf`
/// the input did not hold itself (as a name).
fn check_report(out: &Path, input: &[u8]) -> Result<(), String> {
    let input = String::from_utf8_lossy(input);
    for name in [
        "tables.md",
        "by_depth.svg",
        "by_region.svg",
        "failure_map.svg",
        "precision_recall.svg",
    ] {
        let text = std::fs::read_to_string(out.join(name)).map_err(|e| format!("{name}: {e}"))?;
        let made = |b: &&str| text.contains(b) && !input.contains(b);
        if let Some(bad) = ["NaN", "inf"].into_iter().find(made) {
            return Err(format!("{name} holds {bad}"));
        }
    }
    Ok(())
}
