//! `geltip stability`: where the detectors fail. A sweep of sphere contacts over what the
//! lens sees (arc lengths from the tip to the lens edge, both sides of the junction, several
//! azimuths) and press depths from 0.01 mm to the shell thickness, localised by each
//! detector, with and without sensor noise. Also: contacts the lens cannot see (they must
//! come out "not visible" when nothing of them reaches the image), false detections on
//! empty noisy frames, and two simultaneous contacts.

use crate::error::{GeltipError, Result};
use crate::evaluate::{
    self, Detector, Evaluation, Found, MethodDetector, Options, Scored, Source, Suite, SuiteJob,
    SuitePart, Target,
};
use crate::localise::Method;
use crate::object::{Object, Solid};
use crate::render::{GroundTruth, Place, Press};
use crate::sensor::{Noise, Sensor};
use crate::view;

pub use crate::evaluate::{region_of, REGIONS};

mod report;
use std::path::Path;
use std::sync::Arc;

/// The sweep's size.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Arc-length positions, evenly spaced from the tip to 1.5 mm above the lens edge (the
    /// junction's two sides, 1 mm either way, are always added).
    pub positions: usize,
    /// Azimuths, evenly spaced round the finger.
    pub azimuths: usize,
    /// Press depths (mm); the default is 0.01 mm .. the shell thickness.
    pub depths: Vec<f64>,
    /// Sensor noise (8-bit grey levels) of the noisy pass; 0 skips it.
    pub noise: f64,
    /// How far (mm of arc) below the lens edge the hidden contacts are placed (capped at
    /// the finger's end).
    pub hidden_offset_mm: f64,
    /// Empty noisy frames checked for false detections.
    pub empty_frames: usize,
    pub methods: Vec<Method>,
}

impl Sweep {
    /// The default sweep for `sensor`: well under a minute on a 2-core lavapipe host.
    pub fn default_for(sensor: &Sensor) -> Sweep {
        let t = sensor.finger.shell_thickness;
        Sweep {
            positions: 3,
            azimuths: 2,
            depths: vec![0.01, 0.03, 0.1, 0.3, t],
            // A camera that blurs would blur the renderer's noise: no noisy pass.
            noise: if sensor.config.camera.blurs() {
                0.0
            } else {
                2.0
            },
            hidden_offset_mm: 6.0,
            empty_frames: 10,
            methods: Method::ALL.to_vec(),
        }
    }
}

/// One localisation of one contact.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    pub noisy: bool,
    pub method: Method,
    pub s: f64,
    pub azimuth_deg: f64,
    pub depth: f64,
    pub region: &'static str,
    /// The contact point's pixel is in the image.
    pub visible: bool,
    /// Pixels pressed in by more than 0.01 mm.
    pub mask_pixels: u64,
    /// Whether the noise-free render of this contact differs from the empty finger at all
    /// (the gel's bulge and shading reach further than the pressed pixels).
    pub image_changed: bool,
    pub detected: bool,
    pub error_mm: Option<f64>,
}

/// Everything the sweep measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub sensor: String,
    pub sweep: Sweep,
    pub trials: Vec<Trial>,
    /// Non-finite numbers met in detections (the job errors before returning if any).
    pub non_finite: usize,
    /// Per (noisy, method): detections on the empty frames.
    pub false_detections: Vec<(bool, Method, usize, usize)>,
    /// Per method: (pairs, pairs where something was detected, mean distance to the nearer
    /// of the two contacts).
    pub two_contacts: TwoContactTrials,
}

/// Per method: pairs, pairs where something was detected, mean distance (mm) to the
/// nearer of the two contacts.
type TwoContactTrials = Vec<(Method, usize, usize, Option<f64>)>;

fn sphere(s: f64, azimuth_deg: f64, depth: f64) -> Press {
    let object = Arc::new(Object::Solid(Solid::Sphere));
    Press::at(object, Place::ArcLength(s), azimuth_deg, depth)
}

