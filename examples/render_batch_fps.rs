//! The render bench's "batches of 8 contacts" row, one pass per request, for comparing the
//! Python package against Rust pass by pass on a noisy machine
//! (`python/bench/render_batch.py` drives it):
//!
//! ```sh
//! cargo build --release --workspace --example render_batch_fps
//! echo pass | target/release/examples/render_batch_fps --frames 64
//! ```
//!
//! Prints the host line, then for each line `pass` read from stdin renders the bench's
//! contacts (the paper's 56 taps over and over, `--frames` of them) with
//! `Renderer::render_batch` in batches of `Renderer::batch_frames`, dropping each batch's
//! frames before the next (as `benches/render.rs` does), and prints the pass's frames per
//! second.

use geltip::jobs::experiment::{self, Protocol};
use geltip::render::gpu::Renderer;
use geltip::render::Press;
use geltip::sensor::Sensor;
use std::io::{BufRead, Write};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = match args.iter().position(|a| a == "--frames") {
        Some(i) => args
            .get(i + 1)
            .ok_or_else(|| anyhow::anyhow!("--frames needs a value"))?
            .parse()?,
        None => 64,
    };
    let sensor = Sensor::preset("paper")?;
    let mut renderer = Renderer::new(&sensor)?;
    let taps = experiment::all_taps(&Protocol::default());
    let list: Vec<Press> = taps.iter().cycle().take(frames.max(1)).cloned().collect();
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", geltip::gpu::host_description(renderer.adapter()))?;
    out.flush()?;
    for line in std::io::stdin().lock().lines() {
        match line?.trim() {
            "pass" => {
                let start = Instant::now();
                for batch in list.chunks(renderer.batch_frames()) {
                    renderer.render_batch(batch)?;
                }
                writeln!(out, "{}", list.len() as f64 / start.elapsed().as_secs_f64())?;
                out.flush()?;
            }
            "" => {}
            _ => break,
        }
    }
    Ok(())
}
