//! use shared/common.wgsl
//! use shared/shading.wgsl
//! use shared/probes.wgsl
//! use shared/touched_list.wgsl
// Stage 3, camera: each pixel's lens ray meets the deformed skin inside the shell: uniform
// steps bracket the first point where the ray leaves the gel, bisection refines it.
// Each landing ray is shaded at once (shared/shading.wgsl). The reference frame casts every
// pixel and keeps its ray's probes (shared/probes.wgsl); a contact frame casts only its
// touched pixels (touched.wgsl). Mirror: src/render/camera.rs.

const BISECTION_STEPS: u32 = 6u;

// The probes of the ray along `dir` (shared/probes.wgsl). Mirror: src/render/camera.rs
// ray_probes.
fn ray_probes(dir: vec3<f32>) -> Probes {
    let t_in = capsule_hit(dir, -sensor.shell_thickness);
    let t_out = capsule_hit(dir, 0.5 * sensor.shell_thickness);
    return Probes(
        disc_of_point(t_in * dir),
        disc_of_point(0.5 * (t_in + t_out) * dir),
        disc_of_point(t_out * dir),
        t_in,
        t_out,
    );
}

// The undeformed surface's outward normal on the radial line through p (from the sphere's
// centre on the hemisphere, from the axis on the cylinder): the normal at p's coordinates
// without its trigonometry.
fn normal_of_point(p: vec3<f32>) -> vec3<f32> {
    if p.z > sensor.cylinder_length {
        return normalize(p - vec3<f32>(0.0, 0.0, sensor.cylinder_length));
    }
    return vec3<f32>(normalize(p.xy), 0.0);
}

// Outward normal of the deformed skin over disc position u, whose undeformed normal is n0:
// n0 plus the interpolated offset.
fn skin_normal(n0: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let offset = sample_map_xyz(elastomer_map, texel_of(u));
    let n = n0 + offset;
    let len = length(n);
    if len == 0.0 {
        return n0;
    }
    return n / len;
}

// How far inside the gel the ray point at t is: positive in the gel, negative past the skin.
fn gap(t: f32, dir: vec3<f32>) -> f32 {
    let q = t * dir;
    return -finger_signed_distance(q) - height_at_disc(disc_of_point(q));
}

struct SkinHit {
    point: vec3<f32>,
    normal: vec3<f32>,
    indentation: f32,
    ray: vec3<f32>,
    valid: bool,
}

// The skin a shallow pixel sees (its probes saw skin moved less than SHALLOW_MM): the surface
// point its ray meets, pushed in along the normal by the skin's displacement there. Most
// touched rays cross barely moved skin, where this is as good as the march (the true crossing
// is within depth x tan(incidence), a fraction of a pixel).
fn skin_over_surface(px: vec2<f32>) -> SkinHit {
    var hit: SkinHit;
    let ray = pixel_ray(px);
    hit.valid = ray.w != 0.0;
    let dir = ray.xyz;
    let surface = capsule_hit(dir, 0.0) * dir;
    let u = disc_of_point(surface);
    let n0 = normal_of_point(surface);
    hit.indentation = height_at_disc(u);
    hit.point = surface - hit.indentation * n0;
    hit.normal = skin_normal(n0, u);
    hit.ray = dir;
    return hit;
}

