//! The sweep's report: the tables (detection rate by depth, smallest depth found per region,
//! hidden contacts, false detections, pairs), the CSV of every trial and the two charts.

use super::{Report, Trial, REGIONS};
use crate::error::{GeltipError, Result};
use crate::localise::Method;
use crate::output;
use crate::plot;
use crate::sensor::Sensor;
use crate::view;
use std::fmt::Write as _;
use std::path::Path;

impl Report {
    /// Refuses a sweep whose detections held NaN or infinity, or that localised a contact
    /// of which nothing reaches the image.
    pub(super) fn check(&self, sensor: &Sensor) -> Result<()> {
        if self.non_finite > 0 {
            return Err(GeltipError::input(
                format!("stability sweep on '{}'", sensor.name),
                format!(
                    "{} detections held NaN or infinite numbers",
                    self.non_finite
                ),
            ));
        }
        if let Some(t) = self
            .trials
            .iter()
            .find(|t| !t.visible && !t.image_changed && t.detected)
        {
            return Err(GeltipError::input(
                format!("stability sweep on '{}'", sensor.name),
                format!(
                    "the {} detector placed a contact the lens cannot see (s {:.2} mm, azimuth {}°)",
                    t.method, t.s, t.azimuth_deg
                ),
            ));
        }
        Ok(())
    }

    /// Writes the tables, the CSV and the charts into `dir`.
    pub(super) fn write(&self, dir: &Path, sensor: &Sensor) -> Result<()> {
        output::write_atomic(dir.join("stability.md"), self.markdown().as_bytes())?;
        output::write_atomic(dir.join("stability.csv"), self.csv().as_bytes())?;
        output::write_atomic(
            dir.join("detection_rate.svg"),
            self.rate_chart()?.as_bytes(),
        )?;
        output::write_atomic(
            dir.join("error_map.svg"),
            self.error_map(sensor)?.as_bytes(),
        )
    }

    fn visible_trials(&self, noisy: bool, method: Method) -> impl Iterator<Item = &Trial> {
        self.trials
            .iter()
            .filter(move |t| t.noisy == noisy && t.method == method && t.visible)
    }

    /// Fraction of visible contacts detected at `depth`.
    pub fn rate(&self, noisy: bool, method: Method, depth: f64, region: Option<&str>) -> f64 {
        let (mut n, mut k) = (0, 0);
        for t in self.visible_trials(noisy, method) {
            if (t.depth - depth).abs() < 1e-12 && region.is_none_or(|r| r == t.region) {
                n += 1;
                k += t.detected as usize;
            }
        }
        if n == 0 {
            0.0
        } else {
            k as f64 / n as f64
        }
    }

    /// The smallest sweep depth from which on every deeper one is detected >= 95% of the time
    /// in `region`, or `None`.
    pub fn depth_95(&self, noisy: bool, method: Method, region: &str) -> Option<f64> {
        let has = self
            .visible_trials(noisy, method)
            .any(|t| t.region == region);
        if !has {
            return None;
        }
        let mut best = None;
        for &d in self.sweep.depths.iter().rev() {
            if self.rate(noisy, method, d, Some(region)) >= 0.95 {
                best = Some(d);
            } else {
                break;
            }
        }
        best
    }

    fn passes(&self) -> Vec<bool> {
        let mut p = vec![false];
        if self.trials.iter().any(|t| t.noisy) {
            p.push(true);
        }
        p
    }

    fn pass_name(&self, noisy: bool) -> String {
        if noisy {
            format!("noise σ={}", self.sweep.noise)
        } else {
            "no noise".into()
        }
    }

    /// The report's tables.
    pub fn markdown(&self) -> String {
        let mut md = self.rate_table();
        self.depth_table(&mut md);
        self.hidden_table(&mut md);
        self.empty_and_pair_tables(&mut md);
        md
    }

    /// The detection rate against depth.
    fn rate_table(&self) -> String {
        let mut md = format!(
            "Sensor `{}`: sphere contacts at {} visible places x {} depths; NaN/inf in detections: {}.\n\n**Detection rate against depth (visible contacts)**\n\n| method | pass | {} |\n|---|---|{}\n",
            self.sensor,
            self.trials.iter().filter(|t| t.visible && !t.noisy && t.method == self.sweep.methods[0] && (t.depth - self.sweep.depths[0]).abs() < 1e-12).count(),
            self.sweep.depths.len(),
            self.non_finite,
            self.sweep.depths.iter().map(|d| format!("{d} mm")).collect::<Vec<_>>().join(" | "),
            "---|".repeat(self.sweep.depths.len()),
        );
        for &noisy in &self.passes() {
            for &m in &self.sweep.methods {
                let cells: Vec<String> = self
                    .sweep
                    .depths
                    .iter()
                    .map(|&d| format!("{:.0}%", 100.0 * self.rate(noisy, m, d, None)))
                    .collect();
                let _ = writeln!(
                    md,
                    "| {m} | {} | {} |",
                    self.pass_name(noisy),
                    cells.join(" | ")
                );
            }
        }
        md
    }

