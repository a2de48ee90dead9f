//! use shared/common.wgsl
// Stage 2, elastomer: blend the penetration along meridians, then along parallels (kernels
// in surface millimetres), bulge, cap at the shell. Mirror: src/render/elastomer.rs.

const BLEND_TAPS: i32 = 12;

fn sample_penetration(t: vec2<f32>) -> f32 {
    let taps = bilinear_taps(t);
    var v = 0.0;
    for (var k = 0; k < 4; k++) {
        if taps.index[k] >= 0 {
            v += taps.weight[k] * penetration[taps.index[k]];
        }
    }
    return v;
}

fn sample_meridian(t: vec2<f32>) -> vec2<f32> {
    let taps = bilinear_taps(t);
    var v = vec2<f32>(0.0);
    for (var k = 0; k < 4; k++) {
        if taps.index[k] >= 0 {
            v += taps.weight[k] * meridian[taps.index[k]];
        }
    }
    return v;
}

// Gaussian weights at surface offset x for sigma and 2 sigma.
fn blend_weights(x: f32, sigma: f32) -> vec2<f32> {
    let a = x / sigma;
    return vec2<f32>(exp(-0.5 * a * a), exp(-0.125 * a * a));
}

@compute @workgroup_size(8, 8)
fn blend_meridian(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.texel_rect.z || id.y >= frame.texel_rect.w {
        return;
    }
    let i = frame.texel_rect.x + id.x;
    let j = frame.texel_rect.y + id.y;
    let idx = j * sensor.texels + i;
    let sigma = sensor.blend_mm;
    if sigma <= 0.0 {
        meridian[idx] = vec2<f32>(penetration[idx]);
        return;
    }
    let u = texel_centre(i, j);
    var dir = vec2<f32>(1.0, 0.0);
    if length(u) > 0.0 {
        dir = u / length(u);
    }
    let step = 6.0 * sigma / f32(BLEND_TAPS);
    var sum = vec2<f32>(0.0);
    var norm = vec2<f32>(0.0);
    for (var k = -BLEND_TAPS; k <= BLEND_TAPS; k++) {
        let x = f32(k) * step;
        let w = blend_weights(x, sigma);
        sum += w * sample_penetration(texel_of(u + x * dir));
        norm += w;
    }
    meridian[idx] = sum / norm;
}

@compute @workgroup_size(8, 8)
fn blend_azimuth(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.texel_rect.z || id.y >= frame.texel_rect.w {
        return;
    }
    let i = frame.texel_rect.x + id.x;
    let j = frame.texel_rect.y + id.y;
    let idx = j * sensor.texels + i;
    let c = coord_of_disc(texel_centre(i, j));
    let rho = parallel_radius(c.x);
    let sigma = sensor.blend_mm;
    var blend = meridian[idx];
    if sigma > 0.0 && rho > 1e-6 {
        let step = 6.0 * sigma / f32(BLEND_TAPS);
        var sum = vec2<f32>(0.0);
        var norm = vec2<f32>(0.0);
        for (var k = -BLEND_TAPS; k <= BLEND_TAPS; k++) {
            let x = f32(k) * step;
            let w = blend_weights(x, sigma);
            sum += w * sample_meridian(texel_of(disc_of(vec2<f32>(c.x, c.y + x / rho))));
            norm += w;
        }
        blend = sum / norm;
    }
    let p = penetration[idx];
    let t = sensor.shell_thickness;
    if p > t {
        atomicAdd(&counters[0], 1u);
    }
    let pressed = max(p, blend.x);
    height[idx] = clamp(pressed - sensor.bulge * max(blend.y - blend.x, 0.0), -0.5 * t, t);
}
