//! use shared/common.wgsl
// Test support, not a stage of a frame: the undeformed surface point each of a list of
// pixels sees through the lens, to hold the GPU's lens rays to the CPU's projection map
// (Renderer::unproject_pixels, tests/render.rs). Input: elastomer_scratch[i].xy is a pixel,
// for i < frame.pixel_rect.z; output in its place: (point, 1), or 0 beyond the lens. (Not
// the probes buffer: it keeps the reference frame's probes.)

@compute @workgroup_size(64)
fn unproject_pixels(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    use_frame(group.z);
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
