//! The imprint's look from a real sensor's contact frames, whose contacts are known only
//! roughly (a labelled azimuth and push point, an indenter of unknown size): each imprint is
//! found in its frame by the change localiser, and the gel's values (blend, drape, bulge,
//! how a tilted skin shades) and the indenter's radius are fitted so that the rendered
//! contact changes the empty finger as the real press changed its own t = 0 frame, inside a
//! window round the imprint. Each frame's own depth and place (a few millimetres about where
//! the localiser put it) are fitted beside them.
//!
//! Renders are the CPU mirror's ([`crate::render::cpu::render_contact`]): the look's values
//! change every few renders, which the GPU renderer would pay for with new pipelines.

use super::fit::soft_l1;
use super::solve::{levenberg_marquardt, levenberg_marquardt_sweeps, Bound, Fit, Sweeps};
use super::{AtBound, Value};
use crate::error::{GeltipError, Result};
use crate::evaluate::real::{azimuth_error_deg, RealSet};
use crate::finger::SurfaceCoord;
use crate::localise::{Localiser, Method};
use crate::object::{Object, Primitive};
use crate::render::softness::Softness;
use crate::render::{cpu, Frame, HeightfieldGrid, Place, Press};
use crate::sensor::{LedKindName, Leds, Sensor, SensorConfig};
use glam::DVec2;
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// How the fit runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ImprintOptions {
    /// Contact frames the look is fitted to, spread over the set's groups.
    pub fit_frames: usize,
    /// Other contact frames the result is scored on (none of the fitted ones).
    pub score_frames: usize,
    /// Pixels within this distance of an imprint's middle are compared.
    pub window_px: f64,
    /// Levenberg-Marquardt steps for the shared fit.
    pub iterations: usize,
    /// Levenberg-Marquardt steps placing each scored frame's contact (its depth and place,
    /// the look held).
    pub place_iterations: usize,
    /// The indenter's radius (mm) the fit starts from.
    pub start_radius_mm: f64,
    /// How each pixel's residual counts.
    pub loss: Loss,
}

/// How a pixel's residual (the rendered change less the real one, in levels) counts in the
/// fit and in placing each scored frame's contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Loss {
    /// Soft-L1 with the light fit's scale ([`super::fit::ROBUST_SCALE`], 6 levels): a
    /// residual beyond a few levels counts about linearly, so a strong imprint's flanks
    /// weigh less than in the PSNR the look is scored by.
    #[default]
    SoftL1,
    /// Squared, as the PSNR the look is scored by.
    Squared,
}

impl Loss {
    pub const ALL: [Loss; 2] = [Loss::SoftL1, Loss::Squared];

    /// The value whose square the fit sums.
    fn apply(self, r: f64) -> f64 {
        match self {
            Loss::Squared => r,
            Loss::SoftL1 => soft_l1(r),
        }
    }

    /// The name `--loss` takes.
    pub fn name(self) -> &'static str {
        match self {
            Loss::Squared => "squared",
            Loss::SoftL1 => "soft-l1",
        }
    }
}

impl std::str::FromStr for Loss {
    type Err = GeltipError;

    fn from_str(s: &str) -> Result<Loss> {
        Loss::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                let names = Loss::ALL.map(Loss::name).join(" or ");
                GeltipError::option("loss", format!("must be {names}, got {s:?}"))
            })
    }
}

impl Default for ImprintOptions {
    fn default() -> Self {
        ImprintOptions {
            fit_frames: 20,
            score_frames: 40,
            window_px: 40.0,
            iterations: 20,
            place_iterations: 12,
            start_radius_mm: 6.0,
            loss: Loss::default(),
        }
    }
}

impl ImprintOptions {
    /// Refuses counts of zero and a window that is not a positive number.
    pub fn validate(&self) -> Result<()> {
        if self.fit_frames == 0 {
            return Err(GeltipError::option("fit-frames", "must be at least 1"));
        }
        if !(self.window_px.is_finite() && self.window_px >= 4.0) {
            return Err(GeltipError::option(
                "window",
                format!("must be at least 4 px, got {}", self.window_px),
            ));
        }
        if !(self.start_radius_mm.is_finite()
            && (RADIUS_MM.0..=RADIUS_MM.1).contains(&self.start_radius_mm))
        {
            return Err(GeltipError::option(
                "radius",
                format!(
                    "must be within {} to {} mm, got {}",
                    RADIUS_MM.0, RADIUS_MM.1, self.start_radius_mm
                ),
            ));
        }
        Ok(())
    }
}

