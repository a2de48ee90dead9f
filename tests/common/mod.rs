//! Helpers shared by the integration tests.
#![allow(dead_code)]

use geltip::sensor::{Sensor, SensorConfig, PRESETS};
use geltip::LensModel;
use std::path::PathBuf;
use std::process::Command;

/// The paper preset's configuration, to derive variants from.
pub fn paper_config() -> SensorConfig {
    Sensor::preset("paper").unwrap().config
}

/// Every preset, plus the paper's finger behind each lens model (and a lens wider than 180).
pub fn all_sensors() -> Vec<Sensor> {
    let mut sensors: Vec<Sensor> = PRESETS
        .iter()
        .map(|(n, _)| Sensor::preset(n).unwrap())
        .collect();
    let variants: [(&str, LensModel, f64, f64, [f64; 4]); 5] = [
        ("pinhole160", LensModel::Pinhole, 50.0, 160.0, [0.0; 4]),
        ("equisolid170", LensModel::Equisolid, 190.0, 170.0, [0.0; 4]),
        (
            "kb170",
            LensModel::KannalaBrandt,
            175.0,
            170.0,
            [0.021, -0.0065, 0.0011, -0.00009],
        ),
        (
            "kb-barrel",
            LensModel::KannalaBrandt,
            200.0,
            170.0,
            [-0.05, 0.002, 0.0, 0.0],
        ),
        (
            "equidistant200",
            LensModel::Equidistant,
            130.0,
            200.0,
            [0.0; 4],
        ),
    ];
    for (name, model, focal, fov, k) in variants {
        let mut c = paper_config();
        c.lens.model = model;
        c.lens.focal_px = focal;
        c.lens.fov_deg = fov;
        c.lens.k = k;
        sensors.push(Sensor::from_config(name, c).unwrap());
    }
    sensors
}

/// Runs the `geltip` binary with `args`: its exit code (-1 when a signal ended it), its
/// stdout and its stderr.
pub fn geltip(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_geltip"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The error line geltip printed (Mesa may print its own lines around it).
pub fn error_line(stderr: &str) -> &str {
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error: ") && !l.contains("XDG_RUNTIME_DIR"))
        .collect();
    assert_eq!(lines.len(), 1, "expected one error line, got: {stderr}");
    lines[0]
}

/// `name` in the temporary folder `geltip-{folder}-{process id}`, which is created.
pub fn temp_in(folder: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-{folder}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A folder of real sensor frames under `../shared/real` (their sources: its README, and
/// docs/calibrate.md#real-sensors), or `None` and a message saying the tests on it skip.
pub fn real(sub: &str) -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/real")
        .join(sub);
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: {} is absent (real sensor frames; see docs/calibrate.md#real-sensors)",
            dir.display()
        );
        None
    }
}
