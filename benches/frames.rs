//! `cargo bench --bench frames -- N`: renders N contact frames, one per submit (the paper's
//! taps, every seventh in turn), and exits: a fixed workload for a profiler. The wall clock
//! of a shared 2-core host varies 2x within the hour; instructions do not, so the README's
//! per-frame instruction counts come from this under callgrind (the cost of N frames less
//! that of 2, over N - 2, so start-up, the reference frame and the contact pipelines of
//! the seven solids, built first, cancel out):
//!
//! ```text
//! cargo bench --bench frames --no-run   # prints the binary's path
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/deps/frames-<hash> 2
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/deps/frames-<hash> 18
//! ```
//!
//! (Run it once outside valgrind first, so Mesa's shader cache holds the pipelines, and set
//! `GELTIP_GPU_TIMEOUT_S=900`: under valgrind a frame takes seconds.)

use geltip::jobs::experiment;
use geltip::render::gpu::Renderer;
use geltip::sensor::Sensor;

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    // (cargo bench passes `--bench` too: the count is the argument that is a number.)
    let n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(8);
    let sensor = Sensor::preset("paper")?;
    let mut renderer = Renderer::new(&sensor)?;
    let taps = experiment::all_taps(&Default::default());
    // Each object kind has its own contact pipeline, built at its first frame: render every
    // solid once first, so N frames less 2 counts frames, not pipeline builds.
    let objects: Vec<_> = taps.iter().map(|c| c.object.clone()).collect();
    renderer.ready_objects(&objects)?;
    let mut t = geltip::render::gpu::Timings::default();
    let start = std::time::Instant::now();
    for k in 0..n {
        renderer.render(&taps[(k * 7) % taps.len()])?;
        t.add(&renderer.timings());
    }
    // The split per frame, for a quick look outside a profiler (the wall clock here is
    // noisy: compare two builds run alternately).
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3 / n.max(1) as f64;
    eprintln!(
        "{n} frames, ms a frame: wall {:.3}, prepare {:.3}, render {:.3}, readback {:.3}",
        ms(start.elapsed()),
        ms(t.prepare),
        ms(t.render),
        ms(t.readback)
    );
    Ok(())
}
