//! Real valid inputs to start from: the presets, the scene files and meshes in the tree,
//! glTF and GLB files made from those meshes, PNG frames, poses and places of real contacts,
//! the files of a dataset directory, and a real evaluate run's summary. Also the sensors and
//! set directories the feeds use.

use super::gltf_files::{glb_bytes, gltf_json};
use geltip::jobs::dataset::{self, Shard, Spec};
use geltip::object::{Mesh, Object};
use geltip::render::{Place, Press};
use geltip::sensor::{Sensor, PRESETS};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The repository's root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(repo().join(rel)).unwrap_or_else(|e| panic!("seed {rel}: {e}"))
}

/// The paper's sensor.
pub fn paper() -> &'static Sensor {
    static S: OnceLock<Sensor> = OnceLock::new();
    S.get_or_init(|| Sensor::preset("paper").expect("the paper preset"))
}

/// The paper's finger and lens on a 64x48 image: frames to localise and backgrounds cost
/// little.
pub fn small_toml() -> String {
    let paper = PRESETS[0].1;
    paper
        .replace("focal_px = 180.0", "focal_px = 18.0")
        .replace("cx = 320.0", "cx = 32.0")
        .replace("cy = 240.0", "cy = 24.0")
        .replace("width = 640", "width = 64")
        .replace("height = 480", "height = 48")
}

pub fn small() -> &'static Sensor {
    static S: OnceLock<Sensor> = OnceLock::new();
    S.get_or_init(|| Sensor::from_toml("small", &small_toml()).expect("the small sensor"))
}

pub fn sensor_tomls() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = PRESETS.iter().map(|(_, t)| t.as_bytes().to_vec()).collect();
    seeds.push(small_toml().into_bytes());
    seeds.push(calibrated_toml().into_bytes());
    seeds
}

/// A sensor file as `geltip calibrate` writes it: listed LEDs, ambient light, vignetting,
/// a coloured paint, noise per channel.
pub fn calibrated_toml() -> String {
    small_toml() + "\n" + include_str!("../common/calibrated_light.toml")
}

/// Lines of a calibration's contacts file (each names `c.png`, which the feed writes).
pub fn calibrate_contacts() -> Vec<Vec<u8>> {
    let pose = pose_of("cone", Place::Rotation(40.0), 120.0, 0.8);
    vec![
        concat!(
            r#"{"image": "c.png", "object": "sphere", "at": "rotation=30", "azimuth": 45, "depth": 1}"#,
            "\n",
            r#"{"image": "c.png", "object": "box:x=6,y=4,z=3", "at": {"translation": 4}, "depth": 0.5, "spin": 30}"#,
            "\n"
        )
        .as_bytes()
        .to_vec(),
        format!(
            "{{\"image\": \"c.png\", \"object\": \"cone\", \"pose\": [{}]}}\n",
            numbers(&pose)
        )
        .into_bytes(),
    ]
}

/// A real contact's pose as a row-major 4x4 matrix.
fn pose_of(object: &str, place: Place, azimuth: f64, depth: f64) -> [f64; 16] {
    let object = Arc::new(Object::from_arg(object).expect("a solid"));
    Press::at(object, place, azimuth, depth)
        .pose(paper())
        .expect("a contact the finger takes")
        .matrix_row_major()
}

fn numbers(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x}"))
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn scene_jsons() -> Vec<Vec<u8>> {
    let pose = pose_of("cone", Place::Rotation(40.0), 120.0, 0.8);
    let with_all = format!(
        r#"{{"contacts": [
  {{"object": "sphere", "at": {{"rotation": 30}}, "azimuth": 10, "spin": 5, "tilt": 20, "tilt_towards": 90, "depth": 1}},
  {{"object": "cone", "pose": [{}]}},
  {{"object": "box:x=10,y=6,z=4", "pose": [1, 0, 0, 11.5, 0, 1, 0, 0, 0, 0, 1, 12, 0, 0, 0, 1], "approach": [-1, 0, 0]}}
]}}"#,
        numbers(&pose)
    );
    vec![
        read("docs/images/scene_sphere_torus.json"),
        with_all.into_bytes(),
    ]
}

pub fn scene_tomls() -> Vec<Vec<u8>> {
    let pose = pose_of("edge", Place::Translation(5.0), 200.0, 0.5);
    let text = format!(
        r#"[[contacts]]
object = "sphere"
at = "rotation=30"
depth = 1.0

[[contacts]]
object = "torus"
at = {{ translation = 8 }}
azimuth = 180.0
spin = 15.0
tilt = 10.0
tilt_towards = 90.0
depth = 0.6

[[contacts]]
object = "edge"
pose = [{}]
"#,
        numbers(&pose)
    );
    vec![text.into_bytes()]
}

