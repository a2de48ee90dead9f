//! Stage 3, camera: each pixel's lens ray (the same lens model as [`crate::sensor`]) crosses
//! the transparent rigid shell and the gel, and meets the painted skin where the gel ends.
//! The skin lies at inward depth h(s, phi) below the finger's surface; along the ray the
//! point's own depth D(t) falls from T (inner shell) to 0 (outer surface), so the skin is the
//! first t where D(t) - h(coord(t)) turns negative: `ray_steps` uniform steps bracket it and
//! bisection refines it. A grazing ray simply spends its steps over a longer stretch of shell.
//! CPU mirror of `shaders/camera.wgsl` (same names).

use super::elastomer::{bilinear_taps, sample_field};
use super::{HeightfieldGrid, Rect};
use crate::finger::{Finger, SurfaceCoord};
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};

/// Skin moved less than this (mm) along a ray's stretch of shell is not marched: the surface
/// point pushed in along its normal stands for the crossing.
pub const SHALLOW_MM: f64 = 0.02;

/// Points along a ray's stretch of shell where the skin is probed before marching.
pub const UNTOUCHED_PROBES: u32 = 3;

/// Bisection steps after the march has bracketed the skin (then one secant step).
pub const BISECTION_STEPS: u32 = 6;

/// What a pixel's ray meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkinHit {
    /// The (deformed) skin point.
    pub point: DVec3,
    /// Outward normal of the deformed skin.
    pub normal: DVec3,
    /// Inward displacement of the skin there (mm).
    pub indentation: f64,
    /// Unit ray direction from the camera.
    pub ray: DVec3,
}

/// Distance along `dir` to the finger's surface grown by `offset` mm (negative: the inner
/// face of a shell `-offset` thick).
pub fn capsule_hit(finger: &Finger, dir: DVec3, offset: f64) -> Option<f64> {
    let grown = Finger {
        radius: finger.radius + offset,
        ..*finger
    };
    grown.ray_hit(dir).map(|(t, _)| t)
}

/// The skin's inward displacement at surface coordinates `coord`.
pub fn height_at(grid: &HeightfieldGrid, height: &[f32], coord: SurfaceCoord) -> f64 {
    sample_field(height, grid.texels, grid.texel_of(coord.to_disc()))
}

/// Point of the deformed skin over disc position `disc`: S(u) - h(u) n(u).
fn skin_at(finger: &Finger, grid: &HeightfieldGrid, height: &[f32], disc: DVec2) -> DVec3 {
    let c = SurfaceCoord::from_disc(disc);
    let sp = finger.point_at(c);
    sp.point - height_at(grid, height, c) * sp.normal
}

/// Offsets of the deformed skin's outward normal from the undeformed one, per texel of
/// `rect` (zero elsewhere): central differences of the skin S(u) - h(u) n(u) over one texel
/// on the disc, which has no seam or pole. The camera interpolates these offsets bilinearly,
/// so shading stays smooth across texels (differentiating the bilinear heightfield itself
/// would give a normal that jumps at every texel edge).
pub fn skin_normals(
    finger: &Finger,
    grid: &HeightfieldGrid,
    height: &[f32],
    rect: Rect,
) -> Vec<DVec3> {
    let n = grid.texels as usize;
    let mut out = vec![DVec3::ZERO; n * n];
    let e = grid.texel_mm();
    let (ex, ey) = (DVec2::new(e, 0.0), DVec2::new(0.0, e));
    for j in rect.y..rect.y + rect.h {
        for i in rect.x..rect.x + rect.w {
            let u = grid.texel_centre(i, j);
            let c = SurfaceCoord::from_disc(u);
            if c.s > grid.half_size_mm {
                continue;
            }
            let n0 = finger.point_at(c).normal;
            let dx = skin_at(finger, grid, height, u + ex) - skin_at(finger, grid, height, u - ex);
            let dy = skin_at(finger, grid, height, u + ey) - skin_at(finger, grid, height, u - ey);
            let mut normal = dx.cross(dy).normalize_or_zero();
            if normal.dot(n0) < 0.0 {
                normal = -normal;
            }
            if normal != DVec3::ZERO {
                out[j as usize * n + i as usize] = normal - n0;
            }
        }
    }
    out
}

/// Outward normal of the deformed skin at `coord`: the undeformed normal plus the
/// interpolated offset.
pub fn skin_normal(
    finger: &Finger,
    grid: &HeightfieldGrid,
    normals: &[DVec3],
    coord: SurfaceCoord,
) -> DVec3 {
    let n0 = finger.point_at(coord).normal;
    let offset: DVec3 = bilinear_taps(grid.texels, grid.texel_of(coord.to_disc()))
        .iter()
        .filter_map(|&(i, w)| i.map(|i| normals[i] * w))
        .sum();
    (n0 + offset).try_normalize().unwrap_or(n0)
}

