//! `geltip imprint`: the imprint's look fitted to a real sensor's labelled contact frames
//! ([`crate::calibrate::imprint`]), judged on other contact frames of the same set by the GPU
//! renderer, and written with its report and a picture.

use super::calibrate::{residual_values, sensor_toml};
use crate::calibrate::imprint::{self, ImprintFit, ImprintOptions, Located, Placed, Skipped};
use crate::error::{GeltipError, Result};
use crate::evaluate::real::RealSet;
use crate::output;
use crate::render::background::compose;
use crate::render::gpu::Renderer;
use crate::sensor::Sensor;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Squared errors summed over a window's pixels, per channel (R, G, B), and how many pixels.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Squares {
    pub sum: [f64; 3],
    pub count: usize,
}

impl Squares {
    fn add(&mut self, other: Squares) {
        for (s, o) in self.sum.iter_mut().zip(other.sum) {
            *s += o;
        }
        self.count += other.count;
    }

    /// PSNR (dB) of the mean square pooled over the three channels; infinite for none.
    pub fn psnr_db(&self) -> f64 {
        psnr(self.sum.iter().sum(), 3 * self.count)
    }

    /// PSNR (dB) of each channel alone: which colour a look misses.
    pub fn channel_psnr_db(&self) -> [f64; 3] {
        self.sum.map(|s| psnr(s, self.count))
    }
}

fn psnr(sum: f64, count: usize) -> f64 {
    if count == 0 || sum == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (255.0f64 * 255.0 / (sum / count as f64)).log10()
}

/// How one look matches a frame inside its window: the render, and the real reference with
/// the rendered change added (what a dataset composited over real frames holds). Beside them
/// the light alone: the look's empty finger against the press's real reference (its t = 0
/// frame, nothing touching) inside the window and over the whole image circle, so that the
/// render's error splits into the light's and the imprint's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Match {
    pub render: Squares,
    pub composite: Squares,
    pub light: Squares,
    pub light_circle: Squares,
}

impl Match {
    fn add(&mut self, other: Match) {
        self.render.add(other.render);
        self.composite.add(other.composite);
        self.light.add(other.light);
        self.light_circle.add(other.light_circle);
    }
}

/// A group's (or the whole set's, "all") scores.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub group: String,
    pub frames: usize,
    /// The start sensor's look, the fitted one, and the real reference unchanged (no
    /// imprint at all), each against the real frame.
    pub before: Match,
    pub after: Match,
    pub unchanged: Squares,
}

/// One scored frame.
#[derive(Debug, Clone)]
pub struct Scored {
    pub located: usize,
    pub before: (Placed, Match),
    pub after: (Placed, Match),
    pub unchanged: Squares,
}

/// The fit judged on frames it did not see; nothing written yet.
#[derive(Debug)]
pub struct Judged {
    pub fit: ImprintFit,
    pub sensor_toml: String,
    pub located: Vec<Located>,
    pub skipped: Vec<Skipped>,
    pub scored: Vec<Scored>,
    pub rows: Vec<Row>,
    /// Per group, its first scored frame's window: real | fitted | residual | start.
    pub picture: image::RgbImage,
    pub report: Value,
    pub seconds: f64,
}