// The skin a deep pixel sees, marched from its probes as the reference frame left them (no
// lens or shell geometry recomputed but the ray itself).
fn march_to_skin(px: vec2<f32>, probes: Probes) -> SkinHit {
    var hit: SkinHit;
    let ray = pixel_ray(px);
    hit.valid = ray.w != 0.0 && probes.t_in != 0.0;
    let dir = ray.xyz;
    let t_in = probes.t_in;
    let t_out = probes.t_out;
    var t_hit = capsule_hit(dir, 0.0);
    // Bracket first, refine after: on a SIMD device (llvmpipe runs 8 pixels per lane group
    // and executes both sides of every branch) a refinement inside the stepping loop would
    // cost every pixel the bisection at every step. The gaps at the bracket's ends come from
    // the march (at t_in the ray is on the shell's inner face, T deep: probe a).
    var lo = t_in;
    var hi = t_in;
    var g_lo = sensor.shell_thickness - height_at_disc(probes.a);
    var g_hi = g_lo;
    var found = false;
    for (var k = 1u; k <= RAY_STEPS; k++) {
        let t = t_in + (t_out - t_in) * f32(k) / f32(RAY_STEPS);
        let g = gap(t, dir);
        if g < 0.0 {
            hi = t;
            g_hi = g;
            found = true;
            break;
        }
        lo = t;
        g_lo = g;
    }
    if found {
        for (var b = 0u; b < BISECTION_STEPS; b++) {
            let mid = 0.5 * (lo + hi);
            let g = gap(mid, dir);
            if g < 0.0 { hi = mid; g_hi = g; } else { lo = mid; g_lo = g; }
        }
        // Secant step inside the last bracket.
        t_hit = lo + (hi - lo) * clamp(g_lo / max(g_lo - g_hi, 1e-12), 0.0, 1.0);
    }
    hit.point = t_hit * dir;
    let u = disc_of_point(hit.point);
    hit.normal = skin_normal(normal_of_point(hit.point), u);
    hit.indentation = height_at_disc(u);
    hit.ray = dir;
    return hit;
}

// The reference frame, every pixel of the pixel rect (the whole image): the empty finger,
// whose skin is the undeformed surface itself (the heightfield is zero), shaded; and the
// ray's probes, kept for later frames' selection of touched pixels (touched.wgsl).
@compute @workgroup_size(8, 8)
fn camera(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    use_frame(group.z);
    if id.x >= frame.pixel_rect.z || id.y >= frame.pixel_rect.w {
        return;
    }
    let x = frame.pixel_rect.x + id.x;
    let y = frame.pixel_rect.y + id.y;
    let i = y * sensor.image_size.x + x;
    let ray = pixel_ray(vec2<f32>(f32(x), f32(y)));
    if ray.w == 0.0 {
        write_pixel(vec2<u32>(x, y), vec3<f32>(0.0), 0.0);
        probes[PROBES_STRIDE * i + 1u] = vec4<f32>(0.0);
        return;
    }
    let dir = ray.xyz;
    let point = capsule_hit(dir, 0.0) * dir;
    write_pixel(vec2<u32>(x, y), shade(point, normal_of_point(point), dir, false), 0.0);
    let p = ray_probes(dir);
    probes[PROBES_STRIDE * i] = vec4<f32>(p.a, p.b);
    probes[PROBES_STRIDE * i + 1u] = vec4<f32>(p.c, p.t_in, p.t_out);
}

fn write_hit(xy: vec2<u32>, hit: SkinHit) {
    if !hit.valid {
        write_pixel(xy, vec3<f32>(0.0), 0.0);
        return;
    }
    write_pixel(xy, shade(hit.point, hit.normal, hit.ray, hit.indentation != 0.0), hit.indentation);
}

// A contact frame, second pass: one invocation per shallow pixel, cast and shaded at once
// (the LED stage's shading, shaders/shared/shading.wgsl): the hit goes straight into the
// pixel.
@compute @workgroup_size(64)
fn camera_shallow(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let k = use_listed_frame_of(group, SHALLOW_BASE) * TOUCHED_WORKGROUP + local.x;
    if k >= atomicLoad(&counters[frame_word(SHALLOW_COUNT)]) {
        return;
    }
    let xy = listed_pixel(k, false);
    write_hit(xy, skin_over_surface(vec2<f32>(xy)));
}

// The same for the deep pixels: marched.
@compute @workgroup_size(64)
fn camera_deep(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let k = use_listed_frame_of(group, DEEP_BASE) * TOUCHED_WORKGROUP + local.x;
    if k >= atomicLoad(&counters[frame_word(DEEP_COUNT)]) {
        return;
    }
    let xy = listed_pixel(k, true);
    write_hit(xy, march_to_skin(vec2<f32>(xy), load_probes(xy.x, xy.y)));
}