/// The indenter radii (mm) the fit may reach.
pub const RADIUS_MM: (f64, f64) = (1.0, 15.0);

/// How far (mm, on the unrolled surface) a frame's contact may move from where the
/// localiser put it.
pub const PLACE_REACH_MM: f64 = 3.0;

/// A located contact whose labelled azimuth is further than this (degrees) is not used:
/// the localiser and the label disagree about which imprint it is.
pub const LABEL_AGREEMENT_DEG: f64 = 15.0;

/// A real contact frame whose imprint the change localiser found.
#[derive(Debug, Clone)]
pub struct Located {
    /// The frame's index in the set.
    pub index: usize,
    pub image: PathBuf,
    pub group: String,
    /// The imprint's middle in the image, the window's centre.
    pub pixel: DVec2,
    /// Where the localiser put the contact on the finger.
    pub coord: SurfaceCoord,
    /// The window's pixels (indices into the image, row-major).
    pub window: Vec<usize>,
    /// The frame and its reference (RGB, 8-bit).
    pub frame: Vec<u8>,
    pub reference: Vec<u8>,
}

impl Located {
    /// The real change over the window (RGB, levels).
    fn change(&self) -> Vec<f64> {
        self.window
            .iter()
            .flat_map(|&i| (0..3).map(move |c| i * 3 + c))
            .map(|k| self.frame[k] as f64 - self.reference[k] as f64)
            .collect()
    }
}

/// A contact frame left out, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    pub image: PathBuf,
    pub reason: String,
}

/// How far inside the image circle's edge (pixels) a scored pixel lies at least.
pub const CIRCLE_RIM_PX: f64 = 2.0;

/// The pixels (row-major indices) of `sensor`'s image circle, less its [`CIRCLE_RIM_PX`]
/// rim: where imprints are scored.
pub fn circle_pixels(sensor: &Sensor) -> Vec<usize> {
    let (centre, radius) = sensor.image_circle();
    let rim = radius - CIRCLE_RIM_PX;
    let w = sensor.width as usize;
    (0..w * sensor.height as usize)
        .filter(|&i| (DVec2::new((i % w) as f64, (i / w) as f64) - centre).length() <= rim)
        .collect()
}

/// Finds each contact frame's imprint in `set` with the change localiser; frames with none,
/// or with one away from their labelled azimuth, are skipped with the reason.
pub fn locate(
    sensor: &Sensor,
    set: &RealSet,
    window_px: f64,
) -> Result<(Vec<Located>, Vec<Skipped>)> {
    let localiser = Localiser::new(sensor);
    let w = sensor.width;
    let circle = circle_pixels(sensor);
    let found: Vec<Result<std::result::Result<Located, Skipped>>> = set
        .frames
        .par_iter()
        .enumerate()
        .filter(|(_, f)| f.label.contact)
        .map(|(index, f)| {
            let frame = crate::localise::load_frame(sensor, &f.image)?;
            let reference = crate::localise::load_frame(sensor, &f.reference)?;
            let skip = |reason: String| {
                Ok(Err(Skipped {
                    image: f.image.clone(),
                    reason,
                }))
            };
            let d = localiser.localise(&reference, &frame, Method::Change)?;
            let (Some(pixel), Some(point)) = (d.pixel, d.point) else {
                return skip(d.note.unwrap_or_else(|| "no contact found".into()));
            };
            if let (Some(az), Some(centre)) = (f.label.azimuth_deg, f.label.centre) {
                let off = azimuth_error_deg(pixel, centre, az);
                if off > LABEL_AGREEMENT_DEG {
                    return skip(format!(
                        "found {off:.0} deg from the labelled azimuth (more than {LABEL_AGREEMENT_DEG})"
                    ));
                }
            }
            let r2 = window_px * window_px;
            let window = circle
                .iter()
                .copied()
                .filter(|&i| {
                    let p = DVec2::new((i as u32 % w) as f64, (i as u32 / w) as f64);
                    (p - pixel).length_squared() <= r2
                })
                .collect();
            Ok(Ok(Located {
                index,
                image: f.image.clone(),
                group: f.group.clone(),
                pixel,
                coord: sensor.finger.coord_of(point),
                window,
                frame: frame.into_raw(),
                reference: reference.into_raw(),
            }))
        })
        .collect();
    let mut located = Vec::new();
    let mut skipped = Vec::new();
    for r in found {
        match r? {
            Ok(l) => located.push(l),
            Err(s) => skipped.push(s),
        }
    }
    if located.is_empty() {
        return Err(GeltipError::input(
            "real set",
            format!(
                "no contact frame's imprint was found ({} skipped)",
                skipped.len()
            ),
        ));
    }
    Ok((located, skipped))
}

