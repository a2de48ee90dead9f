//! Stage 4, LEDs: three point lights at the base of the finger, 120 degrees apart, light the
//! painted skin from the inside (diffuse + Blinn-Phong specular, inverse-square-like
//! fall-off, a little ambient light); the result is gamma-encoded to 8 bits, with optional
//! seeded sensor noise. CPU mirror of `shaders/leds.wgsl` (same names).

use super::camera::SkinHit;
use crate::sensor::{LedColours, Sensor};
use glam::DVec3;

/// One LED: position in the camera frame and colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Led {
    pub position: DVec3,
    pub colour: DVec3,
}

/// The sensor's three LEDs: on a ring just inside the elastomer at the configured height.
pub fn leds(sensor: &Sensor) -> [Led; 3] {
    let c = &sensor.config.leds;
    let ring = 0.8 * (sensor.finger.radius - sensor.finger.shell_thickness);
    let colours = match c.colours {
        LedColours::Rgb => [DVec3::X, DVec3::Y, DVec3::Z],
        LedColours::White => [DVec3::splat(0.5); 3],
    };
    std::array::from_fn(|i| {
        let a = (c.azimuth_deg + 120.0 * i as f64).to_radians();
        Led {
            position: DVec3::new(ring * a.cos(), ring * a.sin(), c.z_mm),
            colour: colours[i],
        }
    })
}

/// Relative emission of an LED towards unit direction `towards`: it shines up the finger.
pub fn emission(towards: DVec3, spread: f64) -> f64 {
    if spread == 0.0 {
        return 1.0;
    }
    towards.z.max(0.0).powf(spread)
}

/// Linear radiance reaching the camera from a skin point.
pub fn shade(sensor: &Sensor, hit: &SkinHit) -> DVec3 {
    let c = &sensor.config;
    // The paint faces the inside of the finger, where the camera and the LEDs are.
    let facing = -hit.normal;
    let view = -hit.ray;
    let mut colour = DVec3::splat(c.leds.ambient);
    for led in leds(sensor) {
        let to_led = led.position - hit.point;
        let dist = to_led.length();
        let l = to_led / dist;
        let lambert = facing.dot(l);
        if lambert <= 0.0 {
            continue;
        }
        let falloff = emission(-l, c.leds.spread) / (1.0 + (dist / c.leds.falloff_mm).powi(2));
        let half = (l + view).normalize();
        let spec = facing.dot(half).max(0.0).powf(c.paint.shininess);
        colour += led.colour
            * (c.leds.intensity * falloff * (c.paint.diffuse * lambert + c.paint.specular * spec));
    }
    colour
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
