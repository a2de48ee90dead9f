//! The imprint's look fitted to contact frames whose contacts are known only roughly
//! (`geltip imprint`): a hidden look comes back from rendered frames, the real AllSight
//! frames (from `../shared/real`, skipped without it) are matched better than by the start
//! look and than by no imprint at all, and bad input is refused on one line.

mod common;

use anyhow::Result;
use common::{real, temp_in};
use geltip::calibrate::imprint::{self, ImprintOptions};
use geltip::evaluate::real::RealSet;
use geltip::jobs::imprint as job;
use geltip::object::{Object, Primitive};
use geltip::render::gpu::Renderer;
use geltip::render::{Place, Press};
use geltip::sensor::{Leds, Sensor};
use std::sync::Arc;

fn sphere(radius: f64, s: f64, azimuth: f64, depth: f64) -> Press {
    let shape = Primitive::Sphere { r: radius };
    let object = Object::Primitive {
        name: shape.to_string(),
        shape,
    };
    Press::at(Arc::new(object), Place::ArcLength(s), azimuth, depth)
}

/// The AllSight preset with a hidden look: an indenter of 4 mm (the fit starts at 6), the
/// gel's tilt shading stronger (relief 3, the preset's 2.1), another blend and bulge. Three frames
/// rendered with it give the look back: the cost falls to a small part of the start's and
/// the radius and relief land near the truth, far nearer than they started.
#[test]
fn a_hidden_look_comes_back_from_rendered_frames() -> Result<()> {
    let start = Sensor::preset("allsight")?;
    let mut hidden = start.config.clone();
    hidden.elastomer.blend_mm = 0.8;
    hidden.elastomer.bulge = 0.5;
    if let Leds::List(list) = &mut hidden.leds {
        for l in list.iter_mut() {
            l.relief = Some(3.0);
        }
    }
    let hidden = Sensor::from_config("hidden", hidden)?;
    let dir = temp_in("imprint-hidden", "set.jsonl");
    let dir = dir.parent().unwrap();
    let mut renderer = Renderer::new(&hidden)?;
    let reference = renderer.reference().to_rgb();
    reference.save(dir.join("ref.png"))?;
    let mut lines = String::new();
    for (k, (s, azimuth, depth)) in [(8.0, 40.0, 1.2), (15.0, 200.0, 1.5), (22.0, 300.0, 1.0)]
        .into_iter()
        .enumerate()
    {
        let (frame, _) = renderer.render(&sphere(4.0, s, azimuth, depth))?;
        frame.to_rgb().save(dir.join(format!("c{k}.png")))?;
        lines.push_str(&format!(
            "{{\"image\": \"c{k}.png\", \"reference\": \"ref.png\", \"contact\": true, \"group\": \"g{k}\"}}\n"
        ));
    }
    let path = dir.join("set.jsonl");
    std::fs::write(&path, lines)?;
    let set = RealSet::read(&path)?;
    let options = ImprintOptions {
        fit_frames: 3,
        iterations: 10,
        ..ImprintOptions::default()
    };
    let (located, skipped) = imprint::locate(&start, &set, options.window_px)?;
    assert_eq!((located.len(), skipped.len()), (3, 0), "{skipped:?}");
    let chosen = imprint::spread(&located, 3, &[]);
    let fit = imprint::fit(&start, &located, &chosen, &options, &|_| {})?;
    let value = |name: &str| {
        fit.values
            .iter()
            .find(|v| v.name == name)
            .map(|v| v.value)
            .unwrap()
    };
    let (radius, relief) = (value("indenter.radius_mm"), value("leds.relief"));
    eprintln!(
        "cost {:.0} -> {:.0}, radius {radius:.2}, relief {relief:.2}, values {:?}",
        fit.cost_before, fit.cost_after, fit.values
    );
    assert!(fit.cost_after < 0.2 * fit.cost_before);
    // Half as far from the truth as the start (6 mm) at most: the camera's blur (the
    // preset's 3.5 px) smears the imprint's edge, which tells the radius.
    assert!((radius - 4.0).abs() < 1.0, "radius {radius}");
    assert!((relief - 3.0).abs() < 0.8, "relief {relief}");
    Ok(())
}

