//! The `geltip` command line.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use geltip::jobs::dataset;
use geltip::jobs::experiment::{self, Protocol};
use geltip::jobs::{preview, stability, tradeoff};
use geltip::localise::{load_frame, localise, Method};
use geltip::object::{Object, Solid};
use geltip::output;
use geltip::render::gpu::Renderer;
use geltip::render::{load_scene, parse_pose, Frame, Hold, Place, Press};
use geltip::sensor::{Sensor, PRESETS};
use glam::{DVec2, DVec3};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "geltip",
    version,
    about = "Simulator of the GelTip optical tactile sensor"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the sensor presets.
    Sensors,
    /// Map a pixel to the finger surface point it sees (the paper's map m).
    #[command(allow_negative_numbers = true)]
    Unproject {
        /// Preset name or path to a sensor TOML file.
        #[arg(long)]
        sensor: String,
        /// Pixel column (OpenCV convention: integer values at pixel centres).
        u: f64,
        /// Pixel row.
        v: f64,
    },
    /// Map a point on (or inside) the finger, in mm, to its pixel.
    #[command(allow_negative_numbers = true)]
    Project {
        #[arg(long)]
        sensor: String,
        x: f64,
        y: f64,
        z: f64,
    },
    /// Render a tactile image: an object pressed into the finger, or the empty finger.
    ///
    /// Examples:
    ///   geltip render --sensor paper --object sphere --at rotation=45 --depth 1 -o sphere.png --labels sphere.json
    ///   geltip render --sensor paper --reference -o ref.png
    #[command(allow_negative_numbers = true, verbatim_doc_comment)]
    Render {
        /// Preset name or path to a sensor TOML file.
        #[arg(long)]
        sensor: String,
        /// Render the empty finger (the reference frame detectors subtract).
        #[arg(long, conflicts_with_all = ["object", "at", "depth", "azimuth", "spin", "labels", "pose", "scene", "tilt", "tilt_towards"])]
        reference: bool,
        /// A built-in solid (cone, sphere, irregular-prism, cylinder, edge, tube, slab) or a
        /// mesh file (.obj, .gltf, .glb) whose +z points at the finger.
        #[arg(long, required_unless_present_any = ["reference", "scene"], conflicts_with = "scene")]
        object: Option<String>,
        /// Where: rotation=<deg> about the tip (0 = tip, 90 = junction), translation=<mm>
        /// along the side below the junction, or s=<mm> of arc length from the tip.
        #[arg(long, required_unless_present_any = ["reference", "pose", "scene"], conflicts_with_all = ["pose", "scene"])]
        at: Option<String>,
        /// Azimuth of the contact about the finger's axis, degrees (0 = image +x).
        #[arg(long, default_value_t = 0.0)]
        azimuth: f64,
        /// The object's rotation about the contact normal, degrees.
        #[arg(long, default_value_t = 0.0)]
        spin: f64,
        /// Tilt of the object's axis away from the contact normal, degrees (-90..90).
        #[arg(long, default_value_t = 0.0)]
        tilt: f64,
        /// Direction the object's outer end leans to, in the tangent plane: degrees from the
        /// meridian (away from the tip) towards increasing azimuth.
        #[arg(long = "tilt-towards", default_value_t = 0.0)]
        tilt_towards: f64,
        /// Press depth beyond the object's first touch of the undeformed finger, along the
        /// surface normal, mm.
        #[arg(long, required_unless_present_any = ["reference", "pose", "scene"], conflicts_with_all = ["pose", "scene"])]
        depth: Option<f64>,
        /// A rigid pose in the camera frame instead of --at/--depth: 16 numbers (row-major
        /// 4x4 matrix) or 7 (x y z qw qx qy qz), comma- or space-separated; the depth is
        /// what the pose implies (in the labels). The labels' `pose` loads back as is.
        #[arg(long, conflicts_with_all = ["azimuth", "spin", "tilt", "tilt_towards", "scene"])]
        pose: Option<String>,
        /// Several contacts in one frame: a JSON (.json) or TOML file listing `contacts`,
        /// each with the flags' names (object, at, depth, azimuth, spin, tilt, tilt_towards)
        /// or object and pose. The labels become a list plus the union mask.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Output PNG.
        #[arg(short = 'o', long = "output")]
        output: PathBuf,
        /// Ground truth as JSON (object, point, pixel, normal, depth_mm, region, mask...).
        #[arg(long)]
        labels: Option<PathBuf>,
        /// Indentation (mm) each pixel sees, as a float32 NumPy array (height x width).
        #[arg(long = "depth-map")]
        depth_map: Option<PathBuf>,
    },
    /// Find the contact in a tactile image and map it onto the finger.
    ///
    /// Example:
    ///   geltip localise --sensor paper --reference ref.png --method surface sphere.png
    #[command(verbatim_doc_comment)]
    Localise {
        #[arg(long)]
        sensor: String,
        /// The no-contact image of the same sensor.
        #[arg(long)]
        reference: PathBuf,
        /// paper (the paper's detector) or surface (geltip's: noise-relative threshold,
        /// averaging on the finger's surface).
        #[arg(long, default_value = "surface")]
        method: String,
        /// The image with the contact.
        image: PathBuf,
    },
    /// Run an experiment. `paper`: the paper's contact-localisation protocol (7 solids x 8
    /// taps), rendered, localised by every method, scored against the ground truth.
    ///
    /// Example:
    ///   geltip experiment paper --sensor paper --out out/experiment
    #[command(verbatim_doc_comment)]
    Experiment {
        /// Which experiment (only `paper` for now).
        #[arg(value_parser = ["paper"])]
        name: String,
        #[arg(long)]
        sensor: String,
        /// Directory for images, labels, taps.csv, tables.md and the chart.
        #[arg(long)]
        out: PathBuf,
        /// Press depth of every tap, mm.
        #[arg(long, default_value_t = 1.0)]
        depth: f64,
        /// Azimuth of the tapped side, degrees.
        #[arg(long, default_value_t = 0.0)]
        azimuth: f64,
    },
    /// Render a labelled synthetic dataset: random contacts anywhere the lens can see, drawn
    /// from (seed, sample index) alone; resumable, shardable.
    ///
    /// Examples:
    ///   geltip dataset --sensor paper --count 10000 --seed 1 --out data/train
    ///   geltip dataset --sensor paper --count 10000 --seed 1 --shard 0/4 --out data/s0
    ///   geltip dataset --merge data/train data/s0 data/s1 data/s2 data/s3
    #[command(verbatim_doc_comment)]
    Dataset {
        /// Preset name or path to a sensor TOML file.
        #[arg(long, required_unless_present = "merge")]
        sensor: Option<String>,
        /// Samples in the whole set (all shards).
        #[arg(long, required_unless_present = "merge")]
        count: Option<u64>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Directory of the set (or of this shard).
        #[arg(long, required_unless_present = "merge", conflicts_with = "merge")]
        out: Option<PathBuf>,
        /// Comma-separated built-in solids and/or mesh files (default: the seven solids).
        #[arg(long, value_delimiter = ',')]
        objects: Vec<String>,
        /// Press depths, mm, as min..max (default: 0.2 to the gel's thickness).
        #[arg(long = "depth-range")]
        depth_range: Option<String>,
        /// Render shard i of n (a contiguous block of indices) into --out.
        #[arg(long)]
        shard: Option<String>,
        /// Also write depth/<k>.npy: the indentation (mm) each pixel sees.
        #[arg(long = "depth-maps")]
        depth_maps: bool,
        /// Also write masks/<k>.png: 255 where the skin is pressed in.
        #[arg(long)]
        masks: bool,
        /// Sensor noise, std in 8-bit grey levels (default: the sensor's).
        #[arg(long)]
        noise: Option<f64>,
        /// Per-sample gain of each colour channel drawn from 1 ± this.
        #[arg(long = "light-jitter", default_value_t = 0.0)]
        light_jitter: f64,
        /// Per-sample gain of the tactile change drawn from 1 ± this.
        #[arg(long = "paint-jitter", default_value_t = 0.0)]
        paint_jitter: f64,
        /// A real sensor's empty frame (same size): images are it plus the rendered change.
        #[arg(long)]
        background: Option<PathBuf>,
        /// PNG compression: none, fast, default, best.
        #[arg(long, default_value = "fast")]
        png: String,
        /// Encoder threads (default: the cores available).
        #[arg(long)]
        jobs: Option<usize>,
        /// Render streams, each a renderer on a device of its own (default 3; 1..=4).
        #[arg(long)]
        streams: Option<usize>,
        /// Join shard directories into OUT: --merge OUT SHARD_DIR...
        #[arg(long, num_args = 2.., value_name = "DIR")]
        merge: Vec<PathBuf>,
    },
    /// Preview sensor designs before building them: what the camera sees, the resolution
    /// down the finger, a picture per design, and a lens sweep.
    ///
    /// Example:
    ///   geltip preview --sensors paper,webcam70,tube13,tube21 --out out/preview
    #[command(verbatim_doc_comment)]
    Preview {
        /// Comma-separated presets or sensor TOML files.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "paper,webcam70,tube13,tube21"
        )]
        sensors: Vec<String>,
        /// Directory for the pictures, charts and table.
        #[arg(long)]
        out: PathBuf,
        /// Lens sweep of the first design: equidistant fisheye fields of view <from>:<to>:<step>
        /// in degrees ("none" to skip).
        #[arg(long, default_value = "120:200:10")]
        sweep_fov: String,
        /// Skip the rendered pictures (geometry only, no GPU).
        #[arg(long)]
        no_pictures: bool,
    },
    /// Where the detectors fail: a sweep of contacts over everything the lens sees and press
    /// depths up to the shell thickness, with and without sensor noise.
    ///
    /// Example:
    ///   geltip stability --sensor paper --out out/stability
    #[command(verbatim_doc_comment)]
    Stability {
        #[arg(long)]
        sensor: String,
        #[arg(long)]
        out: PathBuf,
        /// Detectors to test (comma separated): paper, surface.
        #[arg(long, value_delimiter = ',', default_value = "paper,surface")]
        method: Vec<String>,
        /// Arc-length positions per azimuth, tip to lens edge (plus both sides of the junction).
        #[arg(long, default_value_t = 3)]
        positions: usize,
        /// Azimuths round the finger.
        #[arg(long, default_value_t = 2)]
        azimuths: usize,
        /// Press depths (mm, comma separated); default 0.01 .. the shell thickness.
        #[arg(long, value_delimiter = ',')]
        depths: Option<Vec<f64>>,
        /// Sensor noise of the noisy pass (8-bit grey levels); 0 skips it.
        #[arg(long, default_value_t = 2.0)]
        noise: f64,
    },
    /// Speed against accuracy for the renderer's knobs (heightfield texels, ray steps, image
    /// size, mesh SDF voxel size): frames/s, image error and localisation error, Pareto chart.
    ///
    /// Example:
    ///   geltip tradeoff --sensor paper --out out/tradeoff
    #[command(verbatim_doc_comment)]
    Tradeoff {
        #[arg(long)]
        sensor: String,
        #[arg(long)]
        out: PathBuf,
        /// Also every texels x steps pair (128..512 x 4..32), image scale 0.75, voxel 0.125 mm,
        /// and all eight contacts instead of four.
        #[arg(long)]
        full: bool,
        /// Speed rounds per configuration (the median is kept).
        #[arg(long, default_value_t = 3)]
        rounds: usize,
    },
    /// Write the seven built-in solids as OBJ meshes (the files in assets/objects/).
    Objects {
        /// Directory to write into.
        #[arg(long, default_value = "assets/objects")]
        out: PathBuf,
    },
}