/// Fits, judges, writes `out`'s files.
pub fn run(
    start: &Sensor,
    set: &RealSet,
    set_path: &Path,
    options: &ImprintOptions,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<(Judged, Vec<PathBuf>)> {
    let judged = judge(start, set, set_path, options, progress)?;
    progress("writing");
    let files = write(&judged, out)?;
    Ok((judged, files))
}

/// Locates the set's imprints, fits the look to some, scores it on others.
pub fn judge(
    start: &Sensor,
    set: &RealSet,
    set_path: &Path,
    options: &ImprintOptions,
    progress: &dyn Fn(&str),
) -> Result<Judged> {
    options.validate()?;
    let started = Instant::now();
    progress("finding the imprints");
    let (located, skipped) = imprint::locate(start, set, options.window_px)?;
    let chosen = imprint::spread(&located, options.fit_frames, &[]);
    let scored_ids = imprint::spread(&located, options.score_frames, &chosen);
    let fit = imprint::fit(start, &located, &chosen, options, progress)?;
    let sensor_toml = sensor_toml(&fit.config)?;
    let fitted = Sensor::from_toml("imprint", &sensor_toml)?;
    if fitted.config != fit.config {
        return Err(GeltipError::input(
            "sensor.toml",
            "the written file does not load back as the fitted sensor",
        ));
    }
    progress(&format!("scoring on {} other frames", scored_ids.len()));
    let place_steps = options.place_iterations;
    let before_places = imprint::place_all(
        &start.config,
        options.start_radius_mm,
        &located,
        &scored_ids,
        place_steps,
        options.loss,
    )?;
    let after_places = imprint::place_all(
        &fit.config,
        fit.radius_mm,
        &located,
        &scored_ids,
        place_steps,
        options.loss,
    )?;
    let circle = imprint::circle_pixels(start);
    let mut start_look = Look::new(start, &circle)?;
    let mut fitted_look = Look::new(&fitted, &circle)?;
    let mut scored = Vec::new();
    let mut tiles: Vec<Tile> = Vec::new();
    for ((&k, b), a) in scored_ids.iter().zip(before_places).zip(after_places) {
        let l = &located[k];
        let (before, before_img) = start_look.judge(l, &b, options.start_radius_mm)?;
        let (after, after_img) = fitted_look.judge(l, &a, fit.radius_mm)?;
        let unchanged = squares(&l.reference, &l.frame, &l.window);
        if !tiles.iter().any(|t| t.group == l.group) {
            let residual = residual_values(&after_img, &l.frame);
            tiles.push(Tile {
                group: l.group.clone(),
                pixel: l.pixel,
                images: [l.frame.clone(), after_img, residual, before_img],
            });
        }
        scored.push(Scored {
            located: k,
            before: (b, before),
            after: (a, after),
            unchanged,
        });
    }
    let rows = rows(&located, &scored);
    let picture = picture(start, &tiles, options.window_px);
    let seconds = started.elapsed().as_secs_f64();
    let report = report_json(
        start, set_path, options, &fit, &located, &skipped, &scored, &rows, seconds,
    );
    Ok(Judged {
        fit,
        sensor_toml,
        located,
        skipped,
        scored,
        rows,
        picture,
        report,
        seconds,
    })
}

/// A look to judge: its sensor's GPU renderer and empty finger (RGB), and the image circle's
/// pixels.
struct Look<'a> {
    renderer: Renderer,
    empty: Vec<u8>,
    circle: &'a [usize],
}

