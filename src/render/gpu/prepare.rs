//! The CPU's half of rendering, which needs no GPU: each contact's pose (its first-touch
//! search), footprint and frame uniform before the GPU runs, and its labels after.

use crate::error::{GeltipError, Result};
use crate::render::contact::{self, Footprint, IndentationLabels};
use crate::render::uniforms::FrameUniform;
use crate::render::Rect;
use crate::render::{elastomer, ContactPose, GroundTruth, HeightfieldGrid, Hold, Press};
use crate::scene::naming_contact;
use crate::sensor::Sensor;
use rayon::prelude::*;

/// What the CPU prepared for one contact of a frame.
pub(super) struct Prepared {
    /// Its frame uniform (the renderer sets the image rect and the noise seed).
    pub uniform: FrameUniform,
    pub press: Press,
    pub pose: ContactPose,
    /// The heightfield texels it moves, presses and blends along meridians, and the pixels
    /// that can see them move; `None` when it touches nothing.
    pub footprint: Option<Footprint>,
}

impl Prepared {
    /// The pixels it can change; `None` when the lens sees none of its footprint.
    pub fn pixel_rect(&self) -> Option<Rect> {
        self.footprint.and_then(|f| f.pixels)
    }

    /// Bytes of its own penetration field: its pressed rect's rows (none without a
    /// footprint).
    pub fn field_bytes(&self, texels: u32) -> u64 {
        self.footprint
            .map_or(0, |f| f.pressed.h as u64 * texels as u64 * 4)
    }

    /// Its labels from its penetration field as read back (over its pressed rect's rows):
    /// all but the mask and the over-press, which come from the frame.
    pub fn labels(&self, sensor: &Sensor, grid: &HeightfieldGrid, field: &[f32]) -> GroundTruth {
        let labels = self
            .footprint
            .map(|f| contact::indentation_labels(&sensor.finger, grid, field, f.pressed));
        ground_truth(sensor, &self.press, &self.pose, labels)
    }
}

/// Frames prepared for the GPU (their contacts' poses, footprints, uniforms): made by a
/// [`Preparer`], rendered by [`super::Renderer::render_prepared`] in one submission. Each
/// frame holds any number of contacts (none: the empty finger).
pub struct PreparedBatch(pub(super) Vec<Vec<Prepared>>);

/// The CPU half of rendering, which needs no GPU: a contact's pose (its first-touch search)
/// and footprint. Cheap to clone; `Send`, so a pipeline can prepare the next batch while
/// the renderer renders this one.
#[derive(Debug, Clone)]
pub struct Preparer {
    pub(super) sensor: Sensor,
    pub(super) grid: HeightfieldGrid,
}

impl Preparer {
    /// Prepares presses for one submission, a frame each (at most
    /// [`super::Renderer::batch_frames`] render in one), side by side on rayon's threads.
    pub fn prepare(&self, presses: &[Press]) -> Result<PreparedBatch> {
        in_order(presses, |p| Ok(vec![prepare(&self.sensor, &self.grid, p)?])).map(PreparedBatch)
    }

    /// Prepares frames of several contacts each (none: the empty finger) for one submission,
    /// a frame each (at most [`super::Renderer::batch_frames`] render in one), side by side
    /// on rayon's threads.
    pub fn prepare_frames(&self, frames: &[Vec<Press>]) -> Result<PreparedBatch> {
        in_order(frames, |presses| {
            presses
                .iter()
                .map(|p| prepare(&self.sensor, &self.grid, p))
                .collect::<Result<Vec<_>>>()
        })
        .map(PreparedBatch)
    }

