//! Stage 4, LEDs: lights at the base of the finger (the paper's ring of three, or any list
//! of up to sixteen) light the painted skin from the inside. A point LED shines straight at
//! it (diffuse + Blinn-Phong specular, inverse-square-like fall-off); a gel LED's light is
//! carried up the gel and glows in a band above it ([`gel_light`]). Then ambient light, the
//! paint's colour, vignetting, the camera's colour matrix and gamma make 8 bits, with
//! optional seeded sensor noise. CPU mirror of `shaders/shared/shading.wgsl` (same names).

use super::camera::SkinHit;
use crate::finger::Finger;
use crate::sensor::shell_end::SHELL_EDGE_MM;
use crate::sensor::{
    CameraConfig, GelSpread, Led, LedKind, Lighting, PaintConfig, Sensor, ShellEndConfig,
};
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
    let gel = (light.has_gel_leds() || light.has_ambient_relief())
        .then(|| GelPlace::of(&light.finger, hit.point, hit.normal));
    shade_at(light, paint, hit, gel.as_ref())
}

/// [`shade`] with the hit's [`GelPlace`] already known (`None` when no LED is a gel LED and
/// the ambient light is flat).
pub fn shade_at(
    light: &Lighting,
    paint: &PaintConfig,
    hit: &SkinHit,
    gel: Option<&GelPlace>,
) -> DVec3 {
    // The paint faces the inside of the finger, where the camera and the LEDs are.
    let facing = -hit.normal;
    let view = -hit.ray;
    // Only moved skin is tilted: the empty finger keeps the flat ambient's exact light.
    let mut colour = match gel {
        Some(place) if light.has_ambient_relief() && hit.indentation != 0.0 => {
            ambient_light(light.ambient, light.ambient_relief, place)
        }
        _ => light.ambient,
    };
    for led in &light.leds {
        if let (LedKind::Gel(band), Some(place)) = (led.kind, gel) {
            let azimuth = led.position.y.atan2(led.position.x);
            let glow = gel_light(light.finger.radius, azimuth, led.position.z, &band, place);
            colour += led.colour * (led.intensity * glow);
            continue;
        }
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
    if let Some(end) = &light.shell_end {
        colour = shell_end_light(end, &light.leds, colour, hit.ray);
    }
    colour * light.paint_colour
}

/// The light `colour` of the skin a camera ray `ray` sees, past a clear shell's open end
/// ([`ShellEndConfig`]): through the shell it brightens towards the end's edge (in each
/// LED's tint round it, when `leds` glow there); through the open end it is the tip's own
/// light plus the share of the LEDs' that reaches it.
pub fn shell_end_light(end: &ShellEndConfig, leds: &[Led], colour: DVec3, ray: DVec3) -> DVec3 {
    let (scale, beyond) = shell_end_parts(end, leds, ray);
    colour * scale + DVec3::from_array(end.tip_colour) * beyond
}

/// [`shell_end_light`] as colour x scale + tip_colour x beyond: (scale per channel, beyond),
/// beyond the share of the ray that passes the open end. A ray that never rises to the
/// end's plane passes through the shell far from its edge.
pub fn shell_end_parts(end: &ShellEndConfig, leds: &[Led], ray: DVec3) -> (DVec3, f64) {
    let glow = end.led_glow_deg.map(|spread| end_glow(leds, spread, ray));
    shell_end_parts_glowing(end, glow, ray)
}

/// [`shell_end_parts`] with the LEDs' [`end_glow`] where the ray crosses the end already
/// known (`None` when the end has no `led_glow_deg`).
pub fn shell_end_parts_glowing(
    end: &ShellEndConfig,
    glow: Option<DVec3>,
    ray: DVec3,
) -> (DVec3, f64) {
    if ray.z <= 0.0 {
        return (DVec3::ONE, 0.0);
    }
    let outside = end.z_mm * ray.truncate().length() / ray.z - end.inner_radius_mm;
    let beyond = 1.0 / (1.0 + (outside / SHELL_EDGE_MM).clamp(-40.0, 40.0).exp());
    let fade = (-outside.max(0.0) / end.rim_width_mm).exp();
    let rim = match glow {
        Some(glow) => (DVec3::ONE + (DVec3::splat(end.rim_glow) + glow) * fade).max(DVec3::ZERO),
        None => DVec3::splat(1.0 + end.rim_glow * fade),
    };
    (
        DVec3::splat(beyond * end.tip_transmit) + (1.0 - beyond) * rim,
        beyond,
    )
}

/// The LEDs' own glow at the shell's end where `ray` crosses it, per channel: each LED's
/// `end_glow` weighted by a von Mises bump in azimuth about it, exp((cos turn - 1) / s^2),
/// s the spread in radians (a Gaussian of standard deviation s near the LED; periodic, and
/// found from the directions' dot product alone).
pub fn end_glow(leds: &[Led], spread_deg: f64, ray: DVec3) -> DVec3 {
    weighted_end_glow(leds, end_glow_weights(leds, spread_deg, ray))
}

/// The LEDs' `end_glow`s summed with `weights` ([`end_glow_weights`], by LED).
pub fn weighted_end_glow(leds: &[Led], weights: impl Iterator<Item = f64>) -> DVec3 {
    weights.zip(leds).map(|(w, led)| led.end_glow * w).sum()
}

/// How tightly an LED's glow keeps to its azimuth round the end: one over the square of
/// its spread `spread_deg` in radians.
pub fn end_glow_concentration(spread_deg: f64) -> f64 {
    spread_deg.to_radians().powi(-2)
}

/// Each LED's weight in [`end_glow`] where `ray` crosses the end (0 for a ray along the
/// axis).
pub fn end_glow_weights(
    leds: &[Led],
    spread_deg: f64,
    ray: DVec3,
) -> impl Iterator<Item = f64> + '_ {
    let towards = ray.truncate().try_normalize();
    let concentration = end_glow_concentration(spread_deg);
    leds.iter().map(move |led| match towards {
        Some(towards) => {
            let cos_turn = towards.dot(led.position.truncate().normalize_or_zero());
            ((cos_turn - 1.0) * concentration).exp()
        }
        _ => 0.0,
    })
}

