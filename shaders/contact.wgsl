//! use shared/common.wgsl
//! use shared/object.wgsl
// Stage 1, contact: penetration of the object into the skin along the surface normal, per
// heightfield texel the object can press (frame.pressed_rect, inside the footprint's
// texel_rect; the frame starts from zero there). Mirror: src/render/contact.rs.

const MAX_TRACE_STEPS: u32 = 48u;
const TRACE_EPSILON_MM: f32 = 1e-3;

fn grid_value(q: vec3<i32>) -> f32 {
    let dims = vec3<i32>(i32(frame.grid_dims_x), i32(frame.grid_dims_y), i32(frame.grid_dims_z));
    let c = clamp(q, vec3<i32>(0), dims - 1);
    return sdf_grid[c.x + dims.x * (c.y + dims.y * c.z)];
}

// Trilinear sample of the baked SDF; outside the grid's box, max(b, edge value - b) with b
// the distance to the box: a conservative bound. Mirror: src/object/sdf_grid.rs SdfGrid::sample.
fn grid_sdf(p: vec3<f32>) -> f32 {
    let voxel = frame.grid_origin.w;
    let g = (p - frame.grid_origin.xyz) / voxel;
    let top = vec3<f32>(f32(frame.grid_dims_x), f32(frame.grid_dims_y), f32(frame.grid_dims_z)) - 1.0;
    let inside = clamp(g, vec3<f32>(0.0), top);
    let b_out = length(g - inside) * voxel;
    let base = min(floor(inside), max(top - 1.0, vec3<f32>(0.0)));
    let f = inside - base;
    let b = vec3<i32>(base);
    let c00 = mix(grid_value(b), grid_value(b + vec3<i32>(1, 0, 0)), f.x);
    let c10 = mix(grid_value(b + vec3<i32>(0, 1, 0)), grid_value(b + vec3<i32>(1, 1, 0)), f.x);
    let c01 = mix(grid_value(b + vec3<i32>(0, 0, 1)), grid_value(b + vec3<i32>(1, 0, 1)), f.x);
    let c11 = mix(grid_value(b + vec3<i32>(0, 1, 1)), grid_value(b + vec3<i32>(1, 1, 1)), f.x);
    let v = mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
    if b_out > 0.0 {
        return max(v - b_out, b_out);
    }
    return v;
}

// The frame's object (FrameUniform object_kind) as a pipeline constant: the renderer builds
// one contact pipeline per kind it meets (src/render/gpu/pipelines.rs). Why: llvmpipe runs
// both sides of every branch, so with the kind read from the uniform every trace step would
// evaluate every solid and the baked grid's eight loads; with a constant the driver folds
// the rest away.
override OBJECT_KIND: u32 = 0u;

fn object_sdf(p: vec3<f32>) -> f32 {
    if OBJECT_KIND == GRID_OBJECT {
        return grid_sdf(p);
    }
    if OBJECT_KIND >= OBJ_PRIMITIVE_SPHERE {
        return primitive_sdf(OBJECT_KIND, frame.object_size, p);
    }
    return solid_sdf(OBJECT_KIND, p);
}

// Object-local coordinates of a camera-frame point.
fn to_object(p: vec3<f32>) -> vec3<f32> {
    let q = p - frame.origin.xyz;
    return vec3<f32>(dot(frame.object_x.xyz, q), dot(frame.object_y.xyz, q), dot(frame.object_z.xyz, q));
}

// The skin's inward displacement where the object presses it: the largest lambda with
// S - lambda n inside the object grown by drape_mm, less drape_mm (the skin drapes from an
// edge on a circle instead of a cliff). Sphere tracing from the deep end outwards meets the
// deepest object point first. Mirror: src/render/contact.rs penetration.
fn penetration_at(u: vec2<f32>) -> f32 {
    let at = surface_at_disc(u);
    let s = at.point;
    let n = at.normal;
    let drape = sensor.drape_mm;
    var lambda = frame.origin.w + drape;
    for (var i = 0u; i < MAX_TRACE_STEPS; i++) {
        let d = object_sdf(to_object(s - lambda * n)) - drape;
        if d <= TRACE_EPSILON_MM {
            return max(lambda - drape, 0.0);
        }
        lambda -= d;
        if lambda < drape {
            return 0.0;
        }
    }
    return 0.0;
}

@compute @workgroup_size(8, 8)
fn contact(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let id = rect_invocation(use_frame_of(group), frame.pressed_rect.z, local);
    if id.x >= frame.pressed_rect.z || id.y >= frame.pressed_rect.w {
        return;
    }
    let i = frame.pressed_rect.x + id.x;
    let j = frame.pressed_rect.y + id.y;
    // One sample per texel is enough: the drape makes the skin continuous at object edges.
    let u = texel_centre(i, j);
    var p = 0.0;
    if length(u) <= sensor.half_size_mm {
        p = penetration_at(u);
    }
    // Several objects in one frame: each contact pass keeps the deepest press (the frame
    // clears the heightfield first, so one object writes its own penetration).
    let idx = texel_index(i, j);
    penetration[idx] = max(penetration[idx], p);
    // This object's own penetration, for its labels, over its pressed rect's rows (texels
    // wide) in its place after the lanes' heights, read back with the frame.
    height[frame.field_at + (j - frame.pressed_rect.y) * sensor.texels + i] = p;
}
