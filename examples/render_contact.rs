//! Renders the paper's sensor with a cone pressed 1 mm into the side of the finger, and saves
//! the image, the reference frame and the ground truth:
//!
//! ```sh
//! cargo run --example render_contact            # writes out/examples/cone.png, ref.png, cone.json
//! ```

use geltip::object::{Object, Solid};
use geltip::output;
use geltip::render::gpu::Renderer;
use geltip::render::{Place, Press};
use geltip::sensor::Sensor;
use std::path::Path;
use std::sync::Arc;

fn main() -> anyhow::Result<()> {
    let sensor = Sensor::preset("paper")?;
    let mut renderer = Renderer::new(&sensor)?;
    let contact = Press::at(
        Arc::new(Object::Solid(Solid::Cone)),
        Place::Translation(5.0),
        200.0,
        1.0,
    );
    let (frame, truth) = renderer.render(&contact)?;
    let dir = Path::new("out/examples");
    let (w, h) = (frame.width, frame.height);
    output::write_png_rgb8(dir.join("cone.png"), w, h, frame.to_rgb().as_raw())?;
    output::write_png_rgb8(
        dir.join("ref.png"),
        w,
        h,
        renderer.reference().to_rgb().as_raw(),
    )?;
    output::write_json(dir.join("cone.json"), &truth.to_json())?;
    println!(
        "contact at {} (pixel {:?}), {} pixels pressed",
        truth.point, truth.pixel, truth.mask_pixels
    );
    Ok(())
}