/// A small tetrahedron, wound outward.
fn tetrahedron() -> Mesh {
    Mesh {
        positions: vec![
            glam::DVec3::new(0.0, 0.0, 0.0),
            glam::DVec3::new(2.0, 0.0, -2.0),
            glam::DVec3::new(-1.0, 1.7, -2.0),
            glam::DVec3::new(-1.0, -1.7, -2.0),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2], [0, 1, 3], [1, 2, 3]],
    }
}

pub fn objs() -> Vec<Vec<u8>> {
    vec![
        tetrahedron().to_obj_string().into_bytes(),
        read("assets/objects/cone.obj"),
        read("assets/objects/edge.obj"),
    ]
}

fn seed_meshes() -> Vec<Mesh> {
    let cone = Mesh::load(repo().join("assets/objects/cone.obj")).expect("cone.obj");
    vec![tetrahedron(), cone]
}

pub fn gltfs() -> Vec<Vec<u8>> {
    seed_meshes()
        .iter()
        .map(|m| {
            gltf_json(m, [0.5, 0.0, 0.0], [1.0; 3], false)
                .0
                .into_bytes()
        })
        .collect()
}

pub fn glbs() -> Vec<Vec<u8>> {
    seed_meshes()
        .iter()
        .map(|m| {
            let (json, bin) = gltf_json(m, [0.5, 0.0, 0.0], [1.0; 3], true);
            glb_bytes(&json, bin)
        })
        .collect()
}

/// PNG bytes of an image.
fn png_of(image: image::DynamicImage) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut out, image::ImageFormat::Png)
        .expect("PNG encoding");
    out.into_inner()
}

/// Frames of `w` x `h` in the pixel formats PNG files come in: RGB, RGBA, grey, 16-bit.
fn frames(w: u32, h: u32) -> Vec<Vec<u8>> {
    let rgb = image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 4) as u8, (y * 5) as u8, ((x + y) * 3) as u8])
    });
    let dynamic = image::DynamicImage::ImageRgb8(rgb);
    vec![
        png_of(dynamic.clone()),
        png_of(image::DynamicImage::ImageRgba8(dynamic.to_rgba8())),
        png_of(image::DynamicImage::ImageLuma8(dynamic.to_luma8())),
        png_of(image::DynamicImage::ImageRgb16(dynamic.to_rgb16())),
    ]
}

pub fn pngs() -> Vec<Vec<u8>> {
    let mut seeds = frames(9, 7);
    seeds.push(read("tests/reference/paper_sphere_rot45.png"));
    seeds
}

/// Frames of the small sensor's size.
pub fn small_frames() -> Vec<Vec<u8>> {
    frames(small().width, small().height)
}

pub fn pose_texts() -> Vec<Vec<u8>> {
    let m = pose_of("sphere", Place::Rotation(45.0), 60.0, 1.0);
    let r = glam::DMat3::from_cols_array(&[m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]]);
    let q = glam::DQuat::from_mat3(&r);
    let seven = [m[3], m[7], m[11], q.w, q.x, q.y, q.z];
    vec![
        numbers(&m).into_bytes(),
        seven.map(|v| v.to_string()).join(" ").into_bytes(),
    ]
}

pub fn primitive_texts() -> Vec<Vec<u8>> {
    geltip::object::primitive::PRIMITIVE_SYNTAX
        .split(", ")
        .chain([
            "ellipsoid:x=3.5,y=12,z=0.75",
            " capsule : r = 0.5 , l = 40 ",
        ])
        .map(|s| s.as_bytes().to_vec())
        .collect()
}

pub fn place_texts() -> Vec<Vec<u8>> {
    ["rotation=30", "translation=5", "s=12.5", " rotation = 90 "]
        .map(|s| s.as_bytes().to_vec())
        .to_vec()
}

/// A dataset spec of the small sensor whose shard holds no sample: a run checks the
/// directory (manifest, labels, background) and renders nothing.
pub fn empty_shard_spec(background: Option<PathBuf>) -> Spec {
    let mut spec = Spec::new("small", small().clone(), 1, 7);
    spec.objects = vec!["sphere".into()];
    spec.shard = Shard { index: 0, count: 2 };
    spec.background = background;
    spec.workers = 1;
    spec.streams = 1;
    spec
}

/// The manifest a run of [`empty_shard_spec`] writes.
pub fn resume_manifest() -> Vec<u8> {
    static M: OnceLock<Vec<u8>> = OnceLock::new();
    M.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("geltip-fuzz-manifest-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dataset::run(&empty_shard_spec(None), Some(&dir), |_| {}).expect("an empty shard");
        let text = std::fs::read(dir.join(dataset::MANIFEST)).expect("its manifest");
        let _ = std::fs::remove_dir_all(&dir);
        text
    })
    .clone()
}