/// The visible contact positions: (s, azimuth) pairs.
pub fn positions(sensor: &Sensor, sweep: &Sweep) -> Result<Vec<(f64, f64)>> {
    if sweep.positions < 2 || sweep.azimuths < 1 || sweep.depths.is_empty() {
        return Err(GeltipError::input(
            "stability sweep",
            "needs at least 2 positions, 1 azimuth and 1 depth",
        ));
    }
    let t = sensor.finger.shell_thickness;
    if let Some(d) = sweep
        .depths
        .iter()
        .find(|d| !d.is_finite() || **d <= 0.0 || **d > t)
    {
        return Err(GeltipError::option(
            "depths",
            format!("every depth must be in (0, {t}] mm (the shell thickness), got {d}"),
        ));
    }
    let mut out = Vec::new();
    for k in 0..sweep.azimuths {
        let az = 360.0 * k as f64 / sweep.azimuths as f64;
        let edge = view::visible_extent(sensor, az.to_radians());
        let last = (edge - 1.5).max(0.0);
        let sj = sensor.finger.junction_s();
        let mut ss: Vec<f64> = (0..sweep.positions)
            .map(|i| last * i as f64 / (sweep.positions - 1) as f64)
            .collect();
        for s in [sj - 1.0, sj + 1.0] {
            if s < last {
                ss.push(s);
            }
        }
        ss.sort_by(f64::total_cmp);
        out.extend(ss.into_iter().map(|s| (s, az)));
    }
    Ok(out)
}

/// Whether a detection holds only finite numbers.
fn finite(f: &Found) -> bool {
    f.pixel.is_none_or(|p| p.is_finite())
        && f.point.is_none_or(|p| p.is_finite())
        && f.confidence.is_finite()
}

/// What a frame of the sweep's suite is for.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    /// A contact of the sweep (visible or not).
    Contact { noisy: bool },
    /// An empty frame, for false detections.
    Empty { noisy: bool },
    /// Two contacts at once.
    Pair,
}

/// The sphere contacts the lens cannot see: well below the visible edge of each azimuth
/// (when the finger goes on that far), at full depth.
fn hidden_contacts(sensor: &Sensor, sweep: &Sweep) -> Vec<Press> {
    let mut hidden = Vec::new();
    for k in 0..sweep.azimuths {
        let az = 360.0 * k as f64 / sweep.azimuths as f64;
        let edge = view::visible_extent(sensor, az.to_radians());
        let s = (edge + sweep.hidden_offset_mm).min(view::finger_length(sensor));
        if s > edge + 0.5 {
            hidden.push(sphere(s, az, sensor.finger.shell_thickness));
        }
    }
    hidden
}

/// The sweep as a suite, with each frame's role: per pass (without noise, then with), the
/// contacts (every depth at every place, then the hidden ones) in batches of 16, the empty
/// frames, and (without noise) the pairs. Contacts are scored against the pressed point.
fn plan(sensor: &Sensor, sweep: &Sweep) -> Result<(Suite, Vec<Role>)> {
    if sweep.methods.is_empty() {
        return Err(GeltipError::option("methods", "no methods to test"));
    }
    let places = positions(sensor, sweep)?;
    let hidden = hidden_contacts(sensor, sweep);
    if sweep.noise > 0.0 && sensor.config.camera.blurs() {
        return Err(GeltipError::option_value(
            "noise",
            sweep.noise,
            format!(
                "the sensor's camera blurs (camera.blur_px {}), which would blur the noisy \
                 pass's noise; give --noise 0 to sweep without it",
                sensor.config.camera.blur_px
            ),
        ));
    }
    let passes: &[bool] = if sweep.noise > 0.0 {
        &[false, true]
    } else {
        &[false]
    };
    let mut contacts: Vec<Press> = Vec::new();
    for &depth in &sweep.depths {
        for &(s, az) in &places {
            contacts.push(sphere(s, az, depth));
        }
    }
    contacts.extend(hidden.iter().cloned());
    let mut parts = Vec::new();
    let mut roles = Vec::new();
    for &noisy in passes {
        let mut config = sensor.config.clone();
        config.render.noise = Noise::from(if noisy { sweep.noise } else { 0.0 });
        let name = if noisy {
            format!("{} + noise {}", sensor.name, sweep.noise)
        } else {
            sensor.name.clone()
        };
        let variant = Sensor::from_config(name, config)?;
        let mut jobs: Vec<SuiteJob> = contacts
            .chunks(16)
            .map(|c| SuiteJob::Batch(c.to_vec()))
            .collect();
        roles.extend(std::iter::repeat_n(Role::Contact { noisy }, contacts.len()));
        jobs.extend(std::iter::repeat_n(SuiteJob::Empty, sweep.empty_frames));
        roles.extend(std::iter::repeat_n(
            Role::Empty { noisy },
            sweep.empty_frames,
        ));
        if !noisy {
            for pair in pairs(&variant, &contacts, &places, sweep)? {
                jobs.push(SuiteJob::Scene(pair.to_vec()));
                roles.push(Role::Pair);
            }
        }
        parts.push(SuitePart {
            sensor: variant,
            target: Target::ContactPoint,
            jobs,
        });
    }
    let suite = Suite {
        name: "stability".into(),
        parts,
    };
    Ok((suite, roles))
}

