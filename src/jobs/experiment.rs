//! The paper's contact-localisation experiment, on rendered images: seven solids, each tapped
//! at rotations 0, pi/6, pi/4, pi/3 about the tip and translations 0, 5, 10, 15 mm along the
//! side below the junction; every tap localised by every method and scored in millimetres
//! against the exact ground truth. Missed taps are counted, never averaged in.

use crate::error::{GeltipError, Result};
use crate::evaluate::{
    self, Detector, MethodDetector, Options, Sample, Source, Suite, SuiteJob, SuitePart, Target,
};
use crate::localise::Method;
use crate::object::{Object, Solid};
use crate::output;
use crate::plot;
use crate::render::{GroundTruth, Place, Press};
use crate::sensor::Sensor;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

/// The paper's eight tap positions, with the column labels of its Table I.
pub const POSITIONS: [(Place, &str); 8] = [
    (Place::Rotation(0.0), "0"),
    (Place::Rotation(30.0), "π/6"),
    (Place::Rotation(45.0), "π/4"),
    (Place::Rotation(60.0), "π/3"),
    (Place::Translation(0.0), "0 mm"),
    (Place::Translation(5.0), "5 mm"),
    (Place::Translation(10.0), "10 mm"),
    (Place::Translation(15.0), "15 mm"),
];

/// The paper's Table I: mean and standard deviation of the error (mm) per position.
pub const PAPER_PER_POSITION: [(f64, f64); 8] = [
    (4.71, 0.75),
    (2.01, 0.90),
    (1.04, 0.46),
    (6.96, 4.82),
    (7.87, 5.08),
    (8.03, 1.92),
    (7.55, 5.00),
    (4.86, 8.41),
];

/// The paper's Table II: mean and standard deviation of the error (mm) per object, in the
/// order of [`Solid::ALL`].
pub const PAPER_PER_OBJECT: [(f64, f64); 7] = [
    (3.63, 3.26),
    (6.79, 5.38),
    (5.61, 4.08),
    (4.57, 4.30),
    (7.47, 6.29),
    (3.33, 1.90),
    (6.27, 8.17),
];

/// How the taps are made.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// Press depth of every tap (mm).
    pub depth_mm: f64,
    /// Azimuth of the tapped side (degrees).
    pub azimuth_deg: f64,
    /// The methods to score.
    pub methods: Vec<Method>,
}

impl Default for Protocol {
    fn default() -> Self {
        Protocol {
            depth_mm: 1.0,
            azimuth_deg: 0.0,
            methods: Method::ALL.to_vec(),
        }
    }
}

/// One tap scored by one method.
#[derive(Debug, Clone, PartialEq)]
pub struct TapResult {
    pub object: Solid,
    /// Index into [`POSITIONS`].
    pub position: usize,
    pub method: Method,
    pub truth: GroundTruth,
    pub prediction: Option<DVec3>,
    pub confidence: f64,
    /// Euclidean distance between prediction and truth, when detected.
    pub error_mm: Option<f64>,
}

/// Every tap of the experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub sensor: String,
    pub protocol: Protocol,
    pub taps: Vec<TapResult>,
}

/// Mean, sample standard deviation and counts of a set of taps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub mean: f64,
    pub std: f64,
    pub detected: usize,
    pub missed: usize,
}

