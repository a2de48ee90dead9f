//! Localiser speed: both detectors on rendered 640x480 paper-sensor images, in images/s:
//! `cargo bench --bench localise`. Target: >= 500 images/s for the surface
//! detector on 2-core lavapipe hosts; the paper detector is measured beside it.

use geltip::jobs::experiment::{self, Protocol};
use geltip::localise::{Localiser, Method};
use geltip::object::Solid;
use geltip::render::gpu::Renderer;
use geltip::sensor::Sensor;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    let sensor = Sensor::preset("paper")?;
    let mut renderer = Renderer::new(&sensor)?;
    let reference = renderer.render_empty()?.to_rgb();
    // One contact per tap position of the paper, each with another of the seven solids.
    let contacts: Vec<_> = (0..experiment::POSITIONS.len())
        .map(|i| {
            experiment::taps(Solid::ALL[i % Solid::ALL.len()], &Protocol::default())[i].clone()
        })
        .collect();
    let mut frames: Vec<_> = renderer
        .render_batch(&contacts)?
        .into_iter()
        .map(|(f, _)| f.to_rgb())
        .collect();
    // And an empty frame: what a detector sees most of the time on a robot.
    frames.push(reference.clone());
    let localiser = Localiser::new(&sensor);
    localiser.cache();
    println!(
        "geltip localiser speed: paper sensor {}x{}, {} frames ({} contacts + 1 empty)",
        sensor.width,
        sensor.height,
        frames.len(),
        contacts.len()
    );
    println!("| method | images/s (median of 7 rounds) | ms/image | target |");
    println!("|---|---|---|---|");
    for method in Method::NAMED {
        let rounds = 7;
        let mut rates = Vec::new();
        for _ in 0..rounds {
            let start = Instant::now();
            let mut n = 0;
            while start.elapsed().as_secs_f64() < 0.5 {
                for f in &frames {
                    std::hint::black_box(localiser.localise(&reference, f, method)?);
                    n += 1;
                }
            }
            rates.push(n as f64 / start.elapsed().as_secs_f64());
        }
        rates.sort_by(f64::total_cmp);
        let rate = rates[rounds / 2];
        let target = match method {
            Method::Surface => {
                if rate >= 500.0 {
                    ">= 500: met"
                } else {
                    ">= 500: SHORT"
                }
            }
            Method::Paper | Method::Change => "(measured beside)",
        };
        println!(
            "| {} | {rate:.0} | {:.2} | {target} |",
            method.name(),
            1000.0 / rate
        );
    }
    Ok(())
}
