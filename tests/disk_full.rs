//! A full disk, on a size-limited tmpfs: `geltip dataset` stops with a one-line error naming
//! the file, leaves nothing half-written under a final name, and the same command resumes
//! to the set a fresh run makes once there is room. Needs `mount` (root); skipped with a
//! message where mounting is not allowed.

mod sets;

use geltip::output::LineLog;
use sets::{assert_complete, dataset, files, geltip, labels, scratch};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs mounted for one test, unmounted when dropped.
struct Tmpfs(PathBuf);

impl Tmpfs {
    /// Mounts a tmpfs of `size` (e.g. `64k`) at `dir`, or says why it cannot.
    fn mount(dir: &Path, size: &str) -> Result<Tmpfs, String> {
        fs::create_dir_all(dir).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .output()
            .map_err(|e| format!("mount: {e}"))?;
        if !o.status.success() {
            return Err(String::from_utf8_lossy(&o.stderr).trim().to_string());
        }
        Ok(Tmpfs(dir.to_path_buf()))
    }

    fn resize(&self, size: &str) {
        let o = Command::new("mount")
            .args(["-o", &format!("remount,size={size}")])
            .arg(&self.0)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.0).status();
    }
}

fn mounted(dir: &Path, size: &str) -> Option<Tmpfs> {
    match Tmpfs::mount(dir, size) {
        Ok(t) => Some(t),
        Err(why) => {
            eprintln!("skipped: cannot mount a tmpfs ({why}); run as root to test a full disk");
            None
        }
    }
}

/// Fills `dir`'s file system with a file until it refuses more bytes.
fn fill(dir: &Path) {
    let mut f = fs::File::create(dir.join("filler")).unwrap();
    let block = vec![0u8; 1024];
    loop {
        match f.write(&block) {
            Ok(0) | Err(_) => return,
            Ok(_) => {}
        }
    }
}

#[test]
fn a_full_disk_stops_the_run_cleanly_and_it_resumes() {
    let root = scratch("disk_full");
    // About 7 samples' images and masks fit in 1200 KiB.
    let Some(disk) = mounted(&root.join("disk"), "1200k") else {
        return;
    };
    let out = disk.0.join("set");
    let args = ["--count", "24", "--seed", "8", "--masks"];
    let mut cmd = vec![
        "dataset",
        "--sensor",
        "paper",
        "--out",
        out.to_str().unwrap(),
    ];
    cmd.extend(args);
    let o = geltip().args(&cmd).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert!(!o.status.success(), "the run fitted: {err}");
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    assert!(err.contains("No space left on device"), "{err}");
    let named = ["images/", "masks/", "labels.jsonl", "dataset.json"]
        .iter()
        .any(|f| err.contains(&format!("{}/{f}", out.display())));
    assert!(named, "the error names no file of the set: {err}");

    // Nothing half-written under a final name: every label line whole and naming files
    // that decode; no temporary file left; every image and mask decodes.
    let text = fs::read_to_string(out.join("labels.jsonl")).unwrap();
    assert!(text.is_empty() || text.ends_with('\n'), "a torn last line");
    let kept = labels(&out);
    assert!(
        !kept.is_empty() && kept.len() < 24,
        "{} samples",
        kept.len()
    );
    for (rel, bytes) in files(&out) {
        assert!(!rel.ends_with(".tmp"), "temporary file {rel} left");
        if rel.ends_with(".png") {
            image::load_from_memory(&bytes)
                .unwrap_or_else(|e| panic!("{rel} is not a whole PNG: {e}"));
        }
    }

    // Room again: the same command resumes to the set a fresh run makes.
    disk.resize("64m");
    let report = dataset(&out, &args);
    assert_eq!(report["kept"].as_u64(), Some(kept.len() as u64));
    assert_complete(&out, 24);
    let fresh = root.join("fresh");
    dataset(&fresh, &args);
    assert!(
        files(&out) == files(&fresh),
        "the resumed set differs from a fresh one"
    );
}

/// A label line the disk has room for only part of is cut back off: the log keeps whole
/// lines only, and appends again once there is room.
#[test]
fn a_label_line_that_does_not_fit_leaves_no_torn_line() {
    let root = scratch("line_log_full");
    let Some(disk) = mounted(&root.join("disk"), "64k") else {
        return;
    };
    let path = disk.0.join("labels.jsonl");
    let mut log = LineLog::open(&path).unwrap();
    // 4000 bytes: the first page of the file, 96 bytes short of full.
    let line = "x".repeat(99);
    for _ in 0..40 {
        log.append(&line).unwrap();
    }
    fill(&disk.0);
    let long = "y".repeat(200);
    let e = log.append(&long).unwrap_err().to_string();
    assert!(
        e.contains("labels.jsonl") && e.contains("No space left on device"),
        "{e}"
    );
    assert_eq!(
        fs::metadata(&path).unwrap().len(),
        4000,
        "a torn line was left"
    );
    // Room again by growing the disk rather than deleting the filler: a child the other
    // test spawns can hold the filler's descriptor between fork and exec, and its pages
    // stay taken until then.
    disk.resize("1m");
    log.append(&long).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    assert_eq!(text.len(), 4000 + 201);
    assert!(text.lines().all(|l| l == line || l == long));
}
