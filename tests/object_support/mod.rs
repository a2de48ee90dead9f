//! Helpers shared by the object tests (tests/objects*.rs): seeded points around a solid,
//! temporary folders, repository paths.
#![allow(dead_code)]

pub mod gltf;

use geltip::object::Solid;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The voxel size (mm) the object tests bake at.
pub const VOXEL: f64 = 0.25;

/// A small deterministic generator (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(self.next(), self.next(), self.next())
    }
}

/// A fresh, empty temporary folder for one test.
pub fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-objects-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The box around a solid (and 1.5 mm more) in which test points are drawn.
pub fn test_box(s: Solid) -> (DVec3, DVec3) {
    let f = s.footprint_radius() + 1.5;
    let depth = s.bounding_radius() + 1.5;
    (DVec3::new(-f, -f, -depth), DVec3::new(f, f, 1.5))
}
