//! An evaluation's charts: recall and error by group (depth, region), the failure map on the
//! unrolled finger and the precision-recall curves. Each compared detector is a series.

use super::metrics::group_names;
use super::Evaluation;
use crate::error::Result;
use crate::plot;
use crate::sensor::Sensor;
use crate::view;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use serde_json::Value;

/// A detection this far (mm) or farther from its contact is drawn as a large error.
const LARGE_ERROR_MM: f64 = 1.0;

/// The axes a group chart draws on.
type GroupAxes = Cartesian2d<RangedCoordf64, RangedCoordf64>;

/// A chart over `n` groups named by `label`, from 0 to `top` on the y axis.
fn group_chart<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    caption: String,
    (n, label): (usize, &dyn Fn(&f64) -> String),
    (top, y_desc): (f64, &str),
    x_desc: &str,
) -> std::result::Result<ChartContext<'a, SVGBackend<'b>, GroupAxes>, Box<dyn std::error::Error>> {
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 17))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), 0f64..top)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_labels(n)
        .x_label_formatter(label)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(chart)
}

/// Two panels over the groups of `key` (`by_depth`, `by_region`): the share of visible
/// contacts found, and the mean error with a whisker to the 95th percentile.
pub fn by_group(summaries: &[Value], key: &str, order: &[String]) -> Result<String> {
    let groups = group_names(summaries, key, order);
    let n = groups.len().max(1);
    let what = match key {
        "by_depth" => "press depth (mm)".to_string(),
        other => other.trim_start_matches("by_").replace('_', " "),
    };
    let value = |s: &Value, g: &str, path: &[&str]| -> Option<f64> {
        path.iter().fold(&s[key][g], |v, p| &v[*p]).as_f64()
    };
    let top_error = summaries
        .iter()
        .flat_map(|s| {
            groups
                .iter()
                .filter_map(|g| value(s, g, &["error_mm", "p95"]))
        })
        .fold(0.5f64, f64::max)
        * 1.1;
    // A finite axis: a p95 near the largest float would make it infinite, and its ticks
    // endless.
    let top_error = top_error.min(f64::MAX);
    let label = |x: &f64| {
        let i = x.round();
        match groups.get(i as usize) {
            Some(g) if (x - i).abs() < 1e-6 && i >= 0.0 => g.clone(),
            _ => String::new(),
        }
    };
    plot::svg(&format!("by {what}"), (1000, 420), |root| {
        let (left, right) = root.split_horizontally(500);
        let caption = format!("Contacts found, by {what}");
        // Up to 125%: the legend sits above the 100% line.
        let mut recall = group_chart(&left, caption, (n, &label), (125.0, "found (%)"), &what)?;
        let caption = format!("Error by {what} (mean, whisker to p95)");
        let mut error = group_chart(
            &right,
            caption,
            (n, &label),
            (top_error, "error (mm)"),
            &what,
        )?;
        let count = summaries.len() as f64;
        for (k, s) in summaries.iter().enumerate() {
            let c = plot::colour(k);
            let dx = (k as f64 - (count - 1.0) / 2.0) * 0.15;
            let rates: Vec<(f64, f64)> = groups
                .iter()
                .enumerate()
                .filter_map(|(i, g)| Some((i as f64 + dx, 100.0 * value(s, g, &["recall"])?)))
                .collect();
            recall
                .draw_series(LineSeries::new(rates.clone(), c.stroke_width(2)))?
                .label(s["detector"].as_str().unwrap_or("?").to_string())
                .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
            recall.draw_series(rates.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
            error.draw_series(groups.iter().enumerate().filter_map(|(i, g)| {
                let mean = value(s, g, &["error_mm", "mean"])?;
                let p95 = value(s, g, &["error_mm", "p95"]).unwrap_or(mean);
                Some(ErrorBar::new_vertical(
                    i as f64 + dx,
                    mean,
                    mean,
                    p95,
                    c.filled(),
                    8,
                ))
            }))?;
        }
        plot::legend(&mut recall, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
}

/// Where a run's contacts and false positives are on the unrolled finger: (azimuth in
/// degrees, arc length from the tip in mm).
#[derive(Default)]
struct Marks {
    good: Vec<(f64, f64)>,
    large: Vec<(f64, f64)>,
    missed: Vec<(f64, f64)>,
    false_positives: Vec<(f64, f64)>,
}

impl Marks {
    fn of(eval: &Evaluation, sensor: &Sensor) -> Marks {
        let s_top = view::finger_length(sensor);
        let mut marks = Marks::default();
        for f in &eval.frames {
            for (i, c) in f.truth.contacts.iter().enumerate() {
                if !c.visible {
                    continue;
                }
                // On the drawn finger, as false positives are: labels read from a file may
                // put a contact anywhere.
                let at = (c.azimuth_deg.rem_euclid(360.0), c.s_mm.clamp(0.0, s_top));
                match f.score.matches.iter().find(|m| m.contact == i) {
                    Some(m) if m.error_mm >= LARGE_ERROR_MM => marks.large.push(at),
                    Some(_) => marks.good.push(at),
                    None => marks.missed.push(at),
                }
            }
            for &j in &f.score.false_positives {
                if let Some(p) = f.found[j].point {
                    let sc = sensor.finger.coord_of(p);
                    let az = sc.phi.to_degrees().rem_euclid(360.0);
                    marks.false_positives.push((az, sc.s.min(s_top)));
                }
            }
        }
        marks
    }
}

/// The unrolled finger (azimuth across, arc length from the tip down): each visible contact
/// where it is, green when found well, orange when found with an error of 1 mm or more, a
/// red cross when missed; false positives as grey pluses where they were placed.
pub fn failure_map(eval: &Evaluation, sensor: &Sensor) -> Result<String> {
    let s_top = view::finger_length(sensor);
    let finger = &sensor.finger;
    let Marks {
        good,
        large,
        missed,
        false_positives,
    } = Marks::of(eval, sensor);
    let title = format!(
        "{}: where contacts were missed (×) or found 1 mm or more off (orange)",
        eval.detector
    );
    plot::svg("failure map", (760, 560), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 15))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0f64..360f64, s_top..0f64)?;
        chart
            .configure_mesh()
            .x_desc("azimuth (°)")
            .y_desc("arc length from the tip (mm)")
            .draw()?;
        let sj = finger.junction_s();
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.0, sj), (360.0, sj)],
            plot::REFERENCE_GREY,
        )))?;
        let edge: Vec<(f64, f64)> = (0..=72)
            .map(|k| {
                let az = 5.0 * k as f64;
                (az, view::visible_extent(sensor, az.to_radians()))
            })
            .collect();
        chart
            .draw_series(LineSeries::new(edge, BLACK.stroke_width(1)))?
            .label("lens edge")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
        let green = RGBColor(44, 160, 44);
        let orange = RGBColor(255, 127, 14);
        let red = RGBColor(214, 39, 40);
        chart
            .draw_series(good.iter().map(|&p| Circle::new(p, 2, green.filled())))?
            .label(format!("found ({})", good.len()))
            .legend(move |(x, y)| Circle::new((x, y), 3, green.filled()));
        chart
            .draw_series(large.iter().map(|&p| Circle::new(p, 4, orange.filled())))?
            .label(format!(
                "found, ≥ {LARGE_ERROR_MM} mm off ({})",
                large.len()
            ))
            .legend(move |(x, y)| Circle::new((x, y), 4, orange.filled()));
        chart
            .draw_series(
                missed
                    .iter()
                    .map(|&p| Cross::new(p, 4, red.stroke_width(2))),
            )?
            .label(format!("missed ({})", missed.len()))
            .legend(move |(x, y)| Cross::new((x, y), 4, red.stroke_width(2)));
        chart
            .draw_series(false_positives.iter().map(|&(x, y)| {
                PathElement::new(vec![(x - 2.0, y), (x + 2.0, y)], plot::REFERENCE_GREY)
            }))?
            .label(format!("false positives ({})", false_positives.len()))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 10, y)], plot::REFERENCE_GREY));
        plot::legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        Ok(())
    })
}

