//! use shared/common.wgsl
// The probes of each pixel's lens ray, as the reference frame keeps them (camera.wgsl
// camera): the disc positions where the ray's stretch of shell is probed for deformation,
// its ends and middle, and where it enters the gel and leaves the highest bulge (t_in, t_out
// along the ray). The selection of touched pixels (touched.wgsl) reads how far the skin
// moved over them; the march (camera.wgsl camera_deep) starts from them. Mirror:
// src/render/camera.rs ray_probes, probes_depth, UNTOUCHED_PROBES.

struct Probes {
    a: vec2<f32>,
    b: vec2<f32>,
    c: vec2<f32>,
    t_in: f32,
    t_out: f32,
}

// The probes the reference frame kept for pixel (x, y): two texels of the probe map,
// (a, b) and (c, t_in, t_out); t_in is 0 where the lens sees nothing (a seen pixel's ray
// enters the gel some way from the camera).
fn load_probes(x: u32, y: u32) -> Probes {
    let p0 = textureLoad(probe_map, vec2<u32>(2u * x, y), 0);
    let p1 = textureLoad(probe_map, vec2<u32>(2u * x + 1u, y), 0);
    return Probes(p0.xy, p0.zw, p1.xy, p1.z, p1.w);
}

fn height_at_disc(u: vec2<f32>) -> f32 {
    return sample_map_x(height_map, texel_of(u));
}

// The largest displacement the probes see.
fn probes_depth(p: Probes) -> f32 {
    return max(abs(height_at_disc(p.a)), max(abs(height_at_disc(p.b)), abs(height_at_disc(p.c))));
}

// Skin moved less than this (mm) along a ray's stretch of shell is not marched: the surface
// point pushed in along its normal stands for the crossing. Mirror: src/render/camera.rs
// SHALLOW_MM.
const SHALLOW_MM: f32 = 0.02;
