//! The empty finger's picture as a function of the values calibration fits: each LED's
//! place, colour, spread and fall-off, the ambient light, the paint's shine, the camera's
//! vignetting and the finger's length (where the hemisphere meets the cylinder). It is the
//! renderer's own light model ([`crate::render::leds::shade`]), evaluated at sampled
//! pixels, so the fitted values mean in `sensor.toml` what they meant while fitting.

use crate::finger::Finger;
use crate::render::camera::SkinHit;
use crate::render::leds;
use crate::sensor::{Led, LedConfig, Leds, Lighting, Sensor, SensorConfig};
use glam::{DVec2, DVec3};

use super::solve::Bound;

/// Values per LED: azimuth (deg), z (mm), distance from the axis (mm), colour (RGB),
/// spread, fall-off (mm).
pub const PER_LED: usize = 8;
/// Values after the LEDs: ambient (RGB), specular, shininess, vignetting (a, b), the
/// cylinder's length (mm).
pub const GLOBAL: usize = 7;

/// What each value is called in the report, by index.
pub fn names(leds: usize) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..leds {
        for what in [
            "azimuth_deg",
            "z_mm",
            "radius_mm",
            "colour[0]",
            "colour[1]",
            "colour[2]",
            "spread",
            "falloff_mm",
        ] {
            out.push(format!("leds[{i}].{what}"));
        }
    }
    for what in [
        "light.ambient[0]",
        "light.ambient[1]",
        "light.ambient[2]",
        "paint.specular",
        "paint.shininess",
        "light.vignetting[0]",
        "light.vignetting[1]",
        "finger.cylinder_length_mm",
    ] {
        out.push(what.to_string());
    }
    out
}

/// The pixels a fit compares: where each sits and which ray it casts.
#[derive(Debug, Clone)]
pub struct Samples {
    pub pixels: Vec<DVec2>,
    pub rays: Vec<DVec3>,
    /// The observed colour (8-bit levels).
    pub observed: Vec<[f64; 3]>,
    /// Each pixel's vignetting x: its distance from the principal point over the image
    /// circle's radius.
    pub radial: Vec<f64>,
}

impl Samples {
    /// The pixels of `pixels` that the lens of `sensor` sees, with their observed colours.
    pub fn new(sensor: &Sensor, pixels: &[(DVec2, [f64; 3])]) -> Samples {
        let mut out = Samples {
            pixels: Vec::new(),
            rays: Vec::new(),
            observed: Vec::new(),
            radial: Vec::new(),
        };
        let max_rho = sensor.lens.max_rho();
        for &(p, obs) in pixels {
            if let Some(ray) = sensor.ray_direction(p) {
                out.pixels.push(p);
                out.rays.push(ray);
                out.observed.push(obs);
                out.radial.push((p - sensor.principal).length() / max_rho);
            }
        }
        out
    }

    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }
}

/// The model: the start sensor (everything calibration does not fit) and how many LEDs.
#[derive(Debug, Clone)]
pub struct Model {
    pub start: Sensor,
    pub leds: usize,
}

/// The values of `params` as the renderer's light, paint and finger.
pub struct Decoded {
    pub lighting: Lighting,
    pub specular: f64,
    pub shininess: f64,
    pub finger: Finger,
}

