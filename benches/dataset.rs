//! `geltip dataset` throughput at the paper sensor's 640x480, printed as tables:
//! `cargo bench --bench dataset` (`-- --count N` samples per row, default 256;
//! `-- --sensor <preset|file.toml>`; `-- --memory N` for the memory run instead: N samples
//! rendered and encoded with the files discarded, printing resident memory after 1 000 and
//! after N samples).
//!
//! Rows: samples/s of whole runs (after the renderers' start-up) writing PNG only, and PNG +
//! depth map + mask, with the split per sample: contact drawing and CPU preparation (on its
//! own thread), GPU render and readback (on the render streams' threads, wall time summed
//! over the streams), and post-process, encoding and writing (on the encoder threads, wall
//! time summed over them); all of these overlap. Then the PNG compression levels: encode
//! time and size of the same frames at each.

use geltip::jobs::dataset::{self, PngLevel, Spec};
use geltip::output::{self, PngColor};
use geltip::render::gpu::Renderer;
use geltip::sensor::Sensor;
use std::time::{Duration, Instant};

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

/// Resident memory of this process (kB), from /proc/self/status.
fn rss_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn row(name: &str, r: &dataset::Report) {
    let n = r.rendered.max(1) as f64;
    let per = |d: Duration| d.as_secs_f64() * 1e3 / n;
    println!(
        "| {name:<34} | {:>6} | {:>9.1} | {:>7.2} | {:>7.2} | {:>8.2} | {:>6.2} | {:>7.2} | {:>6.2} | {:>7.0} |",
        r.rendered,
        n / r.wall.as_secs_f64(),
        per(r.split.prepare),
        per(r.split.render),
        per(r.split.readback),
        per(r.split.post),
        per(r.split.encode),
        per(r.split.write),
        r.bytes as f64 / n / 1024.0,
    );
}

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let sensor_arg = arg("--sensor").unwrap_or_else(|| "paper".into());
    let sensor = Sensor::load(&sensor_arg)?;
    if let Some(n) = arg("--memory") {
        return memory_run(&sensor_arg, sensor, n.parse()?);
    }
    let count: u64 = arg("--count").map_or(Ok(256), |c| c.parse())?;
    let speed = geltip::host_speed::HostSpeed::measure();
    println!(
        "geltip dataset benchmark on {}: {} samples per row, sensor {sensor_arg} ({}x{}), {} encoder threads and {} render streams by default; {speed}\n",
        geltip::gpu::host_description(&geltip::gpu::GpuContext::shared()?.adapter_info),
        count,
        sensor.width,
        sensor.height,
        dataset::default_workers(),
        dataset::default_streams()
    );
    println!(
        "| {:<34} | {:>6} | {:>9} | {:>7} | {:>7} | {:>8} | {:>6} | {:>7} | {:>6} | {:>7} |",
        "run",
        "samples",
        "samples/s",
        "prep ms",
        "render ms",
        "readback ms",
        "post ms",
        "enc ms",
        "write ms",
        "KB/sample"
    );
    println!(
        "|{}|",
        [36, 8, 11, 9, 9, 10, 8, 9, 8, 9]
            .map(|w| "-".repeat(w))
            .join("|")
    );
    let tmp = std::env::temp_dir().join(format!("geltip-bench-dataset-{}", std::process::id()));
    // (name, depth + mask, encoder threads, render streams, level); 0: the default.
    let rows: [(&str, bool, usize, usize, PngLevel); 7] = [
        ("PNG (fast)", false, 0, 0, PngLevel::Fast),
        ("PNG (fast) + depth + mask", true, 0, 0, PngLevel::Fast),
        ("PNG (fast), 1 render stream", false, 0, 1, PngLevel::Fast),
        ("PNG (fast), 2 render streams", false, 0, 2, PngLevel::Fast),
        ("PNG (fast), 1 encoder thread", false, 1, 0, PngLevel::Fast),
        ("PNG (none)", false, 0, 0, PngLevel::None),
        ("PNG (default)", false, 0, 0, PngLevel::Default),
    ];
    for (i, (name, extras, workers, streams, png)) in rows.into_iter().enumerate() {
        let mut spec = Spec::new(&sensor_arg, sensor.clone(), count, 1);
        spec.depth_maps = extras;
        spec.masks = extras;
        spec.png = png;
        if workers > 0 {
            spec.workers = workers;
        }
        if streams > 0 {
            spec.streams = streams;
        }
        let out = tmp.join(i.to_string());
        let r = dataset::run(&spec, Some(&out), |_| {})?;
        row(name, &r);
        std::fs::remove_dir_all(&out)?;
    }

    png_levels(&sensor)?;
    let _ = std::fs::remove_dir_all(&tmp);
    Ok(())
}

