//! use shared/common.wgsl
// Stage 2, elastomer: the contact stage already drapes the skin from the object's edges;
// here the imprint p blends (narrow Gaussian of blend_mm) and the displaced gel bulges
// around it (the excess of a Gaussian twice as wide), h = max(p, narrow) - bulge *
// max(wide - narrow, 0), capped to [-T/2, T]. Separable passes along the surface (meridians,
// then parallels), kernels in surface millimetres. Mirror: src/render/elastomer.rs.

fn sample_penetration(t: vec2<f32>) -> f32 {
    return sample_map_x(penetration_map, t);
}

fn sample_meridian(t: vec2<f32>) -> vec2<f32> {
    return sample_map_xy(elastomer_map, t);
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
    let taps = BLEND_TAPS;
    let step = sensor.reach_mm / f32(taps);
    var acc = vec2<f32>(0.0);
    for (var k = -taps; k <= taps; k++) {
        let x = f32(k) * step;
        acc += sensor.blend_weights[abs(k)].xy * sample_penetration(texel_of(u + x * dir));
    }
    elastomer_scratch[j * sensor.texels + i] = vec4<f32>(acc, 0.0, 0.0);
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
    var v = elastomer_scratch[idx].xy;
    if rho > 1e-6 {
        let taps = BLEND_TAPS;
        let step = sensor.reach_mm / f32(taps);
        var acc = vec2<f32>(0.0);
        // Walk the parallel by rotating the disc position one tap at a time (one sine and
        // cosine per texel instead of per tap).
        let turn = vec2<f32>(cos(step / rho), sin(step / rho));
        var u = disc_of(vec2<f32>(c.x, c.y - f32(taps) * step / rho));
        for (var k = -taps; k <= taps; k++) {
            acc += sensor.blend_weights[abs(k)].xy * sample_meridian(texel_of(u));
            u = vec2<f32>(u.x * turn.x - u.y * turn.y, u.x * turn.y + u.y * turn.x);
        }
        v = acc;
    }
    let t = sensor.shell_thickness;
    if penetration[idx] > t {
        atomicAdd(&counters[OVER_PRESSED], 1u);
    }
    let pressed = max(penetration[idx], v.x);
    var h = clamp(pressed - sensor.bulge * max(v.y - v.x, 0.0), -0.5 * t, t);
    // Mirror: HEIGHT_EPSILON_MM. Gaussian tails are not a deformation; the camera marches
    // only where there is one.
    if abs(h) < 5e-3 {
        h = 0.0;
    }
    height[idx] = h;
}
