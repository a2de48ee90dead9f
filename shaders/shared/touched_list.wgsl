//! use shared/common.wgsl
// The touched list of a frame (from word frame.list_at of `counters`, a place per pixel of
// the image): the shallow pixels' indices (y * width + x) from its front, the deep ones'
// from its back. touched.wgsl fills it; the camera's passes over the touched pixels read it.

// Pixels the touched list holds: a frame's.
fn list_capacity() -> u32 {
    return sensor.image_size.x * sensor.image_size.y;
}

// Where place k of the touched list's shallow (front) or deep (back) part is.
fn listed_at(k: u32, deep: bool) -> u32 {
    return frame.list_at + select(k, list_capacity() - 1u - k, deep);
}

// The pixel at place k of the touched list's shallow (front) or deep (back) part.
fn listed_pixel(k: u32, deep: bool) -> vec2<u32> {
    let pixel = atomicLoad(&counters[listed_at(k, deep)]);
    return vec2<u32>(pixel % sensor.image_size.x, pixel / sensor.image_size.x);
}

// A pass over the wave's listed frames' lists, each frame's workgroups after the frame
// before's (touched.wgsl wave_bases left the first of each frame's at its counter word
// `base`), rows of GROUPS_ROW: makes current the frame workgroup `group` works for (by
// bisection) and returns its place among that frame's workgroups. Why not a pass sized by
// the longest list: on llvmpipe every workgroup of the shorter lists' share would run.
fn use_listed_frame_of(group: vec3<u32>, base: u32) -> u32 {
    let w = group.y * GROUPS_ROW + group.x;
    var lo = 0u;
    var hi = frames[0].frame.listed_frames;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if atomicLoad(&counters[frames[mid].frame.counters_at + base]) <= w {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    use_frame(lo);
    return w - atomicLoad(&counters[frame_word(base)]);
}