/// Disc positions where the stretch of shell along `dir` is probed for deformation: where
/// the ray enters the gel, where it leaves the highest bulge, and midway (`None` if the ray
/// misses the finger).
pub fn ray_probes(finger: &Finger, dir: DVec3) -> Option<[DVec2; UNTOUCHED_PROBES as usize]> {
    let t_in = capsule_hit(finger, dir, -finger.shell_thickness)?;
    let t_out = capsule_hit(finger, dir, 0.5 * finger.shell_thickness)?;
    Some(std::array::from_fn(|k| {
        let t = t_in + (t_out - t_in) * k as f64 / (UNTOUCHED_PROBES - 1) as f64;
        finger.coord_of(t * dir).to_disc()
    }))
}

/// The largest displacement the probes see.
pub fn probes_depth(grid: &HeightfieldGrid, height: &[f32], probes: &[DVec2]) -> f64 {
    probes
        .iter()
        .map(|&u| sample_field(height, grid.texels, grid.texel_of(u)).abs())
        .fold(0.0, f64::max)
}

/// The pixels of `rect` (indices y * width + x, row by row) whose rays' stretch of shell
/// sees any deformation: the only ones a contact frame re-renders, the rest keep the empty
/// finger's colour. Mirror of `select_touched` (the GPU lists them in no set order).
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

/// Pixels per side of the tiles [`select_tiles`] lists (WGSL `PIXEL_TILE`).
pub const PIXEL_TILE: u32 = 8;

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

/// The skin point a pixel sees, or `None` outside the image or the lens's field of view.
/// Mirror of both of the shader's touched passes: `skin_over_surface` for a ray whose probes
/// see skin moved less than [`SHALLOW_MM`], `march_to_skin` for the others.
pub fn cast_ray(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    height: &[f32],
    normals: &[DVec3],
    pixel: DVec2,
    ray_steps: u32,
) -> Option<SkinHit> {
    let f = &sensor.finger;
    let dir = sensor.ray_direction(pixel)?;
    let t_in = capsule_hit(f, dir, -f.shell_thickness)?;
    // Bulges rise up to half the shell thickness above the surface.
    let t_out = capsule_hit(f, dir, 0.5 * f.shell_thickness)?;
    let gap = |t: f64| {
        let q = t * dir;
        -f.signed_distance(q) - height_at(grid, height, f.coord_of(q))
    };
    let mut t_hit = capsule_hit(f, dir, 0.0)?;
    // Most rays cross untouched skin: then the skin is the surface itself, exactly, with no
    // march (the reference frame is all such rays, so a frame's untouched pixels match it).
    // Over barely moved skin the surface point pushed in along its normal is as good as the
    // march (the true crossing is within depth x tan(incidence), a fraction of a pixel).
    let probes = ray_probes(f, dir)?;
    let deepest = probes_depth(grid, height, &probes);
    if deepest < SHALLOW_MM {
        let surface = t_hit * dir;
        let coord = f.coord_of(surface);
        let indentation = height_at(grid, height, coord);
        return Some(SkinHit {
            point: surface - indentation * f.point_at(coord).normal,
            normal: skin_normal(f, grid, normals, coord),
            indentation,
            ray: dir,
        });
    }
    // Bracket first, refine after (the shader's order: see shaders/camera.wgsl). The gaps at
    // the bracket's ends come from the march: at t_in the ray is on the shell's inner face,
    // T deep, over the first probe.
    let mut bracket = None;
    let mut prev = (
        t_in,
        f.shell_thickness - sample_field(height, grid.texels, grid.texel_of(probes[0])),
    );
    for k in 1..=ray_steps {
        let t = t_in + (t_out - t_in) * k as f64 / ray_steps as f64;
        let g = gap(t);
        if g < 0.0 {
            bracket = Some((prev, (t, g)));
            break;
        }
        prev = (t, g);
    }
    if let Some(((mut lo, mut g_lo), (mut hi, mut g_hi))) = bracket {
        for _ in 0..BISECTION_STEPS {
            let mid = 0.5 * (lo + hi);
            let g = gap(mid);
            if g < 0.0 {
                (hi, g_hi) = (mid, g);
            } else {
                (lo, g_lo) = (mid, g);
            }
        }
        // Secant step inside the last bracket.
        t_hit = lo + (hi - lo) * (g_lo / (g_lo - g_hi).max(1e-12)).clamp(0.0, 1.0);
    }
    let point = t_hit * dir;
    let coord = f.coord_of(point);
    Some(SkinHit {
        point,
        normal: skin_normal(f, grid, normals, coord),
        indentation: height_at(grid, height, coord),
        ray: dir,
    })
}
