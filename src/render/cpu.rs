//! The whole pipeline on the CPU, stage by stage, from the CPU mirrors: slow (seconds per
//! frame) but independent of any GPU, so tests can hold the GPU renderer to it.

use super::softness::Softness;
use super::{camera, contact, elastomer, leds, touched, Frame, HeightfieldGrid, Press, Rect};
use crate::error::Result;
use crate::sensor::Sensor;
use glam::DVec2;
use rayon::prelude::*;

/// Everything the CPU pipeline computed for one frame.
#[derive(Debug, Clone)]
pub struct CpuRender {
    /// The frame as the camera records it (its softness applied, `[camera] blur_px`).
    pub frame: Frame,
    /// The frame's pixels before the camera's softness, where it has one ([`CpuRender::raw`]
    /// gives them either way).
    soft_from: Option<Frame>,
    /// The skin's displacement on the heightfield.
    pub height: Vec<f32>,
    pub penetration: Vec<f32>,
    /// Texels pressed beyond the shell.
    pub over_pressed_texels: u32,
    pub texel_rect: Option<Rect>,
    pub pixel_rect: Option<Rect>,
}

impl CpuRender {
    /// The frame's pixels before the camera's softness (the frame itself without one): what
    /// [`render_contact`] builds a contact on.
    pub fn raw(&self) -> &Frame {
        self.soft_from.as_ref().unwrap_or(&self.frame)
    }

    /// [`CpuRender::raw`], kept.
    pub fn into_raw(self) -> Frame {
        self.soft_from.unwrap_or(self.frame)
    }
}

/// Renders `contact` (or the empty finger) with the CPU mirrors, over the whole image.
pub fn render(sensor: &Sensor, contact: Option<&Press>) -> Result<CpuRender> {
    let grid = HeightfieldGrid::for_sensor(sensor);
    let n = grid.texels as usize;
    let (mut penetration, mut height, mut over, mut footprint) =
        (vec![0.0; n * n], vec![0.0; n * n], 0, None);
    let mut normals = vec![glam::DVec3::ZERO; n * n];
    if let Some(c) = contact {
        let pose = c.pose(sensor)?;
        let config = &sensor.config.elastomer;
        let kernel = elastomer::Kernel::for_config(&sensor.config, &grid);
        footprint = contact::footprint(sensor, &grid, &pose, &c.object, kernel.reach_mm);
        if let Some(rect) = footprint.map(|f| f.texels) {
            penetration = contact::penetration_field(sensor, &grid, &pose, &c.object, rect);
            let meridian = elastomer::blend_meridian(&grid, config, kernel, &penetration, rect);
            let (h, o) = elastomer::blend_azimuth(
                &sensor.finger,
                &grid,
                config,
                kernel,
                &penetration,
                &meridian,
                rect,
            );
            normals = elastomer::skin_normals(&sensor.finger, &grid, &h, rect);
            height = h;
            over = o;
        }
    }
    let (w, h) = (sensor.width, sensor.height);
    let mut rgba = vec![0u8; (w * h * 4) as usize];
    let mut indentation = vec![0.0f32; (w * h) as usize];
    let noise = sensor.config.render.noise.rgb();
    let seed = sensor.config.render.noise_seed;
    let light = sensor.lighting();
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            rgba[i * 4 + 3] = 255;
            let Some(hit) = camera::cast_ray(
                sensor,
                &grid,
                &height,
                &normals,
                DVec2::new(x as f64, y as f64),
                sensor.config.render.ray_steps,
            ) else {
                continue;
            };
            let pixel = DVec2::new(x as f64, y as f64);
            let colour = leds::pixel_colour(sensor, &light, pixel, &hit);
            let samples = leds::noise_samples(i as u32, seed);
            for (ch, level) in colour.into_iter().enumerate() {
                rgba[i * 4 + ch] = if noise[ch] > 0.0 {
                    leds::add_noise(level, noise[ch] * samples[ch])
                } else {
                    level
                };
            }
            indentation[i] = hit.indentation as f32;
        }
    }

    let raw = Frame {
        width: w,
        height: h,
        rgba,
        indentation,
    };
    let (frame, soft_from) = match Softness::of(sensor) {
        Some(softness) => (softness.soften_frame(&raw), Some(raw)),
        None => (raw, None),
    };
    Ok(CpuRender {
        frame,
        soft_from,
        height,
        penetration,
        over_pressed_texels: over,
        texel_rect: footprint.map(|f| f.texels),
        pixel_rect: footprint.and_then(|f| f.pixels),
    })
}

