//! The preview's tables (Markdown, CSV) and charts (resolution curves, the lens sweep).

use super::{finger_length, table_places, Preview};
use crate::error::Result;
use crate::plot;
use crate::sensor::Sensor;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;

/// A chart's drawing area.
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
/// What drawing a panel gives: nothing, or why not.
type Drawn = std::result::Result<(), Box<dyn std::error::Error>>;

/// A table cell: meridian / parallel px/mm, or "not visible".
fn cell(v: Option<(f64, f64)>) -> String {
    match v {
        Some((m, p)) => format!("{m:.2} / {p:.2}"),
        None => "not visible".into(),
    }
}

/// The table, Markdown.
pub fn table_markdown(rows: &[(Sensor, Preview)]) -> String {
    let mut md = String::from(
        "Visible: arc length from the tip (mm) seen all round / on the farthest-reaching meridian; lowest point: height above the camera (mm). Resolution: px/mm along the meridian / along the parallel, on the farthest-reaching meridian.\n\n",
    );
    md.push_str("| design | lens | r (mm) | visible s all round | visible s max | lowest z all round | lowest z | visible area (mm²) | % of finger | tip | junction | 5 mm below | 10 mm below | 15 mm below |\n");
    md.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (sensor, p) in rows {
        let places: Vec<String> = table_places(sensor)
            .iter()
            .map(|(_, s)| cell(p.at(sensor, *s)))
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} | {:.1} | {} |",
            p.sensor,
            p.lens,
            p.radius_mm,
            p.visible_s_all_round,
            p.visible_s_max,
            p.lowest_z_all_round,
            p.lowest_z,
            p.visible_area_mm2,
            p.visible_area_pct,
            places.join(" | ")
        );
    }
    md
}

/// The table, CSV (empty cells where a place is not visible).
pub fn table_csv(rows: &[(Sensor, Preview)]) -> String {
    let mut csv = String::from("design,lens,radius_mm,visible_s_all_round_mm,visible_s_max_mm,lowest_z_all_round_mm,lowest_z_mm,visible_area_mm2,visible_area_pct");
    for place in ["tip", "junction", "5mm", "10mm", "15mm"] {
        let _ = write!(
            csv,
            ",{place}_meridian_px_per_mm,{place}_parallel_px_per_mm"
        );
    }
    csv.push('\n');
    for (sensor, p) in rows {
        let _ = write!(
            csv,
            "{},\"{}\",{},{},{},{},{},{},{}",
            p.sensor,
            p.lens,
            p.radius_mm,
            p.visible_s_all_round,
            p.visible_s_max,
            p.lowest_z_all_round,
            p.lowest_z,
            p.visible_area_mm2,
            p.visible_area_pct
        );
        for (_, s) in table_places(sensor) {
            match p.at(sensor, s) {
                Some((m, q)) => {
                    let _ = write!(csv, ",{m},{q}");
                }
                None => csv.push_str(",,"),
            }
        }
        csv.push('\n');
    }
    csv
}

/// Resolution curves of several designs: meridian (solid) and parallel (dashed) px/mm
/// against the arc length from the tip, the junction of each design marked.
pub fn resolution_chart(rows: &[(Sensor, Preview)], title: &str) -> Result<String> {
    let s_top = rows
        .iter()
        .map(|(_, p)| p.visible_s_max)
        .fold(1.0, f64::max)
        * 1.02;
    let y_top = rows
        .iter()
        .flat_map(|(_, p)| p.curve.iter().map(|c| c.meridian.max(c.parallel)))
        .fold(1.0, f64::max)
        * 1.1;
    plot::svg(title, (900, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0f64..s_top, 0f64..y_top)?;
        chart
            .configure_mesh()
            .x_desc("arc length from the tip, s (mm)")
            .y_desc("pixels per mm (solid: meridian, dashed: parallel)")
            .draw()?;
        for (k, (sensor, p)) in rows.iter().enumerate() {
            let c = plot::colour(k);
            chart
                .draw_series(LineSeries::new(
                    p.curve.iter().map(|r| (r.s, r.meridian)),
                    c.stroke_width(2),
                ))?
                .label(format!("{} ({})", p.sensor, p.lens))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                });
            chart.draw_series(DashedLineSeries::new(
                p.curve.iter().map(|r| (r.s, r.parallel)),
                6,
                4,
                c.stroke_width(1),
            ))?;
            let sj = sensor.finger.junction_s();
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(sj, 0.0), (sj, y_top * 0.04)],
                c.stroke_width(2),
            )))?;
        }
        plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// The lens sweep: visible arc length (all round and farthest) and the resolution at the tip
