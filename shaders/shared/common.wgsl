// Shared by every stage of the renderer: the sensor and frame uniforms, the bindings (one
// layout for the whole pipeline, so binding numbers live in this one place), the lens model,
// the finger's geometry and the unrolled-disc heightfield. Mirrors: src/render/uniforms.rs
// (structs), src/lens.rs, src/finger.rs, src/render/mod.rs (HeightfieldGrid); the bindings,
// the buffers' layout constants and the workgroup sizes the renderer dispatches by are
// mirrored in src/render/gpu/{bindings,layout}.rs, and tests/shaders.rs holds them equal.

const PI: f32 = 3.14159265358979;
const HALF_PI: f32 = 1.57079632679490;
const TAU: f32 = 6.28318530717959;

const LENS_PINHOLE: u32 = 0u;
const LENS_EQUIDISTANT: u32 = 1u;
const LENS_EQUISOLID: u32 = 2u;
const LENS_KANNALA_BRANDT: u32 = 3u;

// Per sensor: src/render/uniforms.rs SensorUniform.
struct Sensor {
    radius: f32,
    cylinder_length: f32,
    shell_thickness: f32,
    junction_s: f32,
    lens_model: u32,
    focal_px: f32,
    max_theta: f32,
    max_rho: f32,
    k: vec4<f32>,
    principal: vec2<f32>,
    image_size: vec2<u32>,
    texels: u32,
    ray_steps: u32,
    half_size_mm: f32,
    texel_mm: f32,
    blend_mm: f32,
    bulge: f32,
    diffuse: f32,
    specular: f32,
    shininess: f32,
    led_count: u32,
    spread: f32,
    // Elastomer: the skin's tightest bend (mm) and the surface mm between the narrow and
    // the wide kernel's taps.
    drape_mm: f32,
    narrow_step_mm: f32,
    wide_step_mm: f32,
    // Their taps on each side of the centre (read as NARROW_TAPS and WIDE_TAPS).
    narrow_taps: u32,
    wide_taps: u32,
    // Sensor noise by channel (8-bit levels).
    noise: vec4<f32>,
    ambient: vec4<f32>,
    paint_colour: vec4<f32>,
    // Vignetting 1 + x r^2 + y r^4, r the distance from the principal point times z.
    vignetting: vec4<f32>,
    // Per LED (led_count of MAX_LEDS): position (w 1 for a gel LED, 0 for a point LED),
    // colour, x intensity, y spread, z falloff_mm; a gel LED's band: x width_mm,
    // y widening, z attenuation_mm, w relief.
    led_position: array<vec4<f32>, 16>,
    led_colour: array<vec4<f32>, 16>,
    led_light: array<vec4<f32>, 16>,
    led_band: array<vec4<f32>, 16>,
    // Per LED, its glow at a clear shell's open end, per channel (xyz; read when END_GLOW).
    led_end_glow: array<vec4<f32>, 16>,
    // The camera: its colour matrix's rows (xyz) and one over each channel's gamma (xyz).
    colour_matrix: array<vec4<f32>, 3>,
    inverse_gamma: vec4<f32>,
    // Read as the pipeline constants GEL_LEDS, CAMERA_RESPONSE and SHELL_END.
    gel_leds: u32,
    camera_response: u32,
    has_shell_end: u32,
    pad: u32,
    // The image circle as a mask: centre (xy), radius squared (z), 1 when there is one (w).
    image_circle: vec4<f32>,
    // A clear shell's open end (shared/shading.wgsl shell_end_light): x its height (mm),
    // y its inner radius (mm), z the rim's glow, w its width (mm); the tip's own light
    // (xyz) and the share of the LEDs' reaching it (w).
    shell_end: vec4<f32>,
    shell_tip: vec4<f32>,
    // How the ambient light shades with the skin's tilt, per channel (xyz; read when
    // AMBIENT_RELIEF).
    ambient_relief: vec4<f32>,
    // x: one over the square of how far round the shell's end each LED's glow spreads
    // (radians; read when END_GLOW).
    shell_glow: vec4<f32>,
    // The elastomer kernels' normalised weights by tap |k| (x narrow, y wide).
    blend_weights: array<vec4<f32>, 65>,
}

