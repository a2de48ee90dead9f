//! use shared/common.wgsl
// A frame's start, every frame of a wave in one dispatch: its image buffers hold its rect of
// the image (image_x, image_y, image_w, image_h), the reference's pixels there and zero
// indentation; its counters before the touched list are zero (the list itself needs no
// clearing: only the places its counts hold are read). The heightfield's clears are copies
// (src/render/gpu/frame.rs). Why a pass: one dispatch for the wave, where copies and
// clears would be several a frame, each behind a barrier of its own.
@compute @workgroup_size(8, 8)
fn frame_start(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    use_frame(group.z);
    // The first workgroup's invocations clear the counters, a word each (TOUCHED_LIST is
    // the workgroup's 64).
    if id.x < 8u && id.y < 8u {
        atomicStore(&counters[frame_word(id.y * 8u + id.x)], 0u);
    }
    if id.x >= frame.image_w || id.y >= frame.image_h {
        return;
    }
    let xy = vec2<u32>(frame.image_x + id.x, frame.image_y + id.y);
    let at = image_index(xy);
    image[at] = textureLoad(reference_image, xy, 0).x;
    indentation[at] = 0.0;
}