/// and at the junction, against the lens's field of view.
pub fn sweep_chart(rows: &[(Sensor, Preview)], fovs: &[f64]) -> Result<String> {
    let title = "Lens sweep: field of view against reach and resolution";
    let x0 = fovs.iter().cloned().fold(f64::INFINITY, f64::min) - 5.0;
    let x1 = fovs.iter().cloned().fold(f64::NEG_INFINITY, f64::max) + 5.0;
    let s_top = rows
        .iter()
        .map(|(s, _)| finger_length(s))
        .fold(1.0, f64::max);
    let res: Vec<(f64, f64, f64)> = rows
        .iter()
        .zip(fovs)
        .map(|((sensor, p), &fov)| {
            let tip = p.at(sensor, 0.0).map_or(0.0, |v| v.0);
            let junction = p
                .at(sensor, sensor.finger.junction_s())
                .map_or(0.0, |v| v.0);
            (fov, tip, junction)
        })
        .collect();
    let y_top = res.iter().map(|r| r.1.max(r.2)).fold(1.0, f64::max) * 1.15;
    plot::svg(title, (900, 420), |root| {
        let (left, right) = root.split_horizontally(450);
        draw_reach(&left, rows, fovs, x0..x1, s_top)?;
        draw_resolution(&right, &res, x0..x1, y_top)
    })
}

/// The sweep's left panel: visible arc length (all round and farthest) against the field
/// of view, the whole side (`s_top`) for reference.
fn draw_reach(
    area: &Area<'_>,
    rows: &[(Sensor, Preview)],
    fovs: &[f64],
    x: std::ops::Range<f64>,
    s_top: f64,
) -> Drawn {
    let (x0, x1) = (x.start, x.end);
    let mut a = ChartBuilder::on(area)
        .caption("visible arc length from the tip (mm)", ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(x0..x1, 0f64..s_top * 1.05)?;
    a.configure_mesh().x_desc("field of view (°)").draw()?;
    type Series<'a> = (&'a str, usize, fn(&Preview) -> f64);
    let series: [Series; 2] = [
        ("all round", 0, |p| p.visible_s_all_round),
        ("farthest meridian", 1, |p| p.visible_s_max),
    ];
    for (name, k, get) in series {
        let c = plot::colour(k);
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .zip(fovs)
            .map(|((_, p), &f)| (f, get(p)))
            .collect();
        a.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        a.draw_series(pts.iter().map(|&q| Circle::new(q, 3, c.filled())))?;
    }
    let len = s_top;
    a.draw_series(std::iter::once(PathElement::new(
        vec![(x0, len), (x1, len)],
        plot::REFERENCE_GREY.stroke_width(1),
    )))?
    .label("whole side (down to the camera)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], plot::REFERENCE_GREY));
    plot::legend(&mut a, SeriesLabelPosition::LowerRight)?;
    Ok(())
}

/// The sweep's right panel: meridian resolution at the tip and at the junction (`res`:
/// field of view, tip, junction) against the field of view.
fn draw_resolution(
    area: &Area<'_>,
    res: &[(f64, f64, f64)],
    x: std::ops::Range<f64>,
    y_top: f64,
) -> Drawn {
    let (x0, x1) = (x.start, x.end);
    let mut b = ChartBuilder::on(area)
        .caption("meridian resolution (px/mm)", ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(x0..x1, 0f64..y_top)?;
    b.configure_mesh().x_desc("field of view (°)").draw()?;
    for (name, k, idx) in [("tip", 2usize, 1usize), ("junction", 3, 2)] {
        let c = plot::colour(k);
        let pts: Vec<(f64, f64)> = res
            .iter()
            .map(|r| (r.0, if idx == 1 { r.1 } else { r.2 }))
            .collect();
        b.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        b.draw_series(pts.iter().map(|&q| Circle::new(q, 3, c.filled())))?;
    }
    plot::legend(&mut b, SeriesLabelPosition::MiddleRight)?;
    Ok(())
}