impl Summary {
    fn of<'a>(taps: impl Iterator<Item = &'a TapResult>) -> Summary {
        let mut errors = Vec::new();
        let mut missed = 0;
        for t in taps {
            match t.error_mm {
                Some(e) => errors.push(e),
                None => missed += 1,
            }
        }
        let n = errors.len();
        let mean = if n > 0 {
            errors.iter().sum::<f64>() / n as f64
        } else {
            f64::NAN
        };
        let std = if n > 1 {
            (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Summary {
            mean,
            std,
            detected: n,
            missed,
        }
    }

    /// "mean ± std", with how many were found when some were missed; "all N missed" when
    /// nothing was found.
    pub fn cell(&self) -> String {
        let mut s = match self.detected {
            0 => return format!("all {} missed", self.missed),
            // One tap has no spread to speak of.
            1 => format!("{:.2}", self.mean),
            _ => format!("{:.2} ± {:.2}", self.mean, self.std),
        };
        if self.missed > 0 {
            let _ = write!(
                s,
                " ({} of {} found)",
                self.detected,
                self.detected + self.missed
            );
        }
        s
    }
}

impl Report {
    /// Summary of the taps of `method` that match `keep`.
    pub fn summary(&self, method: Method, keep: impl Fn(&TapResult) -> bool) -> Summary {
        Summary::of(self.taps.iter().filter(|t| t.method == method && keep(t)))
    }

    /// The two tables of the paper, ours beside theirs, as Markdown.
    pub fn tables_markdown(&self) -> String {
        let mut md = format!(
            "Sensor `{}`, taps {} mm deep at azimuth {}°; error = distance (mm) between the predicted point and the contact's centre (the indented region's centroid on the surface), mean ± sample std over the detected taps; missed taps are counted, not averaged in.\n\n",
            self.sensor, self.protocol.depth_mm, self.protocol.azimuth_deg
        );
        let positions: Vec<&str> = POSITIONS.iter().map(|(_, l)| *l).collect();
        self.table(
            &mut md,
            "position",
            &positions,
            &PAPER_PER_POSITION,
            |t, i| t.position == i,
        );
        md.push('\n');
        let objects: Vec<&str> = Solid::ALL.iter().map(|s| s.name()).collect();
        self.table(&mut md, "object", &objects, &PAPER_PER_OBJECT, |t, i| {
            t.object == Solid::ALL[i]
        });
        md
    }

    /// One table: a column per entry of `columns` (taps in column i are those `in_column`
    /// says), the paper's published row, then a row per method.
    fn table(
        &self,
        md: &mut String,
        per: &str,
        columns: &[&str],
        paper: &[(f64, f64)],
        in_column: impl Fn(&TapResult, usize) -> bool,
    ) {
        let _ = writeln!(md, "**Contact errors per {per} (mm)**\n");
        let _ = writeln!(md, "| method | {} | all |", columns.join(" | "));
        let _ = writeln!(md, "|---|{}---|", "---|".repeat(columns.len()));
        let published: Vec<String> = paper
            .iter()
            .map(|(m, s)| format!("{m:.2} ± {s:.2}"))
            .collect();
        let _ = writeln!(
            md,
            "| paper (published, real sensor) | {} | ~5 |",
            published.join(" | ")
        );
        for &m in &self.protocol.methods {
            let cells: Vec<String> = (0..columns.len())
                .map(|i| self.summary(m, |t| in_column(t, i)).cell())
                .collect();
            let _ = writeln!(
                md,
                "| {} (geltip) | {} | {} |",
                m.name(),
                cells.join(" | "),
                self.summary(m, |_| true).cell()
            );
        }
    }

    /// Every tap as CSV: object, position, method, truth, prediction, error, detected.
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "object,position,method,truth_x,truth_y,truth_z,truth_u,truth_v,pred_x,pred_y,pred_z,error_mm,detected,confidence\n",
        );
        for t in &self.taps {
            let (tu, tv) = t
                .truth
                .pixel
                .as_ref()
                .map(|p| (p.x.to_string(), p.y.to_string()))
                .unwrap_or_default();
            let (px, py, pz) = t
                .prediction
                .map(|p| (p.x.to_string(), p.y.to_string(), p.z.to_string()))
                .unwrap_or_default();
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{tu},{tv},{px},{py},{pz},{},{},{}",
                t.object.name(),
                POSITIONS[t.position].1,
                t.method.name(),
                t.truth.scoring_point().x,
                t.truth.scoring_point().y,
                t.truth.scoring_point().z,
                t.error_mm.map(|e| e.to_string()).unwrap_or_default(),
                t.error_mm.is_some(),
                t.confidence,
            );
        }
        csv
    }
}