fn write_frame(frame: &Frame, png: &PathBuf, depth_map: Option<&PathBuf>) -> Result<()> {
    output::write_png_rgb8(png, frame.width, frame.height, frame.to_rgb().as_raw())?;
    if let Some(path) = depth_map {
        output::write_npy_f32(path, frame.width, frame.height, &frame.indentation)?;
    }
    Ok(())
}

/// A progress callback for long jobs: a bar with rate and ETA on a terminal, a plain line
/// every few seconds otherwise (logs, batch jobs).
fn progress_reporter(unit: &'static str) -> Result<impl FnMut(dataset::Progress)> {
    let terminal = std::io::stderr().is_terminal();
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(&format!(
            "{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} {{per_sec}} ETA {{eta}}"
        ))?
        .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let mut last_line = start;
    Ok(move |p: dataset::Progress| {
        if terminal {
            bar.set_length(p.total);
            bar.set_position(p.done);
            if p.done == p.total && p.total > 0 {
                bar.finish_and_clear();
            }
        } else if last_line.elapsed().as_secs() >= 5 || (p.done == p.total && p.total > 0) {
            last_line = std::time::Instant::now();
            let rate = p.done as f64 / start.elapsed().as_secs_f64().max(1e-9);
            eprintln!("{}/{} {unit} ({rate:.1}/s)", p.done, p.total);
        }
    })
}

