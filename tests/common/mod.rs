//! Helpers shared by the integration tests.
#![allow(dead_code)]

use geltip::sensor::{Sensor, SensorConfig, PRESETS};
use geltip::LensModel;

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