/// The real AllSight contact frames: the preset's look (fitted to other frames of the set)
/// and a look fitted afresh to three frames both match four frames neither saw, inside the
/// window round each imprint, clearly better than no imprint at all (the real reference
/// unchanged), composited over the real reference.
#[test]
fn the_fitted_look_matches_real_imprints_it_did_not_see() -> Result<()> {
    let Some(dir) = real("allsight") else {
        return Ok(());
    };
    let labels = dir.join("labels.json");
    let set = RealSet::read(&labels)?;
    let start = Sensor::preset("allsight")?;
    let options = ImprintOptions {
        fit_frames: 3,
        score_frames: 4,
        iterations: 5,
        place_iterations: 6,
        ..ImprintOptions::default()
    };
    let judged = job::judge(&start, &set, &labels, &options, &|_| {})?;
    let all = judged.rows.last().unwrap();
    let (before, after, none) = (
        all.before.composite.psnr_db(),
        all.after.composite.psnr_db(),
        all.unchanged.psnr_db(),
    );
    eprintln!("{}", job::table(&judged.rows));
    assert!(judged.located.len() >= 380, "{}", judged.located.len());
    assert_eq!(all.frames, 4);
    assert!(
        after > none + 1.0,
        "fitted {after:.2} dB, no imprint {none:.2}"
    );
    assert!(
        before > none + 1.0,
        "preset {before:.2} dB, no imprint {none:.2}"
    );
    // The light alone: the preset's empty finger against the presses' t = 0 frames, over
    // the whole circle (about 32 dB on these sessions) and inside the windows; the render's
    // error is about the light's and the composite's added.
    let (circle, window) = (all.after.light_circle.psnr_db(), all.after.light.psnr_db());
    assert!(circle > 28.0 && window > 25.0, "{circle:.2} / {window:.2}");
    let render = all.after.render.psnr_db();
    let added = -10.0 * (10f64.powf(-window / 10.0) + 10f64.powf(-after / 10.0)).log10();
    assert!(
        (render - added).abs() < 2.0,
        "render {render:.2}, light and composite added {added:.2}"
    );
    // The written sensor file is the fitted look and loads back as it.
    let out = temp_in("imprint-real", "sensor.toml");
    let files = job::write(&judged, out.parent().unwrap())?;
    assert_eq!(files.len(), 4);
    let written = Sensor::load(out.to_str().unwrap())?;
    assert_eq!(written.config, judged.fit.config);
    Ok(())
}

/// A set without contact frames and options that fit nothing are refused on one line each.
#[test]
fn bad_input_is_refused_on_one_line() -> Result<()> {
    let start = Sensor::preset("allsight")?;
    let dir = temp_in("imprint-bad", "set.jsonl");
    let dir = dir.parent().unwrap();
    let reference = Renderer::new(&start)?.reference().to_rgb();
    reference.save(dir.join("ref.png"))?;
    let path = dir.join("set.jsonl");
    std::fs::write(
        &path,
        "{\"image\": \"ref.png\", \"reference\": \"ref.png\", \"contact\": false}\n",
    )?;
    let set = RealSet::read(&path)?;
    let e = job::judge(&start, &set, &path, &ImprintOptions::default(), &|_| {}).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("no contact frame") && !text.contains('\n'),
        "{text}"
    );
    let zero = ImprintOptions {
        fit_frames: 0,
        ..ImprintOptions::default()
    };
    let text = job::judge(&start, &set, &path, &zero, &|_| {})
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("fit-frames") && !text.contains('\n'),
        "{text}"
    );
    let text = "huber"
        .parse::<geltip::calibrate::imprint::Loss>()
        .unwrap_err()
        .to_string();
    assert!(text.contains("loss") && text.contains("huber"), "{text}");
    Ok(())
}
