//! Stage 3, camera: each pixel's lens ray (the same lens model as [`crate::sensor`]) crosses
//! the transparent rigid shell and the gel, and meets the painted skin where the gel ends.
//! The skin lies at inward depth h(s, phi) below the finger's surface; along the ray the
//! point's own depth D(t) falls from T (inner shell) to 0 (outer surface), so the skin is the
//! first t where D(t) - h(coord(t)) turns negative: `ray_steps` uniform steps bracket it and
//! bisection refines it. A grazing ray simply spends its steps over a longer stretch of shell.
//! CPU mirror of `shaders/camera.wgsl` (same names) and of the rays' probes
//! (`shaders/shared/probes.wgsl`).

use super::elastomer::{bilinear_taps, sample_field};
use super::HeightfieldGrid;
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
