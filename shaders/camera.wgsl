//! use shared/common.wgsl
//! use shared/shading.wgsl
// Stage 3, camera: each pixel's lens ray meets the deformed skin inside the shell: uniform
// steps bracket the first point where the ray leaves the gel, bisection refines it.
// Each landing ray is shaded at once (shared/shading.wgsl). Mirror: src/render/camera.rs.

const BISECTION_STEPS: u32 = 6u;

// Where a ray's stretch of shell is probed for deformation: its ends and middle, as disc
// positions, and where it enters the gel and leaves the highest bulge (t_in, t_out along the
// ray). Mirror: src/render/camera.rs ray_probes, UNTOUCHED_PROBES.
struct Probes {
    a: vec2<f32>,
    b: vec2<f32>,
    c: vec2<f32>,
    t_in: f32,
    t_out: f32,
}

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

// Mirror: src/render/camera.rs SHALLOW_MM.
const SHALLOW_MM: f32 = 0.02;

// The skin over disc position u moved in by h.
fn skin_with(u: vec2<f32>, h: f32) -> vec3<f32> {
    let at = surface_at_disc(u);
    return at.point - h * at.normal;
}

// Per texel of the contact's rect: the deformed skin's normal minus the undeformed one, by
// central differences over one texel on the disc. Written into the elastomer's scratch
// buffer once stage 2 is done with it; the camera interpolates it, so shading is smooth
// across texels. Mirror: src/render/camera.rs skin_normals.
@compute @workgroup_size(8, 8)
fn skin_normals(@builtin(global_invocation_id) id: vec3<u32>) {
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
        // zero outside the grid, as the bilinear samples were.
        let texels = f32(sensor.texels);
        let fi = f32(i);
        let fj = f32(j);
        let a = textureGather(0, height_map, map_sampler, vec2<f32>(fi, fj + 1.0) / texels);
        let b = textureGather(0, height_map, map_sampler, vec2<f32>(fi + 1.0, fj) / texels);
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
    elastomer_scratch[j * sensor.texels + i] = vec4<f32>(offset, 0.0);
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
// ray's probe positions, kept for later frames' `select_touched`.
@compute @workgroup_size(8, 8)
fn camera(@builtin(global_invocation_id) id: vec3<u32>) {
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
    write_pixel(vec2<u32>(x, y), shade(point, normal_of_point(point), dir), 0.0);
    let p = ray_probes(dir);
    probes[PROBES_STRIDE * i] = vec4<f32>(p.a, p.b);
    probes[PROBES_STRIDE * i + 1u] = vec4<f32>(p.c, p.t_in, p.t_out);
}

// A contact frame, first pass over its pixel rect: the pixels whose ray's stretch of shell
// sees any deformation (by the probe positions the reference frame left) go on the touched
// list, the shallow ones (SHALLOW_MM) from its front and the deep ones from its back; the
// rest keep the reference's colour. Each kind is cast and shaded by its own pass, in
// dispatches sized on the GPU (SHALLOW_DISPATCH, DEEP_DISPATCH). Why two passes: llvmpipe
// runs 8 pixels per SIMD group and executes both sides of every branch, so one pass would
// cost every pixel the march and the shallow path both; and no pixel off the list pays for
// its neighbours' marches. This entry point runs over every pixel of the rect; contact frames
// run select_listed over the rect's tiles select_tiles kept instead.
@compute @workgroup_size(8, 8)
fn select_touched(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.pixel_rect.z || id.y >= frame.pixel_rect.w {
        return;
    }
    list_if_touched(frame.pixel_rect.x + id.x, frame.pixel_rect.y + id.y);
}

// Puts pixel (x, y) on the touched list if its probes see the skin moved.
fn list_if_touched(x: u32, y: u32) {
    let pixel = y * sensor.image_size.x + x;
    let p = load_probes(x, y);
    if p.t_in == 0.0 {
        return;
    }
    let deepest = probes_depth(p);
    if deepest == 0.0 {
        return;
    }
    // One atomic path for both kinds (selects, not branches: see above).
    let deep = deepest >= SHALLOW_MM;
    let k = list_touched(select(SHALLOW_COUNT, DEEP_COUNT, deep), select(SHALLOW_DISPATCH, DEEP_DISPATCH, deep));
    atomicStore(&counters[listed_at(k, deep)], pixel);
}

fn tiles_x() -> u32 {
    return (sensor.image_size.x + PIXEL_TILE - 1u) / PIXEL_TILE;
}

fn tiles_y() -> u32 {
    return (sensor.image_size.y + PIXEL_TILE - 1u) / PIXEL_TILE;
}

// Once, after the reference frame (whose probes it reads): per tile of pixels, the texels
// its probes' bilinear samples read (in `probes`, after the pixels'). Mirror:
// src/render/camera.rs probe_tiles.
@compute @workgroup_size(64)
fn probe_tiles_of_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let tile = id.x;
    if tile >= tiles_x() * tiles_y() {
        return;
    }
    let x0 = (tile % tiles_x()) * PIXEL_TILE;
    let y0 = (tile / tiles_x()) * PIXEL_TILE;
    let big = 1 << 30u;
    var a = vec4<i32>(big, big, -big, -big);
    var b = a;
    var c = a;
    for (var dy = 0u; dy < PIXEL_TILE; dy++) {
        for (var dx = 0u; dx < PIXEL_TILE; dx++) {
            let x = min(x0 + dx, sensor.image_size.x - 1u);
            let y = min(y0 + dy, sensor.image_size.y - 1u);
            let p = load_probes(x, y);
            if p.t_in != 0.0 {
                a = grown_by_block(a, p.a);
                b = grown_by_block(b, p.b);
                c = grown_by_block(c, p.c);
            }
        }
    }
    let at = probe_tiles_at() + PROBE_TILE_STRIDE * tile;
    probes[at] = bitcast<vec4<f32>>(clamped_to_grid(a));
    probes[at + 1u] = bitcast<vec4<f32>>(clamped_to_grid(b));
    probes[at + 2u] = bitcast<vec4<f32>>(clamped_to_grid(c));
}

