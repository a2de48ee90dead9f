//! A set's directory: the manifest (`dataset.json`), the labels log (`labels.jsonl`), resume
//! (the samples whose line and files exist), temporary files a killed run left, the lock that
//! keeps a second run out, and merging shard directories into one set.

use super::labels::read_labels;
use super::reference::REFERENCE;
use super::spec::{Shard, Spec};
use crate::error::{GeltipError, Result};
use crate::output::{self, DirLock};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fs;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The manifest of a set's options.
pub const MANIFEST: &str = "dataset.json";
/// The labels, one JSON line per sample.
pub const LABELS: &str = "labels.jsonl";

/// A set directory a run writes into, locked against other runs until dropped.
pub(super) struct SetDir<'a> {
    dir: &'a Path,
    _lock: DirLock,
}

impl<'a> SetDir<'a> {
    /// Opens `dir` for `spec`'s run: creates and locks it, writes the manifest or checks the
    /// one there against `options`, removes stale temporary files and drops an unfinished
    /// last label line and lines whose files are gone. Returns the complete samples of the shard, by index.
    pub(super) fn open(
        dir: &'a Path,
        spec: &Spec,
        options: &Value,
    ) -> Result<(SetDir<'a>, BTreeMap<u64, String>)> {
        fs::create_dir_all(dir).map_err(|e| GeltipError::io(dir, e))?;
        let lock = lock(dir, "out")?;
        let wanted = manifest(spec, options);
        match read_manifest(dir)? {
            Some(old) => {
                let mut diff = differing_keys(&old["options"], options);
                if old["shard"] != wanted["shard"] {
                    diff.push("shard".into());
                }
                if !diff.is_empty() {
                    return Err(GeltipError::option_value(
                        "out",
                        dir.display(),
                        format!(
                            "holds a set made with different options ({}); use another directory",
                            diff.join(", ")
                        ),
                    ));
                }
            }
            None => output::write_json(dir.join(MANIFEST), &wanted)?,
        }
        remove_temp_files(dir);
        let mut done = complete_samples(dir)?;
        let range = spec.shard.range(spec.count);
        done.retain(|k, _| range.contains(k));
        // Drop an unfinished last line and dangling lines before appending.
        write_labels(dir, &done)?;
        Ok((SetDir { dir, _lock: lock }, done))
    }

    /// Checks that every sample of `range` is complete and rewrites `labels.jsonl` sorted
    /// by index, so a set's files never depend on how it was produced.
    pub(super) fn finish(&self, range: Range<u64>) -> Result<()> {
        let mut complete = complete_samples(self.dir)?;
        complete.retain(|k, _| range.contains(k));
        let expected = range.end - range.start;
        if complete.len() as u64 != expected {
            return Err(GeltipError::option_value(
                "out",
                self.dir.display(),
                format!(
                    "{} of {} samples complete after the run",
                    complete.len(),
                    expected
                ),
            ));
        }
        write_labels(self.dir, &complete)
    }
}

/// `dir`'s lock, for a run or merge writing there; another run's hold on it is an error
/// about the option `option` that named the directory.
fn lock(dir: &Path, option: &str) -> Result<DirLock> {
    let what = format!("{option} {}", dir.display());
    DirLock::acquire(dir, &what).map_err(|e| match e {
        GeltipError::InvalidInput { reason, .. } => {
            GeltipError::option_value(option, dir.display(), reason)
        }
        other => other,
    })
}