/// `n` of `located` (indices into it), spread evenly over the groups and, within a group,
/// over its frames; those in `taken` are passed over. Deterministic.
pub fn spread(located: &[Located], n: usize, taken: &[usize]) -> Vec<usize> {
    let mut groups: Vec<(&str, Vec<usize>)> = Vec::new();
    for (k, l) in located.iter().enumerate() {
        if taken.contains(&k) {
            continue;
        }
        match groups.iter_mut().find(|(g, _)| *g == l.group) {
            Some((_, list)) => list.push(k),
            None => groups.push((&l.group, vec![k])),
        }
    }
    let mut out = Vec::new();
    let mut round = 0;
    while out.len() < n && groups.iter().any(|(_, list)| round < list.len()) {
        for (_, list) in &groups {
            if out.len() == n {
                break;
            }
            if round < list.len() {
                // A group's frames in the golden-ratio order, which spreads over the list.
                let m = list.len();
                let k = ((0.5 + round as f64 * 0.618_033_988_75).fract() * m as f64) as usize;
                let pick = (0..m)
                    .map(|d| list[(k + d) % m])
                    .find(|i| !out.contains(i))
                    .expect("the group has an unpicked frame");
                out.push(pick);
            }
        }
        round += 1;
    }
    out
}

/// One of the look's values the fit moves: its name, box and finite-difference step, and
/// where it lives in the sensor's configuration (none for the indenter's radius, which is
/// the indenter's, not the sensor's).
struct LookValue {
    name: &'static str,
    lo: f64,
    hi: f64,
    step: f64,
    field: Option<Field>,
}

/// How a look value is read from and written into a sensor's configuration.
#[derive(Clone, Copy)]
struct Field {
    get: fn(&SensorConfig) -> f64,
    set: fn(&mut SensorConfig, f64),
}

/// Whether the sensor's light is carried in the gel (its tilt term is the LEDs' relief) or
/// straight (the paint's specular).
fn has_gel(config: &SensorConfig) -> bool {
    matches!(&config.leds, Leds::List(list) if list.iter().any(|l| l.kind == LedKindName::Gel))
}

/// The gel LEDs' shared relief: the first gel LED's (the fit sets them all alike).
fn gel_relief(config: &SensorConfig) -> f64 {
    match &config.leds {
        Leds::List(list) => list
            .iter()
            .find(|l| l.kind == LedKindName::Gel)
            .map(|l| l.gel_spread().relief)
            .unwrap_or(1.0),
        _ => 1.0,
    }
}

fn set_gel_relief(config: &mut SensorConfig, v: f64) {
    if let Leds::List(list) = &mut config.leds {
        for l in list.iter_mut().filter(|l| l.kind == LedKindName::Gel) {
            l.relief = Some(v);
        }
    }
}

