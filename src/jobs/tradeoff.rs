//! `geltip tradeoff`: the renderer's knobs that trade speed for accuracy, measured on both
//! axes in one run. Knobs: heightfield texels, ray steps, the elastomer kernels' tap spacing,
//! image size, and the SDF grid's voxel size for meshes. Each configuration renders the same eight contacts (one per tap
//! position of the paper, each with another of the seven solids) and is scored by
//! - speed: frames/s, one contact per submit, the median of a few rounds;
//! - image error: mean absolute 8-bit difference against a high-resolution reference
//!   ([`REFERENCE_TEXELS`] texels, [`REFERENCE_STEPS`] ray steps, taps every
//!   [`REFERENCE_TAP_SPACING`] sigma, analytic solids) of the same size, over the pixels
//!   either render changes;
//! - localisation error: the surface detector's mean error (mm) against the exact contact
//!   points, and how many contacts it missed.
//!
//! A configuration is on the Pareto front when no other is at least as fast and at least as
//! accurate, and better in one; differences within the noise of the measurement (see
//! [`SPEED_TIE`]) are ties, not evidence. Three fronts: fps against the image error, against
//! the localisation error, and against both at once (the joint front).

use crate::error::{GeltipError, Result};
use crate::jobs::experiment::{self, Protocol};
use crate::localise::{Localiser, Method};
use crate::object::{Object, SdfGrid, Solid, MESH_PAD_MM, MESH_VOXEL_MM};
use crate::output;
use crate::render::gpu::Renderer;
use crate::render::{Frame, GroundTruth, Press};
use crate::sensor::{Noise, Sensor};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

mod report;

/// One setting of the knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knobs {
    pub texels: u32,
    pub ray_steps: u32,
    /// The elastomer kernels' tap spacing, in narrow-blend standard deviations.
    pub tap_spacing: f64,
    /// Image scale against the sensor's own size (1 = as configured, 0.5 = half each side).
    pub image_scale: f64,
    /// `None`: the analytic solids; `Some(v)`: the solids as meshes baked on voxels of v mm.
    pub voxel_mm: Option<f64>,
}

impl Knobs {
    /// The sensor's own render settings, the solids analytic.
    pub fn default_for(sensor: &Sensor) -> Knobs {
        Knobs {
            texels: sensor.config.render.heightfield_texels,
            ray_steps: sensor.config.render.ray_steps,
            tap_spacing: sensor.config.render.blend_tap_spacing,
            image_scale: 1.0,
            voxel_mm: None,
        }
    }

    /// "256 texels, 8 steps, taps 1 sigma, 640x480, mesh 0.25 mm".
    pub fn label(&self, sensor: &Sensor) -> String {
        let (w, h) = scaled_size(sensor, self.image_scale);
        let mut s = format!(
            "{} texels, {} steps, taps {} sigma, {w}x{h}",
            self.texels, self.ray_steps, self.tap_spacing
        );
        if let Some(v) = self.voxel_mm {
            let _ = write!(s, ", mesh {v} mm");
        }
        s
    }
}

fn scaled_size(sensor: &Sensor, scale: f64) -> (u32, u32) {
    (
        ((sensor.width as f64 * scale).round() as u32).max(1),
        ((sensor.height as f64 * scale).round() as u32).max(1),
    )
}

/// The configurations a run measures: the default and each knob turned down and up on its
/// own (`full`: every texels x steps pair as well).
pub fn configurations(sensor: &Sensor, full: bool) -> Vec<Knobs> {
    let d = Knobs::default_for(sensor);
    let mut out = vec![d];
    let mut push = |k: Knobs| {
        if !out.contains(&k) {
            out.push(k);
        }
    };
    for texels in [128, 512] {
        push(Knobs { texels, ..d });
    }
    for ray_steps in [4, 16] {
        push(Knobs { ray_steps, ..d });
    }
    for tap_spacing in [0.5, 2.0] {
        push(Knobs { tap_spacing, ..d });
    }
    push(Knobs {
        image_scale: 0.5,
        ..d
    });
    for v in [0.5, MESH_VOXEL_MM] {
        push(Knobs {
            voxel_mm: Some(v),
            ..d
        });
    }
    if full {
        for texels in [128, 192, 256, 384, 512] {
            for ray_steps in [4, 8, 16, 32] {
                push(Knobs {
                    texels,
                    ray_steps,
                    ..d
                });
            }
        }
        push(Knobs {
            image_scale: 0.75,
            ..d
        });
        push(Knobs {
            voxel_mm: Some(0.125),
            ..d
        });
    }
    out
}

