//! `Simulator.render_scenes`: frames of several contacts each, rendered on the Simulator's
//! render streams, each frame written straight into the NumPy arrays returned.

use crate::batch::Outputs;
use crate::contact::specs_of;
use crate::convert::repr;
use crate::errors::bad;
use crate::simulator::Simulator;
use geltip::render::gpu::Renderer;
use geltip::render::{scene_labels, Press};
use geltip::scene::ContactSpec;
use geltip::GeltipError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A list of scenes, each a list of contact dicts, as specs; errors name the scene
/// (`scenes[2]: contacts[1].depth: ...`).
pub fn specs_of_scenes(scenes: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<ContactSpec>>> {
    let iter = scenes.try_iter().map_err(|_| {
        bad(
            "scenes",
            format!("expected a list of lists of dicts, got {}", repr(scenes)),
        )
    })?;
    let mut frames = Vec::new();
    for (i, scene) in iter.enumerate() {
        let scene = scene?;
        let specs = specs_of(&scene).map_err(|e| {
            Python::attach(|py| bad(format!("scenes[{i}]"), e.value(py).to_string()))
        })?;
        frames.push(specs);
    }
    Ok(frames)
}

/// Renders `frames` into `outputs`: `(images, [labels], depth maps or None)`, each labels
/// `render_scene`'s plus, when skipping, the indices of the contacts left out.
pub fn render<'py>(
    py: Python<'py>,
    sim: &Simulator,
    frames: &[Vec<ContactSpec>],
    skip_untouching: bool,
    outputs: Outputs<'py>,
) -> PyResult<Bound<'py, PyTuple>> {
    // Every contact is checked before any frame renders (and placed on the finger, unless
    // contacts that do not touch are skipped), so that an error names its scene.
    let presses = || {
        let mut presses = Vec::with_capacity(frames.len());
        for (i, specs) in frames.iter().enumerate() {
            let scene = sim
                .presses(specs, !skip_untouching)
                .map_err(|e| GeltipError::input(format!("scenes[{i}]"), e.to_string()))?;
            presses.push(scene);
        }
        Ok(presses)
    };
    let labels = outputs.render(
        py,
        sim,
        "rendering scenes",
        presses,
        |r, first, chunk: &[Vec<Press>]| {
            let rendered = r
                .render_scenes(chunk, skip_untouching)
                .map_err(|e| name_scene(r, first, chunk, e))?;
            Ok(rendered
                .into_iter()
                .zip(chunk)
                .map(|((frame, kept), contacts)| {
                    let truths: Vec<_> = kept.iter().map(|(_, t)| t.clone()).collect();
                    let mut labels = scene_labels(&frame, &truths);
                    if skip_untouching {
                        let untouched: Vec<usize> = (0..contacts.len())
                            .filter(|k| !kept.iter().any(|(i, _)| i == k))
                            .collect();
                        labels["untouched"] = serde_json::json!(untouched);
                    }
                    (frame, labels)
                })
                .collect())
        },
    )?;
    outputs.with_labels(py, labels)
}

/// An error rendering a submission of scenes, named by the scene whose contacts cannot be
/// placed (found by preparing them one by one, on the error's path only); a GPU error as it
/// is.
fn name_scene(r: &Renderer, first: usize, chunk: &[Vec<Press>], e: GeltipError) -> GeltipError {
    let preparer = r.preparer();
    for (j, frame) in chunk.iter().enumerate() {
        if let Err(why) = preparer.prepare_touching(std::slice::from_ref(frame)) {
            return GeltipError::input(format!("scenes[{}]", first + j), why.to_string());
        }
    }
    e
}
