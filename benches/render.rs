//! Renderer throughput at the paper sensor's 640x480, printed as a table:
//! `cargo bench --bench render` (add `-- --frames N` for more frames per pass, `-- --sensor
//! <preset|file.toml>` for another sensor, `-- --batch 8,64,256` for the batch rows' frames
//! per submission (default 8 and the device's default), `-- --lanes 16,64` for the frames
//! of a submission recorded side by side in them (default the device's); `-- --host-phases N` prints only one contact per
//! submit over N passes, by the host's speed before each; `-- --same N` takes each contact N
//! times in a row, so that the frames a wave of lanes renders together are equal;
//! `-- --wave-stages N` prints only each stage's time for N of the paper's taps alone, in
//! one wave of N lanes, and in waves of N equal frames).
//!
//! Rows: the no-contact frame rendered from scratch (every pixel ray-cast, done once per
//! sensor), one contact per submission, and batches of contacts per submission; each split
//! into CPU preparation, GPU render (record, submit and wait, the copies for reading back
//! included; `record`: its CPU share until the submission) and readback (unpacking the
//! mapped frames), with the pixels re-rendered per frame and the commands recorded per frame
//! (`disp+copy+read`: compute dispatches, copies and clears, and the copies that read the
//! frames back; wgpu puts a barrier before each that writes); two
//! renderers on devices of their own, one contact per submit each on its own thread (fps
//! over both); one and two non-overlapping contacts per frame (`render_scene`); and the CPU
//! alternative (the CPU mirrors over the same footprint, on rayon's threads). Each row is the
//! median of `--repeat N` passes (default 5; the machines here are shared and noisy), with
//! the slowest and fastest pass's fps. Then the stages of a contact frame, the tiles the tile
//! list kept, the texels the elastomer's passes run over (texel rects and meridian rects,
//! over the paper's taps), and what the device charges whatever the work: an empty
//! submission, and a dispatch of one workgroup. The host's speed
//! (`geltip::host_speed::HostSpeed`: a fixed loop's ms on all cores) is timed before every
//! pass, its value for a row's median pass in the `host ms` column, and printed at the start
//! and at the end: shared machines run faster and slower by phases, so a row is only
//! comparable with another beside the same host speed.

use geltip::host_speed::HostSpeed;
use geltip::jobs::dataset;
use geltip::jobs::experiment::{self, Protocol};
use geltip::object::{Object, Solid};
use geltip::render::gpu::{Renderer, Timings};
use geltip::render::{contact, cpu, elastomer, HeightfieldGrid, Hold, Press};
use geltip::sensor::Sensor;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// `n` contacts: the paper's 56 taps (seven solids at its eight positions), over and over,
/// each `same` times in a row (`--same`: a wave of lanes then holds equal frames).
fn contacts(n: usize, same: usize) -> Vec<Press> {
    let all = experiment::all_taps(&Protocol::default());
    (0..n)
        .map(|i| all[(i / same.max(1)) % all.len()].clone())
        .collect()
}

/// One measured pass: frames, wall time and the renderer's split, and the host's speed just
/// before it.
#[derive(Clone, Copy)]
struct Pass {
    frames: usize,
    wall: Duration,
    t: Timings,
    host: HostSpeed,
}

impl Pass {
    fn fps(&self) -> f64 {
        self.frames as f64 / self.wall.as_secs_f64()
    }
}