/// What one configuration measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub knobs: Knobs,
    pub label: String,
    pub is_default: bool,
    pub fps: f64,
    /// Mean absolute 8-bit difference against the reference.
    pub image_error: f64,
    /// Surface detector's mean error (mm) over the detected contacts.
    pub localisation_error_mm: Option<f64>,
    pub missed: usize,
    /// Contacts rendered.
    pub contacts: usize,
    pub on_front_image: bool,
    pub on_front_localisation: bool,
    /// On the front of fps, image error and localisation error taken together.
    pub on_front_joint: bool,
}

/// Marks the Pareto front of (speed, error) points, speed to maximise and error to
/// minimise: `true` where no other point has speed >= and error <=, one strictly. Points
/// with a non-finite coordinate are never on the front and dominate nothing.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    let points: Vec<(f64, Vec<f64>)> = points.iter().map(|&(s, e)| (s, vec![e])).collect();
    pareto_front_within(&points, &Tolerance::EXACT)
}

/// Differences a front reads as ties: fps within `speed` (relative), errors within
/// `errors[i]` (absolute, one per error axis, the last repeated).
#[derive(Debug, Clone, PartialEq)]
pub struct Tolerance {
    pub speed: f64,
    pub errors: Vec<f64>,
}

impl Tolerance {
    pub const EXACT: Tolerance = Tolerance {
        speed: 0.0,
        errors: Vec::new(),
    };
}

/// Ties on a shared machine: fps rounds of one configuration spread by a few percent, and
/// four contacts' mean errors move by about a hundredth when nothing that matters changed.
pub const SPEED_TIE: f64 = 0.05;
/// Image errors closer than this (8-bit levels) are ties.
pub const IMAGE_TIE: f64 = 0.02;
/// Localisation errors closer than this (mm) are ties.
pub const LOCALISATION_TIE_MM: f64 = 0.01;

/// The Pareto front of (speed, errors...) points, speed to maximise and every error to
/// minimise: `true` where no other point is at least as good on every axis (within the
/// tolerance) and better beyond the tolerance on one. With [`Tolerance::EXACT`] this is the
/// usual front. Points with a non-finite coordinate are never on it and dominate nothing.
pub fn pareto_front_within(points: &[(f64, Vec<f64>)], tol: &Tolerance) -> Vec<bool> {
    let ok = |p: &(f64, Vec<f64>)| p.0.is_finite() && p.1.iter().all(|e| e.is_finite());
    let te = |i: usize| {
        tol.errors
            .get(i)
            .or(tol.errors.last())
            .copied()
            .unwrap_or(0.0)
    };
    let dominates = |q: &(f64, Vec<f64>), p: &(f64, Vec<f64>)| {
        let as_good = q.0 >= p.0 * (1.0 - tol.speed)
            && q.1
                .iter()
                .zip(&p.1)
                .enumerate()
                .all(|(i, (a, b))| *a <= b + te(i));
        let better = q.0 > p.0 * (1.0 + tol.speed)
            || q.1
                .iter()
                .zip(&p.1)
                .enumerate()
                .any(|(i, (a, b))| *a < b - te(i));
        as_good && better
    };
    points
        .iter()
        .map(|p| ok(p) && !points.iter().any(|q| ok(q) && dominates(q, p)))
        .collect()
}