/// Precision against recall over the confidence thresholds, a curve per detector.
pub fn precision_recall(summaries: &[Value]) -> Result<String> {
    plot::svg("precision-recall", (560, 460), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Precision against recall (confidence thresholds)",
                ("sans-serif", 17),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0f64..1.02f64, 0f64..1.02f64)?;
        chart
            .configure_mesh()
            .x_desc("recall")
            .y_desc("precision")
            .draw()?;
        for (k, s) in summaries.iter().enumerate() {
            let c = plot::colour(k);
            let points: Vec<(f64, f64)> = s["precision_recall"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|p| Some((p[2].as_f64()?, p[1].as_f64()?)))
                        .collect()
                })
                .unwrap_or_default();
            let ap = s["average_precision"]
                .as_f64()
                .map(|a| format!(" (AP {a:.3})"))
                .unwrap_or_default();
            chart
                .draw_series(LineSeries::new(points.clone(), c.stroke_width(2)))?
                .label(format!("{}{ap}", s["detector"].as_str().unwrap_or("?")))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                });
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 2, c.filled())))?;
        }
        plot::legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
        Ok(())
    })
}

/// A real set's groups as bars: per group, the share of contact frames found, of those
/// labelled with an azimuth found at it, and of the no-contact frames called contacts (a
/// group without such frames has no bar of that kind).
pub fn real_by_group(report: &super::RealReport) -> Result<String> {
    let rows = &report.rows;
    let n = rows.len().max(1);
    let label = |x: &f64| {
        let i = x.round();
        match rows.get(i as usize) {
            Some(r) if (x - i).abs() < 1e-6 && i >= 0.0 => r.group.clone(),
            _ => String::new(),
        }
    };
    fn share(a: usize, n: usize) -> Option<f64> {
        (n > 0).then(|| 100.0 * a as f64 / n as f64)
    }
    type Share = fn(&super::real::RealRow) -> Option<f64>;
    let kinds: [(&str, Share); 3] = [
        ("contacts found", |r| share(r.found, r.contacts)),
        ("at the labelled azimuth", |r| {
            share(r.at_azimuth, r.with_azimuth)
        }),
        ("no-contact frames called contacts", |r| {
            share(r.false_contacts, r.empty)
        }),
    ];
    let width = (160 + 70 * n as u32).max(700);
    plot::svg("real frames by group", (width, 440), |root| {
        let caption = format!("{} on real frames, by group", report.detector);
        let mut chart = group_chart(root, caption, (n, &label), (125.0, "frames (%)"), "group")?;
        for (k, (name, value)) in kinds.iter().enumerate() {
            let c = plot::colour(k);
            let dx = (k as f64 - 1.0) * 0.27;
            let bars: Vec<Rectangle<(f64, f64)>> = rows
                .iter()
                .enumerate()
                .filter_map(|(i, r)| {
                    let v = value(r)?;
                    let x = i as f64 + dx;
                    Some(Rectangle::new([(x - 0.12, 0.0), (x + 0.12, v)], c.filled()))
                })
                .collect();
            chart
                .draw_series(bars)?
                .label(*name)
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], c.filled()));
        }
        plot::legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
}