/// Prints the median pass of `passes` (by fps), with the slowest and fastest pass's fps, and
/// the host's speed before the median pass (the fixed loop on all cores, ms).
fn row(name: &str, passes: &mut [Pass]) {
    passes.sort_by(|a, b| a.fps().total_cmp(&b.fps()));
    let p = passes[passes.len() / 2];
    let per = |d: Duration| d.as_secs_f64() * 1e3 / p.frames as f64;
    let range = format!(
        "{:.0}-{:.0}",
        passes[0].fps(),
        passes[passes.len() - 1].fps()
    );
    let count = |n: u64| n as f64 / p.frames as f64;
    let commands = format!(
        "{:.2}+{:.2}+{:.2}",
        count(p.t.dispatches),
        count(p.t.copies),
        count(p.t.readback_copies)
    );
    println!(
        "| {name:<30} | {:>6} | {:>8.1} | {range:>9} | {:>8.2} | {:>8.2} | {:>8.2} | {:>8.3} | {:>8.2} | {:>8.0} | {:>7.2} | {commands:>16} |",
        p.frames,
        p.fps(),
        per(p.wall),
        per(p.t.prepare),
        per(p.t.render),
        per(p.t.record),
        per(p.t.readback),
        p.t.touched_pixels as f64 / p.frames as f64,
        p.host.all_cores_ms,
    );
}

/// Runs `f` (which renders `frames` frames and returns the renderer's timings) `repeat`
/// times, each after timing the host's speed.
fn passes(
    repeat: usize,
    frames: usize,
    mut f: impl FnMut() -> anyhow::Result<Timings>,
) -> anyhow::Result<Vec<Pass>> {
    (0..repeat)
        .map(|_| {
            let host = HostSpeed::measure();
            let start = Instant::now();
            let t = f()?;
            Ok(Pass {
                frames,
                wall: start.elapsed(),
                t,
                host,
            })
        })
        .collect()
}

/// Renders each of `items` with `render` (whose frames are dropped at once), summing the
/// renderer's timings of each call.
fn each<T, U>(
    r: &mut Renderer,
    items: impl IntoIterator<Item = T>,
    mut render: impl FnMut(&mut Renderer, T) -> geltip::Result<U>,
) -> anyhow::Result<Timings> {
    let mut t = Timings::default();
    for item in items {
        render(r, item)?;
        t.add(&r.timings());
    }
    Ok(t)
}

/// One contact per submission, each of `list` in turn.
fn one_per_submit(r: &mut Renderer, list: &[Press]) -> anyhow::Result<Timings> {
    each(r, list, |r, c| r.render(c))
}