// Where the tiles' texel ranges start in `probes` (after the pixels' probes).
fn probe_tiles_at() -> u32 {
    return PROBES_STRIDE * sensor.image_size.x * sensor.image_size.y;
}

// Range r grown by the 2x2 block of texels a bilinear sample at disc position u reads
// (gather_corner's block: floor(t - 0.5) and the next).
fn grown_by_block(r: vec4<i32>, u: vec2<f32>) -> vec4<i32> {
    let base = vec2<i32>(floor(texel_of(u) - 0.5));
    return vec4<i32>(min(r.xy, base), max(r.zw, base + 1));
}

// A texel range within the grid (texels beyond it read as zero); an empty one stays empty.
fn clamped_to_grid(r: vec4<i32>) -> vec4<i32> {
    if r.x > r.z {
        return vec4<i32>(1, 1, 0, 0);
    }
    let top = i32(sensor.texels) - 1;
    return vec4<i32>(clamp(r.xy, vec2<i32>(0), vec2<i32>(top)), clamp(r.zw, vec2<i32>(0), vec2<i32>(top)));
}

// Whether any texel of range r (x0, y0, x1, y1) of the height map is displaced: 2x2 blocks
// at a time (one gather each; a block reaching past the range's far edge reads a texel more,
// which can only keep a tile that need not be kept).
fn range_moved(r: vec4<i32>) -> bool {
    let texels = f32(sensor.texels);
    for (var j = r.y; j <= r.w; j += 2) {
        for (var i = r.x; i <= r.z; i += 2) {
            let block = textureGather(0, height_map, map_sampler, vec2<f32>(f32(i + 1), f32(j + 1)) / texels);
            if any(block != vec4<f32>(0.0)) {
                return true;
            }
        }
    }
    return false;
}

// A contact frame, before select_listed: the tiles of pixels (on the image's grid) that
// overlap the pixel rect and whose probes' texels hold any displacement go on the tile list.
// A pixel can only be touched if a texel its probes read is displaced, so
// no touched pixel is left out; most of a rect's tiles are: its corners, and the skin beside
// the imprint that the footprint's rectangles cover but the elastomer leaves in place. Why:
// llvmpipe pays for every invocation of select_touched, touched or not (it runs both sides of
// every branch). Displaced texels lie in frame.texel_rect (the height map is zero elsewhere).
// Mirror: src/render/camera.rs select_tiles. (Mirror of the workgroup size:
// src/render/gpu.rs SELECT_TILES_WORKGROUP.)
@compute @workgroup_size(8)
fn select_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let r = frame.pixel_rect;
    let tx0 = r.x / PIXEL_TILE;
    let ty0 = r.y / PIXEL_TILE;
    let across = (r.x + r.z - 1u) / PIXEL_TILE - tx0 + 1u;
    let down = (r.y + r.w - 1u) / PIXEL_TILE - ty0 + 1u;
    if r.z == 0u || r.w == 0u || id.x >= across * down {
        return;
    }
    let tile = (ty0 + id.x / across) * tiles_x() + tx0 + id.x % across;
    let t = frame.texel_rect;
    let lo = vec2<i32>(t.xy);
    let hi = vec2<i32>(t.xy + t.zw) - 1;
    let at = probe_tiles_at() + PROBE_TILE_STRIDE * tile;
    var moved = false;
    for (var k = 0u; k < PROBE_TILE_STRIDE; k++) {
        let range = bitcast<vec4<i32>>(probes[at + k]);
        moved = moved || range_moved(vec4<i32>(max(range.xy, lo), min(range.zw, hi)));
    }
    if !moved {
        return;
    }
    // One workgroup of select_listed per tile.
    let e = atomicAdd(&counters[TILE_COUNT], 1u);
    grow_dispatch(SELECT_DISPATCH, e);
    atomicStore(&counters[TOUCHED_LIST + list_capacity() + e], tile);
}