/// The contacts: one per tap position of the paper, each with another solid (all eight), or
/// every other one of them (four: tip, 45°, junction, 10 mm down) for a quick run.
pub fn contacts(all: bool) -> Vec<Press> {
    (0..experiment::POSITIONS.len())
        .filter(|i| all || i % 2 == 0)
        .map(|i| {
            experiment::taps(Solid::ALL[i % Solid::ALL.len()], &Protocol::default())[i].clone()
        })
        .collect()
}

/// A variant of `sensor` with the knobs' render settings and image size (the lens scaled
/// with the image so it sees the same finger).
pub fn sensor_for(sensor: &Sensor, knobs: &Knobs) -> Result<Sensor> {
    let mut c = sensor.config.clone();
    c.render.heightfield_texels = knobs.texels;
    c.render.ray_steps = knobs.ray_steps;
    c.render.blend_tap_spacing = knobs.tap_spacing;
    c.render.noise = Noise::NONE;
    if knobs.image_scale != 1.0 {
        if !(knobs.image_scale.is_finite() && knobs.image_scale > 0.0) {
            return Err(GeltipError::input(
                "image scale",
                format!("must be a positive number, got {}", knobs.image_scale),
            ));
        }
        let (w, h) = scaled_size(sensor, knobs.image_scale);
        let sx = w as f64 / sensor.width as f64;
        c.image.width = w;
        c.image.height = h;
        c.lens.focal_px *= sx;
        c.lens.cx *= sx;
        c.lens.cy *= h as f64 / sensor.height as f64;
    }
    Sensor::from_config(format!("{} [{}]", sensor.name, knobs.label(sensor)), c)
}

/// The contacts with their solids baked into meshes on voxels of `voxel_mm`.
fn as_meshes(list: &[Press], voxel_mm: f64) -> Result<Vec<Press>> {
    let mut baked: HashMap<String, Arc<Object>> = HashMap::new();
    list.iter()
        .map(|c| {
            let solid = c.object.solid().ok_or_else(|| {
                GeltipError::input("tradeoff", "the contacts must be built-in solids")
            })?;
            let object = match baked.get(solid.name()) {
                Some(o) => o.clone(),
                None => {
                    let mesh = solid.mesh().placed_for_contact();
                    let grid = SdfGrid::bake_padded(&mesh, voxel_mm, MESH_PAD_MM)?;
                    let o = Arc::new(Object::Mesh {
                        name: solid.name().to_string(),
                        mesh,
                        grid,
                    });
                    baked.insert(solid.name().to_string(), o.clone());
                    o
                }
            };
            Ok(Press {
                object,
                hold: c.hold,
            })
        })
        .collect()
}

/// Mean absolute 8-bit channel difference between `a` and `b` over the pixels where either
/// differs from its reference.
pub fn image_error(a: &Frame, a_ref: &Frame, b: &Frame, b_ref: &Frame) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..(a.width * a.height) as usize {
        let changed = (0..3).any(|c| {
            a.rgba[i * 4 + c] != a_ref.rgba[i * 4 + c] || b.rgba[i * 4 + c] != b_ref.rgba[i * 4 + c]
        });
        if changed {
            for c in 0..3 {
                sum += a.rgba[i * 4 + c].abs_diff(b.rgba[i * 4 + c]) as f64;
            }
            n += 3;
        }
    }
    sum / n.max(1) as f64
}

/// Heightfield texels of the high-resolution reference.
pub const REFERENCE_TEXELS: u32 = 768;
/// Ray steps of the high-resolution reference.
pub const REFERENCE_STEPS: u32 = 32;
/// Tap spacing of the high-resolution reference (narrow-blend standard deviations; its
/// texels are finer still, so this is what it samples).
pub const REFERENCE_TAP_SPACING: f64 = 0.25;

/// The full report.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub sensor: String,
    pub adapter: String,
    pub rows: Vec<Row>,
}