/// Where a skin point lies for the gel's light: its azimuth about the axis, its latitude
/// above the hemisphere's equator (0 on the cylinder), how far up the skin it is (its z on
/// the cylinder, the hemisphere's centre's z plus the arc above the equator on the
/// hemisphere) and how far its normal tilts up the finger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GelPlace {
    pub azimuth: f64,
    pub cos_latitude: f64,
    pub height: f64,
    pub tilt_up: f64,
}

impl GelPlace {
    pub fn of(finger: &Finger, point: DVec3, normal: DVec3) -> GelPlace {
        let r = finger.radius;
        let d = finger.cylinder_length;
        let azimuth = point.y.atan2(point.x);
        let (latitude, height) = if point.z > d {
            let latitude = (point.z - d).atan2(point.x.hypot(point.y));
            (latitude, d + r * latitude)
        } else {
            (0.0, point.z)
        };
        let (sin_lat, cos_lat) = latitude.sin_cos();
        let (sin_az, cos_az) = azimuth.sin_cos();
        let way_up = DVec3::new(-sin_lat * cos_az, -sin_lat * sin_az, cos_lat);
        GelPlace {
            azimuth,
            cos_latitude: cos_lat,
            height,
            tilt_up: normal.dot(way_up),
        }
    }
}

/// How bright a gel LED at azimuth `led_azimuth` (radians) and height `led_z` makes the skin
/// at `place`: a band up the finger above the LED, Gaussian across it (distance along the
/// surface, `width_mm` wide at the LED, `widening` more per mm up), thinning as it widens and
/// fading as exp(-s / attenuation_mm) with the distance s up the skin; times
/// max(0, 1 + relief n.t), t the way up the finger, so a skin tilted against the light's
/// path (an imprint's flank) brightens or darkens.
pub fn gel_light(
    radius: f64,
    led_azimuth: f64,
    led_z: f64,
    band: &GelSpread,
    place: &GelPlace,
) -> f64 {
    let up = (place.height - led_z).max(0.0);
    let mut turn = place.azimuth - led_azimuth;
    turn -= std::f64::consts::TAU * (turn / std::f64::consts::TAU).round();
    let across = radius * turn * place.cos_latitude;
    let width = band.width_mm + band.widening * up;
    let g = across / width;
    let glow = (-0.5 * g * g - up / band.attenuation_mm).exp() * (band.width_mm / width);
    glow * (1.0 + band.relief * place.tilt_up).max(0.0)
}

/// The ambient light at `place`: each channel times max(0, 1 + relief n.t), as a gel LED's
/// glow ([`gel_light`]), so a skin tilted against the way up the finger brightens or darkens.
pub fn ambient_light(ambient: DVec3, relief: DVec3, place: &GelPlace) -> DVec3 {
    ambient * (DVec3::ONE + relief * place.tilt_up).max(DVec3::ZERO)
}

/// The vignetting gain at `pixel`: [`Lighting::vignette`] at its distance from the principal
/// point over the image circle's radius.
pub fn vignette(sensor: &Sensor, light: &Lighting, pixel: DVec2) -> f64 {
    light.vignette((pixel - sensor.principal).length() / sensor.image_circle().1)
}

/// The 8-bit colour of `pixel` whose ray meets `hit`: shaded, vignetted, recorded by the
/// camera.
pub fn pixel_colour(sensor: &Sensor, light: &Lighting, pixel: DVec2, hit: &SkinHit) -> [u8; 3] {
    let gain = vignette(sensor, light, pixel);
    record(
        &light.camera,
        shade(light, &sensor.config.paint, hit) * gain,
    )
}

/// The 8-bit values the camera records for linear light `c`: the plain gamma 2.2 of
/// [`encode`] for the default camera, else its colour matrix and per-channel gamma.
pub fn record(camera: &CameraConfig, c: DVec3) -> [u8; 3] {
    if camera.has_default_response() {
        return c.to_array().map(encode);
    }
    let mixed = camera.mix(c).to_array();
    std::array::from_fn(|k| encode_gamma(mixed[k], camera.gamma[k]))
}

/// 8-bit value of a linear channel under the camera's `gamma`, rounded.
fn encode_gamma(linear: f64, gamma: f64) -> u8 {
    (linear.clamp(0.0, 1.0).powf(1.0 / gamma) * 255.0)
        .round()
        .clamp(0.0, 255.0) as u8
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
    encode_gamma(linear, 2.2)
}

/// An 8-bit level with `noise` grey levels added, rounded and clamped (noise is applied to
/// the whole frame after shading, so the cached reference stays noise-free).
pub fn add_noise(level: u8, noise: f64) -> u8 {
    (level as f64 + noise).round().clamp(0.0, 255.0) as u8
}