fn look_values(config: &SensorConfig) -> Vec<LookValue> {
    let shell = config.finger.shell_thickness_mm;
    let value = |name, lo, hi, step, field| LookValue {
        name,
        lo,
        hi,
        step,
        field,
    };
    let at = |get, set| Some(Field { get, set });
    let tilt = if has_gel(config) {
        value(
            "leds.relief",
            -10.0,
            10.0,
            0.05,
            at(gel_relief, set_gel_relief),
        )
    } else {
        value(
            "paint.specular",
            0.0,
            20.0,
            0.02,
            at(|c| c.paint.specular, |c, v| c.paint.specular = v),
        )
    };
    let mut values = vec![
        value("indenter.radius_mm", RADIUS_MM.0, RADIUS_MM.1, 0.1, None),
        value(
            "elastomer.blend_mm",
            0.05,
            3.0,
            0.05,
            at(|c| c.elastomer.blend_mm, |c, v| c.elastomer.blend_mm = v),
        ),
        value(
            "elastomer.drape_mm",
            shell,
            shell.max(20.0),
            0.1,
            at(
                |c| c.elastomer.drape_mm,
                |c, v| c.elastomer.drape_mm = v.max(c.finger.shell_thickness_mm),
            ),
        ),
        value(
            "elastomer.bulge",
            0.0,
            1.0,
            0.05,
            at(|c| c.elastomer.bulge, |c, v| c.elastomer.bulge = v),
        ),
        tilt,
    ];
    if has_gel(config) {
        // Light carried in the gel shades the imprint's flanks; the ambient light may be
        // carried there too, each channel as far as the real imprints show.
        values.extend([
            ambient_relief::<0>(),
            ambient_relief::<1>(),
            ambient_relief::<2>(),
        ]);
    }
    // The camera's softness, last: how sharp an imprint's edges reach the image.
    values.push(value(
        "camera.blur_px",
        0.0,
        BLUR_PX_MAX,
        0.1,
        at(|c| c.camera.blur_px, |c, v| c.camera.blur_px = v),
    ));
    values
}

/// The ambient light's relief in channel `K`, a look value of gel-lit sensors.
fn ambient_relief<const K: usize>() -> LookValue {
    LookValue {
        name: AMBIENT_RELIEF[K],
        lo: -10.0,
        hi: 10.0,
        step: 0.05,
        field: Some(Field {
            get: |c| c.light.ambient_relief[K],
            set: |c, v| c.light.ambient_relief[K] = v,
        }),
    }
}

/// The largest camera blur (pixels) the fit may reach.
pub const BLUR_PX_MAX: f64 = 6.0;

/// The camera blur (pixels) the fit starts from at least.
pub const BLUR_PX_START: f64 = 1.5;

const AMBIENT_RELIEF: [&str; 3] = [
    "light.ambient_relief[0]",
    "light.ambient_relief[1]",
    "light.ambient_relief[2]",
];

/// The look's values in `config` ([`look_values`]' order) with an indenter of `radius` mm.
fn get_look(config: &SensorConfig, radius: f64) -> Vec<f64> {
    look_values(config)
        .iter()
        .map(|l| l.field.map_or(radius, |f| (f.get)(config)))
        .collect()
}

/// The look's values in `config` with an indenter of `radius` mm, named as the fit names them.
pub fn look(config: &SensorConfig, radius: f64) -> Vec<(&'static str, f64)> {
    look_values(config)
        .iter()
        .map(|l| l.name)
        .zip(get_look(config, radius))
        .collect()
}

/// `config` with the look `p` ([`look_values`]' order; the radius is the indenter's, not the
/// sensor's).
fn set_look(config: &SensorConfig, p: &[f64]) -> SensorConfig {
    let mut c = config.clone();
    for (l, &v) in look_values(config).iter().zip(p) {
        if let Some(field) = l.field {
            (field.set)(&mut c, v);
        }
    }
    c
}

/// A frame's own values: depth (mm) and its place's offset on the unrolled surface (mm).
const PER_FRAME: usize = 3;

fn frame_bounds(shell: f64) -> [Bound; PER_FRAME] {
    [
        Bound {
            lo: 0.05,
            hi: shell,
            step: 0.02,
        },
        Bound {
            lo: -PLACE_REACH_MM,
            hi: PLACE_REACH_MM,
            step: 0.05,
        },
        Bound {
            lo: -PLACE_REACH_MM,
            hi: PLACE_REACH_MM,
            step: 0.05,
        },
    ]
}

/// Where a frame's contact is: the sphere's place and depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    pub s_mm: f64,
    pub azimuth_deg: f64,
    pub depth_mm: f64,
}

impl Placed {
    fn of(located: &Located, q: &[f64]) -> Placed {
        let c = SurfaceCoord::from_disc(located.coord.to_disc() + DVec2::new(q[1], q[2]));
        Placed {
            s_mm: c.s,
            azimuth_deg: c.phi.to_degrees(),
            depth_mm: q[0],
        }
    }

