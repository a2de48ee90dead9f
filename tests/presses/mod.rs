//! The paper sensor's renderer and the presses shared by the contact tests
//! (tests/contacts.rs, tests/contact_scenes.rs).
#![allow(dead_code)]

use geltip::object::{Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{Frame, GroundTruth, Hold, Place, Press};
use geltip::sensor::Sensor;
use std::sync::{Arc, Mutex, OnceLock};

/// The paper preset's renderer, one for the whole test binary (tests take turns).
pub fn paper() -> std::sync::MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    R.get_or_init(|| {
        Mutex::new(
            Renderer::new(&Sensor::preset("paper").unwrap())
                .expect("renderer (is lavapipe installed?)"),
        )
    })
    .lock()
    .unwrap_or_else(|e| e.into_inner())
}

/// `solid` pressed `depth` mm at `place`, untilted.
pub fn press(solid: Solid, place: Place, azimuth: f64, depth: f64) -> Press {
    tilted(solid, place, azimuth, 0.0, 0.0, 0.0, depth)
}

/// `solid` pressed `depth` mm at `place`, spun and tilted (degrees).
pub fn tilted(
    solid: Solid,
    place: Place,
    azimuth: f64,
    spin: f64,
    tilt: f64,
    towards: f64,
    depth: f64,
) -> Press {
    Press {
        object: Arc::new(Object::Solid(solid)),
        hold: Hold::Surface {
            place,
            azimuth_deg: azimuth,
            spin_deg: spin,
            tilt_deg: tilt,
            tilt_towards_deg: towards,
            depth_mm: depth,
        },
    }
}

/// One press rendered alone: its frame and its ground truth.
pub fn render_one(r: &mut Renderer, p: &Press) -> (Frame, GroundTruth) {
    let (frame, mut truths) = r.render_scene(std::slice::from_ref(p)).unwrap();
    (frame, truths.remove(0))
}

/// The RGBA bytes of the pixel nearest `px`.
pub fn rgb_at(frame: &Frame, px: glam::DVec2) -> [u8; 4] {
    let (u, v) = (px.x.round() as usize, px.y.round() as usize);
    let i = (v * frame.width as usize + u) * 4;
    frame.rgba[i..i + 4].try_into().unwrap()
}
