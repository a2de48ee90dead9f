//! `geltip preview`: what a sensor design sees before anyone builds it. Pure geometry from
//! the sensor model (the finger, the lens and the image rectangle through
//! [`Sensor::project`]), plus one render of the empty finger per design for the picture.
//!
//! For each design: how far down the side the camera sees (per azimuth: the image rectangle
//! crops some meridians earlier than others), the lowest visible point, the visible area
//! (mm² and % of the finger's surface, hemisphere 2πr² + cylinder 2πrd), and the resolution
//! in pixels per mm along the meridian and along the parallel, as a curve of the arc length
//! s from the tip (finite differences of `project` along the surface).

use crate::error::{GeltipError, Result};
use crate::finger::SurfaceCoord;
use crate::lens::LensModel;
use crate::output;
use crate::render::gpu::Renderer;
use crate::sensor::Sensor;
pub use crate::view::{finger_length, px_per_mm, visible, visible_extent};
use image::{Rgb, RgbImage};
use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

mod figures;
pub use figures::{resolution_chart, sweep_chart, table_csv, table_markdown};

/// Azimuths sampled around the finger for the visible extent and area.
pub const AZIMUTHS: usize = 720;

/// Step (mm) of the resolution curves.
pub const CURVE_STEP_MM: f64 = 0.25;

/// Resolution levels (px/mm along the meridian) drawn as iso-lines on the pictures.
pub const ISO_LEVELS: [f64; 5] = [2.0, 4.0, 6.0, 8.0, 10.0];

/// One point of a resolution curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resolution {
    /// Arc length from the tip (mm).
    pub s: f64,
    /// Pixels per mm along the meridian (down the finger).
    pub meridian: f64,
    /// Pixels per mm along the parallel (around the finger).
    pub parallel: f64,
}

/// What one design sees.
#[derive(Debug, Clone, PartialEq)]
pub struct Preview {
    pub sensor: String,
    /// "equidistant f=180 px, 170°".
    pub lens: String,
    pub radius_mm: f64,
    pub cylinder_length_mm: f64,
    /// Visible arc length from the tip on the meridian that is cropped soonest (mm): the
    /// camera sees all the way round down to here.
    pub visible_s_all_round: f64,
    /// Visible arc length on the meridian that reaches farthest (mm).
    pub visible_s_max: f64,
    /// Azimuth (radians) of that meridian.
    pub best_azimuth: f64,
    /// Height (z, mm above the camera centre) of the lowest visible point.
    pub lowest_z: f64,
    /// Height of the lowest ring seen all round.
    pub lowest_z_all_round: f64,
    pub visible_area_mm2: f64,
    /// Visible area as % of 2πr² + 2πrd.
    pub visible_area_pct: f64,
    /// Resolution along the meridian that reaches farthest, from the tip to its visible end.
    pub curve: Vec<Resolution>,
}