/// Measures every configuration: accuracy first, then `rounds` speed rounds that each time
/// every configuration in turn (the median is kept). `progress` gets each configuration's
/// label when its accuracy is measured, then "speed round k/n" after each round
/// (`configs.len() + rounds` calls in all).
pub fn run(
    sensor: &Sensor,
    configs: &[Knobs],
    list: &[Press],
    rounds: usize,
    out: Option<&Path>,
    mut progress: impl FnMut(&str),
) -> Result<Report> {
    if configs.is_empty() || rounds == 0 || list.is_empty() {
        return Err(GeltipError::input(
            "tradeoff",
            "needs at least one configuration, one contact and one speed round",
        ));
    }
    // High-resolution references, one per image size.
    let mut references: Vec<(u32, u32, Frame, Vec<Frame>)> = Vec::new();
    let mut adapter = String::new();
    let mut rows = Vec::new();
    // Each configuration's renderer and contacts, kept for the speed rounds.
    let mut timed: Vec<(Renderer, Vec<Press>)> = Vec::new();
    let default = Knobs::default_for(sensor);
    for knobs in configs {
        let t0 = Instant::now();
        let variant = sensor_for(sensor, knobs)?;
        let (w, h) = (variant.width, variant.height);
        if !references.iter().any(|r| r.0 == w && r.1 == h) {
            let (name, empty, frames) = render_references(sensor, knobs, list)?;
            adapter = name;
            references.push((w, h, empty, frames));
        }
        let (_, _, ref_empty, ref_frames) = references
            .iter()
            .find(|r| r.0 == w && r.1 == h)
            .expect("reference rendered above");
        log::info!(
            "{}: reference ready after {:.1} s",
            knobs.label(sensor),
            t0.elapsed().as_secs_f64()
        );
        let (renderer, scene, accuracy) =
            measure_accuracy(&variant, knobs, list, ref_empty, ref_frames)?;
        log::info!(
            "{}: accuracy done after {:.1} s",
            knobs.label(sensor),
            t0.elapsed().as_secs_f64()
        );
        let label = knobs.label(sensor);
        timed.push((renderer, scene));
        rows.push(Row {
            knobs: *knobs,
            label: label.clone(),
            is_default: *knobs == default,
            fps: f64::NAN,
            image_error: accuracy.image_error,
            localisation_error_mm: accuracy.localisation_error_mm,
            missed: accuracy.missed,
            contacts: accuracy.contacts,
            on_front_image: false,
            on_front_localisation: false,
            on_front_joint: false,
        });
        progress(&label);
    }
    time_speed_rounds(&mut timed, &mut rows, rounds, &mut progress)?;
    drop(timed);
    mark_fronts(&mut rows);
    let report = Report {
        sensor: sensor.name.clone(),
        adapter,
        rows,
    };
    if let Some(dir) = out {
        output::write_atomic(dir.join("tradeoff.md"), report.markdown().as_bytes())?;
        output::write_atomic(dir.join("tradeoff.csv"), report.csv().as_bytes())?;
        output::write_atomic(dir.join("tradeoff.svg"), report.chart()?.as_bytes())?;
    }
    Ok(report)
}

/// The high-resolution references at `knobs`' image size: the adapter's name, the empty
/// finger and each contact of `list`.
fn render_references(
    sensor: &Sensor,
    knobs: &Knobs,
    list: &[Press],
) -> Result<(String, Frame, Vec<Frame>)> {
    let best = sensor_for(
        sensor,
        &Knobs {
            texels: REFERENCE_TEXELS,
            ray_steps: REFERENCE_STEPS,
            tap_spacing: REFERENCE_TAP_SPACING,
            voxel_mm: None,
            ..*knobs
        },
    )?;
    let mut r = Renderer::new(&best)?;
    let adapter = r.adapter().name.clone();
    // One contact per submit: a batch of high-resolution renders can outlast the GPU
    // watchdog on a software rasteriser.
    let frames = list
        .iter()
        .map(|c| r.render(c).map(|(f, _)| f))
        .collect::<Result<Vec<_>>>()?;
    Ok((adapter, r.reference().clone(), frames))
}

/// One configuration's accuracy over its contacts.
struct Accuracy {
    image_error: f64,
    localisation_error_mm: Option<f64>,
    missed: usize,
    contacts: usize,
}