/// The sweep as a suite of frames (see [`run`]).
pub fn suite(sensor: &Sensor, sweep: &Sweep) -> Result<Suite> {
    Ok(plan(sensor, sweep)?.0)
}

/// Pairs of the sweep's visible contacts at its deepest depth (same arc length, azimuths
/// half a turn apart where the sweep has them, else consecutive ones), to render together.
fn pairs(
    sensor: &Sensor,
    contacts: &[Press],
    places: &[(f64, f64)],
    sweep: &Sweep,
) -> Result<Vec<[Press; 2]>> {
    let pair_depth = sweep.depths.iter().cloned().fold(0.0, f64::max);
    let mut chosen = Vec::new();
    for c in contacts {
        let pose = c.pose(sensor)?;
        let visible = sensor.project(pose.point).is_ok();
        if (pose.depth_mm - pair_depth).abs() < 1e-9 && visible && chosen.len() < 2 * places.len() {
            chosen.push(c.clone());
        }
    }
    let n = chosen.len();
    let half = if sweep.azimuths >= 2 && n >= 2 {
        n / 2
    } else {
        1
    };
    Ok((0..n.saturating_sub(half))
        .map(|i| [chosen[i].clone(), chosen[i + half].clone()])
        .collect())
}

/// Runs the sweep through [`crate::evaluate`] (any distance matching: one contact, one
/// answer). `progress(done, total)` is called after each frame.
pub fn run(
    sensor: &Sensor,
    sweep: &Sweep,
    out: Option<&Path>,
    mut progress: impl FnMut(usize, usize),
) -> Result<Report> {
    let (suite, roles) = plan(sensor, sweep)?;
    let total = roles.len();
    let source = Source::Suite(suite);
    let mut methods: Vec<MethodDetector> = sweep
        .methods
        .iter()
        .map(|&m| MethodDetector::new(m))
        .collect();
    let mut detectors: Vec<&mut dyn Detector> =
        methods.iter_mut().map(|d| d as &mut dyn Detector).collect();
    let options = Options {
        gate_mm: None,
        work_dir: None,
    };
    let mut frames: Vec<(Option<GroundTruth>, bool)> = Vec::with_capacity(total);
    let evaluations = evaluate::evaluate(&source, &mut detectors, &options, |sample, _| {
        let truth = sample.rendered.as_ref().and_then(|t| t.first()).cloned();
        // In the noisy pass this is settled from the noise-free twin below.
        let changed = sample.image.rgb(&sample.sensor)? != sample.reference.rgb(&sample.sensor)?;
        frames.push((truth, changed));
        progress(frames.len(), total);
        Ok(())
    })?;
    let report = Report {
        sensor: sensor.name.clone(),
        sweep: sweep.clone(),
        trials: trials(sensor, sweep, &roles, &frames, &evaluations),
        non_finite: evaluations
            .iter()
            .flat_map(|e| e.frames.iter().flat_map(|f| f.found.iter()))
            .filter(|f| !finite(f))
            .count(),
        false_detections: false_detections(sweep, &roles, &evaluations),
        two_contacts: two_contact_trials(sweep, &roles, &evaluations),
    };
    report.check(sensor)?;
    if let Some(dir) = out {
        report.write(dir, sensor)?;
    }
    Ok(report)
}

