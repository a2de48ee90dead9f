//! use shared/common.wgsl
// Stage 2, elastomer: the contact stage already drapes the skin from the object's edges;
// here the imprint p blends (narrow Gaussian of blend_mm) and the displaced gel bulges
// around it (the excess of a Gaussian twice as wide), h = max(p, narrow) - bulge *
// max(wide - narrow, 0), capped to [-T/2, T]. Separable passes along the surface (meridians,
// then parallels), kernels in surface millimetres; then the normals of the skin they leave.
// Mirror: src/render/elastomer.rs.

// Each Gaussian samples at its own taps (the wide one's twice as far apart): the narrow
// blend reads channel x, the wide one channel y. Mirror: src/render/elastomer.rs Kernel.

fn sample_penetration(t: vec2<f32>) -> f32 {
    return sample_map_x(penetration_map, t);
}

@compute @workgroup_size(8, 8)
fn blend_meridian(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let id = rect_invocation(use_frame_of(group), frame.meridian_rect.z, local);
    // Over the meridian rect alone: beyond the kernels' reach of every pressed texel the
    // blends are zero, as the frame's clear left them.
    if id.x >= frame.meridian_rect.z || id.y >= frame.meridian_rect.w {
        return;
    }
    let i = frame.meridian_rect.x + id.x;
    let j = frame.meridian_rect.y + id.y;
    let u = texel_centre(i, j);
    var dir = vec2<f32>(1.0, 0.0);
    if length(u) > 0.0 {
        dir = u / length(u);
    }
    var narrow = 0.0;
    var wide = 0.0;
    for (var k = -NARROW_TAPS; k <= NARROW_TAPS; k++) {
        let x = f32(k) * sensor.narrow_step_mm;
        let p = sample_penetration(texel_of(u + x * dir));
        narrow += sensor.blend_weights[abs(k)].x * p;
        // Nested kernels: wide tap k / 2 is this place (the loops have constant bounds, so
        // the driver unrolls them and these conditions fold away).
        if WIDE_TAPS_NESTED && k % 2 == 0 && abs(k / 2) <= WIDE_TAPS {
            wide += sensor.blend_weights[abs(k / 2)].y * p;
        }
    }
    for (var k = -WIDE_TAPS; k <= WIDE_TAPS; k++) {
        if WIDE_TAPS_NESTED && abs(2 * k) <= NARROW_TAPS {
            continue;
        }
        let x = f32(k) * sensor.wide_step_mm;
        wide += sensor.blend_weights[abs(k)].y * sample_penetration(texel_of(u + x * dir));
    }
    elastomer_scratch[texel_index(i, j)] = vec4<f32>(narrow, wide, 0.0, 0.0);
}

// u turned by (cos, sin) of an angle about the disc's centre.
fn rotate(u: vec2<f32>, turn: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(u.x * turn.x - u.y * turn.y, u.x * turn.y + u.y * turn.x);
}