    /// The smallest depth found 95% of the time, per region, and the mean error.
    fn depth_table(&self, md: &mut String) {
        let _ = writeln!(
            *md,
            "\n**Smallest depth detected ≥ 95% (and at every deeper depth), per region; mean error (mm) of detected contacts at ≥ 0.3 mm**\n\n| method | pass | {} | mean error |\n|---|---|{}---|",
            REGIONS.join(" | "),
            "---|".repeat(REGIONS.len())
        );
        for &noisy in &self.passes() {
            for &m in &self.sweep.methods {
                let cells: Vec<String> = REGIONS
                    .iter()
                    .map(|r| match self.depth_95(noisy, m, r) {
                        Some(d) => format!("{d} mm"),
                        None => "never".into(),
                    })
                    .collect();
                let errs: Vec<f64> = self
                    .visible_trials(noisy, m)
                    .filter(|t| t.depth >= 0.3)
                    .filter_map(|t| t.error_mm)
                    .collect();
                let mean = if errs.is_empty() {
                    "—".into()
                } else {
                    format!("{:.2}", errs.iter().sum::<f64>() / errs.len() as f64)
                };
                let _ = writeln!(
                    *md,
                    "| {m} | {} | {} | {mean} |",
                    self.pass_name(noisy),
                    cells.join(" | ")
                );
            }
        }
    }

    /// The contacts the lens cannot see, and how many were localised.
    fn hidden_table(&self, md: &mut String) {
        let _ = writeln!(*md, "\n**Contacts the lens cannot see** (full depth, up to 6 mm below the visible edge of their meridian, where the finger goes on that far)\n\n| method | pass | contacts | leaving no trace in the image | localised anyway | of which leaving no trace |\n|---|---|---|---|---|---|");
        for &noisy in &self.passes() {
            for &m in &self.sweep.methods {
                let hidden: Vec<&Trial> = self
                    .trials
                    .iter()
                    .filter(|t| t.noisy == noisy && t.method == m && !t.visible)
                    .collect();
                let _ = writeln!(
                    *md,
                    "| {m} | {} | {} | {} | {} | {} |",
                    self.pass_name(noisy),
                    hidden.len(),
                    hidden.iter().filter(|t| !t.image_changed).count(),
                    hidden.iter().filter(|t| t.detected).count(),
                    hidden
                        .iter()
                        .filter(|t| t.detected && !t.image_changed)
                        .count()
                );
            }
        }
    }

    /// False detections on empty frames, and the pairs of contacts.
    fn empty_and_pair_tables(&self, md: &mut String) {
        let _ = writeln!(*md, "\n**False detections on empty frames**\n\n| method | pass | detected / frames |\n|---|---|---|");
        for (noisy, m, hits, n) in &self.false_detections {
            let _ = writeln!(*md, "| {m} | {} | {hits} / {n} |", self.pass_name(*noisy));
        }
        let _ = writeln!(*md, "\n**Two simultaneous contacts** (at the deepest depth, on opposite meridians, rendered as one scene)\n\n| method | pairs | something detected | mean distance to the nearer contact (mm) |\n|---|---|---|---|");
        for (m, pairs, found, err) in &self.two_contacts {
            let _ = writeln!(
                *md,
                "| {m} | {pairs} | {found} | {} |",
                err.map_or("—".into(), |e| format!("{e:.2}"))
            );
        }
    }

