//! use shared/common.wgsl
// Stage 2, elastomer: from the penetration p, the skin's drape (max-plus dilation with a
// parabola of radius drape_mm), a narrow Gaussian blend and a wide one for the bulge, each
// as two separable passes along the surface (meridians, then parallels), kernels in surface
// millimetres; then h = max(drape, narrow) - bulge * max(wide - narrow, 0), capped to
// [-T/2, T]. Mirror: src/render/elastomer.rs.

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

fn sample_meridian(t: vec2<f32>) -> vec3<f32> {
    let taps = bilinear_taps(t);
    var v = vec3<f32>(0.0);
    for (var k = 0; k < 4; k++) {
        if taps.index[k] >= 0 {
            v += taps.weight[k] * elastomer_scratch[taps.index[k]].xyz;
        }
    }
    return v;
}

// Accumulates one separable pass.
struct Pass {
    drape: f32,
    narrow: f32,
    narrow_norm: f32,
    wide: f32,
    wide_norm: f32,
}

fn pass_start() -> Pass {
    return Pass(-1e30, 0.0, 0.0, 0.0, 0.0);
}

fn pass_add(acc: ptr<function, Pass>, k: i32, x: f32, v: vec3<f32>) {
    (*acc).drape = max((*acc).drape, v.x - x * x / (2.0 * sensor.drape_mm));
    let sigma = sensor.blend_mm;
    var a = select(0.0, 1.0, k == 0);
    var b = a;
    if sigma > 0.0 {
        let q = x / sigma;
        a = exp(-0.5 * q * q);
        b = exp(-0.125 * q * q);
    }
    (*acc).narrow += a * v.y;
    (*acc).narrow_norm += a;
    (*acc).wide += b * v.z;
    (*acc).wide_norm += b;
}

fn pass_result(acc: Pass) -> vec3<f32> {
    return vec3<f32>(acc.drape, acc.narrow / acc.narrow_norm, acc.wide / acc.wide_norm);
}

@compute @workgroup_size(8, 8)
fn blend_meridian(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.texel_rect.z || id.y >= frame.texel_rect.w {
        return;
    }
    let i = frame.texel_rect.x + id.x;
    let j = frame.texel_rect.y + id.y;
    let u = texel_centre(i, j);
    var dir = vec2<f32>(1.0, 0.0);
    if length(u) > 0.0 {
        dir = u / length(u);
    }
    let taps = i32(sensor.blend_taps);
    let step = sensor.reach_mm / f32(taps);
    var acc = pass_start();
    for (var k = -taps; k <= taps; k++) {
        let x = f32(k) * step;
        pass_add(&acc, k, x, vec3<f32>(sample_penetration(texel_of(u + x * dir))));
    }
    elastomer_scratch[j * sensor.texels + i] = vec4<f32>(pass_result(acc), 0.0);
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
    var v = elastomer_scratch[idx].xyz;
    if rho > 1e-6 {
        let taps = i32(sensor.blend_taps);
        let step = sensor.reach_mm / f32(taps);
        var acc = pass_start();
        for (var k = -taps; k <= taps; k++) {
            let x = f32(k) * step;
            pass_add(&acc, k, x, sample_meridian(texel_of(disc_of(vec2<f32>(c.x, c.y + x / rho)))));
        }
        v = pass_result(acc);
    }
    let t = sensor.shell_thickness;
    if penetration[idx] > t {
        atomicAdd(&counters[0], 1u);
    }
    let pressed = max(v.x, v.y);
    var h = clamp(pressed - sensor.bulge * max(v.z - v.y, 0.0), -0.5 * t, t);
    // Mirror: HEIGHT_EPSILON_MM. Gaussian tails are not a deformation; the camera marches
    // only where there is one.
    if abs(h) < 1e-3 {
        h = 0.0;
    }
    height[idx] = h;
}
