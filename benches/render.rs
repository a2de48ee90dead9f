//! Renderer throughput at the paper sensor's 640x480, printed as a table:
//! `cargo bench --bench render` (add `-- --frames N` for more frames per row, `-- --sensor
//! <preset|file.toml>` for another sensor).
//!
//! Rows: the no-contact frame rendered from scratch (every pixel ray-cast, done once per
//! sensor), one contact per submission, and batches of contacts per submission; each split
//! into CPU preparation, GPU render (submit + wait) and readback (copy, map, unpack).

use geltip::experiment::{self, Protocol};
use geltip::object::Solid;
use geltip::render::gpu::{Renderer, Timings, MAX_BATCH};
use geltip::render::Contact;
use geltip::sensor::Sensor;
use std::time::{Duration, Instant};

/// `n` contacts: the paper's 56 taps (seven solids at its eight positions), over and over.
fn contacts(n: usize) -> Vec<Contact> {
    let all: Vec<Contact> = Solid::ALL
        .iter()
        .flat_map(|&s| experiment::taps(s, &Protocol::default()))
        .collect();
    all.iter().cycle().take(n).cloned().collect()
}

fn row(name: &str, frames: usize, wall: Duration, t: Timings) {
    let per = |d: Duration| d.as_secs_f64() * 1e3 / frames as f64;
    println!(
        "| {name:<28} | {frames:>6} | {:>8.1} | {:>8.2} | {:>8.2} | {:>8.2} | {:>8.2} |",
        frames as f64 / wall.as_secs_f64(),
        per(wall),
        per(t.prepare),
        per(t.render),
        per(t.readback),
    );
}

fn main() -> anyhow::Result<()> {
    env_logger::init();
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse())
        .transpose()?
        .unwrap_or(64);
    let sensor_arg = args
        .iter()
        .position(|a| a == "--sensor")
        .and_then(|i| args.get(i + 1))
        .cloned()
        .unwrap_or_else(|| "paper".to_string());
    let sensor = Sensor::load(&sensor_arg)?;
    let start = Instant::now();
    let mut r = Renderer::new(&sensor)?;
    let info = r.adapter().clone();
    println!(
        "geltip render benchmark: sensor {}, {}x{}, heightfield {}, adapter {} ({:?}), start-up {:.2} s",
        sensor.name,
        sensor.width,
        sensor.height,
        sensor.config.render.heightfield_texels,
        info.name,
        info.backend,
        start.elapsed().as_secs_f64()
    );
    println!(
        "| {:<28} | {:>6} | {:>8} | {:>8} | {:>8} | {:>8} | {:>8} |",
        "what", "frames", "fps", "ms/frame", "prepare", "render", "readback"
    );
    println!(
        "|{:-<30}|{:->8}|{:->10}|{:->10}|{:->10}|{:->10}|{:->10}|",
        "", "", "", "", "", "", ""
    );

    let n_ref = (frames / 8).max(4);
    let mut t = Timings::default();
    let start = Instant::now();
    for _ in 0..n_ref {
        r.render_reference()?;
        let rt = r.timings();
        t.render += rt.render;
        t.readback += rt.readback;
    }
    row("no contact, full ray cast", n_ref, start.elapsed(), t);

    let list = contacts(frames);
    let mut t = Timings::default();
    let start = Instant::now();
    for c in &list {
        r.render(c)?;
        let rt = r.timings();
        t.prepare += rt.prepare;
        t.render += rt.render;
        t.readback += rt.readback;
    }
    row("one contact per submit", frames, start.elapsed(), t);

    // A streaming consumer: each batch's frames are dropped before the next (keeping all of
    // them would time the allocator's fresh pages, not the renderer).
    let mut t = Timings::default();
    let start = Instant::now();
    for batch in list.chunks(MAX_BATCH) {
        r.render_batch(batch)?;
        let rt = r.timings();
        t.prepare += rt.prepare;
        t.render += rt.render;
        t.readback += rt.readback;
    }
    row(
        &format!("batches of {MAX_BATCH} contacts"),
        frames,
        start.elapsed(),
        t,
    );

    // Where a contact frame's time goes: each stage submitted and waited for on its own,
    // averaged over eight of the paper's taps (every solid, every position).
    println!();
    println!("| {:<28} | {:>8} |", "stage (one contact)", "ms");
    println!("|{:-<30}|{:->10}|", "", "");
    let mut totals: Vec<(&str, f64)> = Vec::new();
    // Every seventh of the paper's taps: each solid and each position once.
    let sample: Vec<&Contact> = list.iter().step_by(7).take(8).collect();
    for c in sample.iter().copied() {
        for (i, (name, d)) in r.profile_stages(c)?.into_iter().enumerate() {
            if totals.len() <= i {
                totals.push((name, 0.0));
            }
            totals[i].1 += d.as_secs_f64() * 1e3 / sample.len() as f64;
        }
    }
    for (name, ms) in totals {
        println!("| {name:<28} | {ms:>8.2} |");
    }
    Ok(())
}