// Per frame (one contact): src/render/uniforms.rs FrameUniform.
struct Frame {
    // Heightfield texels the contact can touch: x, y, w, h.
    texel_rect: vec4<u32>,
    // Pixels whose rays can meet those texels: x, y, w, h.
    pixel_rect: vec4<u32>,
    // Rows of the rotation taking camera-frame vectors to object-local ones.
    object_x: vec4<f32>,
    object_y: vec4<f32>,
    object_z: vec4<f32>,
    // xyz: the object's origin (its top) in the camera frame; w: deepest trace (mm).
    origin: vec4<f32>,
    // 0..8: a built-in solid, 10..14: a sized primitive (shaders/shared/object.wgsl);
    // GRID_OBJECT: the baked SDF grid.
    object_kind: u32,
    grid_dims_x: u32,
    grid_dims_y: u32,
    grid_dims_z: u32,
    // xyz: centre of voxel 0; w: voxel size (mm).
    grid_origin: vec4<f32>,
    noise_seed: u32,
    // The rect of the image the image and indentation buffers hold: its corner, and the
    // pixels from one of its rows to the next (src/render/uniforms.rs image_pitch).
    image_x: u32,
    image_y: u32,
    image_pitch: u32,
    pressed_rect: vec4<u32>,
    // Texels the elastomer's meridians pass runs over: those within the kernels' reach of
    // pressed_rect (inside texel_rect).
    meridian_rect: vec4<u32>,
    // A sized primitive's sizes (object.wgsl primitive_sdf); zero for other objects.
    object_size: vec4<f32>,
    // Where the frame's data lies in the buffers bound for its wave: its lane (heightfield
    // and map layer), the words its image and indentation slice and its counters start at,
    // and a contact's own penetration field's first word in `height` (contact.wgsl).
    lane: u32,
    image_at: u32,
    counters_at: u32,
    field_at: u32,
    // Frames of the wave whose pixels are selected and cast (touched.wgsl wave_bases).
    listed_frames: u32,
    // The size of the rect the image buffers hold (from image_x, image_y).
    image_w: u32,
    image_h: u32,
    // The word of `counters` where the frame's touched list starts, its tile list after it.
    list_at: u32,
    // A dispatch over the bound frames' work side by side (use_frame_of): the first of the
    // dispatch's workgroups that are this frame's, and how many frames the dispatch binds.
    group_base: u32,
    group_items: u32,
}

// A frame uniform in its place of the frame uniforms' buffer (src/render/gpu/resources.rs
// UNIFORM_STRIDE bytes apart).
struct FrameSlot {
    frame: Frame,
    pad: vec4<u32>,
}

// The sensor's lens model, ray steps, kernel taps, LED count and shading exponents (the
// Sensor uniform's lens_model, ray_steps, narrow_taps, wide_taps, led_count, spread and
// shininess, which the shaders do not read) as pipeline constants, set when the renderer builds its pipelines
// (SensorUniform::pipeline_constants): the driver folds the lens switch and knows the loops'
// trip counts (callgrind: 1.2% fewer instructions a contact frame on lavapipe). The defaults
// are the paper sensor's.
override LENS_MODEL: u32 = 1u;
override RAY_STEPS: u32 = 4u;
override NARROW_TAPS: i32 = 3;
override WIDE_TAPS: i32 = 3;
// Whether the wide kernel's taps lie on every other narrow tap (its step exactly twice the
// narrow one's, as on the paper sensor): the meridians pass then samples those places once.
override WIDE_TAPS_NESTED: bool = true;
// The LEDs in use; their shared emission exponent (-1 when each has its own, read from
// led_light) and the paint's shininess: whole exponents are multiplied out
// (shared/shading.wgsl power); whether the camera vignettes.
override LED_COUNT: i32 = 3;
override LED_SPREAD: f32 = 2.0;
override PAINT_SHININESS: f32 = 24.0;
override VIGNETTING: bool = false;
// Whether any LED is a gel LED (shared/shading.wgsl gel_light), and whether the camera has
// its own colour matrix and gamma (else the plain gamma 2.2).
override GEL_LEDS: bool = false;
override CAMERA_RESPONSE: bool = false;
// Whether a clear shell under the gel ends below the tip (shared/shading.wgsl
// shell_end_light), and how sharp its edge is (mm; src/sensor/shell_end.rs SHELL_EDGE_MM).
override SHELL_END: bool = false;
override SHELL_EDGE_MM: f32 = 0.08;
// Whether the LEDs tint the rim at the shell's end each round its azimuth
// (shared/shading.wgsl shell_end_light).
override END_GLOW: bool = false;
// Whether the ambient light shades with the skin's tilt (shared/shading.wgsl ambient_light).
override AMBIENT_RELIEF: bool = false;