/// The places the table reports resolution at: (label, arc length from the tip).
pub fn table_places(sensor: &Sensor) -> [(&'static str, f64); 5] {
    let j = sensor.finger.junction_s();
    [
        ("tip", 0.0),
        ("junction", j),
        ("5 mm below", j + 5.0),
        ("10 mm below", j + 10.0),
        ("15 mm below", j + 15.0),
    ]
}

/// "equidistant f=180 px, 170°".
pub fn lens_label(sensor: &Sensor) -> String {
    let l = &sensor.config.lens;
    format!("{} f={:.1} px, {}°", l.model.name(), l.focal_px, l.fov_deg)
}

/// Analyses one design.
pub fn analyse(sensor: &Sensor) -> Result<Preview> {
    let f = &sensor.finger;
    let (r, d) = (f.radius, f.cylinder_length);
    let sj = f.junction_s();
    let dphi = TAU / AZIMUTHS as f64;
    let mut area = 0.0;
    let (mut s_min, mut s_max, mut best_phi) = (f64::INFINITY, -1.0, 0.0);
    for k in 0..AZIMUTHS {
        let phi = (k as f64 + 0.5) * dphi;
        let s = visible_extent(sensor, phi);
        // Exact area of the meridian's strip from the tip down to s.
        let hemi = r * r * (1.0 - (s.min(sj) / r).cos());
        let cyl = r * (s - sj).max(0.0);
        area += (hemi + cyl) * dphi;
        s_min = f64::min(s_min, s);
        if s > s_max {
            s_max = s;
            best_phi = phi;
        }
    }
    let z_of = |s: f64| f.point_at(SurfaceCoord { s, phi: 0.0 }).point.z;
    let total = TAU * r * r + TAU * r * d;
    let mut curve = Vec::new();
    let n = (s_max / CURVE_STEP_MM).floor() as usize;
    for i in 0..=n {
        let s = (i as f64 * CURVE_STEP_MM).min(s_max);
        if let Some((m, p)) = px_per_mm(sensor, s, best_phi) {
            curve.push(Resolution {
                s,
                meridian: m,
                parallel: p,
            });
        }
    }
    if let Some((m, p)) = px_per_mm(sensor, s_max, best_phi) {
        if curve.last().is_some_and(|c| c.s < s_max - 1e-9) {
            curve.push(Resolution {
                s: s_max,
                meridian: m,
                parallel: p,
            });
        }
    }
    let values = [s_min, s_max, area, z_of(s_max), z_of(s_min)];
    if values.iter().any(|v| !v.is_finite()) || curve.iter().any(|c| !c.meridian.is_finite()) {
        return Err(GeltipError::input(
            format!("sensor '{}'", sensor.name),
            "the preview's geometry is not finite",
        ));
    }
    Ok(Preview {
        sensor: sensor.name.clone(),
        lens: lens_label(sensor),
        radius_mm: r,
        cylinder_length_mm: d,
        visible_s_all_round: s_min,
        visible_s_max: s_max,
        best_azimuth: best_phi,
        lowest_z: z_of(s_max),
        lowest_z_all_round: z_of(s_min),
        visible_area_mm2: area,
        visible_area_pct: 100.0 * area / total,
        curve,
    })
}

impl Preview {
    /// Resolution at arc length `s` on the meridian that reaches farthest, from the sensor.
    pub fn at(&self, sensor: &Sensor, s: f64) -> Option<(f64, f64)> {
        px_per_mm(sensor, s, self.best_azimuth)
    }
}

/// Variants of `base` with an equidistant fisheye of each full field of view in `fovs_deg`,
/// its focal length chosen so the field of view's edge lands on the image's shorter half
/// side (the lens fills the picture's height): f = (min(w, h) / 2) / (fov / 2).
pub fn fov_sweep(base: &Sensor, fovs_deg: &[f64]) -> Result<Vec<Sensor>> {
    fovs_deg
        .iter()
        .map(|&fov| {
            let mut c = base.config.clone();
            let half_side = 0.5 * base.width.min(base.height) as f64;
            c.lens.model = LensModel::Equidistant;
            c.lens.k = [0.0; 4];
            c.lens.fov_deg = fov;
            c.lens.focal_px = half_side / (0.5 * fov.to_radians());
            c.description = format!("{} with an equidistant {fov}° lens", base.name);
            Sensor::from_config(format!("{}-fish{fov}", base.name), c)
        })
        .collect()
}

/// Parses `a:b:step` (degrees) into the list a, a+step, ..., b.
pub fn parse_range(text: &str) -> Result<Vec<f64>> {
    let bad = |why: &str| GeltipError::option_value("sweep_fovs", text, why);
    let parts: Vec<f64> = text
        .split(':')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad("expected <from>:<to>:<step> in degrees, e.g. 120:200:20"))?;
    let [a, b, step] = parts[..] else {
        return Err(bad(
            "expected <from>:<to>:<step> in degrees, e.g. 120:200:20",
        ));
    };
    if !(a.is_finite() && b.is_finite() && step.is_finite()) || step <= 0.0 || b < a {
        return Err(bad("need from <= to and a positive step"));
    }
    let n = ((b - a) / step + 1e-9).floor() as usize;
    if n > 200 {
        return Err(bad("more than 200 lenses; take a larger step"));
    }
    Ok((0..=n).map(|i| a + i as f64 * step).collect())
}

/// The preview picture: the empty finger as rendered, the visible region's edge in yellow
/// and iso-lines of meridian resolution ([`ISO_LEVELS`]) in shades from white (low) to
/// magenta (high).
pub fn picture(sensor: &Sensor, reference: &RgbImage) -> RgbImage {
    let mut img = reference.clone();
    let mut dot = |p: glam::DVec2, c: Rgb<u8>| {
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                let (u, v) = (p.x.round() as i64 + dx, p.y.round() as i64 + dy);
                if u >= 0 && v >= 0 && (u as u32) < img.width() && (v as u32) < img.height() {
                    img.put_pixel(u as u32, v as u32, c);
                }
            }
        }
    };
    let steps = 1440;
    for k in 0..steps {
        let phi = TAU * k as f64 / steps as f64;
        let s_end = visible_extent(sensor, phi);
        let edge = sensor.finger.point_at(SurfaceCoord { s: s_end, phi }).point;
        if let Ok(p) = sensor.project(edge) {
            dot(p, Rgb([255, 220, 0]));
        }
        // Iso-lines: where the meridian resolution crosses each level on this meridian.
        let mut prev: Option<(f64, f64)> = None;
        let n = (s_end / 0.05).floor() as usize;
        for i in 0..=n {
            let s = i as f64 * 0.05;
            let Some((m, _)) = px_per_mm(sensor, s, phi) else {
                continue;
            };
            if let Some((s0, m0)) = prev {
                for (li, &level) in ISO_LEVELS.iter().enumerate() {
                    if (m0 - level) * (m - level) <= 0.0 && m0 != m {
                        let t = (level - m0) / (m - m0);
                        let sc = s0 + t * (s - s0);
                        let pt = sensor.finger.point_at(SurfaceCoord { s: sc, phi }).point;
                        if let Ok(p) = sensor.project(pt) {
                            let w = 255 - (li as u32 * 40) as u8;
                            dot(p, Rgb([255, w, 255]));
                        }
                    }
                }
            }
            prev = Some((s, m));
        }
    }
    img
}