    /// Every trial, CSV.
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "noisy,method,s_mm,azimuth_deg,depth_mm,region,visible,mask_pixels,image_changed,detected,error_mm\n",
        );
        for t in &self.trials {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{}",
                t.noisy,
                t.method,
                t.s,
                t.azimuth_deg,
                t.depth,
                t.region,
                t.visible,
                t.mask_pixels,
                t.image_changed,
                t.detected,
                t.error_mm.map(|e| e.to_string()).unwrap_or_default()
            );
        }
        csv
    }

    /// Detection rate against depth (log scale), a line per method and pass.
    pub fn rate_chart(&self) -> Result<String> {
        use plotters::prelude::*;
        let lo = self
            .sweep
            .depths
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min);
        let hi = self.sweep.depths.iter().cloned().fold(0.0, f64::max);
        plot::svg("detection rate", (760, 440), |root| {
            let mut chart = ChartBuilder::on(root)
                .caption(
                    "Detection rate against press depth (visible contacts)",
                    ("sans-serif", 18),
                )
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d((lo * 0.8..hi * 1.2).log_scale(), 0f64..105f64)?;
            chart
                .configure_mesh()
                .x_desc("press depth (mm, log scale)")
                .y_desc("detected (%)")
                .draw()?;
            let mut k = 0;
            for &noisy in &self.passes() {
                for &m in &self.sweep.methods {
                    let c = plot::colour(k);
                    k += 1;
                    let pts: Vec<(f64, f64)> = self
                        .sweep
                        .depths
                        .iter()
                        .map(|&d| (d, 100.0 * self.rate(noisy, m, d, None)))
                        .collect();
                    chart
                        .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
                        .label(format!("{m}, {}", self.pass_name(noisy)))
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                        });
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
                }
            }
            plot::legend(&mut chart, SeriesLabelPosition::LowerRight)?;
            Ok(())
        })
    }

    /// Error against position over the unrolled finger (azimuth across, arc length down),
    /// colour = error (mm) of the noise-free trials at the deepest sweep depth; a cross
    /// where the contact was missed. One panel per method.
    pub fn error_map(&self, sensor: &Sensor) -> Result<String> {
        use plotters::prelude::*;
        let depth = self.sweep.depths.iter().cloned().fold(0.0, f64::max);
        let s_top = view::finger_length(sensor);
        let cap = 3.0;
        let methods = self.sweep.methods.clone();
        let n = methods.len() as u32;
        plot::svg("error map", (420 * n + 80, 520), |root| {
            let (panels, legend) = root.split_horizontally(420 * n);
            let areas = panels.split_evenly((1, n as usize));
            for (area, &m) in areas.iter().zip(&methods) {
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!("{m}: error at {depth} mm deep (no noise)"),
                        ("sans-serif", 15),
                    )
                    .margin(10)
                    .x_label_area_size(35)
                    .y_label_area_size(45)
                    .build_cartesian_2d(-20f64..360f64, s_top..0f64)?;
                chart
                    .configure_mesh()
                    .x_desc("azimuth (°)")
                    .y_desc("arc length from the tip (mm)")
                    .draw()?;
                let sj = sensor.finger.junction_s();
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(-20.0, sj), (360.0, sj)],
                    plot::REFERENCE_GREY,
                )))?;
                // The lens edge per azimuth.
                let edge: Vec<(f64, f64)> = (0..=72)
                    .map(|k| {
                        let az = 5.0 * k as f64;
                        (az, view::visible_extent(sensor, az.to_radians()))
                    })
                    .collect();
                chart.draw_series(LineSeries::new(edge, BLACK.stroke_width(1)))?;
                for t in self.trials.iter().filter(|t| {
                    !t.noisy && t.method == m && (t.depth - depth).abs() < 1e-12 && t.visible
                }) {
                    let pos = (t.azimuth_deg, t.s);
                    match t.error_mm {
                        Some(e) => {
                            chart.draw_series(std::iter::once(Circle::new(
                                pos,
                                7,
                                plot::heat(e / cap).filled(),
                            )))?;
                        }
                        None => {
                            chart.draw_series(std::iter::once(Cross::new(
                                pos,
                                6,
                                BLACK.stroke_width(2),
                            )))?;
                        }
                    }
                }
            }
            // Colour bar.
            let bar = legend.margin(60, 60, 10, 30);
            let (_, h) = bar.dim_in_pixel();
            for y in 0..h {
                let t = 1.0 - y as f64 / h as f64;
                bar.draw(&Rectangle::new(
                    [(0, y as i32), (15, y as i32 + 1)],
                    plot::heat(t).filled(),
                ))?;
            }
            bar.draw(&Text::new(
                format!("≥{cap} mm"),
                (0, -15),
                ("sans-serif", 11),
            ))?;
            bar.draw(&Text::new("0 mm", (0, h as i32 + 3), ("sans-serif", 11)))?;
            Ok(())
        })
    }
}