const GRID_OBJECT: u32 = 100u;
// object_kind of the reference frame (no object; every pixel is shaded).
const REFERENCE_FRAME: u32 = 101u;

@group(0) @binding(0) var<uniform> sensor: Sensor;
// The frames of a dispatch: a dispatch runs a stage over every frame (or piece of one) of a
// wave at once, each workgroup finding its own (use_frame_of, use_listed_frame_of, or the
// third coordinate for a pass over whole frames).
@group(0) @binding(1) var<uniform> frames: array<FrameSlot, FRAMES_BOUND>;
const FRAMES_BOUND: u32 = 256u;
// The frame an invocation works on (use_frame).
var<private> frame: Frame;
// The heightfield's buffers hold every lane's, texels x texels each (texel_index); its maps
// are arrays of a layer per lane.
// Stage 1 output: penetration of the object along the normal, per texel.
@group(0) @binding(2) var<storage, read_write> penetration: array<f32>;
// Stage 2 scratch: (drape, narrow blend, wide blend, -) along meridians; once the skin is
// known, the offsets of its normals from the undeformed ones (read by the camera).
@group(0) @binding(3) var<storage, read_write> elastomer_scratch: array<vec4<f32>>;
// Stage 2 output: the skin's inward displacement, per texel. After the lanes' texels, the
// contacts' own penetration fields (contact.wgsl).
@group(0) @binding(4) var<storage, read_write> height: array<f32>;
// Written once by the reference frame, PROBES_STRIDE vec4 per pixel: the disc positions of
// the three probes of the pixel's ray and where it enters and leaves the gel, (a.xy, b.xy),
// (c.xy, t_in, t_out), t_in 0 where the lens sees nothing (shared/probes.wgsl). After the pixels' (at probe_tiles_at()),
// PROBE_TILE_STRIDE vec4 per tile of PIXEL_TILE x PIXEL_TILE pixels (on the image's grid,
// row by row): for each of its rays' probes a, b and c, the range of texels (x0, y0, x1, y1,
// i32 bits) their bilinear samples read over the tile's seen pixels (x0 > x1 when the lens
// sees none of them); touched.wgsl select_tiles reads them. (In this buffer rather than one
// of their own: WebGPU guarantees eight storage buffers a stage, and these are the eight.)
@group(0) @binding(5) var<storage, read_write> probes: array<vec4<f32>>;
const PROBES_STRIDE: u32 = 2u;
// The image: packed RGBA8 per pixel; each frame's slice from frame.image_at.
@group(0) @binding(6) var<storage, read_write> image: array<u32>;
// Indentation (mm) each pixel sees, in slices as the image's.
@group(0) @binding(7) var<storage, read_write> indentation: array<f32>;
// A loaded mesh's SDF: x fastest, then y, then z.
@group(0) @binding(8) var<storage, read> sdf_grid: array<f32>;
// Each frame's counters from frame.counters_at (words below: frame_word; a wave's frames'
// counters side by side) and its touched-pixel and tile lists from frame.list_at
// (shared/touched_list.wgsl). The indirect dispatches' arguments are the wave's, in its
// first frame's words.
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>>;
// What the heightfield's samplers read (taps along the surface, steps along a ray): copies of
// the three buffers above as textures, refreshed after each stage that writes them
// (src/render/gpu/stages.rs). Why: llvmpipe (Mesa 22) loads a storage buffer at an index that
// differs between invocations one invocation at a time, with two branches each, while it
// fetches texels for all eight lanes at once.
@group(0) @binding(10) var penetration_map: texture_2d_array<f32>;
@group(0) @binding(11) var elastomer_map: texture_2d_array<f32>;
@group(0) @binding(12) var height_map: texture_2d_array<f32>;
// The same for the rays' probes: pixel (x, y)'s two vec4 are texels (2x, y) and (2x + 1, y).
@group(0) @binding(13) var probe_map: texture_2d<f32>;
const PROBE_TILE_STRIDE: u32 = 3u;
const PIXEL_TILE: u32 = 8u;
// Nearest, clamped to the edge: only for textureGather, which fetches a texel's 2x2 block
// in one sampler operation (the weights and the zero outside the grid are ours).
@group(0) @binding(14) var map_sampler: sampler;
// The empty finger's image, packed RGBA8 (start.wgsl copies a frame's rect of it).
@group(0) @binding(15) var reference_image: texture_2d<u32>;

