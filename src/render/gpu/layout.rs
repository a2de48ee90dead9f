//! Where the shaders put things, as the renderer needs to know it: the words of a frame's
//! counters, the strides of the rays' probes, and the workgroup sizes it dispatches by. Each
//! value mirrors one in `shaders/` (same name); `tests/shaders.rs` reads the shaders with
//! naga and holds every one of them equal.

/// Defines each constant and lists it, by its WGSL name, in [`WGSL_CONSTANTS`]: a mirror
/// cannot be added without the test seeing it.
macro_rules! wgsl_constants {
    ($($(#[$doc:meta])* $name:ident = $value:expr;)*) => {
        $($(#[$doc])* pub const $name: u32 = $value;)*
        /// Every constant above by its WGSL name (`shaders/shared/common.wgsl`).
        pub const WGSL_CONSTANTS: &[(&str, u32)] = &[$((stringify!($name), $name)),*];
    };
}

wgsl_constants! {
    /// Word of a frame's counters: texels pressed beyond the shell.
    OVER_PRESSED = 0;
    /// Word: touched pixels whose probes see skin moved less than `SHALLOW_MM`.
    SHALLOW_COUNT = 1;
    /// Word: touched pixels whose probes see skin moved more.
    DEEP_COUNT = 2;
    /// Word: tiles on the tile list.
    TILE_COUNT = 3;
    /// Words: the indirect dispatch arguments (three words, 16 bytes apart) of the pass over
    /// the shallow pixels, the deep ones and the listed tiles.
    SHALLOW_DISPATCH = 4;
    DEEP_DISPATCH = 8;
    SELECT_DISPATCH = 12;
    /// Words: the first workgroup of the frame's share of the wave's passes over the tile
    /// lists, the shallow and the deep pixels (`touched.wgsl` wave_bases).
    TILE_BASE = 16;
    SHALLOW_BASE = 17;
    DEEP_BASE = 18;
    /// Words of a frame's counters (cleared and read back; its lists are elsewhere).
    TOUCHED_LIST = 64;
    /// Invocations per workgroup of the camera's passes over the touched list.
    TOUCHED_WORKGROUP = 64;
    /// vec4 per pixel of the rays' probes.
    PROBES_STRIDE = 2;
    /// vec4 per tile of the tiles' texel ranges after them.
    PROBE_TILE_STRIDE = 3;
    /// Pixels per side of a tile.
    PIXEL_TILE = 8;
    /// Most workgroups along x of a dispatch over a list or over frames side by side (more
    /// go on in rows along y).
    GROUPS_ROW = 65535;
}

/// Bytes of a frame's counters: what is cleared and read back.
pub const COUNTER_HEADER_BYTES: u64 = TOUCHED_LIST as u64 * 4;

/// Bytes per pixel of the rays' probes.
pub const PROBES_BYTES_PER_PIXEL: u64 = PROBES_STRIDE as u64 * 16;

/// Bytes per tile of the tiles' texel ranges.
pub const PROBE_TILE_BYTES: u64 = PROBE_TILE_STRIDE as u64 * 16;

/// Where counter word `word` (one of the dispatches') lands in a frame's slice of the
/// indirect dispatch buffer, which holds the counters' words from [`SHALLOW_DISPATCH`] on (a
/// buffer bound for storage cannot also feed an indirect dispatch, so they are copied).
pub const fn dispatch_args_at(word: u32) -> u64 {
    (word - SHALLOW_DISPATCH) as u64 * 4
}

/// Bytes of the shallow and the deep pass's arguments, copied together once the touched
/// list is known.
pub const TOUCHED_ARGS_BYTES: u64 = dispatch_args_at(DEEP_DISPATCH) + 12;

/// Bytes of a frame's slice of the indirect dispatch buffer: up to the tile list's arguments
/// and their 16 bytes.
pub const DISPATCH_ARGS_BYTES: u64 = dispatch_args_at(SELECT_DISPATCH) + 16;

/// Side of the square workgroups of the passes over texels and pixels.
pub const WORKGROUP: u32 = 8;

/// Invocations (tiles) per workgroup of `select_tiles`: one SIMD group on llvmpipe, so the
/// tiles of a small rect still spread over the cores.
pub const SELECT_TILES_WORKGROUP: u32 = 8;

/// Invocations per workgroup of the passes over a list (tiles, pixels to unproject).
pub const LIST_WORKGROUP: u32 = 64;

/// The workgroup size of every compute entry point: `(stage, entry point, size)`. The
/// renderer sizes its direct dispatches by these; the indirect ones are sized on the GPU.
pub const WORKGROUP_SIZES: &[(&str, &str, [u32; 3])] = &[
    ("start", "frame_start", [WORKGROUP, WORKGROUP, 1]),
    ("contact", "contact", [WORKGROUP, WORKGROUP, 1]),
    ("elastomer", "blend_meridian", [WORKGROUP, WORKGROUP, 1]),
    ("elastomer", "blend_azimuth", [WORKGROUP, WORKGROUP, 1]),
    ("elastomer", "skin_normals", [WORKGROUP, WORKGROUP, 1]),
    ("touched", "probe_tiles_of_rays", [LIST_WORKGROUP, 1, 1]),
    ("touched", "select_tiles", [SELECT_TILES_WORKGROUP, 1, 1]),
    ("touched", "tile_bases", [1, 1, 1]),
    ("touched", "touched_bases", [1, 1, 1]),
    // A workgroup a tile: a pixel an invocation.
    ("touched", "select_listed", [PIXEL_TILE, PIXEL_TILE, 1]),
    ("camera", "camera", [WORKGROUP, WORKGROUP, 1]),
    ("camera", "camera_shallow", [TOUCHED_WORKGROUP, 1, 1]),
    ("camera", "camera_deep", [TOUCHED_WORKGROUP, 1, 1]),
    ("leds", "add_noise", [WORKGROUP, WORKGROUP, 1]),
    ("lens_rays", "unproject_pixels", [LIST_WORKGROUP, 1, 1]),
];

/// Workgroups of a direct dispatch over `n` items, `size` an item each.
pub fn groups(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}