/// Renders `list` (as meshes when `knobs` says so) on `variant` and scores it against the
/// references; returns the renderer and the contacts as rendered, for the speed rounds.
fn measure_accuracy(
    variant: &Sensor,
    knobs: &Knobs,
    list: &[Press],
    ref_empty: &Frame,
    ref_frames: &[Frame],
) -> Result<(Renderer, Vec<Press>, Accuracy)> {
    let scene = match knobs.voxel_mm {
        Some(v) => as_meshes(list, v)?,
        None => list.to_vec(),
    };
    let mut renderer = Renderer::new(variant)?;
    let localiser = Localiser::new(variant);
    let reference_rgb = renderer.reference().to_rgb();
    let (mut img_err, mut loc_sum, mut found) = (0.0, 0.0, 0usize);
    for (c, t) in scene.iter().zip(ref_frames) {
        let (f, truth): (Frame, GroundTruth) = renderer.render(c)?;
        img_err += image_error(&f, renderer.reference(), t, ref_empty) / scene.len() as f64;
        let d = localiser.localise(&reference_rgb, &f.to_rgb(), Method::Surface)?;
        if let (true, Some(p)) = (d.detected, d.point) {
            loc_sum += (p - truth.point).length();
            found += 1;
        }
    }
    let accuracy = Accuracy {
        image_error: img_err,
        localisation_error_mm: (found > 0).then(|| loc_sum / found as f64),
        missed: scene.len() - found,
        contacts: scene.len(),
    };
    Ok((renderer, scene, accuracy))
}

/// Sets each row's fps: the median over `rounds` speed rounds. The rounds interleave the
/// configurations (each round times every one in turn), so that a load which comes and goes
/// on a shared machine weighs on all of them alike.
fn time_speed_rounds(
    timed: &mut [(Renderer, Vec<Press>)],
    rows: &mut [Row],
    rounds: usize,
    progress: &mut impl FnMut(&str),
) -> Result<()> {
    let mut rates = vec![Vec::with_capacity(rounds); rows.len()];
    for round in 0..rounds {
        for ((renderer, scene), rates) in timed.iter_mut().zip(&mut rates) {
            let start = Instant::now();
            for c in scene.iter() {
                renderer.render(c)?;
            }
            rates.push(scene.len() as f64 / start.elapsed().as_secs_f64());
        }
        progress(&format!("speed round {}/{rounds}", round + 1));
    }
    for (row, mut rates) in rows.iter_mut().zip(rates) {
        rates.sort_by(f64::total_cmp);
        row.fps = rates[rates.len() / 2];
    }
    Ok(())
}

/// Marks the rows on each of the three Pareto fronts. A configuration that misses contacts
/// is scored as if each miss were 10 mm off.
fn mark_fronts(rows: &mut [Row]) {
    let front = |errors: &dyn Fn(&Row) -> Vec<f64>, ties: Vec<f64>| {
        let points: Vec<(f64, Vec<f64>)> = rows.iter().map(|r| (r.fps, errors(r))).collect();
        pareto_front_within(
            &points,
            &Tolerance {
                speed: SPEED_TIE,
                errors: ties,
            },
        )
    };
    let front_img = front(&|r| vec![r.image_error], vec![IMAGE_TIE]);
    let front_loc = front(&|r| vec![loc_score(r)], vec![LOCALISATION_TIE_MM]);
    let front_joint = front(
        &|r| vec![r.image_error, loc_score(r)],
        vec![IMAGE_TIE, LOCALISATION_TIE_MM],
    );
    for (i, r) in rows.iter_mut().enumerate() {
        r.on_front_image = front_img[i];
        r.on_front_localisation = front_loc[i];
        r.on_front_joint = front_joint[i];
    }
}

/// Localisation score of a row: mean error over all contacts, a miss counting 10 mm.
pub fn loc_score(r: &Row) -> f64 {
    let detected = r.contacts.saturating_sub(r.missed);
    let sum = r.localisation_error_mm.unwrap_or(0.0) * detected as f64 + 10.0 * r.missed as f64;
    sum / r.contacts.max(1) as f64
}
