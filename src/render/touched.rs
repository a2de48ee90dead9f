//! The touched pixels of a contact frame: the pixels whose rays' stretch of shell sees any
//! deformation, the only ones the camera casts and shades again (the rest keep the empty
//! finger's colour). The GPU tests only the pixels of the tiles whose probes read a displaced
//! texel. CPU mirror of `shaders/touched.wgsl` (same names).

use super::camera::{probes_depth, ray_probes};
use super::{HeightfieldGrid, Rect};
use crate::sensor::Sensor;
use glam::DVec2;

/// The pixels of `rect` (indices y * width + x, row by row) whose rays' stretch of shell
/// sees any deformation: the only ones a contact frame re-renders, the rest keep the empty
/// finger's colour. Mirror of `list_if_touched` over every pixel of `rect` (the GPU tests
/// only the pixels of the tiles [`select_tiles`] keeps, and lists them in no set order).
pub fn select_touched(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    height: &[f32],
    rect: Rect,
) -> Vec<u32> {
    let mut touched = Vec::new();
    for y in rect.y..rect.y + rect.h {
        for x in rect.x..rect.x + rect.w {
            let Some(dir) = sensor.ray_direction(DVec2::new(x as f64, y as f64)) else {
                continue;
            };
            let Some(probes) = ray_probes(&sensor.finger, dir) else {
                continue;
            };
            if probes_depth(grid, height, &probes) > 0.0 {
                touched.push(y * sensor.width + x);
            }
        }
    }
    touched
}

/// Pixels per side of the tiles [`select_tiles`] lists.
pub use super::gpu::layout::PIXEL_TILE;

/// Texels x0..=x1 by y0..=y1 as `[x0, y0, x1, y1]`; empty when x0 > x1.
pub type TexelRange = [i64; 4];

/// Tiles across and down an image `width` x `height` (the last ones may be partial).
pub fn tile_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(PIXEL_TILE), height.div_ceil(PIXEL_TILE))
}

/// The columns and rows of the image's tiles that `rect` overlaps (empty for an empty rect).
pub fn tiles_over(rect: Rect) -> (std::ops::Range<u32>, std::ops::Range<u32>) {
    if rect.w == 0 || rect.h == 0 {
        return (0..0, 0..0);
    }
    let span = |lo: u32, len: u32| lo / PIXEL_TILE..(lo + len - 1) / PIXEL_TILE + 1;
    (span(rect.x, rect.w), span(rect.y, rect.h))
}

/// Per tile of [`PIXEL_TILE`]^2 pixels (row by row on the image's grid), for each of its rays'
/// probes (in [`ray_probes`]' order), the texels the bilinear samples of the tile's seen
/// pixels read, within the grid. Mirror of `probe_tiles_of_rays` (which reads the GPU's
/// own f32 probes).
pub fn probe_tiles(sensor: &Sensor, grid: &HeightfieldGrid) -> Vec<[TexelRange; 3]> {
    let (across, down) = tile_grid(sensor.width, sensor.height);
    let top = grid.texels as i64 - 1;
    (0..across * down)
        .map(|tile| {
            let (x0, y0) = ((tile % across) * PIXEL_TILE, (tile / across) * PIXEL_TILE);
            let mut ranges = [[i64::MAX, i64::MAX, i64::MIN, i64::MIN]; 3];
            for y in y0..(y0 + PIXEL_TILE).min(sensor.height) {
                for x in x0..(x0 + PIXEL_TILE).min(sensor.width) {
                    let Some(dir) = sensor.ray_direction(DVec2::new(x as f64, y as f64)) else {
                        continue;
                    };
                    let Some(probes) = ray_probes(&sensor.finger, dir) else {
                        continue;
                    };
                    for (r, u) in ranges.iter_mut().zip(probes) {
                        let base = (grid.texel_of(u) - 0.5).floor();
                        let (i, j) = (base.x as i64, base.y as i64);
                        *r = [r[0].min(i), r[1].min(j), r[2].max(i + 1), r[3].max(j + 1)];
                    }
                }
            }
            ranges.map(|r| {
                if r[0] > r[2] {
                    [1, 1, 0, 0]
                } else {
                    [
                        r[0].clamp(0, top),
                        r[1].clamp(0, top),
                        r[2].clamp(0, top),
                        r[3].clamp(0, top),
                    ]
                }
            })
        })
        .collect()
}

/// The tiles (indices into `tiles`, from [`probe_tiles`]) overlapping `pixel_rect` whose
/// probes read a displaced texel of `texel_rect` (the height is zero outside it): every
/// pixel [`select_touched`] lists lies in one of them. Mirror of `select_tiles` (which reads
/// the ranges a 2x2 block at a time, so it may keep a tile more).
pub fn select_tiles(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    height: &[f32],
    tiles: &[[TexelRange; 3]],
    pixel_rect: Rect,
    texel_rect: Rect,
) -> Vec<u32> {
    let (across, _) = tile_grid(sensor.width, sensor.height);
    let n = grid.texels as i64;
    let moved = |r: TexelRange| {
        let (x0, y0) = (r[0].max(texel_rect.x as i64), r[1].max(texel_rect.y as i64));
        let x1 = r[2].min((texel_rect.x + texel_rect.w) as i64 - 1);
        let y1 = r[3].min((texel_rect.y + texel_rect.h) as i64 - 1);
        (y0..=y1).any(|j| (x0..=x1).any(|i| height[(j * n + i) as usize] != 0.0))
    };
    let mut listed = Vec::new();
    let (columns, rows) = tiles_over(pixel_rect);
    for ty in rows {
        for tx in columns.clone() {
            let tile = ty * across + tx;
            if tiles[tile as usize].iter().any(|&r| moved(r)) {
                listed.push(tile);
            }
        }
    }
    listed
}