/// A contact frame made the way the GPU renderer makes it, with the CPU mirrors: `reference`
/// (the empty finger before the camera's softness, [`CpuRender::raw`] from [`render`] once)
/// with only the pixels whose rays the deformation reaches cast and shaded again, in
/// parallel on rayon's threads. The alternative a user has to lavapipe on the same cores;
/// `benches/render.rs` times it beside the GPU. Noise-free (the sensor's noise is not added),
/// and before the camera's softness ([`record_contact`] applies it).
pub fn render_contact(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    reference: &Frame,
    contact: &Press,
) -> Result<Frame> {
    Ok(render_contact_over(sensor, grid, reference, contact)?.0)
}

/// [`render_contact`] as the camera records it: `softness` (the sensor's) applied where the
/// contact changed the frame, the rest `soft_reference` (`reference` softened).
pub fn record_contact(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    reference: &Frame,
    soft_reference: &Frame,
    softness: &Softness,
    contact: &Press,
) -> Result<Frame> {
    let (raw, changed) = render_contact_over(sensor, grid, reference, contact)?;
    let mut rgba = soft_reference.rgba.clone();
    if let Some(rect) = changed {
        softness.soften_changed(&raw.rgba, &mut rgba, rect);
    }
    Ok(Frame { rgba, ..raw })
}

/// [`render_contact`] and the pixel rect it may have changed.
fn render_contact_over(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    reference: &Frame,
    contact: &Press,
) -> Result<(Frame, Option<Rect>)> {
    let mut frame = reference.clone();
    let pose = contact.pose(sensor)?;
    let config = &sensor.config.elastomer;
    let kernel = elastomer::Kernel::for_config(&sensor.config, grid);
    let Some(footprint) = contact::footprint(sensor, grid, &pose, &contact.object, kernel.reach_mm)
    else {
        return Ok((frame, None));
    };
    let rect = footprint.texels;
    let penetration = contact::penetration_field(sensor, grid, &pose, &contact.object, rect);
    let meridian = elastomer::blend_meridian(grid, config, kernel, &penetration, rect);
    let (height, _) = elastomer::blend_azimuth(
        &sensor.finger,
        grid,
        config,
        kernel,
        &penetration,
        &meridian,
        rect,
    );
    let normals = elastomer::skin_normals(&sensor.finger, grid, &height, rect);
    let Some(pixels) = footprint.pixels else {
        return Ok((frame, None));
    };
    let w = sensor.width;
    let touched_pixels = touched::select_touched(sensor, grid, &height, pixels);
    let light = sensor.lighting();
    let shaded: Vec<(usize, [u8; 3], f32)> = touched_pixels
        .par_iter()
        .map(|&i| {
            let pixel = DVec2::new((i % w) as f64, (i / w) as f64);
            let steps = sensor.config.render.ray_steps;
            match camera::cast_ray(sensor, grid, &height, &normals, pixel, steps) {
                Some(hit) => {
                    let c = leds::pixel_colour(sensor, &light, pixel, &hit);
                    (i as usize, c, hit.indentation as f32)
                }
                None => (i as usize, [0; 3], 0.0),
            }
        })
        .collect();
    for (i, colour, depth) in shaded {
        frame.rgba[i * 4..i * 4 + 3].copy_from_slice(&colour);
        frame.indentation[i] = depth;
    }
    Ok((frame, Some(pixels)))
}