/// A label line of sample `k` (a real render's labels, with the sample's index and files).
pub fn label_line(k: u64) -> String {
    let text = std::fs::read_to_string(repo().join("docs/images/sphere_translation5.json"))
        .expect("a label file");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("labels");
    v["index"] = k.into();
    v["image"] = format!("images/{k:06}.png").into();
    v["mask"] = format!("masks/{k:06}.png").into();
    v.to_string()
}

pub fn labels_jsonl() -> Vec<Vec<u8>> {
    vec![format!("{}\n{}\n", label_line(0), label_line(1)).into_bytes()]
}

/// The manifest of shard `i` of 2 of a two-sample set.
pub fn shard_manifest(i: u64) -> Vec<u8> {
    serde_json::json!({
        "geltip_version": env!("CARGO_PKG_VERSION"),
        "options": {"count": 2, "seed": 7, "sensor": "paper", "objects": ["sphere"]},
        "shard": [i, 2],
        "shard_range": [i, i + 1],
        "command": ["geltip", "dataset", "--shard", format!("{i}/2")],
    })
    .to_string()
    .into_bytes()
}

/// Writes shard `i` of 2 into `dir`: its manifest, label line and files.
pub fn write_shard(dir: &Path, i: u64, manifest: &[u8], labels: &[u8]) {
    for sub in ["images", "masks"] {
        std::fs::create_dir_all(dir.join(sub)).expect("a shard directory");
        std::fs::write(dir.join(format!("{sub}/{i:06}.png")), b"png").expect("a file");
    }
    std::fs::write(dir.join(dataset::MANIFEST), manifest).expect("a manifest");
    std::fs::write(dir.join(dataset::LABELS), labels).expect("labels");
}

/// Predictions files for a set of four frames: pixels, points, confidences, empty frames.
pub fn predictions_jsonl() -> Vec<Vec<u8>> {
    vec![
        concat!(
            "{\"sample\": 0, \"detections\": [{\"pixel\": [400.0, 240.0], \"confidence\": 0.9}]}\n",
            "{\"sample\": 1, \"detections\": []}\n",
            "{\"sample\": 2, \"detections\": [{\"point\": [7.5, 0.0, 15.75]}, {\"pixel\": [320, 240], \"confidence\": 0.1}]}\n",
            "{\"sample\": 3, \"detections\": [{\"point\": [0.0, 0.0, 27.5], \"pixel\": [320.0, 240.0], \"confidence\": 1}]}\n",
        )
        .as_bytes()
        .to_vec(),
        b"{\"sample\": 3, \"detections\": []}\n{\"sample\": 2, \"detections\": []}\n{\"sample\": 1, \"detections\": []}\n{\"sample\": 0, \"detections\": []}\n".to_vec(),
    ]
}

/// A detector program's answers to one frame.
pub fn detector_answers() -> Vec<Vec<u8>> {
    vec![
        b"{\"detections\": [{\"pixel\": [400.0, 240.0], \"confidence\": 0.9}]}".to_vec(),
        b"{\"sample\": 0, \"detections\": [{\"point\": [7.5, 0.0, 15.75]}]}".to_vec(),
        b"{\"detections\": []}".to_vec(),
    ]
}

/// The manifest of a whole set of `count` samples of the paper sensor: a real run's (an
/// empty shard, which renders nothing) made whole.
pub fn evaluate_manifest(count: u64) -> Vec<u8> {
    static M: OnceLock<Vec<u8>> = OnceLock::new();
    let real = M.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!(
            "geltip-fuzz-evaluate-manifest-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        let mut spec = empty_shard_spec(None);
        spec.sensor_arg = "paper".into();
        spec.sensor = paper().clone();
        dataset::run(&spec, Some(&dir), |_| {}).expect("an empty shard");
        let text = std::fs::read(dir.join(dataset::MANIFEST)).expect("its manifest");
        let _ = std::fs::remove_dir_all(&dir);
        text
    });
    let mut v: serde_json::Value = serde_json::from_slice(real).expect("a manifest");
    v["options"]["count"] = count.into();
    v["shard"] = serde_json::json!([0, 1]);
    v["shard_range"] = serde_json::json!([0, count]);
    v.to_string().into_bytes()
}