impl Model {
    pub fn len(&self) -> usize {
        self.leds * PER_LED + GLOBAL
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Each value's box and finite-difference step.
    pub fn bounds(&self) -> Vec<Bound> {
        let f = &self.start.finger;
        let b = |lo: f64, hi: f64, step: f64| Bound { lo, hi, step };
        let mut out = Vec::with_capacity(self.len());
        // The boxes keep the model physical and every fitted sensor valid: LEDs at the
        // finger's base, inside it, below the hemisphere (z < half the radius, the finger at
        // least a radius long); a fall-off no shorter than a millimetre (shorter ones only
        // trade the LED's brightness for its distance); a paint that shines at most twice
        // as much as it scatters, in a lobe no wider than cos^4; vignetting whose gain stays
        // above 0.01 across the circle (1 + a x^2 + b x^4 with a >= -0.9, b >= -0.09).
        for _ in 0..self.leds {
            out.extend([
                b(-1e4, 1e4, 1e-3),
                b(-4.0 * f.radius, 0.5 * f.radius, 1e-4),
                b(0.0, f.radius * 0.999, 1e-4),
                b(0.0, 1e3, 1e-6),
                b(0.0, 1e3, 1e-6),
                b(0.0, 1e3, 1e-6),
                b(0.0, 40.0, 1e-4),
                b(1.0, 500.0, 1e-3),
            ]);
        }
        out.extend([
            b(0.0, 50.0, 1e-6),
            b(0.0, 50.0, 1e-6),
            b(0.0, 50.0, 1e-6),
            b(0.0, 2.0 * self.start.config.paint.diffuse, 1e-5),
            b(4.0, 200.0, 1e-3),
            b(-0.9, 3.0, 1e-5),
            b(-0.09, 3.0, 1e-5),
            b(f.radius, f.radius * 8.0, 1e-4),
        ]);
        out
    }

    /// The start sensor's values (its LEDs when it has `leds` of them, else a ring at
    /// `ring_azimuth`), as a parameter vector.
    pub fn initial(&self, ring_azimuth_deg: f64) -> Vec<f64> {
        let s = &self.start;
        let light = s.lighting();
        let paint = &s.config.paint;
        let ring = crate::sensor::lighting::ring_radius(s.finger.radius, s.finger.shell_thickness);
        let mut p = Vec::with_capacity(self.len());
        for i in 0..self.leds {
            let led = light.leds.get(i).copied().unwrap_or(Led {
                position: DVec3::new(0.0, 0.0, -2.0),
                colour: DVec3::splat(0.5),
                intensity: 2.0,
                spread: 2.0,
                falloff_mm: 10.0,
            });
            let azimuth = ring_azimuth_deg + 360.0 * i as f64 / self.leds as f64;
            let c = led.colour * led.intensity;
            p.extend([
                azimuth,
                led.position.z,
                ring,
                c.x,
                c.y,
                c.z,
                led.spread,
                led.falloff_mm,
            ]);
        }
        p.extend([
            light.ambient.x,
            light.ambient.y,
            light.ambient.z,
            paint.specular,
            paint.shininess,
            0.0,
            0.0,
            s.finger.cylinder_length,
        ]);
        p
    }

    pub fn decode(&self, p: &[f64]) -> Decoded {
        let leds = (0..self.leds)
            .map(|i| {
                let v = &p[i * PER_LED..(i + 1) * PER_LED];
                let a = v[0].to_radians();
                Led {
                    position: DVec3::new(v[2] * a.cos(), v[2] * a.sin(), v[1]),
                    colour: DVec3::new(v[3], v[4], v[5]),
                    intensity: 1.0,
                    spread: v[6],
                    falloff_mm: v[7],
                }
            })
            .collect();
        let g = &p[self.leds * PER_LED..];
        Decoded {
            lighting: Lighting {
                leds,
                ambient: DVec3::new(g[0], g[1], g[2]),
                paint_colour: DVec3::ONE,
                vignetting: [g[5], g[6]],
            },
            specular: g[3],
            shininess: g[4],
            finger: Finger {
                cylinder_length: g[7],
                ..self.start.finger
            },
        }
    }

    /// The predicted 8-bit colour of every sample, before clipping at 255 (so a fit can see
    /// how far past saturation a value lies).
    pub fn predict(&self, p: &[f64], samples: &Samples) -> Vec<[f64; 3]> {
        let d = self.decode(p);
        let mut paint = self.start.config.paint.clone();
        paint.specular = d.specular;
        paint.shininess = d.shininess;
        samples
            .rays
            .iter()
            .zip(&samples.radial)
            .map(|(&ray, &x)| match d.finger.surface_along(ray) {
                Some(s) => {
                    let hit = SkinHit {
                        point: s.point,
                        normal: s.normal,
                        indentation: 0.0,
                        ray,
                    };
                    let gain = d.lighting.vignette(x);
                    let c = leds::shade(&d.lighting, &paint, &hit) * gain;
                    c.to_array().map(|v| 255.0 * v.max(0.0).powf(1.0 / 2.2))
                }
                None => [0.0; 3],
            })
            .collect()
    }

    /// The sensor these values describe: the start sensor with its light, paint and
    /// finger length replaced. Each LED's colour is written normalised to its brightest
    /// channel, that channel's value becoming its intensity.
    pub fn config(&self, p: &[f64]) -> SensorConfig {
        let d = self.decode(p);
        let mut c = self.start.config.clone();
        c.finger.cylinder_length_mm = d.finger.cylinder_length;
        c.paint.specular = d.specular;
        c.paint.shininess = d.shininess;
        c.paint.colour = [1.0; 3];
        c.light.ambient = Some(d.lighting.ambient.to_array());
        c.light.vignetting = d.lighting.vignetting;
        c.leds = Leds::List(
            (0..self.leds)
                .map(|i| {
                    let v = &p[i * PER_LED..(i + 1) * PER_LED];
                    let colour = [v[3], v[4], v[5]];
                    let peak = colour.iter().copied().fold(0.0, f64::max);
                    let (colour, intensity) = if peak > 0.0 {
                        (colour.map(|c| c / peak), peak)
                    } else {
                        ([1.0; 3], 0.0)
                    };
                    LedConfig {
                        colour,
                        azimuth_deg: v[0].rem_euclid(360.0),
                        z_mm: v[1],
                        radius_mm: Some(v[2]),
                        intensity,
                        spread: v[6],
                        falloff_mm: v[7],
                    }
                })
                .collect(),
        );
        c
    }
}
