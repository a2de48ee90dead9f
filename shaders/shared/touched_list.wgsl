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

// Place on the touched list of invocation `id` of a pass over it (TOUCHED_WORKGROUP
// invocations a workgroup, at most TOUCHED_MAX_GROUPS workgroups a row).
fn touched_index(id: vec3<u32>) -> u32 {
    return id.y * TOUCHED_MAX_GROUPS * TOUCHED_WORKGROUP + id.x;
}