/// A label line of sample `k` in the scene form (`--contacts-per-sample`,
/// `--empty-fraction`): `contacts` real contacts' labels (none: an empty frame).
fn scene_label_line(k: u64, contacts: usize) -> String {
    let one: serde_json::Value = serde_json::from_str(&label_line(k)).expect("a label line");
    let mut contact = one.clone();
    for key in ["index", "image", "mask"] {
        contact.as_object_mut().expect("an object").remove(key);
    }
    // A dataset's labels carry the indented area's centre, which detectors are scored
    // against.
    contact["contact_centre"] = serde_json::json!([6.4, 3.8, 15.1]);
    serde_json::json!({
        "index": k,
        "image": one["image"],
        "mask": one["mask"],
        "contacts": vec![contact; contacts],
        "mask_pixels": if contacts == 0 { 0 } else { one["mask_pixels"].as_u64().unwrap_or(0) },
        "mask_bbox": if contacts == 0 { serde_json::Value::Null } else { one["mask_bbox"].clone() },
        "over_pressed": false,
    })
    .to_string()
}

/// `labels.jsonl` of a two-sample set as `geltip evaluate` reads it: one contact a line,
/// and the scene form (two contacts, an empty frame).
pub fn evaluate_labels() -> Vec<Vec<u8>> {
    vec![
        labels_jsonl()[0].clone(),
        format!("{}\n{}\n", scene_label_line(0, 2), scene_label_line(1, 0)).into_bytes(),
    ]
}

/// Writes a two-sample set of the paper sensor into `dir` with `labels`: its manifest and
/// its images' files (any bytes: predictions need no pixels).
pub fn write_evaluate_set(dir: &Path, labels: &[u8]) {
    std::fs::create_dir_all(dir.join("images")).expect("a set directory");
    for k in 0..2 {
        std::fs::write(dir.join(format!("images/{k:06}.png")), b"png").expect("a file");
    }
    std::fs::write(dir.join(dataset::MANIFEST), evaluate_manifest(2)).expect("a manifest");
    std::fs::write(dir.join(dataset::LABELS), labels).expect("labels");
}

/// Predictions for the samples `indices` (each once): the first near the seed labels'
/// contact, the others a pixel far from it.
pub fn evaluate_predictions(indices: &[u64]) -> String {
    let mut seen = std::collections::BTreeSet::new();
    let mut text = String::new();
    for &k in indices {
        if !seen.insert(k) {
            continue;
        }
        let detection = if seen.len() == 1 {
            r#"{"point": [6.5, 3.75, 15.0], "confidence": 0.9}"#
        } else {
            r#"{"pixel": [100.0, 100.0], "confidence": 0.2}"#
        };
        text.push_str(&format!(
            "{{\"sample\": {k}, \"detections\": [{detection}]}}\n"
        ));
    }
    text
}

/// `summary.json` files of real `geltip evaluate` runs (the predictions above on each set of
/// [`evaluate_labels`]), as `--compare` reads them.
pub fn evaluate_summaries() -> Vec<Vec<u8>> {
    static S: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    S.get_or_init(|| {
        let root = std::env::temp_dir().join(format!(
            "geltip-fuzz-evaluate-summaries-{}",
            std::process::id()
        ));
        let summaries = evaluate_labels()
            .iter()
            .enumerate()
            .map(|(i, labels)| {
                let dir = root.join(format!("run{i}"));
                write_evaluate_set(&dir.join("set"), labels);
                let (out, _) = evaluate_run(&dir, None).expect("a real evaluation");
                let text = std::fs::read(out.join("summary.json")).expect("its summary");
                // What differs from run to run (this process's paths, the time) fixed, so
                // that a case's number alone makes its input.
                let mut v: serde_json::Value = serde_json::from_slice(&text).expect("JSON");
                v["detector"] = "predictions.jsonl".into();
                v["source"] = "dataset data/test".into();
                v["seconds"] = 0.25.into();
                let text = serde_json::to_string_pretty(&v).expect("JSON");
                (text + "\n").into_bytes()
            })
            .collect();
        let _ = std::fs::remove_dir_all(&root);
        summaries
    })
    .clone()
}

/// Scores [`evaluate_predictions`] of its samples on the set in `dir/set`, writing the report into
/// `dir/out` beside `compare`'s: the report's directory and what the run gave back.
pub fn evaluate_run(
    dir: &Path,
    compare: Option<&Path>,
) -> geltip::Result<(PathBuf, geltip::jobs::evaluate::Outcome)> {
    let source = geltip::jobs::evaluate::source(Some(&dir.join("set")), None, None)?;
    let predictions = dir.join("predictions.jsonl");
    std::fs::write(&predictions, evaluate_predictions(&source.indices())).expect("predictions");
    let mut detector = geltip::evaluate::Predictions::read(&predictions, source.sensor())?;
    let out = dir.join("out");
    let outcome = geltip::jobs::evaluate::run(
        &source,
        &mut detector,
        Some(3.0),
        Some(&out),
        compare,
        |_, _| {},
    )?;
    Ok((out, outcome))
}