@compute @workgroup_size(8, 8)
fn blend_azimuth(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let id = rect_invocation(use_frame_of(group), frame.texel_rect.z, local);
    if id.x >= frame.texel_rect.z || id.y >= frame.texel_rect.w {
        return;
    }
    let i = frame.texel_rect.x + id.x;
    let j = frame.texel_rect.y + id.y;
    let idx = texel_index(i, j);
    let here = texel_centre(i, j);
    let rho = parallel_radius(length(here));
    // This texel's penetration and meridian blends from the maps, which hold their buffers'
    // values over the texel rect (copied after each stage): llvmpipe fetches a texel for all
    // lanes at once, where a storage buffer load at a per-lane index is a loop over lanes.
    let texel = vec2<u32>(i, j);
    let pen = textureLoad(penetration_map, texel, frame.lane, 0).x;
    var v = textureLoad(elastomer_map, texel, frame.lane, 0).xy;
    if rho > 1e-6 {
        // The centre taps are this texel's own blends (v); the others walk out from it both
        // ways, a turn of the parallel at a time.
        var narrow = sensor.blend_weights[0].x * v.x;
        let n_step = sensor.narrow_step_mm;
        let n_turn = vec2<f32>(cos(n_step / rho), sin(n_step / rho));
        var ahead = here;
        var behind = here;
        for (var k = 1; k <= NARROW_TAPS; k++) {
            ahead = rotate(ahead, n_turn);
            behind = rotate(behind, vec2<f32>(n_turn.x, -n_turn.y));
            narrow += sensor.blend_weights[k].x
                * (sample_map_x(elastomer_map, texel_of(ahead)) + sample_map_x(elastomer_map, texel_of(behind)));
        }
        var wide = sensor.blend_weights[0].y * v.y;
        let w_step = sensor.wide_step_mm;
        let w_turn = vec2<f32>(cos(w_step / rho), sin(w_step / rho));
        ahead = here;
        behind = here;
        for (var k = 1; k <= WIDE_TAPS; k++) {
            ahead = rotate(ahead, w_turn);
            behind = rotate(behind, vec2<f32>(w_turn.x, -w_turn.y));
            wide += sensor.blend_weights[k].y
                * (sample_map_y(elastomer_map, texel_of(ahead)) + sample_map_y(elastomer_map, texel_of(behind)));
        }
        v = vec2<f32>(narrow, wide);
    }
    let t = sensor.shell_thickness;
    if pen > t {
        atomicAdd(&counters[frame_word(OVER_PRESSED)], 1u);
    }
    let pressed = max(pen, v.x);
    var h = clamp(pressed - sensor.bulge * max(v.y - v.x, 0.0), -0.5 * t, t);
    // Mirror: HEIGHT_EPSILON_MM. Gaussian tails are not a deformation; the camera marches
    // only where there is one.
    if abs(h) < 5e-3 {
        h = 0.0;
    }
    height[idx] = h;
}

// The skin over disc position u moved in by h.
fn skin_with(u: vec2<f32>, h: f32) -> vec3<f32> {
    let at = surface_at_disc(u);
    return at.point - h * at.normal;
}

// Per texel of the contact's rect: the deformed skin's normal minus the undeformed one, by
// central differences over one texel on the disc. Written into the elastomer's scratch
// buffer once the blends are done with it; the camera interpolates it, so shading is smooth
// across texels. Mirror: src/render/elastomer.rs skin_normals.
@compute @workgroup_size(8, 8)
fn skin_normals(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let id = rect_invocation(use_frame_of(group), frame.texel_rect.z, local);
    if id.x >= frame.texel_rect.z || id.y >= frame.texel_rect.w {
        return;
    }
    let i = frame.texel_rect.x + id.x;
    let j = frame.texel_rect.y + id.y;
    let u = texel_centre(i, j);
    var offset = vec3<f32>(0.0);
    if length(u) <= sensor.half_size_mm {
        let n0 = surface_at_disc(u).normal;
        let ex = vec2<f32>(sensor.texel_mm, 0.0);
        let ey = vec2<f32>(0.0, sensor.texel_mm);
        // The four neighbours' heights are texel values (a bilinear sample at a texel's
        // centre is the texel): two gathers of the 2x2 blocks from (i-1, j) and (i, j-1)
        // hold them all, in textureGather's order (x, y+1), (x+1, y+1), (x+1, y), (x, y);
        // zero outside the grid, as a bilinear sample is there.
        let texels = f32(sensor.texels);
        let fi = f32(i);
        let fj = f32(j);
        let a = textureGather(0, height_map, map_sampler, vec2<f32>(fi, fj + 1.0) / texels, frame.lane);
        let b = textureGather(0, height_map, map_sampler, vec2<f32>(fi + 1.0, fj) / texels, frame.lane);
        let h_left = select(0.0, a.w, fi >= 1.0);
        let h_up = select(0.0, a.y, fj + 1.0 < texels);
        let h_right = select(0.0, b.y, fi + 1.0 < texels);
        let h_down = select(0.0, b.w, fj >= 1.0);
        var n = cross(
            skin_with(u + ex, h_right) - skin_with(u - ex, h_left),
            skin_with(u + ey, h_up) - skin_with(u - ey, h_down),
        );
        let len = length(n);
        if len > 0.0 {
            n = n / len;
            if dot(n, n0) < 0.0 {
                n = -n;
            }
            offset = n - n0;
        }
    }
    elastomer_scratch[texel_index(i, j)] = vec4<f32>(offset, 0.0);
}