/// A set directory's manifest as JSON.
fn read_manifest(dir: &Path) -> Result<Option<Value>> {
    let path = dir.join(MANIFEST);
    match fs::read_to_string(&path) {
        Ok(text) => serde_json::from_str(&text).map(Some).map_err(|e| {
            GeltipError::input(path.display().to_string(), format!("not valid JSON: {e}"))
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(GeltipError::io(path, e)),
    }
}

/// The keys whose values differ between two JSON objects.
fn differing_keys(a: &Value, b: &Value) -> Vec<String> {
    let empty = serde_json::Map::new();
    let (a, b) = (
        a.as_object().unwrap_or(&empty),
        b.as_object().unwrap_or(&empty),
    );
    let mut keys: Vec<String> = a
        .keys()
        .chain(b.keys())
        .filter(|k| a.get(*k) != b.get(*k))
        .cloned()
        .collect();
    keys.sort();
    keys.dedup();
    keys
}

/// Removes temporary files a killed run left (`.<name>.<pid>.<n>.tmp`) in a set directory.
fn remove_temp_files(dir: &Path) {
    for sub in ["", "images", "depth", "masks"] {
        let Ok(entries) = fs::read_dir(dir.join(sub)) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with('.') && name.ends_with(".tmp") {
                let _ = fs::remove_file(entry.path());
            }
        }
    }
}

/// The complete samples listed in a set directory's `labels.jsonl` (read by
/// [`read_labels`]'s rule): the lines (by index) whose files exist.
fn complete_samples(dir: &Path) -> Result<BTreeMap<u64, String>> {
    let path = dir.join(LABELS);
    if !path.exists() {
        return Ok(BTreeMap::new());
    }
    let mut done = BTreeMap::new();
    for line in read_labels(&path)? {
        let files_exist = ["image", "depth", "mask"]
            .iter()
            .all(|key| match line.value.get(*key) {
                Some(Value::String(rel)) => dir.join(rel).is_file(),
                _ => *key != "image",
            });
        if files_exist {
            done.insert(line.index, line.text);
        }
    }
    Ok(done)
}

/// Writes `labels.jsonl` holding `lines` (sorted by index), atomically.
fn write_labels(dir: &Path, lines: &BTreeMap<u64, String>) -> Result<()> {
    let mut text = String::new();
    for line in lines.values() {
        text.push_str(line);
        text.push('\n');
    }
    output::write_atomic(dir.join(LABELS), text.as_bytes())
}

/// The manifest of a run.
fn manifest(spec: &Spec, options: &Value) -> Value {
    json!({
        "geltip_version": env!("CARGO_PKG_VERSION"),
        "options": options,
        "shard": [spec.shard.index, spec.shard.count],
        "shard_range": [spec.shard.range(spec.count).start, spec.shard.range(spec.count).end],
        "command": spec.command,
    })
}

/// Joins the shard directories of one set into `out`: checks that they hold the shards
/// 0..n of the same options, each complete and none being written, links (or copies) their
/// files into `out` and writes one `dataset.json` and one `labels.jsonl` sorted by index,
/// as an unsharded run would. Returns the number of samples. Errors name the target `out`
/// and the list `shards`, or the shard directory they are about.
pub fn merge(out: &Path, shards: &[PathBuf], command: &[String]) -> Result<u64> {
    if shards.is_empty() {
        return Err(GeltipError::option(
            "shards",
            "name the shard directories to join",
        ));
    }
    let mut set = ShardSet::default();
    for dir in shards {
        set.add(dir, &shards[0], out)?;
    }
    set.check_complete()?;
    let options = set.options.unwrap_or(Value::Null);
    let count = options["count"].as_u64().unwrap_or(0);
    let wanted = json!({
        "geltip_version": set.version,
        "options": options,
        "shard": [0, 1],
        "shard_range": [0, count],
        "command": command,
    });
    fs::create_dir_all(out).map_err(|e| GeltipError::io(out, e))?;
    let _lock = lock(out, "out")?;
    if let Some(old) = read_manifest(out)? {
        if old["options"] != wanted["options"] || old["shard"] != wanted["shard"] {
            return Err(GeltipError::option_value(
                "out",
                out.display(),
                "already holds a different set; use another directory",
            ));
        }
    } else {
        output::write_json(out.join(MANIFEST), &wanted)?;
    }
    let reference = shards[0].join(REFERENCE);
    if reference.is_file() && !same_dir(&shards[0], out) {
        output::link_or_copy_atomic(&reference, out.join(REFERENCE))?;
    }
    let mut merged = BTreeMap::new();
    // A background's empty frame is shared by many samples: copied once.
    let mut references = std::collections::BTreeSet::new();
    for (k, (dir, line)) in set.lines {
        let v: Value = serde_json::from_str(&line).unwrap_or(Value::Null);
        for key in ["image", "depth", "mask", "reference"] {
            if let Some(rel) = v[key].as_str() {
                let first = key != "reference" || references.insert(rel.to_string());
                if dir.as_path() != out && first {
                    output::link_or_copy_atomic(dir.join(rel), out.join(rel))?;
                }
            }
        }
        merged.insert(k, line);
    }
    write_labels(out, &merged)?;
    Ok(merged.len() as u64)
}

/// The shards given to [`merge`], checked one by one as they are added.
#[derive(Default)]
struct ShardSet {
    /// The first shard's options, which every other shard's must equal.
    options: Option<Value>,
    version: Value,
    /// The shard count.
    count: Option<u64>,
    /// Shard index -> directory.
    seen: BTreeMap<u64, PathBuf>,
    /// Sample index -> the directory holding it and its label line.
    lines: BTreeMap<u64, (PathBuf, String)>,
}

impl ShardSet {
    /// Adds the shard in `dir` (`first`: the first one given; `out`: the merge's target,
    /// which this process locks itself).
    fn add(&mut self, dir: &Path, first: &Path, out: &Path) -> Result<()> {
        let what = || format!("shard {}", dir.display());
        if !same_dir(dir, out) {
            if let Some(holder) = DirLock::holder(dir)? {
                return Err(GeltipError::input(
                    what(),
                    format!("is being written by another run ({holder}); wait for it to end"),
                ));
            }
        }
        let m = read_manifest(dir)?
            .ok_or_else(|| GeltipError::input(what(), format!("has no {MANIFEST}")))?;
        let opts = m["options"].clone();
        match &self.options {
            None => self.options = Some(opts.clone()),
            Some(o) if *o != opts => {
                return Err(GeltipError::input(
                    what(),
                    format!(
                        "was made with different options than {} ({})",
                        first.display(),
                        differing_keys(o, &opts).join(", ")
                    ),
                ))
            }
            Some(_) => {}
        }
        self.version = m["geltip_version"].clone();
        let (Some(i), Some(n)) = (m["shard"][0].as_u64(), m["shard"][1].as_u64()) else {
            return Err(GeltipError::input(
                what(),
                format!("{MANIFEST} has no shard i/n"),
            ));
        };
        if i >= n {
            return Err(GeltipError::input(
                what(),
                format!("{MANIFEST} names shard {i}/{n}, which is none of 0..{n}"),
            ));
        }
        if *self.count.get_or_insert(n) != n {
            return Err(GeltipError::input(
                what(),
                format!(
                    "is shard {i}/{n}, the others are of {}",
                    self.count.unwrap_or(n)
                ),
            ));
        }
        if let Some(other) = self.seen.insert(i, dir.to_path_buf()) {
            return Err(GeltipError::input(
                what(),
                format!("is shard {i}/{n}, as is {}", other.display()),
            ));
        }
        let count = opts["count"].as_u64().unwrap_or(0);
        let range = Shard { index: i, count: n }.range(count);
        let mut done = complete_samples(dir)?;
        done.retain(|k, _| range.contains(k));
        if done.len() as u64 != range.end - range.start {
            return Err(GeltipError::input(
                what(),
                format!(
                    "is incomplete: {} of {} samples (rerun its command to finish it)",
                    done.len(),
                    range.end - range.start
                ),
            ));
        }
        for (k, line) in done {
            self.lines.insert(k, (dir.to_path_buf(), line));
        }
        Ok(())
    }

    /// Refuses a set that misses some of the shards 0..n.
    fn check_complete(&self) -> Result<()> {
        let n = self.count.unwrap_or(1);
        if self.seen.len() as u64 != n {
            let missing: Vec<String> = (0..n)
                .filter(|i| !self.seen.contains_key(i))
                .map(|i| format!("{i}/{n}"))
                .collect();
            return Err(GeltipError::option(
                "shards",
                format!("missing shards {}", missing.join(", ")),
            ));
        }
        Ok(())
    }
}

/// Whether two paths name one directory (both existing).
fn same_dir(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}