/// All the paper's taps: the seven solids' eight each, solid by solid (56).
pub fn all_taps(protocol: &Protocol) -> Vec<Press> {
    Solid::ALL.iter().flat_map(|&s| taps(s, protocol)).collect()
}

/// The paper's eight taps of `object`, as [`run`] renders them.
pub fn taps(object: Solid, protocol: &Protocol) -> Vec<Press> {
    POSITIONS
        .iter()
        .map(|(place, _)| {
            let object = Arc::new(Object::Solid(object));
            Press::at(object, *place, protocol.azimuth_deg, protocol.depth_mm)
        })
        .collect()
}

/// File-name stem of a tap's image.
pub fn tap_name(object: Solid, position: usize) -> String {
    let slug = match POSITIONS[position].0 {
        Place::Rotation(d) => format!("rot{d:02}"),
        Place::Translation(mm) => format!("trans{mm:02}"),
        Place::ArcLength(s) => format!("s{s}"),
    };
    format!("{}_{slug}", object.name())
}

/// The paper's taps as a suite: one frame per tap, solid by solid, scored against each
/// contact's centre.
pub fn suite(sensor: &Sensor, protocol: &Protocol) -> Result<Suite> {
    Ok(Suite {
        name: "paper".into(),
        parts: vec![SuitePart {
            sensor: sensor.clone(),
            target: Target::ContactCentre,
            jobs: Solid::ALL
                .iter()
                .map(|&s| SuiteJob::Batch(taps(s, protocol)))
                .collect(),
        }],
    })
}

/// Renders every tap, localises it with every method and scores it ([`crate::evaluate`],
/// any distance matching). `out`, when given, receives the images and labels; `progress`
/// is called after each tap.
pub fn run(
    sensor: &Sensor,
    protocol: &Protocol,
    out: Option<&Path>,
    mut progress: impl FnMut(&str),
) -> Result<Report> {
    if protocol.methods.is_empty() {
        return Err(GeltipError::input("experiment", "no methods to score"));
    }
    let source = Source::Suite(suite(sensor, protocol)?);
    let mut methods: Vec<MethodDetector> = protocol
        .methods
        .iter()
        .map(|&m| MethodDetector::new(m))
        .collect();
    let mut detectors: Vec<&mut dyn Detector> =
        methods.iter_mut().map(|d| d as &mut dyn Detector).collect();
    // A tap is one contact: its detection is scored however far it lands, as the paper does.
    let options = Options {
        gate_mm: None,
        work_dir: None,
    };
    let mut truths = Vec::new();
    let evaluations = evaluate::evaluate(&source, &mut detectors, &options, |sample, _| {
        let k = truths.len();
        let (object, position) = (Solid::ALL[k / POSITIONS.len()], k % POSITIONS.len());
        let truth = sample
            .rendered
            .as_ref()
            .and_then(|t| t.first())
            .cloned()
            .ok_or_else(|| GeltipError::input("experiment", "a tap rendered no contact"))?;
        let name = tap_name(object, position);
        if let Some(dir) = out {
            save_tap(dir, sample, &name, &truth)?;
        }
        truths.push(truth);
        progress(&name);
        Ok(())
    })?;
    let mut results = Vec::new();
    for (k, truth) in truths.into_iter().enumerate() {
        let (object, position) = (Solid::ALL[k / POSITIONS.len()], k % POSITIONS.len());
        for (e, &method) in evaluations.iter().zip(&protocol.methods) {
            let frame = &e.frames[k];
            let hit = frame.score.matches.first();
            results.push(TapResult {
                object,
                position,
                method,
                prediction: frame.found.first().and_then(|f| f.point),
                confidence: frame.found.first().map_or(0.0, |f| f.confidence),
                error_mm: hit.map(|m| m.error_mm),
                truth: truth.clone(),
            });
        }
    }
    let report = Report {
        sensor: sensor.name.clone(),
        protocol: protocol.clone(),
        taps: results,
    };
    if let Some(dir) = out {
        output::write_atomic(dir.join("taps.csv"), report.csv().as_bytes())?;
        output::write_atomic(dir.join("tables.md"), report.tables_markdown().as_bytes())?;
        output::write_atomic(
            dir.join("errors_per_position.svg"),
            chart_svg(&report)?.as_bytes(),
        )?;
    }
    Ok(report)
}

