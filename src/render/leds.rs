//! Stage 4, LEDs: point lights at the base of the finger (the paper's ring of three, or any
//! list of up to eight) light the painted skin from the inside (diffuse + Blinn-Phong
//! specular, inverse-square-like fall-off, ambient light, the paint's colour, vignetting);
//! the result is gamma-encoded to 8 bits, with optional seeded sensor noise. CPU mirror of `shaders/leds.wgsl` (same names).

use super::camera::SkinHit;
use crate::sensor::{Lighting, PaintConfig, Sensor};
use glam::{DVec2, DVec3};

/// Relative emission of an LED towards unit direction `towards`: it shines up the finger.
pub fn emission(towards: DVec3, spread: f64) -> f64 {
    if spread == 0.0 {
        return 1.0;
    }
    towards.z.max(0.0).powf(spread)
}

/// Linear radiance reaching the camera from a skin point, under the sensor's light resolved
/// once ([`Sensor::lighting`]) for every pixel shaded.
pub fn shade(light: &Lighting, paint: &PaintConfig, hit: &SkinHit) -> DVec3 {
    // The paint faces the inside of the finger, where the camera and the LEDs are.
    let facing = -hit.normal;
    let view = -hit.ray;
    let mut colour = light.ambient;
    for led in &light.leds {
        let to_led = led.position - hit.point;
        let dist = to_led.length();
        let l = to_led / dist;
        let lambert = facing.dot(l);
        if lambert <= 0.0 {
            continue;
        }
        let falloff = emission(-l, led.spread) / (1.0 + (dist / led.falloff_mm).powi(2));
        let half = (l + view).normalize();
        let spec = facing.dot(half).max(0.0).powf(paint.shininess);
        colour += led.colour
            * (led.intensity * falloff * (paint.diffuse * lambert + paint.specular * spec));
    }
    colour * light.paint_colour
}

/// The vignetting gain at `pixel`: [`Lighting::vignette`] at its distance from the principal
/// point over the lens's image-circle radius.
pub fn vignette(sensor: &Sensor, light: &Lighting, pixel: DVec2) -> f64 {
    light.vignette((pixel - sensor.principal).length() / sensor.lens.max_rho())
}

/// The 8-bit colour of `pixel` whose ray meets `hit`: shaded, vignetted, gamma-encoded.
pub fn pixel_colour(sensor: &Sensor, light: &Lighting, pixel: DVec2, hit: &SkinHit) -> [u8; 3] {
    let gain = vignette(sensor, light, pixel);
    (shade(light, &sensor.config.paint, hit) * gain)
        .to_array()
        .map(encode)
}

/// PCG hash (the same integer arithmetic runs in WGSL).
pub fn pcg_hash(input: u32) -> u32 {
    let state = input.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28).wrapping_add(4))) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// Three standard-normal samples for pixel `i` (y * width + x), one per channel, from
/// `seed`: Box-Muller on two hashed pairs of 16-bit uniforms (tails end at 4.7 sigma).
/// Deterministic: the same inputs give the same values on CPU and GPU (to float precision).
pub fn noise_samples(i: u32, seed: u32) -> [f64; 3] {
    let a = pcg_hash(i ^ pcg_hash(seed));
    let b = pcg_hash(a);
    let radius = |h: u32| (-2.0 * (((h >> 16) as f64 + 1.0) / 65_536.0).ln()).sqrt();
    let angle = |h: u32| std::f64::consts::TAU * (h & 0xFFFF) as f64 / 65_536.0;
    let (r0, r1) = (radius(a), radius(b));
    [
        r0 * angle(a).cos(),
        r0 * angle(a).sin(),
        r1 * angle(b).cos(),
    ]
}

/// 8-bit value of a linear channel: gamma 2.2, rounded.
pub fn encode(linear: f64) -> u8 {
    (linear.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0)
        .round()
        .clamp(0.0, 255.0) as u8
}

/// An 8-bit level with `noise` grey levels added, rounded and clamped (noise is applied to
/// the whole frame after shading, so the cached reference stays noise-free).
pub fn add_noise(level: u8, noise: f64) -> u8 {
    (level as f64 + noise).round().clamp(0.0, 255.0) as u8
}