// select_touched over the listed tiles, one workgroup each, within the pixel rect (a tile on
// the rect's edge reaches past it, and the frame's buffers hold its rect alone).
@compute @workgroup_size(8, 8)
fn select_listed(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let e = group.y * TOUCHED_MAX_GROUPS + group.x;
    if e >= atomicLoad(&counters[TILE_COUNT]) {
        return;
    }
    let tile = atomicLoad(&counters[TOUCHED_LIST + list_capacity() + e]);
    let x = (tile % tiles_x()) * PIXEL_TILE + local.x;
    let y = (tile / tiles_x()) * PIXEL_TILE + local.y;
    let r = frame.pixel_rect;
    if x < r.x || y < r.y || x >= r.x + r.z || y >= r.y + r.w {
        return;
    }
    list_if_touched(x, y);
}

// Where place k of the touched list's shallow (front) or deep (back) part is.
fn listed_at(k: u32, deep: bool) -> u32 {
    return select(TOUCHED_LIST + k, TOUCHED_LIST + list_capacity() - 1u - k, deep);
}

// Pixels the touched list holds: a frame's.
fn list_capacity() -> u32 {
    return sensor.image_size.x * sensor.image_size.y;
}

// Takes the next place of a kind of touched pixel (its count at word `count`) and keeps the
// dispatch over that kind (at word `dispatch`) large enough: the first pixel of each
// workgroup's share sizes it.
fn list_touched(count: u32, dispatch: u32) -> u32 {
    let k = atomicAdd(&counters[count], 1u);
    if k % TOUCHED_WORKGROUP == 0u {
        grow_dispatch(dispatch, k / TOUCHED_WORKGROUP);
    }
    return k;
}

// Makes the indirect dispatch at word `dispatch` reach workgroup g: G groups in all as
// min(G, TOUCHED_MAX_GROUPS) x ceil(G / TOUCHED_MAX_GROUPS) x 1.
fn grow_dispatch(dispatch: u32, g: u32) {
    atomicMax(&counters[dispatch], min(g + 1u, TOUCHED_MAX_GROUPS));
    atomicMax(&counters[dispatch + 1u], g / TOUCHED_MAX_GROUPS + 1u);
    atomicStore(&counters[dispatch + 2u], 1u);
}

// The pixel at place k of the touched list's shallow (front) or deep (back) part.
fn listed_pixel(k: u32, deep: bool) -> vec2<u32> {
    let pixel = atomicLoad(&counters[listed_at(k, deep)]);
    return vec2<u32>(pixel % sensor.image_size.x, pixel / sensor.image_size.x);
}

fn write_hit(xy: vec2<u32>, hit: SkinHit) {
    if !hit.valid {
        write_pixel(xy, vec3<f32>(0.0), 0.0);
        return;
    }
    write_pixel(xy, shade(hit.point, hit.normal, hit.ray), hit.indentation);
}

// A contact frame, second pass: one invocation per shallow pixel, cast and shaded at once
// (the LED stage's shading, shaders/shared/shading.wgsl): the hit goes straight into the
// pixel.
@compute @workgroup_size(64)
fn camera_shallow(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = touched_index(id);
    if k >= atomicLoad(&counters[SHALLOW_COUNT]) {
        return;
    }
    let xy = listed_pixel(k, false);
    write_hit(xy, skin_over_surface(vec2<f32>(xy)));
}

// The same for the deep pixels: marched.
@compute @workgroup_size(64)
fn camera_deep(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = touched_index(id);
    if k >= atomicLoad(&counters[DEEP_COUNT]) {
        return;
    }
    let xy = listed_pixel(k, true);
    write_hit(xy, march_to_skin(vec2<f32>(xy), load_probes(xy.x, xy.y)));
}

// For tests: the undeformed surface point each listed pixel sees. Input:
// elastomer_scratch[i].xy is a pixel, for i < frame.pixel_rect.z; output: (point, 1), or 0
// beyond the lens. (Not the probes buffer: it keeps the reference frame's probe positions.)
@compute @workgroup_size(64)
fn unproject_pixels(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.pixel_rect.z {
        return;
    }
    let ray = pixel_ray(elastomer_scratch[id.x].xy);
    if ray.w == 0.0 {
        elastomer_scratch[id.x] = vec4<f32>(0.0);
        return;
    }
    elastomer_scratch[id.x] = vec4<f32>(capsule_hit(ray.xyz, 0.0) * ray.xyz, 1.0);
}
