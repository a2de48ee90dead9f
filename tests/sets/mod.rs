//! Helpers of the `geltip dataset` tests: running the binary, reading a set's files.
// Each test file uses its own subset of these.
#![allow(dead_code)]

use serde_json::Value;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn geltip() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_geltip"));
    c.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    c
}

/// A fresh empty directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("dataset")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn run(args: &[&str]) -> Output {
    geltip().args(args).output().unwrap()
}

pub fn dataset(out: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "dataset",
        "--sensor",
        "paper",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(
        o.status.success(),
        "geltip {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// Every file of a set by relative path, with `dataset.json`'s command line (which names the
/// directory) removed.
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            let mut bytes = fs::read(&p).unwrap();
            if rel == "dataset.json" {
                let mut v: Value = serde_json::from_slice(&bytes).unwrap();
                v.as_object_mut().unwrap().remove("command");
                bytes = serde_json::to_vec(&v).unwrap();
            }
            out.insert(rel, bytes);
        }
    }
    out
}

pub fn labels(dir: &Path) -> Vec<Value> {
    fs::read_to_string(dir.join("labels.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The set is complete: `n` labels sorted by index, each file present, no temporary file.
pub fn assert_complete(dir: &Path, n: u64) {
    let labels = labels(dir);
    let indices: Vec<u64> = labels
        .iter()
        .map(|l| l["index"].as_u64().unwrap())
        .collect();
    assert_eq!(indices, (0..n).collect::<Vec<_>>());
    for l in &labels {
        for key in ["image", "depth", "mask"] {
            if let Some(rel) = l[key].as_str() {
                assert!(dir.join(rel).is_file(), "{rel} missing");
            }
        }
    }
    let leftovers: Vec<String> = files(dir)
        .into_keys()
        .filter(|p| p.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    assert!(
        !dir.join(geltip::output::LOCK_FILE).exists(),
        "the run's lock file was left behind"
    );
    let images = fs::read_dir(dir.join("images")).unwrap().count() as u64;
    assert_eq!(images, n);
}

/// Runs geltip expecting failure; returns its one-line error.
pub fn error_of(args: &[&str]) -> String {
    let o = run(args);
    assert!(!o.status.success(), "geltip {args:?} succeeded");
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    err
}