    /// Prepares frames of several contacts each for one submission, a frame each, leaving
    /// out the rigid poses that do not touch the finger ([`Press::pose_if_touching`]): the
    /// batch, and for each frame the indices (in its list) of the contacts kept. Every
    /// contact of every frame is prepared side by side on rayon's threads; an error names
    /// the contact in its frame (`contacts[1].pose: ...`).
    pub fn prepare_touching(
        &self,
        frames: &[Vec<Press>],
    ) -> Result<(PreparedBatch, Vec<Vec<usize>>)> {
        let contacts: Vec<(usize, usize, &Press)> = frames
            .iter()
            .enumerate()
            .flat_map(|(f, presses)| presses.iter().enumerate().map(move |(k, p)| (f, k, p)))
            .collect();
        let prepared = contacts
            .par_iter()
            .map(|&(f, k, press)| {
                let pose = press
                    .pose_if_touching(&self.sensor)
                    .map_err(|e| naming_contact(e, k))?;
                Ok(pose.map(|pose| (f, k, prepare_posed(&self.sensor, &self.grid, press, pose))))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut batch: Vec<Vec<Prepared>> = frames.iter().map(|_| Vec::new()).collect();
        let mut kept: Vec<Vec<usize>> = frames.iter().map(|_| Vec::new()).collect();
        for (f, k, p) in prepared.into_iter().flatten() {
            batch[f].push(p);
            kept[f].push(k);
        }
        Ok((PreparedBatch(batch), kept))
    }

    /// Prepares the presses of one scene, side by side on rayon's threads (each scan inside
    /// is parallel too, but a contact's own serial steps, such as its first-touch
    /// refinement, are not).
    pub(super) fn prepare_scene(&self, presses: &[Press]) -> Result<Vec<Prepared>> {
        if presses.is_empty() {
            return Err(GeltipError::input("scene", "no contacts to render"));
        }
        presses
            .par_iter()
            .map(|p| prepare(&self.sensor, &self.grid, p))
            .collect()
    }
}

/// The error for a batch of `n` frames, more than a submission of `batch` takes.
pub(super) fn too_many(n: usize, batch: usize) -> GeltipError {
    GeltipError::input(
        "batch",
        format!("{n} frames, at most {batch} a submission (Renderer::set_batch_frames)"),
    )
}

/// Each item of `items` through `f` on rayon's threads, in order; the first item's error in
/// order (not whichever thread failed first), so an error is the same from run to run.
fn in_order<I: Sync, O: Send>(items: &[I], f: impl Fn(&I) -> Result<O> + Sync) -> Result<Vec<O>> {
    let all: Vec<Result<O>> = items.par_iter().map(&f).collect();
    all.into_iter().collect()
}

/// Pose, footprint and frame uniform of one press.
fn prepare(sensor: &Sensor, grid: &HeightfieldGrid, press: &Press) -> Result<Prepared> {
    Ok(prepare_posed(sensor, grid, press, press.pose(sensor)?))
}

/// Footprint and frame uniform of one press placed at `pose`.
fn prepare_posed(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    press: &Press,
    pose: ContactPose,
) -> Prepared {
    let reach = elastomer::blend_reach_mm(&sensor.config.elastomer);
    let footprint = contact::footprint(sensor, grid, &pose, &press.object, reach);
    let max_depth = pose.trace_depth_mm;
    let uniform = FrameUniform::contact(&pose, &press.object, max_depth, footprint, 0);
    Prepared {
        uniform,
        press: press.clone(),
        pose,
        footprint,
    }
}

/// The labels of one press, from its pose and (on the CPU, over its footprint's texels) the
/// contact stage's penetration field; the mask and over-press are filled in after rendering.
fn ground_truth(
    sensor: &Sensor,
    press: &Press,
    pose: &ContactPose,
    labels: Option<IndentationLabels>,
) -> GroundTruth {
    let f = &sensor.finger;
    let (place, azimuth_deg, spin_deg, tilt_deg, tilt_towards_deg) = match press.hold {
        Hold::Surface {
            place,
            azimuth_deg,
            spin_deg,
            tilt_deg,
            tilt_towards_deg,
            ..
        } => (
            place.label(),
            azimuth_deg,
            spin_deg,
            tilt_deg,
            tilt_towards_deg,
        ),
        Hold::Pose { .. } => (
            "pose".to_string(),
            pose.coord.phi.to_degrees(),
            0.0,
            0.0,
            0.0,
        ),
    };
    GroundTruth {
        object: press.object.name().to_string(),
        place,
        point: pose.point,
        pixel: sensor.project(pose.point).map_err(|why| why.to_string()),
        normal: pose.normal,
        depth_mm: pose.depth_mm,
        region: pose.region,
        s_mm: pose.coord.s,
        azimuth_deg,
        spin_deg,
        mask_pixels: 0,
        mask_bbox: None,
        over_pressed: false,
        contact_indentation_mm: contact::penetration(
            pose,
            &press.object,
            &f.point_at(pose.coord),
            pose.trace_depth_mm,
            sensor.config.elastomer.drape_mm,
            contact::TRACE_EPSILON_MM,
        ),
        tilt_deg,
        tilt_towards_deg,
        pose: pose.matrix_row_major(),
        first_touch_offset_mm: pose.first_touch_offset_mm,
        first_touch: pose.first_touch.clone(),
        indentation_reached_mm: labels.as_ref().map_or(0.0, |l| l.reached_mm),
        deepest_point: labels.as_ref().and_then(|l| l.deepest),
        contact_centre: labels.as_ref().and_then(|l| l.centre),
        indented_area_mm2: labels.as_ref().map_or(0.0, |l| l.area_mm2),
    }
}