/// The PNG levels' table: encode time and size of the same 16 rendered frames at each level,
/// and at the fast level against the empty finger's cached rows.
fn png_levels(sensor: &Sensor) -> anyhow::Result<()> {
    // PNG levels on the same rendered frames.
    let mut renderer = Renderer::new(sensor)?;
    let objects = dataset::load_objects(&["sphere".into(), "cone".into(), "tube".into()])?;
    let contacts = (0..16)
        .map(|k| dataset::sample_contact(sensor, &objects, (0.2, 1.5), 1, k))
        .collect::<geltip::Result<Vec<_>>>()?;
    let frames = renderer.render_batch(&contacts)?;
    println!("\n| PNG level | encode ms/image | KB/image | mask encode ms | mask KB |");
    println!("|-----------|-----------------|----------|----------------|---------|");
    for level in PngLevel::ALL {
        let (c, f) = level.settings();
        let (mut t, mut bytes, mut tm, mut mbytes) = (Duration::ZERO, 0, Duration::ZERO, 0);
        for (frame, _) in &frames {
            let rgb = frame.to_rgb().into_raw();
            let s = Instant::now();
            bytes +=
                output::png_bytes(frame.width, frame.height, &rgb, PngColor::Rgb8, c, f)?.len();
            t += s.elapsed();
            let grey: Vec<u8> = frame
                .indentation
                .iter()
                .map(|&d| {
                    if d as f64 > geltip::render::MASK_THRESHOLD_MM {
                        255
                    } else {
                        0
                    }
                })
                .collect();
            let s = Instant::now();
            mbytes +=
                output::png_bytes(frame.width, frame.height, &grey, PngColor::Gray8, c, f)?.len();
            tm += s.elapsed();
        }
        let n = frames.len() as f64;
        println!(
            "| {:<9} | {:>15.2} | {:>8.0} | {:>14.2} | {:>7.1} |",
            level.name(),
            t.as_secs_f64() * 1e3 / n,
            bytes as f64 / n / 1024.0,
            tm.as_secs_f64() * 1e3 / n,
            mbytes as f64 / n / 1024.0,
        );
    }
    // What `geltip dataset` runs at the fast level: the empty finger's rows compressed once,
    // then only each frame's changed rows (the same compressed stream as fast's compressor).
    let reference = renderer.reference();
    let start = Instant::now();
    let rows = output::PngRowCache::new(reference.width, reference.height, &reference.rgba)?;
    let cache_ms = start.elapsed().as_secs_f64() * 1e3;
    let (mut t, mut bytes) = (Duration::ZERO, 0);
    for (frame, _) in &frames {
        let s = Instant::now();
        bytes += rows.encode(&frame.rgba)?.len();
        t += s.elapsed();
    }
    let n = frames.len() as f64;
    println!(
        "| fast, the empty finger's rows cached ({cache_ms:.1} ms once) | {:>15.2} | {:>8.0} | | |",
        t.as_secs_f64() * 1e3 / n,
        bytes as f64 / n / 1024.0,
    );
    Ok(())
}

/// Renders and encodes `n` samples (PNG + depth + mask), discarding the files; prints
/// resident memory after 1 000 samples and at the end.
fn memory_run(sensor_arg: &str, sensor: Sensor, n: u64) -> anyhow::Result<()> {
    let mut spec = Spec::new(sensor_arg, sensor, n, 1);
    spec.depth_maps = true;
    spec.masks = true;
    let mut at_1000 = None;
    let start = Instant::now();
    let mut last = Instant::now();
    let r = dataset::run(&spec, None, |p| {
        if at_1000.is_none() && p.done >= 1000 {
            at_1000 = Some((p.done, rss_kb()));
        }
        if last.elapsed() > Duration::from_secs(30) {
            last = Instant::now();
            eprintln!(
                "{}/{} samples, {:.0} s, VmRSS {:?} kB",
                p.done,
                p.total,
                start.elapsed().as_secs_f64(),
                rss_kb()
            );
        }
    })?;
    let end = rss_kb();
    println!("memory run: {n} samples (PNG + depth + mask, encoded and discarded)");
    if let Some((done, kb)) = at_1000 {
        println!("VmRSS after {done} samples: {} kB", kb.unwrap_or(0));
    }
    println!(
        "VmRSS after {} samples: {} kB",
        r.rendered,
        end.unwrap_or(0)
    );
    println!(
        "{:.1} samples/s over {:.0} s",
        r.rendered as f64 / r.wall.as_secs_f64(),
        r.wall.as_secs_f64()
    );
    Ok(())
}