/// A progress bar on a terminal; plain periodic lines on stderr otherwise (indicatif hides
/// itself when stderr is not a terminal, so those lines come from the caller's messages).
fn progress_bar(unit: &str) -> Result<ProgressBar> {
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(&format!(
            "{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} {{msg}}"
        ))?
        .progress_chars("=> "),
    );
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        let unit = unit.to_string();
        let shown = bar.clone();
        std::thread::spawn(move || loop {
            std::thread::sleep(std::time::Duration::from_secs(5));
            if shown.is_finished() {
                break;
            }
            eprintln!(
                "{}/{} {unit}",
                shown.position(),
                shown.length().unwrap_or(0)
            );
        });
    }
    Ok(bar)
}

fn main() {
    // Frames are megabytes each, a new pair per frame: keep freed memory instead of
    // page-faulting it back in every frame (see geltip::memory).
    geltip::memory::keep_freed_memory();
    // Mesa's Vulkan loader prints "error: XDG_RUNTIME_DIR is invalid" on headless machines
    // while probing for a Wayland display geltip never uses; point it somewhere harmless.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Sensors => {
            for (name, _) in PRESETS {
                let s = Sensor::preset(name)?;
                println!("{name:10} {}", s.config.description);
            }
        }
        Command::Unproject { sensor, u, v } => {
            let sensor = Sensor::load(&sensor)?;
            let out = match sensor.unproject(DVec2::new(u, v)) {
                Some(sp) => json!({
                    "point": sp.point.to_array(),
                    "normal": sp.normal.to_array(),
                    "region": sp.region.name(),
                }),
                None => json!({ "region": "none" }),
            };
            println!("{out}");
        }
        Command::Project { sensor, x, y, z } => {
            let sensor = Sensor::load(&sensor)?;
            let out = match sensor.project(DVec3::new(x, y, z)) {
                Ok(px) => json!({ "pixel": px.to_array() }),
                Err(why) => json!({ "pixel": null, "reason": why.to_string() }),
            };
            println!("{out}");
        }
        Command::Render {
            sensor,
            reference,
            object,
            at,
            azimuth,
            spin,
            tilt,
            tilt_towards,
            depth,
            pose,
            scene,
            output: png,
            labels,
            depth_map,
        } => {
            let sensor = Sensor::load(&sensor)?;
            if reference {
                let mut renderer = Renderer::new(&sensor)?;
                write_frame(&renderer.render_empty()?, &png, depth_map.as_ref())?;
                println!("{}", json!({ "image": png, "reference": true }));
                return Ok(());
            }
            let presses = match (&scene, &pose) {
                (Some(path), _) => load_scene(path)?,
                (None, Some(pose)) => vec![Press {
                    object: Arc::new(Object::from_arg(&object.context("--object is required")?)?),
                    hold: parse_pose(pose)?,
                }],
                (None, None) => vec![Press {
                    object: Arc::new(Object::from_arg(&object.context("--object is required")?)?),
                    hold: Hold::Surface {
                        place: Place::parse(&at.context("--at is required")?)?,
                        azimuth_deg: azimuth,
                        spin_deg: spin,
                        tilt_deg: tilt,
                        tilt_towards_deg: tilt_towards,
                        depth_mm: depth.context("--depth is required")?,
                    },
                }],
            };
            // Refuse a bad pose before paying for the GPU's start-up.
            for p in &presses {
                p.pose(&sensor)?;
            }
            let mut renderer = Renderer::new(&sensor)?;
            let (frame, truths) = renderer.render_scene(&presses)?;
            write_frame(&frame, &png, depth_map.as_ref())?;
            let labels_json = if scene.is_some() {
                let (count, bbox) = frame.mask();
                json!({
                    "contacts": truths.iter().map(|t| t.to_json()).collect::<Vec<_>>(),
                    "mask_pixels": count,
                    "mask_bbox": bbox,
                    "over_pressed": truths.iter().any(|t| t.over_pressed),
                })
            } else {
                truths[0].to_json()
            };
            if let Some(path) = &labels {
                output::write_json(path, &labels_json)?;
            }
            if truths.iter().any(|t| t.over_pressed) {
                eprintln!("warning: the object pressed the gel against the rigid shell (depth beyond {} mm)", sensor.finger.shell_thickness);
            }
            println!("{labels_json}");
        }
        Command::Localise {
            sensor,
            reference,
            method,
            image,
        } => {
            let sensor = Sensor::load(&sensor)?;
            let method = Method::from_name(&method)?;
            let reference = load_frame(&sensor, &reference)?;
            let frame = load_frame(&sensor, &image)?;
            let detection = localise(&sensor, &reference, &frame, method)?;
            println!("{}", detection.to_json());
        }
        Command::Experiment {
            name: _,
            sensor,
            out,
            depth,
            azimuth,
        } => {
            let sensor = Sensor::load(&sensor)?;
            let protocol = Protocol {
                depth_mm: depth,
                azimuth_deg: azimuth,
                ..Protocol::default()
            };
            let total = (Solid::ALL.len() * experiment::POSITIONS.len()) as u64;
            let bar = ProgressBar::new(total).with_style(
                ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {pos}/{len} taps {msg}",
                )?
                .progress_chars("=> "),
            );
            let report = experiment::run(&sensor, &protocol, Some(&out), |name| {
                bar.set_message(name.to_string());
                bar.inc(1);
            })?;
            bar.finish_and_clear();
            println!("{}", report.tables_markdown());
            println!(
                "Wrote {}: images/, labels/, taps.csv, tables.md, errors_per_position.svg",
                out.display()
            );
        }
        Command::Dataset {
            sensor,
            count,
            seed,
            out,
            objects,
            depth_range,
            shard,
            depth_maps,
            masks,
            noise,
            light_jitter,
            paint_jitter,
            background,
            png,
            jobs,
            streams,
            merge,
        } => {
            let command: Vec<String> = std::env::args().collect();
            if let Some((out, shards)) = merge.split_first() {
                let n = dataset::merge(out, shards, &command)?;
                println!("{}", json!({ "merged": out, "samples": n }));
                return Ok(());
            }
            let (sensor_arg, count, out) = (
                sensor.context("--sensor is required")?,
                count.context("--count is required")?,
                out.context("--out is required")?,
            );
            let sensor = Sensor::load(&sensor_arg)?;
            let mut spec = dataset::Spec::new(&sensor_arg, sensor, count, seed);
            if !objects.is_empty() {
                spec.objects = objects;
            }
            if let Some(r) = depth_range {
                spec.depth_range = dataset::parse_depth_range(&r)?;
            }
            if let Some(s) = shard {
                spec.shard = dataset::Shard::parse(&s)?;
            }
            spec.depth_maps = depth_maps;
            spec.masks = masks;
            spec.noise = noise.unwrap_or(spec.sensor.config.render.noise);
            spec.light_jitter = light_jitter;
            spec.paint_jitter = paint_jitter;
            spec.background = background;
            spec.png = dataset::PngLevel::from_name(&png)?;
            spec.workers = jobs.unwrap_or(spec.workers);
            spec.streams = streams.unwrap_or(spec.streams);
            spec.command = command;
            let report = dataset::run(&spec, Some(&out), progress_reporter("samples")?)?;
            println!(
                "{}",
                json!({
                    "out": out,
                    "samples": report.shard_samples,
                    "kept": report.kept,
                    "rendered": report.rendered,
                    "samples_per_s": report.rendered as f64 / report.wall.as_secs_f64().max(1e-9),
                })
            );
        }
        Command::Preview {
            sensors,
            out,
            sweep_fov,
            no_pictures,
        } => {
            let designs = sensors
                .iter()
                .map(|s| Sensor::load(s.trim()))
                .collect::<geltip::Result<Vec<_>>>()?;
            let fovs = if sweep_fov == "none" {
                vec![]
            } else {
                preview::parse_range(&sweep_fov)?
            };
            let report = preview::run(&designs, &fovs, Some(&out), !no_pictures, |name| {
                eprintln!("previewed {name}");
            })?;
            println!("{}", preview::table_markdown(&report.designs));
            if let Some((_, best)) = report.best_sweep() {
                println!("Best lens of the sweep: {}", best.lens);
            }
            println!(
                "Wrote {}: preview.md, preview.csv, resolution.svg, lens_sweep.svg, <design>.png",
                out.display()
            );
        }
        Command::Stability {
            sensor,
            out,
            method,
            positions,
            azimuths,
            depths,
            noise,
        } => {
            let sensor = Sensor::load(&sensor)?;
            let mut sweep = stability::Sweep::default_for(&sensor);
            sweep.methods = method
                .iter()
                .map(|m| Method::from_name(m.trim()))
                .collect::<geltip::Result<_>>()?;
            sweep.positions = positions;
            sweep.azimuths = azimuths;
            if let Some(d) = depths {
                sweep.depths = d;
            }
            if !(noise.is_finite() && noise >= 0.0) {
                anyhow::bail!("--noise: must be a finite number >= 0, got {noise}");
            }
            sweep.noise = noise;
            let bar = progress_bar("contacts")?;
            let report = stability::run(&sensor, &sweep, Some(&out), |done, total| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            })?;
            bar.finish_and_clear();
            println!("{}", report.markdown());
            println!(
                "Wrote {}: stability.md, stability.csv, detection_rate.svg, error_map.svg",
                out.display()
            );
        }
        Command::Tradeoff {
            sensor,
            out,
            full,
            rounds,
        } => {
            let sensor = Sensor::load(&sensor)?;
            let configs = tradeoff::configurations(&sensor, full);
            let bar = progress_bar("configurations")?;
            bar.set_length((configs.len() + rounds) as u64);
            let contacts = tradeoff::contacts(full);
            let report =
                tradeoff::run(&sensor, &configs, &contacts, rounds, Some(&out), |label| {
                    bar.set_message(label.to_string());
                    bar.inc(1);
                })?;
            bar.finish_and_clear();
            println!("{}", report.markdown());
            println!(
                "Wrote {}: tradeoff.md, tradeoff.csv, tradeoff.svg",
                out.display()
            );
        }
        Command::Objects { out } => {
            geltip::object::write_builtin_objects(&out)?;
            println!("{}", json!({ "written": out }));
        }
    }
    Ok(())
}
