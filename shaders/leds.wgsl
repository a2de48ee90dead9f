//! use shared/common.wgsl
//! use shared/shading.wgsl
// Stage 4, LEDs: point lights at the finger's base light the painted skin (the light
// model, shared/shading.wgsl, is applied by the camera's passes as each ray lands, so no
// G-buffer travels between the stages); here, the sensor's seeded noise on the finished
// frame. Mirror: src/render/leds.rs.

fn pcg_hash(input: u32) -> u32 {
    let state = input * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Three standard-normal samples for pixel `i` (one per channel) from `seed`: Box-Muller on
// two hashed pairs of 16-bit uniforms (tails end at 4.7 sigma). Two hashes and two
// logarithms a pixel: the noise pass runs over the whole frame, every frame.
// Mirror: src/render/leds.rs noise_samples.
fn noise_samples(i: u32, seed: u32) -> vec3<f32> {
    let a = pcg_hash(i ^ pcg_hash(seed));
    let b = pcg_hash(a);
    let r0 = sqrt(-2.0 * log((f32(a >> 16u) + 1.0) / 65536.0));
    let r1 = sqrt(-2.0 * log((f32(b >> 16u) + 1.0) / 65536.0));
    let t0 = 2.0 * PI * f32(a & 65535u) / 65536.0;
    let t1 = 2.0 * PI * f32(b & 65535u) / 65536.0;
    return vec3<f32>(r0 * cos(t0), r0 * sin(t0), r1 * cos(t1));
}

// Sensor noise over the whole frame (the cached reference is noise-free), on every pixel the
// lens sees.
@compute @workgroup_size(8, 8)
fn add_noise(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    use_frame(group.z);
    if id.x >= sensor.image_size.x || id.y >= sensor.image_size.y {
        return;
    }
    let i = id.y * sensor.image_size.x + id.x;
    // The reference frame left t_in = 0 where the lens sees nothing (camera.wgsl camera).
    if textureLoad(probe_map, vec2<u32>(2u * id.x + 1u, id.y), 0).z == 0.0 {
        return;
    }
    let at = image_index(id.xy);
    let v = image[at];
    let n = sensor.noise.xyz * noise_samples(i, frame.noise_seed);
    let level = vec3<f32>(vec3<u32>(v, v >> 8u, v >> 16u) & vec3<u32>(255u)) + n;
    let out = vec3<u32>(clamp(round(level), vec3<f32>(0.0), vec3<f32>(255.0)));
    image[at] = pack_rgba(out);
}