// Makes the invocation work on frame k of its dispatch's frames: k the workgroup's third
// coordinate, which llvmpipe knows to be one value for the workgroup (a uniform load then,
// where an invocation's own coordinate would be a load per invocation).
fn use_frame(k: u32) {
    frame = frames[k].frame;
}

// A dispatch over the bound frames' work side by side, each frame's workgroups after the
// frame before's (src/render/gpu/frame.rs Binds::spread), rows of GROUPS_ROW: makes
// current the frame workgroup `group` works for (the last whose group_base is at most its
// place, by bisection) and returns its place among that frame's workgroups. Why: sized by
// the largest frame, every workgroup of the smaller frames' share runs on llvmpipe only to
// find it has nothing to do.
fn use_frame_of(group: vec3<u32>) -> u32 {
    let w = group.y * GROUPS_ROW + group.x;
    var lo = 0u;
    var hi = frames[0].frame.group_items;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if frames[mid].frame.group_base <= w {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    use_frame(lo);
    return w - frame.group_base;
}

// Invocation `local` of workgroup g of a frame's square workgroups over a rect `width`
// wide, row by row: its place in the rect.
fn rect_invocation(g: u32, width: u32, local: vec3<u32>) -> vec2<u32> {
    let across = max((width + 7u) / 8u, 1u);
    return vec2<u32>(g % across, g / across) * 8u + local.xy;
}

// Word w of the frame's counters.
fn frame_word(w: u32) -> u32 {
    return frame.counters_at + w;
}

// Where pixel xy lies in the image and indentation buffers, which hold only the rect of the
// image a frame can change (a contact frame copies, clears and reads back that much).
fn image_index(xy: vec2<u32>) -> u32 {
    return frame.image_at + (xy.y - frame.image_y) * frame.image_pitch + (xy.x - frame.image_x);
}

// Texel (i, j) of the frame's lane in the heightfield's buffers.
fn texel_index(i: u32, j: u32) -> u32 {
    return (frame.lane * sensor.texels + j) * sensor.texels + i;
}

// Texels pressed beyond the shell.
const OVER_PRESSED: u32 = 0u;
// Touched pixels (touched.wgsl list_if_touched) by what their rays' probes see: skin moved less
// than SHALLOW_MM (listed from the list's front), or more (from its back).
const SHALLOW_COUNT: u32 = 1u;
const DEEP_COUNT: u32 = 2u;
// Three words each (at a 16-byte stride): the workgroups of the passes over the shallow and
// the deep pixels, as indirect dispatches.
const SHALLOW_DISPATCH: u32 = 4u;
const DEEP_DISPATCH: u32 = 8u;
// Tiles on the tile list (touched.wgsl select_tiles), and the indirect dispatch of
// select_listed over them (three words).
const TILE_COUNT: u32 = 3u;
const SELECT_DISPATCH: u32 = 12u;
// The first workgroup of a frame's share of the wave's passes over the tile lists, the
// shallow and the deep pixels (touched.wgsl wave_bases).
const TILE_BASE: u32 = 16u;
const SHALLOW_BASE: u32 = 17u;
const DEEP_BASE: u32 = 18u;
// Words of a frame's counters (the rest of a frame's words are its lists, from
// frame.list_at: the touched pixels' indices (y * width + x), a place per pixel of the
// image, then the tile list's tile indices, row by row on the image's grid of tiles).
const TOUCHED_LIST: u32 = 64u;
// Invocations per workgroup of the passes over the touched list.
const TOUCHED_WORKGROUP: u32 = 64u;
// Most workgroups a dispatch over a list or over frames side by side has along x (WebGPU's
// least limit per dimension); more go on in further rows of workgroups (y).
const GROUPS_ROW: u32 = 65535u;

// ---- Lens (src/lens.rs) ----

fn lens_project(theta: f32) -> f32 {
    let f = sensor.focal_px;
    switch LENS_MODEL {
        case LENS_PINHOLE: { return f * tan(theta); }
        case LENS_EQUIDISTANT: { return f * theta; }
        case LENS_EQUISOLID: { return 2.0 * f * sin(0.5 * theta); }
        default: {
            let t2 = theta * theta;
            let k = sensor.k;
            return f * theta * (1.0 + t2 * (k.x + t2 * (k.y + t2 * (k.z + t2 * k.w))));
        }
    }
}

fn lens_project_derivative(theta: f32) -> f32 {
    let t2 = theta * theta;
    let k = sensor.k;
    return sensor.focal_px * (1.0 + t2 * (3.0 * k.x + t2 * (5.0 * k.y + t2 * (7.0 * k.z + t2 * 9.0 * k.w))));
}

// Angle off the axis of the ray landing rho px from the principal point; negative beyond
// the lens's field of view.
fn lens_unproject(rho: f32) -> f32 {
    if rho > sensor.max_rho * 1.000001 {
        return -1.0;
    }
    let f = sensor.focal_px;
    switch LENS_MODEL {
        case LENS_PINHOLE: { return min(atan(rho / f), sensor.max_theta); }
        case LENS_EQUIDISTANT: { return min(rho / f, sensor.max_theta); }
        case LENS_EQUISOLID: {
            // 2 asin(x), written with atan2: some drivers' asin is far less precise.
            let x = min(rho / (2.0 * f), 1.0);
            return min(2.0 * atan2(x, sqrt(max(1.0 - x * x, 0.0))), sensor.max_theta);
        }
        default: {
            // Safeguarded Newton: the polynomial is increasing on [0, max_theta] (validated).
            var lo = 0.0;
            var hi = sensor.max_theta;
            var theta = clamp(rho / f, lo, hi);
            for (var i = 0; i < 24; i++) {
                let err = lens_project(theta) - rho;
                if err > 0.0 { hi = theta; } else { lo = theta; }
                var next = theta - err / lens_project_derivative(theta);
                if !(next > lo && next < hi) { next = 0.5 * (lo + hi); }
                theta = next;
            }
            return theta;
        }
    }
}

// Unit direction of the lens ray through pixel `px` (integer coordinates at pixel centres);
// w = 0 when the pixel lies beyond the lens's field of view or outside the image circle.
fn pixel_ray(px: vec2<f32>) -> vec4<f32> {
    let cut = px - sensor.image_circle.xy;
    if sensor.image_circle.w != 0.0 && dot(cut, cut) > sensor.image_circle.z {
        return vec4<f32>(0.0);
    }
    let offset = px - sensor.principal;
    let rho = length(offset);
    let theta = lens_unproject(rho);
    if theta < 0.0 {
        return vec4<f32>(0.0);
    }
    if rho == 0.0 {
        return vec4<f32>(0.0, 0.0, 1.0, 1.0);
    }
    let s = sin(theta);
    return vec4<f32>(s * offset.x / rho, s * offset.y / rho, cos(theta), 1.0);
}

// ---- Finger (src/finger.rs) ----

// Distance along the unit ray `dir` from the camera to the finger's surface grown by
// `offset` mm (negative: the inner face of the shell).
fn capsule_hit(dir: vec3<f32>, offset: f32) -> f32 {
    let r = sensor.radius + offset;
    let d = sensor.cylinder_length;
    let sin_t = length(dir.xy);
    let cos_t = dir.z;
    if r * cos_t <= d * sin_t {
        return r / sin_t;
    }
    let disc = r * r - d * d * sin_t * sin_t;
    return d * cos_t + sqrt(max(disc, 0.0));
}

// Negative inside the finger, positive outside (exact for the convex capsule).
fn finger_signed_distance(p: vec3<f32>) -> f32 {
    if p.z > sensor.cylinder_length {
        return length(p - vec3<f32>(0.0, 0.0, sensor.cylinder_length)) - sensor.radius;
    }
    return length(p.xy) - sensor.radius;
}

// The disc position of p's surface coordinates (Finger::coord_of) without the azimuth's
// atan2, cos and sin: (cos phi, sin phi) is p.xy / |p.xy| (on the axis the disc position is
// 0 above the junction; below it phi = 0).
fn disc_of_point(p: vec3<f32>) -> vec2<f32> {
    let lateral = length(p.xy);
    var s: f32;
    if p.z > sensor.cylinder_length {
        s = sensor.radius * atan2(lateral, p.z - sensor.cylinder_length);
    } else {
        s = sensor.junction_s + (sensor.cylinder_length - p.z);
    }
    if lateral == 0.0 {
        return vec2<f32>(s, 0.0);
    }
    return s * p.xy / lateral;
}

// The undeformed surface over disc position u: its point and outward normal at u's surface
// coordinates (Finger::point_at), with the azimuth's cosine and sine taken from u itself (no
// atan2, cos or sin of it; at the tip, phi = 0 as SurfaceCoord::from_disc has it).
struct SurfaceAt {
    point: vec3<f32>,
    normal: vec3<f32>,
}

fn surface_at_disc(u: vec2<f32>) -> SurfaceAt {
    let s = length(u);
    var dir = vec2<f32>(1.0, 0.0);
    if s > 0.0 {
        dir = u / s;
    }
    let r = sensor.radius;
    if s <= sensor.junction_s {
        let beta = s / r;
        let sb = sin(beta);
        let cb = cos(beta);
        return SurfaceAt(vec3<f32>(r * sb * dir, sensor.cylinder_length + r * cb), vec3<f32>(sb * dir, cb));
    }
    return SurfaceAt(vec3<f32>(r * dir, sensor.cylinder_length - (s - sensor.junction_s)), vec3<f32>(dir, 0.0));
}

// Radius of the parallel circle at arc length s.
fn parallel_radius(s: f32) -> f32 {
    if s <= sensor.junction_s {
        return sensor.radius * sin(s / sensor.radius);
    }
    return sensor.radius;
}

// ---- The unrolled disc (src/render/mod.rs HeightfieldGrid) ----

fn texel_centre(i: u32, j: u32) -> vec2<f32> {
    return (vec2<f32>(f32(i), f32(j)) + 0.5) * sensor.texel_mm - sensor.half_size_mm;
}

fn texel_of(disc: vec2<f32>) -> vec2<f32> {
    return (disc + sensor.half_size_mm) / sensor.texel_mm;
}

// Bilinear samples of a heightfield map at continuous texel coordinates t (centres at
// +0.5), zero outside the grid, with no branches (mirror: src/render/elastomer.rs
// bilinear_taps): the 2x2 block of texels (x, y) .. (x+1, y+1) is gathered at its shared
// corner (half a texel from any rounding decision the sampler makes), one component at a
// time, and weighed here, a texel outside the grid weighing 0 (the clamped sampler returns
// the edge's). Why gather: llvmpipe fetches the block with one vectorised sampler
// operation, where four textureLoads cost about twice as much.
fn gather_weights(t: vec2<f32>) -> vec4<f32> {
    let p = t - 0.5;
    let base = floor(p);
    let f = p - base;
    let n = f32(sensor.texels);
    // In textureGather's order: (x, y+1), (x+1, y+1), (x+1, y), (x, y).
    let x = vec4<f32>(base.x) + vec4<f32>(0.0, 1.0, 1.0, 0.0);
    let y = vec4<f32>(base.y) + vec4<f32>(1.0, 1.0, 0.0, 0.0);
    let inside = x >= vec4<f32>(0.0) & y >= vec4<f32>(0.0) & x < vec4<f32>(n) & y < vec4<f32>(n);
    let weight = vec4<f32>((1.0 - f.x) * f.y, f.x * f.y, f.x * (1.0 - f.y), (1.0 - f.x) * (1.0 - f.y));
    return select(vec4<f32>(0.0), weight, inside);
}

fn gather_corner(t: vec2<f32>) -> vec2<f32> {
    return (floor(t - 0.5) + 1.0) / f32(sensor.texels);
}

fn sample_map_x(map: texture_2d_array<f32>, t: vec2<f32>) -> f32 {
    return dot(textureGather(0, map, map_sampler, gather_corner(t), frame.lane), gather_weights(t));
}

fn sample_map_y(map: texture_2d_array<f32>, t: vec2<f32>) -> f32 {
    return dot(textureGather(1, map, map_sampler, gather_corner(t), frame.lane), gather_weights(t));
}

fn sample_map_xyz(map: texture_2d_array<f32>, t: vec2<f32>) -> vec3<f32> {
    let w = gather_weights(t);
    let at = gather_corner(t);
    return vec3<f32>(
        dot(textureGather(0, map, map_sampler, at, frame.lane), w),
        dot(textureGather(1, map, map_sampler, at, frame.lane), w),
        dot(textureGather(2, map, map_sampler, at, frame.lane), w),
    );
}