/// What [`run`] produced.
#[derive(Debug, Clone)]
pub struct Report {
    pub designs: Vec<(Sensor, Preview)>,
    pub sweep: Vec<(Sensor, Preview)>,
    pub sweep_fovs: Vec<f64>,
}

impl Report {
    /// The sweep's design with the largest [`sweep_score`], if any.
    pub fn best_sweep(&self) -> Option<&(Sensor, Preview)> {
        self.sweep
            .iter()
            .max_by(|a, b| sweep_score(&a.0, &a.1).total_cmp(&sweep_score(&b.0, &b.1)))
    }
}

/// How the sweep ranks lenses: the number of pixels per mm² averaged over the whole side
/// down to the camera, counting what the lens does not see as 0 — i.e. the visible area
/// weighted by its resolution (meridian x parallel px/mm), divided by the finger's area.
/// It rewards seeing more and seeing it sharper in one figure.
pub fn sweep_score(sensor: &Sensor, p: &Preview) -> f64 {
    let f = &sensor.finger;
    let (r, sj) = (f.radius, f.junction_s());
    let ds = CURVE_STEP_MM;
    let mut sum = 0.0;
    for c in &p.curve {
        let ring = if c.s <= sj {
            TAU * r * (c.s / r).sin()
        } else {
            TAU * r
        };
        sum += c.meridian * c.parallel * ring * ds;
    }
    sum / (TAU * r * r + TAU * r * f.cylinder_length)
}

/// Analyses `designs` and the `sweep_fovs` lens sweep of the first design; with `out`,
/// writes a picture per design (`<name>.png`, needs the GPU renderer), `resolution.svg`,
/// `lens_sweep.svg`, `preview.md` and `preview.csv`. `progress` is called per design.
pub fn run(
    designs: &[Sensor],
    sweep_fovs: &[f64],
    out: Option<&Path>,
    pictures: bool,
    mut progress: impl FnMut(&str),
) -> Result<Report> {
    if designs.is_empty() {
        return Err(GeltipError::option("designs", "no designs to preview"));
    }
    let mut rows = Vec::new();
    for s in designs {
        rows.push((s.clone(), analyse(s)?));
        if let (Some(dir), true) = (out, pictures) {
            let renderer = Renderer::new(s)?;
            let reference = renderer.reference().to_rgb();
            let img = picture(s, &reference);
            output::write_png_rgb8(
                dir.join(format!("{}.png", file_stem(&s.name))),
                img.width(),
                img.height(),
                img.as_raw(),
            )?;
        }
        progress(&s.name);
    }
    let mut sweep = Vec::new();
    for s in fov_sweep(&designs[0], sweep_fovs)? {
        sweep.push((s.clone(), analyse(&s)?));
        progress(&s.name);
    }
    let report = Report {
        designs: rows,
        sweep,
        sweep_fovs: sweep_fovs.to_vec(),
    };
    if let Some(dir) = out {
        let mut md = table_markdown(&report.designs);
        let mut csv = table_csv(&report.designs);
        if !report.sweep.is_empty() {
            md.push_str("\n**Lens sweep** (equidistant fisheye, focal length fitted so the field of view fills the image height)\n\n");
            md.push_str(&table_markdown(&report.sweep));
            md.push_str("\n| design | score: mean px² per mm² over the whole side |\n|---|---|\n");
            for (s, p) in &report.sweep {
                let _ = writeln!(md, "| {} | {:.2} |", p.sensor, sweep_score(s, p));
            }
            if let Some((_, best)) = report.best_sweep() {
                let _ = writeln!(
                    md,
                    "\nBest lens of the sweep by that score: **{}**.",
                    best.lens
                );
            }
            if let Some((_, rows)) = table_csv(&report.sweep).split_once('\n') {
                csv.push_str(rows);
            }
            output::write_atomic(
                dir.join("lens_sweep.svg"),
                sweep_chart(&report.sweep, &report.sweep_fovs)?.as_bytes(),
            )?;
        }
        output::write_atomic(dir.join("preview.md"), md.as_bytes())?;
        output::write_atomic(dir.join("preview.csv"), csv.as_bytes())?;
        output::write_atomic(
            dir.join("resolution.svg"),
            resolution_chart(&report.designs, "Resolution from the tip down the side")?.as_bytes(),
        )?;
    }
    Ok(report)
}

/// A file-name-safe stem for a design name (a TOML path becomes its stem).
pub fn file_stem(name: &str) -> String {
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| name.to_string());
    stem.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