    /// The press of a sphere of `radius` mm here.
    pub fn press(&self, radius: f64) -> Press {
        let shape = Primitive::Sphere { r: radius };
        let object = Object::Primitive {
            name: shape.to_string(),
            shape,
        };
        Press::at(
            Arc::new(object),
            Place::ArcLength(self.s_mm),
            self.azimuth_deg,
            self.depth_mm,
        )
    }
}

/// A sensor and its empty finger, rendered by the CPU mirror once (`raw`, before the camera's
/// softness): the look's values do not change it; the camera's blur, one of them, softens
/// it for each look.
struct Stage<'a> {
    sensor: Sensor,
    grid: HeightfieldGrid,
    raw: &'a Frame,
    /// The camera's softness and the empty finger softened by it.
    softness: Option<(Softness, Frame)>,
    loss: Loss,
}

impl<'a> Stage<'a> {
    /// `seen`: the pixels the lens sees ([`Softness::seen_by`]), which no look changes.
    fn new(sensor: Sensor, raw: &'a Frame, seen: &Arc<[f32]>, loss: Loss) -> Stage<'a> {
        let softness = Softness::with_seen(&sensor, seen.clone()).map(|s| {
            let soft = s.soften_frame(raw);
            (s, soft)
        });
        Stage {
            grid: HeightfieldGrid::for_sensor(&sensor),
            sensor,
            raw,
            softness,
            loss,
        }
    }

    /// The rendered change over `located`'s window less the real one, each counted by the
    /// stage's loss.
    fn residuals(&self, located: &Located, real: &[f64], press: &Press) -> Result<Vec<f64>> {
        let (frame, reference) = match &self.softness {
            Some((softness, soft)) => (
                cpu::record_contact(&self.sensor, &self.grid, self.raw, soft, softness, press)?,
                soft,
            ),
            None => (
                cpu::render_contact(&self.sensor, &self.grid, self.raw, press)?,
                self.raw,
            ),
        };
        Ok(located
            .window
            .iter()
            .flat_map(|&i| (0..3).map(move |c| (i, c)))
            .zip(real)
            .map(|((i, c), r)| {
                let change = frame.rgba[i * 4 + c] as f64 - reference.rgba[i * 4 + c] as f64;
                self.loss.apply(change - r)
            })
            .collect())
    }
}

/// What the fit found.
#[derive(Debug, Clone)]
pub struct ImprintFit {
    /// The sensor's configuration with the fitted look.
    pub config: SensorConfig,
    pub radius_mm: f64,
    /// The look's values with their standard errors.
    pub values: Vec<Value>,
    pub at_bounds: Vec<AtBound>,
    /// The fitted frames (indices into the located list) and where each contact ended.
    pub frames: Vec<(usize, Placed)>,
    /// Half the sum of the squared residuals (each counted by the fit's loss), at the start
    /// and the end.
    pub cost_before: f64,
    pub cost_after: f64,
    pub iterations: usize,
    pub renders: usize,
}

/// Runs `eval` and keeps its first error.
struct Errors(std::sync::Mutex<Option<GeltipError>>);

impl Errors {
    fn new() -> Errors {
        Errors(std::sync::Mutex::new(None))
    }

    fn keep(&self, e: GeltipError) {
        self.0.lock().expect("not poisoned").get_or_insert(e);
    }