/// Every contact's trial, for every method.
fn trials(
    sensor: &Sensor,
    sweep: &Sweep,
    roles: &[Role],
    frames: &[(Option<GroundTruth>, bool)],
    evaluations: &[Evaluation],
) -> Vec<Trial> {
    let mut trials = Vec::new();
    for (k, role) in roles.iter().enumerate() {
        if let (Role::Contact { noisy }, (Some(truth), changed)) = (role, &frames[k]) {
            for (e, &method) in evaluations.iter().zip(&sweep.methods) {
                trials.push(trial(sensor, *noisy, method, truth, *changed, &e.frames[k]));
            }
        }
    }
    settle_noisy_traces(&mut trials);
    trials
}

/// The frames of `role`, as `e` scored them.
fn frames_of<'a>(roles: &[Role], e: &'a Evaluation, role: Role) -> Vec<&'a Scored> {
    roles
        .iter()
        .zip(&e.frames)
        .filter(|(r, _)| **r == role)
        .map(|(_, f)| f)
        .collect()
}

/// Per pass and method: the empty frames where something was detected, of how many.
fn false_detections(
    sweep: &Sweep,
    roles: &[Role],
    evaluations: &[Evaluation],
) -> Vec<(bool, Method, usize, usize)> {
    let mut out = Vec::new();
    for noisy in [false, true] {
        if noisy && !roles.contains(&Role::Contact { noisy: true }) {
            continue;
        }
        for (e, &method) in evaluations.iter().zip(&sweep.methods) {
            let empties = frames_of(roles, e, Role::Empty { noisy });
            let hits = empties.iter().filter(|f| !f.found.is_empty()).count();
            out.push((noisy, method, hits, empties.len()));
        }
    }
    out
}

/// Per method: the pairs, those where something was matched, and the mean distance to the
/// contact it matched (the nearer, there being one answer).
fn two_contact_trials(
    sweep: &Sweep,
    roles: &[Role],
    evaluations: &[Evaluation],
) -> TwoContactTrials {
    evaluations
        .iter()
        .zip(&sweep.methods)
        .map(|(e, &method)| {
            let pairs = frames_of(roles, e, Role::Pair);
            let errors: Vec<f64> = pairs
                .iter()
                .filter_map(|f| f.score.matches.first().map(|m| m.error_mm))
                .collect();
            let mean =
                (!errors.is_empty()).then(|| errors.iter().sum::<f64>() / errors.len() as f64);
            (method, pairs.len(), errors.len(), mean)
        })
        .collect()
}

/// One contact's trial for one method.
fn trial(
    sensor: &Sensor,
    noisy: bool,
    method: Method,
    truth: &GroundTruth,
    image_changed: bool,
    frame: &Scored,
) -> Trial {
    let first = frame.found.first();
    // A contact the lens cannot see is never matched; its trial still says how far off a
    // detection of it landed.
    let error_mm = match frame.score.matches.first() {
        Some(m) => Some(m.error_mm),
        None => first
            .filter(|_| !frame.truth.contacts.first().is_some_and(|c| c.visible))
            .and_then(|f| f.point)
            .map(|p| (p - truth.point).length()),
    };
    Trial {
        noisy,
        method,
        s: truth.s_mm,
        azimuth_deg: truth.azimuth_deg,
        depth: truth.depth_mm,
        region: region_of(sensor, truth.s_mm),
        visible: truth.pixel.is_ok(),
        mask_pixels: truth.mask_pixels,
        image_changed,
        detected: first.is_some(),
        error_mm,
    }
}

/// The noisy pass's contacts leave a trace exactly when their noise-free twins do.
fn settle_noisy_traces(trials: &mut [Trial]) {
    let clean: Vec<(f64, f64, f64, bool)> = trials
        .iter()
        .filter(|t| !t.noisy)
        .map(|t| (t.s, t.azimuth_deg, t.depth, t.image_changed))
        .collect();
    for t in trials.iter_mut().filter(|t| t.noisy) {
        if let Some(c) = clean
            .iter()
            .find(|c| c.0 == t.s && c.1 == t.azimuth_deg && c.2 == t.depth)
        {
            t.image_changed = c.3;
        }
    }
}