/// `--host-phases N`: N passes of one contact per submit, each after timing the host's
/// speed, as a table of fps by host speed (the fixed loop on all cores, ms): how much of a
/// run's spread is the host's, and the rate at the host's full speed (its fastest bins).
fn host_phases(r: &mut Renderer, list: &[Press], n: usize) -> anyhow::Result<()> {
    let mut all = passes(n, list.len(), || one_per_submit(r, list))?;
    all.sort_by(|a, b| a.host.all_cores_ms.total_cmp(&b.host.all_cores_ms));
    println!(
        "one contact per submit by the host's speed before each pass ({n} passes of {} frames)",
        list.len()
    );
    println!("| host ms | passes | fps median | fps range |");
    println!("|---------|--------|------------|-----------|");
    // Bins of a tenth of the fastest host time each.
    let fastest = all[0].host.all_cores_ms;
    let mut rest = &mut all[..];
    while !rest.is_empty() {
        let lo = rest[0].host.all_cores_ms;
        let bin = ((lo - fastest) / (0.1 * fastest)).floor();
        let hi = fastest * (1.0 + 0.1 * (bin + 1.0));
        let k = rest
            .iter()
            .take_while(|p| p.host.all_cores_ms < hi)
            .count()
            .max(1);
        let (here, later) = rest.split_at_mut(k);
        here.sort_by(|a, b| a.fps().total_cmp(&b.fps()));
        println!(
            "| {:.1}-{:.1} | {:>6} | {:>10.1} | {:>4.0}-{:<4.0} |",
            fastest * (1.0 + 0.1 * bin),
            hi,
            here.len(),
            here[here.len() / 2].fps(),
            here[0].fps(),
            here[here.len() - 1].fps()
        );
        rest = later;
    }
    // How closely the rate follows the host: Pearson's correlation of fps with the loop's
    // speed (1 / its ms), over every pass.
    let pairs: Vec<(f64, f64)> = all
        .iter()
        .map(|p| (p.fps(), 1.0 / p.host.all_cores_ms))
        .collect();
    let mean = |f: fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / pairs.len() as f64;
    let (mx, my) = (mean(|p| p.0), mean(|p| p.1));
    let sum = |f: &dyn Fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>();
    let cov = sum(&|p| (p.0 - mx) * (p.1 - my));
    let spread = (sum(&|p| (p.0 - mx).powi(2)) * sum(&|p| (p.1 - my).powi(2))).sqrt();
    println!(
        "correlation of fps with the host's speed (1 / host ms) over the {} passes: {:.2}",
        pairs.len(),
        if spread > 0.0 { cov / spread } else { 0.0 }
    );
    Ok(())
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> anyhow::Result<Option<T>>
where
    T::Err: std::error::Error + Send + Sync + 'static,
{
    match args.iter().position(|a| a == name) {
        None => Ok(None),
        Some(i) => {
            let v = args
                .get(i + 1)
                .ok_or_else(|| anyhow::anyhow!("{name} needs a value"))?;
            Ok(Some(
                v.parse()
                    .map_err(|e| anyhow::anyhow!("{name} {v:?}: {e}"))?,
            ))
        }
    }
}

/// A comma-separated list of counts after `name` (`--batch 8,64,256`).
fn counts(args: &[String], name: &str) -> anyhow::Result<Option<Vec<usize>>> {
    let Some(list) = arg::<String>(args, name)? else {
        return Ok(None);
    };
    let counts = list
        .split(',')
        .map(|n| n.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("{name} {list:?}: {e}"))?;
    Ok(Some(counts))
}

fn main() -> anyhow::Result<()> {
    // As the geltip binary does (see geltip::memory); GELTIP_FREE_MEMORY=1 measures without.
    let kept =
        std::env::var_os("GELTIP_FREE_MEMORY").is_none() && geltip::memory::keep_freed_memory();
    env_logger::init();
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = arg(&args, "--frames")?.unwrap_or(64).max(1);
    let repeat: usize = arg(&args, "--repeat")?.unwrap_or(5).max(1);
    let same: usize = arg(&args, "--same")?.unwrap_or(1).max(1);
    let sensor_arg: String = arg(&args, "--sensor")?.unwrap_or_else(|| "paper".to_string());
    let sensor = Sensor::load(&sensor_arg)?;
    // Before anything else runs: the host's speed now (and again at the end), so that rows
    // from different runs, or hosts, can be told apart from the host's own phases.
    let speed_before = HostSpeed::measure();
    let start = Instant::now();
    let mut r = Renderer::new(&sensor)?;
    let startup = start.elapsed();
    // The contact stage's pipeline of each object kind is built at its first frame; build
    // the seven solids' now, so no pass times a build (their time is printed).
    let start = Instant::now();
    let solids: Vec<_> = experiment::all_taps(&Protocol::default())
        .iter()
        .map(|c| c.object.clone())
        .collect();
    r.ready_objects(&solids)?;
    let contact_pipelines = start.elapsed();
    println!(
        "geltip render benchmark on {}: sensor {}, {}x{}, heightfield {}, start-up {:.2} s (+ {:.2} s for the seven solids' contact pipelines); freed frame memory {}; median of {repeat} passes",
        geltip::gpu::host_description(r.adapter()),
        sensor.name,
        sensor.width,
        sensor.height,
        sensor.config.render.heightfield_texels,
        startup.as_secs_f64(),
        contact_pipelines.as_secs_f64(),
        if kept { "kept" } else { "returned to the kernel" }
    );
    println!("{speed_before} (at the start)");
    print_table_header();

    let n_ref = (frames / 8).max(4);
    let mut reference = passes(repeat, n_ref, || {
        each(&mut r, 0..n_ref, |r, _| r.render_reference())
    })?;
    row("no contact, full ray cast", &mut reference);

    let list = contacts(frames, same);
    if let Some(n) = arg::<usize>(&args, "--host-phases")? {
        return host_phases(&mut r, &list, n.max(1));
    }
    if let Some(n) = arg::<usize>(&args, "--wave-stages")? {
        return wave_stage_table(&mut r, &list, n.max(2), repeat);
    }
    let mut batches = counts(&args, "--batch")?.unwrap_or(vec![8, r.batch_frames()]);
    batches.dedup();
    let lanes = counts(&args, "--lanes")?.unwrap_or(vec![r.lanes()]);
    let single = gpu_rows(&mut r, &solids, &list, (repeat, &batches, &lanes))?;
    cpu_row(&r, &list, repeat)?;
    stage_table(&mut r, &list)?;
    let per_frame = |f: fn(&Timings) -> u64| {
        single.iter().map(|p| f(&p.t)).sum::<u64>() as f64 / (repeat * frames) as f64
    };
    println!(
        "tile list, one contact per submit: {:.0} tiles ({:.0} pixels) selected from a frame, {:.0} pixels touched",
        per_frame(|t| t.listed_tiles),
        64.0 * per_frame(|t| t.listed_tiles),
        per_frame(|t| t.touched_pixels)
    );
    texel_rects(&sensor, r.grid(), &contacts(56, 1))?;
    device_overhead(geltip::gpu::GpuContext::shared()?)?;
    println!("{} (at the end)", HostSpeed::measure());
    Ok(())
}

fn print_table_header() {
    println!(
        "| {:<30} | {:>6} | {:>8} | {:>9} | {:>8} | {:>8} | {:>8} | {:>8} | {:>8} | {:>8} | {:>7} | {:>16} |",
        "what",
        "frames",
        "fps",
        "fps range",
        "ms/frame",
        "prepare",
        "render",
        "record",
        "readback",
        "touched",
        "host ms",
        "disp+copy+read"
    );
    println!(
        "|{:-<32}|{:->8}|{:->10}|{:->11}|{:->10}|{:->10}|{:->10}|{:->10}|{:->10}|{:->10}|{:->9}|{:->18}|",
        "", "", "", "", "", "", "", "", "", "", "", ""
    );
}

/// The GPU's rows over `list`: one contact per submit (its passes are returned), on two
/// streams, in batches of each of `batches` frames, and one and two contacts per scene
/// (the two also in batches).
fn gpu_rows(
    r: &mut Renderer,
    solids: &[Arc<Object>],
    list: &[Press],
    (repeat, batches, lane_counts): (usize, &[usize], &[usize]),
) -> anyhow::Result<Vec<Pass>> {
    let frames = list.len();
    let mut single = passes(repeat, frames, || one_per_submit(r, list))?;
    row("one contact per submit", &mut single);

    // What a program that renders many contacts can do on the same cores: two renderers on
    // devices of their own (GpuContext::stream, as `geltip dataset --streams` does), each
    // rendering half the contacts one per submit on its own thread; fps over both. Its
    // split is summed over the two.
    let mut second = Renderer::on(r.sensor(), geltip::gpu::GpuContext::stream(1)?)?;
    second.ready_objects(solids)?;
    let mut two_streams = passes(repeat, frames, || {
        let (a, b) = list.split_at(list.len() / 2);
        let (ta, tb) = std::thread::scope(|scope| {
            let other = scope.spawn(|| one_per_submit(&mut second, b));
            let mine = one_per_submit(r, a);
            (mine, other.join())
        });
        let mut t = ta?;
        t.add(&tb.map_err(|_| anyhow::anyhow!("the second stream panicked"))??);
        Ok(t)
    })?;
    row("one per submit, 2 streams", &mut two_streams);

    // Batches (Renderer::render_batch: a submission of n frames, the next batch prepared
    // while this one renders), as a streaming consumer calls it: the frames of each call
    // (four submissions) are dropped before the next (keeping all of them would time the
    // allocator's fresh pages, not the renderer).
    let default = (r.batch_frames(), r.lanes());
    for &n in batches {
        r.set_batch_frames(n)?;
        let mut lanes: Vec<usize> = lane_counts.iter().map(|&l| l.min(n)).collect();
        lanes.dedup();
        for l in lanes {
            r.set_lanes(l)?;
            let mut batched = passes(repeat, frames, || {
                each(r, list.chunks(4 * n), |r, batch| r.render_batch(batch))
            })?;
            row(&format!("batches of {n}, {l} lanes"), &mut batched);
        }
    }
    r.set_batch_frames(default.0)?;
    r.set_lanes(default.1)?;

    // Several objects in one frame (Renderer::render_scene): each tap with its twin on the
    // opposite side of the finger (azimuth + 180: imprints that do not overlap), against the
    // same taps one per scene.
    let ones: Vec<Press> = list.to_vec();
    let twins: Vec<[Press; 2]> = list
        .iter()
        .map(|c| {
            let mut twin = c.clone();
            if let Hold::Surface { azimuth_deg, .. } = &mut twin.hold {
                *azimuth_deg += 180.0;
            }
            [c.clone(), twin]
        })
        .collect();
    let mut one_scene = passes(repeat, frames, || {
        each(r, &ones, |r, p| r.render_scene(std::slice::from_ref(p)))
    })?;
    row("one contact per scene", &mut one_scene);
    let mut two_scene = passes(repeat, frames, || {
        each(r, &twins, |r, pair| r.render_scene(pair))
    })?;
    row("two contacts per scene", &mut two_scene);
    // The same scenes in batches (Renderer::render_scenes), at the largest batch and lanes.
    let scenes: Vec<Vec<Press>> = twins.iter().map(|t| t.to_vec()).collect();
    let n = batches.iter().copied().max().unwrap_or(default.0);
    let l = lane_counts
        .iter()
        .copied()
        .max()
        .unwrap_or(default.1)
        .min(n);
    r.set_batch_frames(n)?;
    r.set_lanes(l)?;
    let mut two_batched = passes(repeat, frames, || {
        each(r, scenes.chunks(4 * n), |r, chunk| {
            r.render_scenes(chunk, false)
        })
    })?;
    row(
        &format!("two per scene, batches of {n}, {l} lanes"),
        &mut two_batched,
    );
    r.set_batch_frames(default.0)?;
    r.set_lanes(default.1)?;
    Ok(single)
}

/// What a user could run instead on the same cores: the CPU mirrors over the same
/// footprint (the GPU's reference frame as the empty finger), rayon over the touched
/// pixels. Fewer frames: it is the slow row. Its split is not measured (all "render").
fn cpu_row(r: &Renderer, list: &[Press], repeat: usize) -> anyhow::Result<()> {
    let cpu_list = &list[..(list.len() / 4).max(8).min(list.len())];
    let reference_frame = r.reference().clone();
    let (sensor, grid) = (r.sensor().clone(), *r.grid());
    let mut cpu_passes = passes(repeat, cpu_list.len(), || {
        let start = Instant::now();
        for c in cpu_list {
            cpu::render_contact(&sensor, &grid, &reference_frame, c)?;
        }
        Ok(Timings {
            render: start.elapsed(),
            ..Timings::default()
        })
    })?;
    row(
        &format!("CPU mirrors, rayon x{}", rayon::current_num_threads()),
        &mut cpu_passes,
    );
    Ok(())
}

/// Where a contact frame's time goes, averaged over eight of the paper's taps and over
/// random dataset contacts: from timestamps between the stages of one submission where
/// the device writes them (lavapipe does), else each stage submitted and waited for on
/// its own (then a stage's time includes a submission and a wait).
fn stage_table(r: &mut Renderer, list: &[Press]) -> anyhow::Result<()> {
    println!();
    let how = if geltip::gpu::GpuContext::shared()?.has_timestamps() {
        "ms, timestamps"
    } else {
        "ms, own submit"
    };
    println!(
        "| {:<28} | {:>14} | {:>22} |",
        "stage (one contact)", how, "random dataset contacts"
    );
    println!("|{:-<30}|{:->16}|{:->24}|", "", "", "");
    // Every seventh of the paper's taps (each solid and each position once), and 100 of
    // `geltip dataset`'s random contacts (seed 1, the seven solids, default depths).
    let taps: Vec<Press> = list.iter().step_by(7).take(8).cloned().collect();
    let objects: Vec<_> = Solid::ALL
        .iter()
        .map(|s| Arc::new(Object::Solid(*s)))
        .collect();
    let sensor = r.sensor().clone();
    let depths = dataset::default_depth_range(sensor.finger.shell_thickness);
    let random = (0..100)
        .map(|k| dataset::sample_contact(&sensor, &objects, depths, 1, k))
        .collect::<geltip::Result<Vec<_>>>()?;
    let mut columns = Vec::new();
    for sample in [&taps, &random] {
        let mut totals: Vec<(&str, f64)> = Vec::new();
        for c in sample {
            for (i, (name, d)) in r.profile_stages(c)?.into_iter().enumerate() {
                if totals.len() <= i {
                    totals.push((name, 0.0));
                }
                totals[i].1 += d.as_secs_f64() * 1e3 / sample.len() as f64;
            }
        }
        columns.push(totals);
    }
    for ((name, ms), (_, random_ms)) in columns[0].iter().zip(&columns[1]) {
        println!("| {name:<28} | {ms:>14.3} | {random_ms:>22.3} |");
    }
    println!();
    Ok(())
}

/// What recording frames side by side in one wave does to each stage, from timestamps (ms
/// for `n` frames, the median of `repeat` runs): `n` of the paper's taps each alone, the
/// same `n` in one wave (`n` lanes), and each tap `n` times in a wave of its own, divided
/// by `n` (a wave of equal frames).
fn wave_stage_table(
    r: &mut Renderer,
    list: &[Press],
    n: usize,
    repeat: usize,
) -> anyhow::Result<()> {
    r.set_lanes(n)?;
    let taps: Vec<Press> = list.iter().step_by(7).cycle().take(n).cloned().collect();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut table: Vec<(&str, [f64; 3])> = Vec::new();
    let mut add = |column: usize, stages: Vec<(&'static str, f64)>| {
        for (i, (name, ms)) in stages.into_iter().enumerate() {
            if table.len() <= i {
                table.push((name, [0.0; 3]));
            }
            table[i].1[column] += ms;
        }
    };
    let timed = |r: &mut Renderer, presses: &[Press]| -> anyhow::Result<Vec<(&'static str, f64)>> {
        let runs = (0..repeat)
            .map(|_| r.profile_wave(presses))
            .collect::<geltip::Result<Vec<_>>>()?;
        Ok((0..runs[0].len())
            .map(|i| {
                let times = runs.iter().map(|s| s[i].1.as_secs_f64() * 1e3).collect();
                (runs[0][i].0, median(times))
            })
            .collect())
    };
    for t in &taps {
        add(0, timed(r, std::slice::from_ref(t))?);
    }
    add(1, timed(r, &taps)?);
    for t in &taps {
        let equal = timed(r, &vec![t.clone(); n])?;
        add(
            2,
            equal
                .into_iter()
                .map(|(s, ms)| (s, ms / n as f64))
                .collect(),
        );
    }
    println!();
    println!("stages of {n} of the paper's taps, ms for all {n} (median of {repeat}):");
    println!(
        "| {:<30} | {:>10} | {:>12} | {:>16} |",
        "stage", "each alone", "in one wave", "equal-frame waves"
    );
    println!("|{:-<32}|{:->12}|{:->14}|{:->18}|", "", "", "", "");
    let mut sums = [0.0; 3];
    for (name, ms) in &table {
        println!(
            "| {name:<30} | {:>10.3} | {:>12.3} | {:>16.3} |",
            ms[0], ms[1], ms[2]
        );
        for (s, m) in sums.iter_mut().zip(ms) {
            *s += m;
        }
    }
    println!(
        "| {:<30} | {:>10.3} | {:>12.3} | {:>16.3} |",
        "all", sums[0], sums[1], sums[2]
    );
    Ok(())
}

/// The texels the elastomer's passes run over a frame, on average over `list`: the texel
/// rects (the parallels pass and the skin normals) and the meridian rects (the meridians
/// pass: the pressed rect grown by the kernels' reach).
fn texel_rects(sensor: &Sensor, grid: &HeightfieldGrid, list: &[Press]) -> anyhow::Result<()> {
    let reach = elastomer::blend_reach_mm(&sensor.config.elastomer);
    let (mut texels, mut meridians) = (0, 0);
    for press in list {
        let pose = press.pose(sensor)?;
        if let Some(f) = contact::footprint(sensor, grid, &pose, &press.object, reach) {
            texels += f.texels.area();
            meridians += f.meridians.area();
        }
    }
    let n = list.len().max(1) as f64;
    println!(
        "texels a frame over the paper's {} taps: {:.0} in the texel rect (parallels, skin normals), {:.0} in the meridian rect ({:.0}%)",
        list.len(),
        texels as f64 / n,
        meridians as f64 / n,
        100.0 * meridians as f64 / texels.max(1) as f64
    );
    Ok(())
}

/// What the device charges whatever the work: a submission with nothing in it, and each
/// compute dispatch of one workgroup that does next to nothing (50 in one submission), in a
/// compute pass of its own and all in one pass. A contact frame has eight dispatches in six
/// passes and some fifteen copies and clears; on lavapipe each pass costs more than the
/// dispatches in it (the renderer's passes, with their many bindings, still more than these),
/// which is why the renderer puts in one pass what the copies between its stages allow.
fn device_overhead(ctx: &geltip::gpu::GpuContext) -> anyhow::Result<()> {
    let d = &ctx.device;
    let buffer = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("overhead probe"),
        size: 256,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("overhead probe"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<storage, read_write> b: array<u32>;\n\
             @compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) \
             { b[id.x] = b[id.x] + 1u; }"
                .into(),
        ),
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("overhead probe"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    // Seconds per submission of `dispatches` dispatches (each in its own pass, or all in
    // one), the median of 9 after a warm-up.
    let time = |dispatches: usize, passes: usize| -> anyhow::Result<f64> {
        let mut seconds = Vec::new();
        for _ in 0..10 {
            let start = Instant::now();
            let mut encoder = d.create_command_encoder(&Default::default());
            for _ in 0..passes {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                for _ in 0..dispatches / passes {
                    pass.set_pipeline(&pipeline);
                    pass.set_bind_group(0, &bind, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
            }
            ctx.submit_and_wait("timing the device's overhead", encoder)?;
            seconds.push(start.elapsed().as_secs_f64());
        }
        seconds.remove(0);
        seconds.sort_by(f64::total_cmp);
        Ok(seconds[seconds.len() / 2])
    };
    let empty = time(0, 0)?;
    let apart = time(50, 50)?;
    let together = time(50, 1)?;
    println!(
        "device overhead: an empty submission and its wait {:.0} us; a dispatch of one workgroup {:.1} us in a pass of its own, {:.1} us in one pass with the others",
        empty * 1e6,
        (apart - empty) / 50.0 * 1e6,
        (together - empty) / 50.0 * 1e6
    );
    Ok(())
}