impl<'a> Look<'a> {
    fn new(sensor: &Sensor, circle: &'a [usize]) -> Result<Look<'a>> {
        let renderer = Renderer::new(sensor)?;
        let empty = renderer.reference().to_rgb().into_raw();
        Ok(Look {
            renderer,
            empty,
            circle,
        })
    }

    /// Renders `placed` and compares it inside `l`'s window; also returns the composite
    /// (the real reference plus the rendered change, as `dataset --background` makes it)
    /// as a full image.
    fn judge(&mut self, l: &Located, placed: &Placed, radius: f64) -> Result<(Match, Vec<u8>)> {
        let (frame, _) = self.renderer.render(&placed.press(radius))?;
        let render = frame.to_rgb().into_raw();
        let composite = compose(
            &l.reference,
            render.iter().copied(),
            &self.empty,
            1.0,
            [1.0; 3],
            None::<fn(usize) -> f64>,
        );
        Ok((
            Match {
                render: squares(&render, &l.frame, &l.window),
                composite: squares(&composite, &l.frame, &l.window),
                light: squares(&self.empty, &l.reference, &l.window),
                light_circle: squares(&self.empty, &l.reference, self.circle),
            },
            composite,
        ))
    }
}

/// A group's row of the picture: its first scored frame's window centre and images.
struct Tile {
    group: String,
    pixel: glam::DVec2,
    images: [Vec<u8>; 4],
}

fn squares(a: &[u8], b: &[u8], window: &[usize]) -> Squares {
    let mut sum = [0.0; 3];
    for &i in window {
        for (c, s) in sum.iter_mut().enumerate() {
            *s += (a[i * 3 + c] as f64 - b[i * 3 + c] as f64).powi(2);
        }
    }
    Squares {
        sum,
        count: window.len(),
    }
}

fn rows(located: &[Located], scored: &[Scored]) -> Vec<Row> {
    let mut rows: Vec<Row> = Vec::new();
    let empty = |group: &str| Row {
        group: group.to_string(),
        frames: 0,
        before: Match::default(),
        after: Match::default(),
        unchanged: Squares::default(),
    };
    let mut all = empty("all");
    for s in scored {
        let group = &located[s.located].group;
        let i = match rows.iter().position(|r| r.group == *group) {
            Some(i) => i,
            None => {
                rows.push(empty(group));
                rows.len() - 1
            }
        };
        for row in [&mut rows[i], &mut all] {
            row.frames += 1;
            row.before.add(s.before.1);
            row.after.add(s.after.1);
            row.unchanged.add(s.unchanged);
        }
    }
    rows.push(all);
    rows
}

/// Per group, a row of four windows (2x): the real frame, the fitted look composited on the
/// real reference, their difference (twice, about grey), the start look composited.
fn picture(sensor: &Sensor, tiles: &[Tile], window_px: f64) -> image::RgbImage {
    let half = window_px.ceil() as i64;
    let side = (2 * half + 1) as u32;
    let scale = 2;
    let tile = side * scale;
    let mut out = image::RgbImage::from_pixel(
        4 * tile + 3 * 4,
        (tile + 4) * tiles.len().max(1) as u32,
        image::Rgb([255, 255, 255]),
    );
    let w = sensor.width as i64;
    let h = sensor.height as i64;
    for (row, group) in tiles.iter().enumerate() {
        let (cx, cy) = (group.pixel.x.round() as i64, group.pixel.y.round() as i64);
        for (col, img) in group.images.iter().enumerate() {
            for dy in -half..=half {
                for dx in -half..=half {
                    let (x, y) = (cx + dx, cy + dy);
                    let px = if (0..w).contains(&x) && (0..h).contains(&y) {
                        let i = ((y * w + x) * 3) as usize;
                        image::Rgb([img[i], img[i + 1], img[i + 2]])
                    } else {
                        image::Rgb([0, 0, 0])
                    };
                    for sy in 0..scale {
                        for sx in 0..scale {
                            out.put_pixel(
                                col as u32 * (tile + 4) + (dx + half) as u32 * scale + sx,
                                row as u32 * (tile + 4) + (dy + half) as u32 * scale + sy,
                                px,
                            );
                        }
                    }
                }
            }
        }
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn report_json(
    start: &Sensor,
    set_path: &Path,
    options: &ImprintOptions,
    fit: &ImprintFit,
    located: &[Located],
    skipped: &[Skipped],
    scored: &[Scored],
    rows: &[Row],
    seconds: f64,
) -> Value {
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    let rgb = |q: &Squares| q.channel_psnr_db().map(finite).to_vec();
    let placed =
        |p: &Placed| json!({"s_mm": p.s_mm, "azimuth_deg": p.azimuth_deg, "depth_mm": p.depth_mm});
    let matched = |m: &Match| {
        json!({
            "render_psnr_db": finite(m.render.psnr_db()),
            "composite_psnr_db": finite(m.composite.psnr_db()),
            "render_psnr_db_rgb": rgb(&m.render),
            "composite_psnr_db_rgb": rgb(&m.composite),
            "light_psnr_db": finite(m.light.psnr_db()),
            "light_circle_psnr_db": finite(m.light_circle.psnr_db()),
        })
    };
    json!({
        "start_sensor": start.name,
        "real_set": set_path,
        "window_px": options.window_px,
        "located": located.len(),
        "skipped": skipped.iter().map(|s| json!({"image": s.image, "reason": s.reason})).collect::<Vec<_>>(),
        "fitted_frames": fit.frames.iter().map(|(k, p)| json!({"image": located[*k].image, "group": located[*k].group, "contact": placed(p)})).collect::<Vec<_>>(),
        "start_values": imprint::look(&start.config, options.start_radius_mm)
            .into_iter()
            .map(|(name, value)| json!({"name": name, "value": value}))
            .collect::<Vec<_>>(),
        "values": fit.values.iter().map(|v| json!({
            "name": v.name,
            "value": v.value,
            "std_error": finite(v.std_error),
        })).collect::<Vec<_>>(),
        "at_bounds": fit.at_bounds.iter().map(|b| json!({"name": b.name, "value": b.value, "bound": b.side})).collect::<Vec<_>>(),
        "fit": {
            "robust_cost": {"before": fit.cost_before, "after": fit.cost_after},
            "iterations": fit.iterations,
            "renders": fit.renders,
            "start_radius_mm": options.start_radius_mm,
            "loss": options.loss.name(),
        },
        "rows": rows.iter().map(|r| json!({
            "group": r.group,
            "frames": r.frames,
            "before": matched(&r.before),
            "after": matched(&r.after),
            "unchanged_psnr_db": finite(r.unchanged.psnr_db()),
            "unchanged_psnr_db_rgb": rgb(&r.unchanged),
        })).collect::<Vec<_>>(),
        "scored_frames": scored.iter().map(|s| json!({
            "image": located[s.located].image,
            "group": located[s.located].group,
            "window_centre": [located[s.located].pixel.x, located[s.located].pixel.y],
            "before": {"contact": placed(&s.before.0), "match": matched(&s.before.1)},
            "after": {"contact": placed(&s.after.0), "match": matched(&s.after.1)},
            "unchanged_psnr_db": finite(s.unchanged.psnr_db()),
            "unchanged_psnr_db_rgb": rgb(&s.unchanged),
        })).collect::<Vec<_>>(),
        "seconds": seconds,
    })
}

/// A Markdown table: `header`'s columns, then a line of `cells` per row.
fn markdown(header: &[&str], rows: &[Row], cells: impl Fn(&Row) -> Vec<String>) -> String {
    let mut s = format!(
        "| {} |\n|{}\n",
        header.join(" | "),
        "---|".repeat(header.len())
    );
    for r in rows {
        s.push_str(&format!("| {} |\n", cells(r).join(" | ")));
    }
    s
}

fn db(q: &Squares) -> String {
    format!("{:.1}", q.psnr_db())
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let header = [
        "group",
        "frames",
        "render, start",
        "render, fitted",
        "composite, start",
        "composite, fitted",
        "no imprint",
    ];
    markdown(&header, rows, |r| {
        vec![
            r.group.clone(),
            r.frames.to_string(),
            db(&r.before.render),
            db(&r.after.render),
            db(&r.before.composite),
            db(&r.after.composite),
            db(&r.unchanged),
        ]
    })
}

/// The fitted look's rows channel by channel (R / G / B): which colour the look misses.
pub fn channel_table(rows: &[Row]) -> String {
    let header = [
        "group",
        "render, fitted (R / G / B)",
        "composite, fitted (R / G / B)",
        "no imprint (R / G / B)",
    ];
    let rgb = |q: &Squares| {
        let [r, g, b] = q.channel_psnr_db();
        format!("{r:.1} / {g:.1} / {b:.1}")
    };
    markdown(&header, rows, |r| {
        vec![
            r.group.clone(),
            rgb(&r.after.render),
            rgb(&r.after.composite),
            rgb(&r.unchanged),
        ]
    })
}

/// The fitted look's light alone beside its render, per group: its empty finger against the
/// presses' real references (their t = 0 frames) over the whole image circle and inside the
/// windows, and the render and the composite inside the windows. The render's error is about
/// the light's and the imprint's (the composite's) added as squares.
pub fn light_table(rows: &[Row]) -> String {
    let header = [
        "group",
        "frames",
        "empty finger vs t = 0, whole circle",
        "empty finger vs t = 0, windows",
        "render, windows",
        "composite, windows",
    ];
    markdown(&header, rows, |r| {
        vec![
            r.group.clone(),
            r.frames.to_string(),
            db(&r.after.light_circle),
            db(&r.after.light),
            db(&r.after.render),
            db(&r.after.composite),
        ]
    })
}

/// Writes `out`/sensor.toml, report.json, tables.md and imprints.png, each whole or not at all.
pub fn write(judged: &Judged, out: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let path = out.join("sensor.toml");
    output::write_atomic(&path, judged.sensor_toml.as_bytes())?;
    files.push(path);
    let path = out.join("imprints.png");
    let p = &judged.picture;
    output::write_png_rgb8(&path, p.width(), p.height(), p.as_raw())?;
    files.push(path);
    let path = out.join("tables.md");
    let tables = format!(
        "{}\nBy channel (PSNR in dB of each channel alone):\n\n{}\nThe fitted look's light alone (its empty finger against each press's t = 0 frame):\n\n{}",
        table(&judged.rows),
        channel_table(&judged.rows),
        light_table(&judged.rows)
    );
    output::write_atomic(&path, tables.as_bytes())?;
    files.push(path);
    let path = out.join("report.json");
    output::write_json(&path, &judged.report)?;
    files.push(path);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squares_split_by_channel_and_pool_to_the_mean_square() {
        // Two pixels, the second off by 10 levels in red and 5 in blue; the first not in the
        // window.
        let a = [9, 9, 9, 100, 50, 20];
        let b = [0, 0, 0, 90, 50, 25];
        let q = squares(&a, &b, &[1]);
        assert_eq!(q.sum, [100.0, 0.0, 25.0]);
        assert_eq!(q.count, 1);
        let [r, g, bl] = q.channel_psnr_db();
        assert!((r - 10.0 * (65025.0f64 / 100.0).log10()).abs() < 1e-12);
        assert!(g.is_infinite());
        assert!((bl - 10.0 * (65025.0f64 / 25.0).log10()).abs() < 1e-12);
        // Pooled: the mean over the three channels' values.
        assert!((q.psnr_db() - 10.0 * (65025.0f64 / (125.0 / 3.0)).log10()).abs() < 1e-12);
        let mut both = q;
        both.add(squares(&a, &b, &[0]));
        assert_eq!(both.sum, [181.0, 81.0, 106.0]);
        assert_eq!(both.count, 2);
        assert!(Squares::default().psnr_db().is_infinite());
    }

    #[test]
    fn the_channel_table_names_each_group_and_its_three_channels() {
        let m = |s: [f64; 3]| Squares { sum: s, count: 1 };
        let row = Row {
            group: "s1 push 2".into(),
            frames: 1,
            before: Match::default(),
            after: Match {
                render: m([650.25, 65.025, 6.5025]),
                composite: m([65.025, 65.025, 65.025]),
                ..Match::default()
            },
            unchanged: m([6502.5, 650.25, 65.025]),
        };
        let t = channel_table(&[row]);
        assert!(
            t.contains(
                "| s1 push 2 | 20.0 / 30.0 / 40.0 | 30.0 / 30.0 / 30.0 | 10.0 / 20.0 / 30.0 |"
            ),
            "{t}"
        );
    }

    #[test]
    fn the_light_table_puts_the_empty_finger_beside_the_render() {
        let m = |v: f64| Squares {
            sum: [v; 3],
            count: 1,
        };
        let row = Row {
            group: "all".into(),
            frames: 2,
            before: Match::default(),
            after: Match {
                render: m(65.025),
                composite: m(6.5025),
                light: m(0.65025),
                light_circle: m(0.065025),
            },
            unchanged: m(650.25),
        };
        let t = light_table(&[row]);
        assert!(t.contains("| all | 2 | 60.0 | 50.0 | 30.0 | 40.0 |"), "{t}");
    }
}
