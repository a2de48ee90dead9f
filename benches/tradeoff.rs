//! Speed against accuracy for the renderer's knobs (heightfield texels, ray steps), at the
//! paper sensor's 640x480: `cargo bench --bench tradeoff`. Prints a table and writes the
//! chart to docs/images/tradeoff.svg.
//!
//! Accuracy is measured against a render with every knob turned far up (1024 texels, 48 ray
//! steps) of the same eight contacts (one per tap position of the paper, seven solids):
//! the mean absolute difference of the 8-bit channels inside the re-rendered region, and the
//! mean error of the indentation map (mm) where either render is pressed.

use geltip::jobs::experiment::{self, Protocol};
use geltip::object::Solid;
use geltip::render::gpu::Renderer;
use geltip::render::{Frame, Press};
use geltip::sensor::Sensor;
use plotters::prelude::*;
use std::time::Instant;

/// One contact per tap position of the paper, each with another of the seven solids.
fn contacts() -> Vec<Press> {
    (0..experiment::POSITIONS.len())
        .map(|i| {
            experiment::taps(Solid::ALL[i % Solid::ALL.len()], &Protocol::default())[i].clone()
        })
        .collect()
}

fn sensor(texels: u32, steps: u32) -> anyhow::Result<Sensor> {
    let mut c = Sensor::preset("paper")?.config;
    c.render.heightfield_texels = texels;
    c.render.ray_steps = steps;
    Ok(Sensor::from_config(format!("paper-{texels}-{steps}"), c)?)
}

/// (mean abs channel difference over pixels that differ from the reference in either,
/// mean indentation error in mm over pixels pressed in either).
fn error(a: &Frame, b: &Frame, reference: &Frame) -> (f64, f64) {
    let (mut px_sum, mut px_n, mut mm_sum, mut mm_n) = (0.0, 0usize, 0.0, 0usize);
    for i in 0..(a.width * a.height) as usize {
        let changed = (0..3).any(|c| {
            a.rgba[i * 4 + c] != reference.rgba[i * 4 + c]
                || b.rgba[i * 4 + c] != reference.rgba[i * 4 + c]
        });
        if changed {
            for c in 0..3 {
                px_sum += a.rgba[i * 4 + c].abs_diff(b.rgba[i * 4 + c]) as f64;
            }
            px_n += 3;
        }
        if a.indentation[i] > 0.01 || b.indentation[i] > 0.01 {
            mm_sum += (a.indentation[i] - b.indentation[i]).abs() as f64;
            mm_n += 1;
        }
    }
    (px_sum / px_n.max(1) as f64, mm_sum / mm_n.max(1) as f64)
}

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    let list = contacts();
    let mut best = Renderer::new(&sensor(1024, 48)?)?;
    let truth: Vec<Frame> = best
        .render_batch(&list)?
        .into_iter()
        .map(|(f, _)| f)
        .collect();
    println!(
        "geltip speed/accuracy: paper sensor 640x480, {} contacts, adapter {}",
        list.len(),
        best.adapter().name
    );
    println!(
        "| texels | ray steps | fps | mean abs error (8-bit levels) | indentation error (mm) |"
    );
    println!("|---|---|---|---|---|");
    let mut rows = Vec::new();
    for texels in [128, 192, 256, 384, 512] {
        for steps in [4, 8, 16] {
            let (fps, px, mm) = measure(&list, &truth, texels, steps)?;
            println!("| {texels} | {steps} | {fps:.1} | {px:.2} | {mm:.4} |");
            rows.push((texels, steps, fps, px));
        }
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/images/tradeoff.svg");
    write_chart(path, &rows)?;
    println!("chart: docs/images/tradeoff.svg (points labelled with heightfield texels)");
    Ok(())
}

/// One configuration's (fps, mean abs error in 8-bit levels, indentation error in mm)
/// against `truth`, the high-resolution renders of `list`.
fn measure(
    list: &[Press],
    truth: &[Frame],
    texels: u32,
    steps: u32,
) -> anyhow::Result<(f64, f64, f64)> {
    let mut r = Renderer::new(&sensor(texels, steps)?)?;
    // Accuracy from one render of each contact (also the warm-up: renders are
    // deterministic).
    let (mut px, mut mm) = (0.0, 0.0);
    for (c, t) in list.iter().zip(truth) {
        let (f, _) = r.render(c)?;
        let (a, b) = error(&f, t, r.reference());
        px += a / list.len() as f64;
        mm += b / list.len() as f64;
    }
    // Speed: one contact per submit, as the render bench's headline row; the median
    // of seven rounds (these machines are shared and noisy).
    let mut round_fps = Vec::new();
    for _ in 0..7 {
        let start = Instant::now();
        for c in list {
            r.render(c)?;
        }
        round_fps.push(list.len() as f64 / start.elapsed().as_secs_f64());
    }
    round_fps.sort_by(f64::total_cmp);
    Ok((round_fps[round_fps.len() / 2], px, mm))
}

/// The chart of `rows` (texels, ray steps, fps, mean abs error) written to `path`: one
/// line per ray-step count, points labelled with their texels.
fn write_chart(path: &str, rows: &[(u32, u32, f64, f64)]) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (760, 460)).into_drawing_area();
    root.fill(&WHITE)?;
    let max_fps = rows.iter().map(|r| r.2).fold(1.0, f64::max) * 1.1;
    let max_err = rows.iter().map(|r| r.3).fold(0.1, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Renderer: speed against accuracy (lavapipe, 640x480)",
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0f64..max_fps, 0f64..max_err)?;
    chart
        .configure_mesh()
        .x_desc("frames per second (one contact per submit)")
        .y_desc("mean abs error vs 1024 texels / 48 steps (8-bit levels)")
        .draw()?;
    // The speed target: 100 fps full frame on 2-core lavapipe.
    if max_fps > 100.0 {
        chart.draw_series(LineSeries::new(
            vec![(100.0, 0.0), (100.0, max_err)],
            BLACK.mix(0.4).stroke_width(1),
        ))?;
        chart.draw_series(std::iter::once(Text::new(
            "100 fps",
            (101.0, max_err * 0.97),
            ("sans-serif", 11),
        )))?;
    }
    let colours = [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
    ];
    for (k, steps) in [4u32, 8, 16].into_iter().enumerate() {
        let c = colours[k];
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.1 == steps)
            .map(|r| (r.2, r.3))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
            .label(format!("{steps} ray steps"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
        for r in rows.iter().filter(|r| r.1 == steps) {
            chart.draw_series(std::iter::once(Text::new(
                format!("{}", r.0),
                (r.2, r.3),
                ("sans-serif", 11),
            )))?;
        }
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    root.present()?;
    Ok(())
}