/// Writes a tap's image and labels (and, with the first tap, the reference) into `dir`.
fn save_tap(dir: &Path, sample: &Sample, name: &str, truth: &GroundTruth) -> Result<()> {
    let reference = dir.join("reference.png");
    if sample.truth.index == 0 {
        let r = sample.reference.rgb(&sample.sensor)?;
        output::write_png_rgb8(reference, r.width(), r.height(), r.as_raw())?;
    }
    let image = sample.image.rgb(&sample.sensor)?;
    output::write_png_rgb8(
        dir.join("images").join(format!("{name}.png")),
        image.width(),
        image.height(),
        image.as_raw(),
    )?;
    output::write_json(
        dir.join("labels").join(format!("{name}.json")),
        &truth.to_json(),
    )
}

/// One method's points on the chart: (position, mean, std) and the positions with misses.
struct Series {
    name: String,
    colour: plotters::style::RGBColor,
    points: Vec<(usize, f64, f64)>,
    missed: Vec<usize>,
}

/// The chart's series: the paper's published errors, then each method's.
fn chart_series(report: &Report) -> Vec<Series> {
    let mut series = vec![Series {
        name: "paper (published)".into(),
        colour: plot::REFERENCE_GREY,
        points: PAPER_PER_POSITION
            .iter()
            .enumerate()
            .map(|(i, (m, s))| (i, *m, *s))
            .collect(),
        missed: vec![],
    }];
    for (k, &m) in report.protocol.methods.iter().enumerate() {
        let mut points = Vec::new();
        let mut missed = Vec::new();
        for p in 0..POSITIONS.len() {
            let s = report.summary(m, |t| t.position == p);
            if s.detected > 0 {
                points.push((p, s.mean, s.std));
            }
            if s.missed > 0 {
                missed.push(p);
            }
        }
        series.push(Series {
            name: format!("{} detector (geltip)", m.name()),
            colour: plot::colour(k),
            points,
            missed,
        });
    }
    series
}

/// Error per position per method, with the paper's published numbers, as an SVG chart.
pub fn chart_svg(report: &Report) -> Result<String> {
    use plotters::prelude::*;
    let series = chart_series(report);
    let top = series
        .iter()
        .flat_map(|s| s.points.iter().map(|(_, m, sd)| m + sd))
        .fold(1.0f64, f64::max)
        * 1.1;
    plot::svg("errors per position", (900, 480), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Localisation error per tap position (mean ± std, mm; × = missed taps)",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(-0.5f64..7.5f64, 0f64..top)?;
        chart
            .configure_mesh()
            .x_labels(8)
            .x_label_formatter(&|x| {
                let i = x.round() as i64;
                if (0..8).contains(&i) && (x - i as f64).abs() < 1e-6 {
                    POSITIONS[i as usize].1.to_string()
                } else {
                    String::new()
                }
            })
            .y_desc("error (mm)")
            .draw()?;
        let n = series.len() as f64;
        for (k, line) in series.iter().enumerate() {
            let dx = (k as f64 - (n - 1.0) / 2.0) * 0.18;
            let c = line.colour;
            chart
                .draw_series(line.points.iter().map(|&(p, m, s)| {
                    ErrorBar::new_vertical(p as f64 + dx, (m - s).max(0.0), m, m + s, c.filled(), 6)
                }))?
                .label(line.name.clone())
                .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
            chart.draw_series(
                line.missed
                    .iter()
                    .map(|&p| Cross::new((p as f64 + dx, top * 0.02), 6, c.stroke_width(2))),
            )?;
        }
        plot::legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
}