    fn take(&self) -> Result<()> {
        match self.0.lock().expect("not poisoned").take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Fits the look of `sensor`'s imprint (and the indenter's radius) to `located[chosen]`.
pub fn fit(
    sensor: &Sensor,
    located: &[Located],
    chosen: &[usize],
    options: &ImprintOptions,
    progress: &dyn Fn(&str),
) -> Result<ImprintFit> {
    options.validate()?;
    let reference = cpu::render(sensor, None)?.into_raw();
    let seen = Softness::seen_by(sensor);
    let looks = look_values(&sensor.config);
    let shell = sensor.config.finger.shell_thickness_mm;
    let frames: Vec<&Located> = chosen.iter().map(|&k| &located[k]).collect();
    let real: Vec<Vec<f64>> = frames.iter().map(|l| l.change()).collect();
    let mut start = get_look(&sensor.config, options.start_radius_mm);
    for (v, b) in start.iter_mut().zip(&looks) {
        *v = v.clamp(b.lo, b.hi);
        // A blur's effect grows as its square: from none, every step would see none.
        if b.name == "camera.blur_px" {
            *v = v.max(BLUR_PX_START);
        }
    }
    let n_look = start.len();
    for _ in &frames {
        start.extend([1.0, 0.0, 0.0]);
    }
    let mut bounds: Vec<Bound> = looks
        .iter()
        .map(|l| Bound {
            lo: l.lo,
            hi: l.hi,
            step: l.step,
        })
        .collect();
    for _ in &frames {
        bounds.extend(frame_bounds(shell));
    }
    // Each frame's residuals, in order: its values move only those.
    let mut ranges = Vec::new();
    let mut at = 0;
    for r in &real {
        ranges.push(at..at + r.len());
        at += r.len();
    }
    let mut sweeps: Vec<Vec<(usize, Option<std::ops::Range<usize>>)>> =
        (0..n_look).map(|i| vec![(i, None)]).collect();
    for v in 0..PER_FRAME {
        sweeps.push(
            ranges
                .iter()
                .enumerate()
                .map(|(f, r)| (n_look + f * PER_FRAME + v, Some(r.clone())))
                .collect(),
        );
    }
    let errors = Errors::new();
    let renders = std::sync::atomic::AtomicUsize::new(0);
    let total = real.iter().map(Vec::len).sum::<usize>();
    let residuals = |p: &[f64]| -> Vec<f64> {
        let stage = match Sensor::from_config("imprint", set_look(&sensor.config, p)) {
            Ok(s) => Stage::new(s, &reference, &seen, options.loss),
            Err(e) => {
                errors.keep(e);
                return vec![f64::INFINITY; total];
            }
        };
        let per: Vec<Result<Vec<f64>>> = frames
            .par_iter()
            .enumerate()
            .map(|(f, l)| {
                let q = &p[n_look + f * PER_FRAME..n_look + (f + 1) * PER_FRAME];
                stage.residuals(l, &real[f], &Placed::of(l, q).press(p[0]))
            })
            .collect();
        renders.fetch_add(frames.len(), std::sync::atomic::Ordering::Relaxed);
        let mut out = Vec::with_capacity(total);
        for r in per {
            match r {
                Ok(r) => out.extend(r),
                Err(e) => {
                    errors.keep(e);
                    return vec![f64::INFINITY; total];
                }
            }
        }
        out
    };
    progress(&format!(
        "fitting the imprint to {} real contact frames",
        frames.len()
    ));
    let before = half_squares(&residuals(&start));
    errors.take()?;
    let fit: Fit = levenberg_marquardt_sweeps(
        &start,
        &bounds,
        options.iterations,
        &Sweeps(sweeps),
        residuals,
    );
    errors.take()?;
    let std_errors = fit.standard_errors();
    let config = set_look(&sensor.config, &fit.params);
    let values: Vec<Value> = looks
        .iter()
        .zip(&fit.params)
        .zip(&std_errors)
        .map(|((l, &v), &e)| Value {
            name: l.name.to_string(),
            value: v,
            std_error: e,
        })
        .collect();
    let at_bounds = looks
        .iter()
        .zip(&fit.params)
        .filter_map(|(l, &v)| {
            let side = if v <= l.lo + 1e-9 {
                "lower"
            } else if v >= l.hi - 1e-9 {
                "upper"
            } else {
                return None;
            };
            Some(AtBound {
                name: l.name.to_string(),
                value: v,
                side,
            })
        })
        .collect();
    Ok(ImprintFit {
        config,
        radius_mm: fit.params[0],
        values,
        at_bounds,
        frames: chosen
            .iter()
            .enumerate()
            .map(|(f, &k)| {
                let q = &fit.params[n_look + f * PER_FRAME..n_look + (f + 1) * PER_FRAME];
                (k, Placed::of(&located[k], q))
            })
            .collect(),
        cost_before: before,
        cost_after: fit.cost,
        iterations: fit.iterations,
        renders: renders.into_inner(),
    })
}

/// Where `located`'s contact is on `stage` with a sphere of `radius` mm: its depth and place
/// fitted, the look held.
fn place_on(stage: &Stage, radius: f64, located: &Located, iterations: usize) -> Result<Placed> {
    let real = located.change();
    let errors = Errors::new();
    let residuals =
        |q: &[f64]| match stage.residuals(located, &real, &Placed::of(located, q).press(radius)) {
            Ok(r) => r,
            Err(e) => {
                errors.keep(e);
                vec![f64::INFINITY; real.len()]
            }
        };
    let bounds = frame_bounds(stage.sensor.config.finger.shell_thickness_mm);
    let fit = levenberg_marquardt(&[1.0, 0.0, 0.0], &bounds, iterations, residuals);
    errors.take()?;
    Ok(Placed::of(located, &fit.params))
}

/// Each of `located[chosen]` placed under `config`'s look with a sphere of `radius` mm (its
/// depth and place fitted, the look held), in parallel.
pub fn place_all(
    config: &SensorConfig,
    radius: f64,
    located: &[Located],
    chosen: &[usize],
    iterations: usize,
    loss: Loss,
) -> Result<Vec<Placed>> {
    let sensor = Sensor::from_config("imprint", config.clone())?;
    let reference = cpu::render(&sensor, None)?.into_raw();
    let seen = Softness::seen_by(&sensor);
    let stage = Stage::new(sensor, &reference, &seen, loss);
    chosen
        .par_iter()
        .map(|&k| place_on(&stage, radius, &located[k], iterations))
        .collect()
}

fn half_squares(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn located(group: &str) -> Located {
        Located {
            index: 0,
            image: PathBuf::new(),
            group: group.into(),
            pixel: DVec2::ZERO,
            coord: SurfaceCoord { s: 10.0, phi: 0.5 },
            window: Vec::new(),
            frame: Vec::new(),
            reference: Vec::new(),
        }
    }

    #[test]
    fn frames_are_spread_over_the_groups_and_never_taken_twice() {
        let list: Vec<Located> = ["a", "a", "a", "a", "b", "b", "c"]
            .iter()
            .map(|g| located(g))
            .collect();
        let first = spread(&list, 3, &[]);
        let groups: Vec<&str> = first.iter().map(|&k| list[k].group.as_str()).collect();
        assert_eq!(groups, ["a", "b", "c"]);
        let rest = spread(&list, 10, &first);
        assert_eq!(rest.len(), 4);
        assert!(rest.iter().all(|k| !first.contains(k)));
        let mut all: Vec<usize> = first.iter().chain(&rest).copied().collect();
        all.sort();
        assert_eq!(all, (0..7).collect::<Vec<_>>());
    }

    #[test]
    fn a_place_offset_moves_the_contact_on_the_unrolled_surface() {
        let l = located("a");
        let p = Placed::of(&l, &[1.0, 0.0, 0.0]);
        assert!(
            (p.s_mm - 10.0).abs() < 1e-12 && (p.azimuth_deg - 0.5f64.to_degrees()).abs() < 1e-9
        );
        let moved = Placed::of(&l, &[1.0, 0.5f64.cos(), 0.5f64.sin()]);
        assert!((moved.s_mm - 11.0).abs() < 1e-9, "{moved:?}");
    }

    #[test]
    fn each_look_value_is_written_where_it_is_read() {
        for preset in ["allsight", "paper"] {
            let config = crate::sensor::Sensor::preset(preset).unwrap().config;
            let names: Vec<&str> = look(&config, 6.0).iter().map(|(n, _)| *n).collect();
            let start = get_look(&config, 6.0);
            assert_eq!(start[0], 6.0);
            assert_eq!(set_look(&config, &start), config, "{preset}");
            // Each value moved alone is read back moved, and only it.
            for k in 1..start.len() {
                let mut p = start.clone();
                p[k] += 0.25;
                let moved = get_look(&set_look(&config, &p), 6.0);
                for (j, (&m, &s)) in moved.iter().zip(&start).enumerate() {
                    let want = if j == k { s + 0.25 } else { s };
                    assert!(
                        (m - want).abs() < 1e-12,
                        "{preset}: {} moved {}",
                        names[j],
                        names[k]
                    );
                }
            }
        }
    }
}
