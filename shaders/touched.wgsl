//! use shared/common.wgsl
//! use shared/probes.wgsl
//! use shared/touched_list.wgsl
// The touched pixels of a contact frame: the only pixels the camera casts and shades again
// (the rest keep the empty finger's colour). A pixel is touched when its ray's stretch of
// shell sees any deformation, by the probes the reference frame left. It goes on the touched
// list (shared/touched_list.wgsl), the shallow ones (SHALLOW_MM) from its front and the deep
// ones from its back, and the camera casts each kind in a pass of its own, dispatched by
// the counts this stage leaves (SHALLOW_DISPATCH, DEEP_DISPATCH). Why two passes: llvmpipe
// runs 8 pixels per SIMD group and executes both sides of every branch, so one pass would
// cost every pixel the march and the shallow path both; and no pixel off the list pays for
// its neighbours' marches. Only the tiles of pixels select_tiles keeps are tested, by
// select_listed. Mirror: src/render/touched.rs.

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
    let k = atomicAdd(&counters[frame_word(select(SHALLOW_COUNT, DEEP_COUNT, deep))], 1u);
    atomicStore(&counters[listed_at(k, deep)], pixel);
}

// Once a wave's lists of a kind are whole (their counts at the frames' words `count`): each
// listed frame's first workgroup of the pass over them (`per_group` entries a workgroup) at
// its word `base`, after the frame before's, and the wave's indirect dispatch over all
// (at word `dispatch`) as min(G, GROUPS_ROW) x ceil(G / GROUPS_ROW) workgroups.
fn wave_bases(count: u32, base: u32, dispatch: u32, per_group: u32) {
    var total = 0u;
    for (var k = 0u; k < frames[0].frame.listed_frames; k++) {
        let at = frames[k].frame.counters_at;
        atomicStore(&counters[at + base], total);
        total += (atomicLoad(&counters[at + count]) + per_group - 1u) / per_group;
    }
    atomicStore(&counters[dispatch], min(total, GROUPS_ROW));
    atomicStore(&counters[dispatch + 1u], (total + GROUPS_ROW - 1u) / GROUPS_ROW);
    atomicStore(&counters[dispatch + 2u], 1u);
}

// After select_tiles: the pass over the tile lists (select_listed), a workgroup a tile.
@compute @workgroup_size(1)
fn tile_bases() {
    wave_bases(TILE_COUNT, TILE_BASE, SELECT_DISPATCH, 1u);
}

// After select_listed: the camera's passes over the shallow and the deep pixels.
@compute @workgroup_size(1)
fn touched_bases() {
    wave_bases(SHALLOW_COUNT, SHALLOW_BASE, SHALLOW_DISPATCH, TOUCHED_WORKGROUP);
    wave_bases(DEEP_COUNT, DEEP_BASE, DEEP_DISPATCH, TOUCHED_WORKGROUP);
}

fn tiles_x() -> u32 {
    return (sensor.image_size.x + PIXEL_TILE - 1u) / PIXEL_TILE;
}

fn tiles_y() -> u32 {
    return (sensor.image_size.y + PIXEL_TILE - 1u) / PIXEL_TILE;
}

// Where the tiles' texel ranges start in `probes` (after the pixels' probes).
fn probe_tiles_at() -> u32 {
    return PROBES_STRIDE * sensor.image_size.x * sensor.image_size.y;
}

// Once, after the reference frame (whose probes it reads): per tile of pixels, the texels
// its probes' bilinear samples read (in `probes`, after the pixels'). Mirror:
// src/render/touched.rs probe_tiles.
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
            let block = textureGather(0, height_map, map_sampler, vec2<f32>(f32(i + 1), f32(j + 1)) / texels, frame.lane);
            if any(block != vec4<f32>(0.0)) {
                return true;
            }
        }
    }
    return false;
}

// A contact frame, first: the tiles of pixels (on the image's grid) that overlap the pixel
// rect and whose probes' texels hold any displacement go on the tile list. A pixel can only
// be touched if a texel its probes read is displaced, so no touched pixel is left out; most
// of a rect's tiles are: its corners, and the skin beside the imprint that the footprint's
// rectangles cover but the elastomer leaves in place. Why: llvmpipe pays for every
// invocation that tests a pixel, touched or not (it runs both sides of every branch).
// Displaced texels lie in frame.texel_rect (the height map is zero elsewhere). Mirror:
// src/render/touched.rs select_tiles.
@compute @workgroup_size(8)
fn select_tiles(@builtin(local_invocation_id) local: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let id = vec2<u32>(use_frame_of(group) * 8u + local.x, 0u);
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
    // One workgroup of select_listed per tile (tile_bases sizes its pass).
    let e = atomicAdd(&counters[frame_word(TILE_COUNT)], 1u);
    atomicStore(&counters[frame.list_at + list_capacity() + e], tile);
}

// Then the pixels of the listed tiles, a workgroup (PIXEL_TILE x PIXEL_TILE) a tile, within
// the pixel rect (a tile on the rect's edge reaches past it, and the frame's buffers hold its
// rect alone). Mirror: src/render/touched.rs select_touched.
@compute @workgroup_size(8, 8)
fn select_listed(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let e = use_listed_frame_of(group, TILE_BASE);
    if e >= atomicLoad(&counters[frame_word(TILE_COUNT)]) {
        return;
    }
    let tile = atomicLoad(&counters[frame.list_at + list_capacity() + e]);
    let x = (tile % tiles_x()) * PIXEL_TILE + local.x;
    let y = (tile / tiles_x()) * PIXEL_TILE + local.y;
    let r = frame.pixel_rect;
    if x < r.x || y < r.y || x >= r.x + r.z || y >= r.y + r.w {
        return;
    }
    list_if_touched(x, y);
}
