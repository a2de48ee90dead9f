//! Helpers shared by the renderer's tests (tests/render.rs, tests/mirrors.rs): contacts,
//! a small sensor, and the one image tolerance.
#![allow(dead_code)]

use geltip::object::{Object, Solid};
use geltip::render::{Frame, Place, Press};
use geltip::sensor::Sensor;
use std::sync::Arc;

/// `solid` pressed `depth` mm at `place`, at azimuth 30 degrees.
pub fn contact(solid: Solid, place: Place, depth: f64) -> Press {
    Press::at(Arc::new(Object::Solid(solid)), place, 30.0, depth)
}

/// A small sensor for CPU-vs-GPU comparisons (the CPU mirror is slow at full size). 150 px
/// wide: a row of its rays' probes (150 x 32 bytes) is not a whole number of 256-byte copy
/// rows, so the renderer copies them row by row.
pub fn small_sensor() -> Sensor {
    let mut c = super::common::paper_config();
    c.image.width = 150;
    c.image.height = 120;
    c.lens.cx = 75.0;
    c.lens.cy = 60.0;
    c.lens.focal_px = 45.0;
    c.render.heightfield_texels = 256;
    Sensor::from_config("small", c).unwrap()
}

/// Per-channel differences between two images.
#[derive(Debug)]
pub struct Diff {
    pub mean_abs: f64,
    /// Fraction of channel values that differ by more than `loose` levels.
    pub frac_over: f64,
}

pub fn diff(a: &[u8], b: &[u8], loose: u8) -> Diff {
    assert_eq!(a.len(), b.len());
    let (mut sum, mut over) = (0u64, 0u64);
    for (x, y) in a.iter().zip(b) {
        let d = x.abs_diff(*y);
        sum += d as u64;
        if d > loose {
            over += 1;
        }
    }
    Diff {
        mean_abs: sum as f64 / a.len() as f64,
        frac_over: over as f64 / a.len() as f64,
    }
}

/// The tolerance every image comparison uses: small rounding differences everywhere are fine,
/// a changed region is not.
pub fn close_enough(d: &Diff) -> bool {
    d.mean_abs < 0.5 && d.frac_over < 0.002
}

pub fn rgb(frame: &Frame) -> Vec<u8> {
    frame.to_rgb().into_raw()
}
