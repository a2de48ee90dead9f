//! The trade-off report's outputs: the Markdown table, the CSV and the Pareto charts.

use super::{loc_score, Report, Row, IMAGE_TIE, LOCALISATION_TIE_MM, SPEED_TIE};
use super::{REFERENCE_STEPS, REFERENCE_TEXELS};
use crate::error::Result;
use crate::plot;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;

/// Reads a row's error on one axis, and whether the row is on that axis's front.
type Get = fn(&Row) -> (f64, bool);

impl Report {
    /// The default's row.
    pub fn default_row(&self) -> Option<&Row> {
        self.rows.iter().find(|r| r.is_default)
    }

    /// The table, Markdown, with a sentence on the default.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "Sensor `{}`, adapter {}, {} contacts. Image error: mean |Δ| (8-bit levels) against {} texels / {} steps / analytic solids at the same image size. Localisation: surface detector, mean error (mm) of detected contacts. Front: on the Pareto front of fps against that error; joint: against both errors at once. Differences within {:.0}% fps, {} levels and {} mm count as ties (the noise between speed rounds on a shared machine and between runs of a few contacts).\n\n| configuration | fps | image error | front (image) | localisation error (mm) | missed | front (localisation) | front (joint) |\n|---|---|---|---|---|---|---|---|\n",
            self.sensor, self.adapter, self.rows.first().map_or(0, |r| r.contacts), REFERENCE_TEXELS, REFERENCE_STEPS, 100.0 * SPEED_TIE, IMAGE_TIE, LOCALISATION_TIE_MM
        );
        for r in &self.rows {
            let _ = writeln!(
                md,
                "| {}{} | {:.1} | {:.2} | {} | {} | {} | {} | {} |",
                r.label,
                if r.is_default { " (default)" } else { "" },
                r.fps,
                r.image_error,
                if r.on_front_image { "yes" } else { "" },
                r.localisation_error_mm
                    .map_or("—".into(), |e| format!("{e:.3}")),
                r.missed,
                if r.on_front_localisation { "yes" } else { "" },
                if r.on_front_joint { "yes" } else { "" },
            );
        }
        if let Some(d) = self.default_row() {
            let _ = writeln!(
                md,
                "\nThe default is {} the image-error front, {} the localisation front and {} the joint front.",
                if d.on_front_image { "on" } else { "NOT on" },
                if d.on_front_localisation {
                    "on"
                } else {
                    "NOT on"
                },
                if d.on_front_joint { "on" } else { "NOT on" },
            );
        }
        md
    }

    /// The table, CSV.
    pub fn csv(&self) -> String {
        let mut csv = String::from("texels,ray_steps,tap_spacing,image_scale,voxel_mm,default,fps,image_error,front_image,localisation_error_mm,missed,front_localisation,front_joint\n");
        for r in &self.rows {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                r.knobs.texels,
                r.knobs.ray_steps,
                r.knobs.tap_spacing,
                r.knobs.image_scale,
                r.knobs.voxel_mm.map(|v| v.to_string()).unwrap_or_default(),
                r.is_default,
                r.fps,
                r.image_error,
                r.on_front_image,
                r.localisation_error_mm
                    .map(|e| e.to_string())
                    .unwrap_or_default(),
                r.missed,
                r.on_front_localisation,
                r.on_front_joint
            );
        }
        csv
    }

    /// Two Pareto charts side by side (fps against image error, fps against localisation
    /// error), the front drawn as a step line, the default ringed, every point labelled.
    pub fn chart(&self) -> Result<String> {
        let max_fps = self.rows.iter().map(|r| r.fps).fold(1.0, f64::max) * 1.15;
        let panels: [(&str, &str, Get); 2] = [
            (
                "image error vs reference",
                "mean |Δ| (8-bit levels)",
                |r| (r.image_error, r.on_front_image),
            ),
            (
                "surface detector error",
                "mean error (mm; a miss counts 10 mm)",
                |r| (loc_score(r), r.on_front_localisation),
            ),
        ];
        plot::svg("tradeoff", (1100, 480), |root| {
            let areas = root.split_evenly((1, 2));
            for (area, (title, ydesc, get)) in areas.iter().zip(panels) {
                self.draw_panel(area, title, ydesc, get, max_fps)?;
            }
            Ok(())
        })
    }

    /// One Pareto chart on `area`: fps against the error `get` reads (with whether the row
    /// is on that error's front).
    fn draw_panel(
        &self,
        area: &DrawingArea<SVGBackend<'_>, Shift>,
        title: &str,
        ydesc: &str,
        get: Get,
        max_fps: f64,
    ) -> std::result::Result<(), Box<dyn std::error::Error>> {
        let top = self.rows.iter().map(|r| get(r).0).fold(0.01, f64::max) * 1.15;
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(0f64..max_fps, 0f64..top)?;
        chart
            .configure_mesh()
            .x_desc("frames per second (one contact per submit)")
            .y_desc(ydesc)
            .draw()?;
        let mut front: Vec<(f64, f64)> = self
            .rows
            .iter()
            .filter(|r| get(r).1)
            .map(|r| (r.fps, get(r).0))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut steps = Vec::new();
        for (i, p) in front.iter().enumerate() {
            if i > 0 {
                steps.push((front[i - 1].0, p.1));
            }
            steps.push(*p);
        }
        let c0 = plot::colour(0);
        chart
            .draw_series(LineSeries::new(steps, c0.stroke_width(2)))?
            .label("Pareto front")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c0.stroke_width(2)));
        let c1 = plot::colour(1);
        chart.draw_series(self.rows.iter().map(|r| {
            let (e, on) = get(r);
            let style = if on { c0.filled() } else { c1.filled() };
            Circle::new((r.fps, e), 4, style)
        }))?;
        if let Some(d) = self.default_row() {
            chart
                .draw_series(std::iter::once(Circle::new(
                    (d.fps, get(d).0),
                    9,
                    BLACK.stroke_width(2),
                )))?
                .label("default")
                .legend(|(x, y)| Circle::new((x + 8, y), 5, BLACK.stroke_width(2)));
        }
        for r in &self.rows {
            let mut short = format!("{}t/{}s", r.knobs.texels, r.knobs.ray_steps);
            if r.knobs.image_scale != 1.0 {
                let _ = write!(short, " x{}", r.knobs.image_scale);
            }
            if let Some(v) = r.knobs.voxel_mm {
                let _ = write!(short, " mesh {v}");
            }
            chart.draw_series(std::iter::once(Text::new(
                short,
                (r.fps, get(r).0),
                ("sans-serif", 10),
            )))?;
        }
        plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}
