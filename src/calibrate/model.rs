//! The empty finger's picture as a function of the values calibration fits: each LED's
//! place, colour and spread (point LEDs: height, distance from the axis, spread, fall-off;
//! gel LEDs: their azimuth, and the band all of them share), the ambient light, the paint's
//! shine (point LEDs), the camera's vignetting, colour matrix and gamma, a clear shell's
//! open end where the sensor has one, and, when asked, the finger's length. It is the
//! renderer's own light model ([`crate::render::leds::shade`],
//! [`crate::render::leds::record`]) evaluated at sampled pixels, so the fitted values mean in
//! `sensor.toml` what they meant while fitting.

use crate::finger::Finger;
use crate::lens::Lens;
use crate::render::camera::SkinHit;
use crate::render::leds::{self, GelPlace};
use crate::sensor::{
    CameraConfig, GelSpread, Led, LedConfig, LedKind, LedKindName, Leds, Lighting, Sensor,
    SensorConfig,
};
use glam::{DVec2, DVec3};

use super::solve::Bound;

/// Values per point LED: azimuth (deg), z (mm), distance from the axis (mm), colour (RGB),
/// spread, fall-off (mm).
pub const PER_POINT_LED: usize = 8;
/// Values per gel LED: azimuth (deg), colour (RGB).
pub const PER_GEL_LED: usize = 4;

/// Where each group of values sits in a parameter vector: what a [`Model`] fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub per_led: usize,
    /// Where an LED's colour (RGB) starts among its values.
    pub colour: usize,
    /// Ambient light (RGB).
    pub ambient: usize,
    /// Vignetting a, b.
    pub vignetting: usize,
    /// Paint specular and shininess (point LEDs only: gel light has no highlight).
    pub shine: Option<usize>,
    /// The gel LEDs' shared band: width (mm), widening, attenuation (mm). Their height is
    /// held: it only trades with the width and the colours' scale.
    pub band: Option<usize>,
    /// The camera's colour matrix off its diagonal (6, by row) and its gamma (3).
    pub camera: Option<usize>,
    /// The cylinder's length (mm).
    pub length: Option<usize>,
    /// The lens's principal point (px), when the image circle is a mask apart from it.
    pub principal: Option<usize>,
    /// The lens's focal length (px).
    pub focal: Option<usize>,
    /// A clear shell's open end, when the start sensor has one: its height (mm), the tip's
    /// own light (RGB), the share of the LEDs' reaching the tip, the rim's glow and width
    /// (mm). Its inner radius is held (the build's).
    pub shell_end: Option<usize>,
    /// Each LED's glow at that end (RGB, by LED) and how far round it spreads (deg), when
    /// the start's end has `led_glow_deg`: all of their values.
    pub end_glow: Option<std::ops::Range<usize>>,
    pub len: usize,
}

/// Values of a shell's open end ([`Layout::shell_end`]).
pub const SHELL_END_VALUES: usize = 7;

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
    /// Where each ray meets the start sensor's finger, and that place for the gel's light:
    /// what every prediction reuses while the finger is held.
    pub hits: Vec<Option<(SkinHit, GelPlace)>>,
}

impl Samples {
    /// The pixels of `pixels` that the lens of `sensor` sees, with their observed colours.
    pub fn new(sensor: &Sensor, pixels: &[(DVec2, [f64; 3])]) -> Samples {
        let mut out = Samples {
            pixels: Vec::new(),
            rays: Vec::new(),
            observed: Vec::new(),
            radial: Vec::new(),
            hits: Vec::new(),
        };
        let radius = sensor.image_circle().1;
        for &(p, obs) in pixels {
            if let Some(ray) = sensor.ray_direction(p) {
                out.pixels.push(p);
                out.rays.push(ray);
                out.observed.push(obs);
                out.radial.push((p - sensor.principal).length() / radius);
                out.hits.push(hit_on(&sensor.finger, ray));
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

/// The model: the start sensor (everything calibration does not fit), how many LEDs of
/// which kind, and which of the camera and the finger's length are fitted too.
#[derive(Debug, Clone)]
pub struct Model {
    pub start: Sensor,
    pub leds: usize,
    pub kind: LedKindName,
    /// Fit the camera's colour matrix and gamma (else the start's are held).
    pub camera: bool,
    /// Fit the finger's length (else the start's is held).
    pub geometry: bool,
    /// Fit the lens's principal point within this many px of the start's (else held): where
    /// the image circle is a mask, its centre need not be the lens's.
    pub principal: Option<f64>,
    /// Fit the focal length from this fraction of the start's up to 1 + [`FOCAL_REACH`] of
    /// it (else held).
    pub focal: Option<f64>,
}

/// How far the focal length may be fitted from the start's, as a fraction of it.
pub const FOCAL_REACH: f64 = 0.3;

/// The values of `params` as the renderer's light, paint and finger.
pub struct Decoded {
    pub lighting: Lighting,
    pub specular: f64,
    pub shininess: f64,
    pub finger: Finger,
    pub principal: DVec2,
    pub lens: Lens,
}

impl Model {
    /// A model of `leds` point LEDs with the camera and the finger held: what calibration
    /// fitted before it knew other kinds.
    pub fn point(start: Sensor, leds: usize) -> Model {
        Model {
            start,
            leds,
            kind: LedKindName::Point,
            camera: false,
            geometry: false,
            principal: None,
            focal: None,
        }
    }

    pub fn layout(&self) -> Layout {
        let (per_led, colour) = match self.kind {
            LedKindName::Point => (PER_POINT_LED, 3),
            LedKindName::Gel => (PER_GEL_LED, 1),
        };
        let mut at = self.leds * per_led;
        let mut take = |n: usize| {
            let i = at;
            at += n;
            i
        };
        let ambient = take(3);
        let vignetting = take(2);
        let shine = (self.kind == LedKindName::Point).then(|| take(2));
        let band = (self.kind == LedKindName::Gel).then(|| take(3));
        let camera = self.camera.then(|| take(9));
        let length = self.geometry.then(|| take(1));
        let principal = self.principal.map(|_| take(2));
        let focal = self.focal.map(|_| take(1));
        let shell_end = self
            .start
            .config
            .shell_end
            .is_some()
            .then(|| take(SHELL_END_VALUES));
        let glow_values = 3 * self.leds + 1;
        let end_glow = self.fits_end_glow().then(|| {
            let from = take(glow_values);
            from..from + glow_values
        });
        Layout {
            per_led,
            colour,
            ambient,
            vignetting,
            shine,
            band,
            camera,
            length,
            principal,
            focal,
            shell_end,
            end_glow,
            len: at,
        }
    }

    /// Whether the LEDs' glow at a shell's open end is fitted: when the start's end says
    /// how far round it spreads.
    pub fn fits_end_glow(&self) -> bool {
        self.start
            .config
            .shell_end
            .is_some_and(|e| e.led_glow_deg.is_some())
    }

    pub fn len(&self) -> usize {
        self.layout().len
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// What each value is called in the report, by index.
    pub fn names(&self) -> Vec<String> {
        let l = self.layout();
        let mut out = Vec::with_capacity(l.len);
        let per_led: &[&str] = match self.kind {
            LedKindName::Point => &[
                "azimuth_deg",
                "z_mm",
                "radius_mm",
                "colour[0]",
                "colour[1]",
                "colour[2]",
                "spread",
                "falloff_mm",
            ],
            LedKindName::Gel => &["azimuth_deg", "colour[0]", "colour[1]", "colour[2]"],
        };
        for i in 0..self.leds {
            out.extend(per_led.iter().map(|what| format!("leds[{i}].{what}")));
        }
        out.extend(
            [
                "light.ambient[0]",
                "light.ambient[1]",
                "light.ambient[2]",
                "light.vignetting[0]",
                "light.vignetting[1]",
            ]
            .map(String::from),
        );
        if l.shine.is_some() {
            out.extend(["paint.specular", "paint.shininess"].map(String::from));
        }
        if l.band.is_some() {
            out.extend(
                [
                    "leds[*].width_mm",
                    "leds[*].widening",
                    "leds[*].attenuation_mm",
                ]
                .map(String::from),
            );
        }
        if l.camera.is_some() {
            for (i, j) in OFF_DIAGONAL {
                out.push(format!("camera.colour_matrix[{i}][{j}]"));
            }
            out.extend((0..3).map(|k| format!("camera.gamma[{k}]")));
        }
        if l.length.is_some() {
            out.push("finger.cylinder_length_mm".to_string());
        }
        if l.principal.is_some() {
            out.extend(["lens.cx", "lens.cy"].map(String::from));
        }
        if l.focal.is_some() {
            out.push("lens.focal_px".to_string());
        }
        if l.shell_end.is_some() {
            out.extend(
                [
                    "shell_end.z_mm",
                    "shell_end.tip_colour[0]",
                    "shell_end.tip_colour[1]",
                    "shell_end.tip_colour[2]",
                    "shell_end.tip_transmit",
                    "shell_end.rim_glow",
                    "shell_end.rim_width_mm",
                ]
                .map(String::from),
            );
        }
        if l.end_glow.is_some() {
            for i in 0..self.leds {
                out.extend((0..3).map(|k| format!("leds[{i}].end_glow[{k}]")));
            }
            out.push("shell_end.led_glow_deg".to_string());
        }
        out
    }

    /// Each value's box and finite-difference step.
    pub fn bounds(&self) -> Vec<Bound> {
        let f = &self.start.finger;
        let l = self.layout();
        let b = |lo: f64, hi: f64, step: f64| Bound { lo, hi, step };
        let mut out = Vec::with_capacity(l.len);
        // The boxes keep the model physical and every fitted sensor valid: LEDs at the
        // finger's base, inside it, below the hemisphere (z < half the radius, the finger at
        // least a radius long); a fall-off no shorter than a millimetre (shorter ones only
        // trade the LED's brightness for its distance); a paint that shines at most twice
        // as much as it scatters, in a lobe no wider than cos^4; vignetting whose gain stays
        // above 0.01 across the circle (1 + a x^2 + b x^4 with a >= -0.9, b >= -0.09); a
        // gel band at least 0.3 mm wide that fades over at least a millimetre; a camera
        // whose channels mix by at most their own size and whose gamma is 1 to 5.
        for _ in 0..self.leds {
            match self.kind {
                LedKindName::Point => out.extend([
                    b(-1e4, 1e4, 1e-3),
                    b(-4.0 * f.radius, 0.5 * f.radius, 1e-4),
                    b(0.0, f.radius * 0.999, 1e-4),
                    b(0.0, 1e3, 1e-6),
                    b(0.0, 1e3, 1e-6),
                    b(0.0, 1e3, 1e-6),
                    b(0.0, 40.0, 1e-4),
                    b(1.0, 500.0, 1e-3),
                ]),
                LedKindName::Gel => out.extend([
                    b(-1e4, 1e4, 1e-3),
                    b(0.0, 1e3, 1e-6),
                    b(0.0, 1e3, 1e-6),
                    b(0.0, 1e3, 1e-6),
                ]),
            }
        }
        out.extend([
            b(0.0, 50.0, 1e-6),
            b(0.0, 50.0, 1e-6),
            b(0.0, 50.0, 1e-6),
            b(-0.9, 3.0, 1e-5),
            b(-0.09, 3.0, 1e-5),
        ]);
        if l.shine.is_some() {
            out.extend([
                b(0.0, 2.0 * self.start.config.paint.diffuse, 1e-5),
                b(4.0, 200.0, 1e-3),
            ]);
        }
        if l.band.is_some() {
            out.extend([
                b(0.3, 4.0 * f.radius, 1e-4),
                b(0.0, 5.0, 1e-5),
                b(1.0, 1e3, 1e-3),
            ]);
        }
        if l.camera.is_some() {
            out.extend((0..6).map(|_| b(-1.0, 1.0, 1e-5)));
            out.extend((0..3).map(|_| b(1.0, 5.0, 1e-5)));
        }
        if l.length.is_some() {
            out.push(b(f.radius, f.radius * 8.0, 1e-4));
        }
        if let Some(reach) = self.principal {
            let c = self.start.principal;
            out.extend([
                b(c.x - reach, c.x + reach, 1e-3),
                b(c.y - reach, c.y + reach, 1e-3),
            ]);
        }
        if let Some(low) = self.focal {
            let f = self.start.lens.focal_px;
            out.push(b(f * low, f * (1.0 + FOCAL_REACH), 1e-4 * f));
        }
        if let Some(end) = &self.start.config.shell_end {
            // The end between the shell's own radius above the camera and the tip; a tip
            // that may get up to all the LEDs' light back; a rim at most ten times as bright,
            // fading over 0.1 mm to the finger's size.
            let top = f.cylinder_length + f.radius;
            out.push(b(end.inner_radius_mm, top * 0.999, 1e-4));
            out.extend((0..3).map(|_| b(0.0, 50.0, 1e-6)));
            out.extend([
                b(0.0, 1.0, 1e-5),
                b(-0.9, 10.0, 1e-5),
                b(0.1, 2.0 * f.radius, 1e-4),
            ]);
        }
        if l.end_glow.is_some() {
            // Each LED's tint of the rim as bounded as the rim's own glow; spread over 5 to
            // 120 degrees (narrower than the band of an LED, wider than a third of the ring).
            out.extend((0..3 * self.leds).map(|_| b(-0.9, 10.0, 1e-5)));
            out.push(b(5.0, 120.0, 1e-3));
        }
        out
    }

    /// The start sensor's values as a parameter vector: its LEDs when it has `leds` of this
    /// kind (turned by `ring_azimuth_deg`), else a ring starting at `ring_azimuth_deg`.
    pub fn initial(&self, ring_azimuth_deg: f64) -> Vec<f64> {
        let s = &self.start;
        let light = s.lighting();
        let paint = &s.config.paint;
        let ring = crate::sensor::lighting::ring_radius(s.finger.radius, s.finger.shell_thickness);
        let own: Vec<&Led> = light
            .leds
            .iter()
            .filter(|l| kind_name(l.kind) == self.kind)
            .collect();
        let keep_own = own.len() == self.leds;
        let mut p = Vec::with_capacity(self.len());
        let mut band = GelSpread::DEFAULT;
        for i in 0..self.leds {
            let led = if let (true, Some(own)) = (keep_own, own.get(i)) {
                **own
            } else {
                Led {
                    position: DVec3::new(0.0, 0.0, -2.0),
                    colour: DVec3::splat(0.5),
                    intensity: 2.0,
                    spread: 2.0,
                    falloff_mm: 10.0,
                    kind: LedKind::Point,
                    end_glow: DVec3::ZERO,
                }
            };
            let azimuth = if keep_own {
                led.position.y.atan2(led.position.x).to_degrees() + ring_azimuth_deg
            } else {
                ring_azimuth_deg + 360.0 * i as f64 / self.leds as f64
            };
            let c = led.colour * led.intensity;
            match self.kind {
                LedKindName::Point => p.extend([
                    azimuth,
                    led.position.z,
                    ring,
                    c.x,
                    c.y,
                    c.z,
                    led.spread,
                    led.falloff_mm,
                ]),
                LedKindName::Gel => {
                    if let LedKind::Gel(b) = led.kind {
                        band = b;
                    }
                    p.extend([azimuth, c.x, c.y, c.z]);
                }
            }
        }
        p.extend([
            light.ambient.x,
            light.ambient.y,
            light.ambient.z,
            light.vignetting[0],
            light.vignetting[1],
        ]);
        let l = self.layout();
        if l.shine.is_some() {
            p.extend([paint.specular, paint.shininess]);
        }
        if l.band.is_some() {
            p.extend([band.width_mm, band.widening, band.attenuation_mm]);
        }
        if l.camera.is_some() {
            let cam = &s.config.camera;
            p.extend(OFF_DIAGONAL.map(|(i, j)| cam.colour_matrix[i][j]));
            p.extend(cam.gamma);
        }
        if l.length.is_some() {
            p.push(s.finger.cylinder_length);
        }
        if l.principal.is_some() {
            p.extend([s.principal.x, s.principal.y]);
        }
        if l.focal.is_some() {
            p.push(s.lens.focal_px);
        }
        if let Some(end) = &s.config.shell_end {
            p.push(end.z_mm);
            p.extend(end.tip_colour);
            p.extend([end.tip_transmit, end.rim_glow, end.rim_width_mm]);
        }
        if let (Some(_), Some(end)) = (&l.end_glow, &s.config.shell_end) {
            for i in 0..self.leds {
                let glow = match (keep_own, own.get(i)) {
                    (true, Some(led)) => led.end_glow,
                    _ => DVec3::ZERO,
                };
                p.extend(glow.to_array());
            }
            p.push(end.led_glow_deg.unwrap_or(30.0));
        }
        p
    }

    pub fn decode(&self, p: &[f64]) -> Decoded {
        let l = self.layout();
        let start_paint = &self.start.config.paint;
        let (specular, shininess) = match l.shine {
            Some(i) => (p[i], p[i + 1]),
            None => (start_paint.specular, start_paint.shininess),
        };
        let finger = Finger {
            cylinder_length: l.length.map_or(self.start.finger.cylinder_length, |i| p[i]),
            ..self.start.finger
        };
        let ring = crate::sensor::lighting::ring_radius(finger.radius, finger.shell_thickness);
        let band = l.band.map(|i| {
            let (z, relief) = self.start_gel();
            (
                GelSpread {
                    width_mm: p[i],
                    widening: p[i + 1],
                    attenuation_mm: p[i + 2],
                    relief,
                },
                z,
            )
        });
        let leds = (0..self.leds)
            .map(|i| {
                let v = &p[i * l.per_led..(i + 1) * l.per_led];
                let a = v[0].to_radians();
                let colour = DVec3::from_slice(&v[l.colour..l.colour + 3]);
                let end_glow = l.end_glow.as_ref().map_or(DVec3::ZERO, |g| {
                    DVec3::from_slice(&p[g.start + 3 * i..g.start + 3 * i + 3])
                });
                match (self.kind, band) {
                    (LedKindName::Gel, Some((band, z))) => Led {
                        position: DVec3::new(ring * a.cos(), ring * a.sin(), z),
                        colour,
                        intensity: 1.0,
                        spread: 0.0,
                        falloff_mm: 1.0,
                        kind: LedKind::Gel(band),
                        end_glow,
                    },
                    _ => Led {
                        position: DVec3::new(v[2] * a.cos(), v[2] * a.sin(), v[1]),
                        colour,
                        intensity: 1.0,
                        spread: v[6],
                        falloff_mm: v[7],
                        kind: LedKind::Point,
                        end_glow,
                    },
                }
            })
            .collect();
        let camera = match l.camera {
            Some(i) => {
                let mut c = CameraConfig {
                    blur_px: self.start.config.camera.blur_px,
                    ..CameraConfig::default()
                };
                for (k, (r, col)) in OFF_DIAGONAL.iter().enumerate() {
                    c.colour_matrix[*r][*col] = p[i + k];
                }
                c.gamma = [p[i + 6], p[i + 7], p[i + 8]];
                c
            }
            None => self.start.config.camera,
        };
        let a = l.ambient;
        let v = l.vignetting;
        Decoded {
            lighting: Lighting {
                leds,
                ambient: DVec3::new(p[a], p[a + 1], p[a + 2]),
                ambient_relief: DVec3::from_array(self.start.config.light.ambient_relief),
                paint_colour: DVec3::ONE,
                vignetting: [p[v], p[v + 1]],
                finger,
                camera,
                shell_end: l.shell_end.and_then(|i| {
                    let end = self.start.config.shell_end?;
                    Some(crate::sensor::ShellEndConfig {
                        z_mm: p[i],
                        tip_colour: [p[i + 1], p[i + 2], p[i + 3]],
                        tip_transmit: p[i + 4],
                        rim_glow: p[i + 5],
                        rim_width_mm: p[i + 6],
                        led_glow_deg: l
                            .end_glow
                            .as_ref()
                            .map_or(end.led_glow_deg, |g| Some(p[g.end - 1])),
                        ..end
                    })
                }),
            },
            specular,
            shininess,
            finger,
            principal: l
                .principal
                .map_or(self.start.principal, |i| DVec2::new(p[i], p[i + 1])),
            lens: Lens {
                focal_px: l.focal.map_or(self.start.lens.focal_px, |i| p[i]),
                ..self.start.lens
            },
        }
    }

    /// The height and relief of the start sensor's first gel LED (the ring's height and the
    /// default relief without one): both held, as an empty frame cannot show the relief
    /// (the undeformed skin runs along the light) and the height only trades with the band.
    fn start_gel(&self) -> (f64, f64) {
        self.start
            .lighting()
            .leds
            .iter()
            .find_map(|l| match l.kind {
                LedKind::Gel(b) => Some((l.position.z, b.relief)),
                LedKind::Point => None,
            })
            .unwrap_or((
                crate::sensor::LedsConfig::default().z_mm,
                GelSpread::DEFAULT.relief,
            ))
    }

    /// Where sample `i`'s ray meets the finger the values `d` describe, and its vignetting
    /// x: the sample's cached hit and x on the start sensor while the finger and the
    /// lens are held.
    pub fn hit(
        &self,
        d: &Decoded,
        samples: &Samples,
        i: usize,
    ) -> (Option<(SkinHit, GelPlace)>, f64) {
        if d.principal != self.start.principal || d.lens != self.start.lens {
            let offset = samples.pixels[i] - d.principal;
            let x = offset.length() / self.start.image_circle().1;
            let hit = d.lens.ray(offset).and_then(|ray| hit_on(&d.finger, ray));
            (hit, x)
        } else if self.geometry {
            (hit_on(&d.finger, samples.rays[i]), samples.radial[i])
        } else {
            (samples.hits[i], samples.radial[i])
        }
    }

    /// The start's paint with the shine the values `d` give it.
    pub fn paint(&self, d: &Decoded) -> crate::sensor::PaintConfig {
        crate::sensor::PaintConfig {
            specular: d.specular,
            shininess: d.shininess,
            ..self.start.config.paint.clone()
        }
    }

    /// The predicted 8-bit colour of every sample, before clipping at 255 (so a fit can see
    /// how far past saturation a value lies).
    pub fn predict(&self, p: &[f64], samples: &Samples) -> Vec<[f64; 3]> {
        let d = self.decode(p);
        let paint = self.paint(&d);
        (0..samples.len())
            .map(|i| match self.hit(&d, samples, i) {
                (Some((hit, place)), x) => {
                    let gain = d.lighting.vignette(x);
                    let light = leds::shade_at(&d.lighting, &paint, &hit, Some(&place));
                    recorded(&d.lighting.camera, light * gain)
                }
                (None, _) => [0.0; 3],
            })
            .collect()
    }

    /// The sensor these values describe: the start sensor with its light, paint, camera and
    /// finger length replaced. Each LED's colour is written normalised to its brightest
    /// channel, that channel's value becoming its intensity.
    pub fn config(&self, p: &[f64]) -> SensorConfig {
        let d = self.decode(p);
        let mut c = self.start.config.clone();
        c.finger.cylinder_length_mm = d.finger.cylinder_length;
        c.lens.cx = d.principal.x;
        c.lens.cy = d.principal.y;
        c.lens.focal_px = d.lens.focal_px;
        c.paint = crate::sensor::PaintConfig {
            colour: [1.0; 3],
            ..self.paint(&d)
        };
        c.light.ambient = Some(d.lighting.ambient.to_array());
        c.light.vignetting = d.lighting.vignetting;
        c.camera = d.lighting.camera;
        c.shell_end = d.lighting.shell_end;
        c.leds = Leds::List(
            d.lighting
                .leds
                .iter()
                .map(|led| {
                    let colour = led.colour.to_array();
                    let peak = colour.iter().copied().fold(0.0, f64::max);
                    let (colour, intensity) = if peak > 0.0 {
                        (colour.map(|c| c / peak), peak)
                    } else {
                        ([1.0; 3], 0.0)
                    };
                    let azimuth = led.position.y.atan2(led.position.x).to_degrees();
                    let base = LedConfig {
                        colour,
                        azimuth_deg: azimuth.rem_euclid(360.0),
                        z_mm: led.position.z,
                        intensity,
                        end_glow: led.end_glow.to_array(),
                        ..LedConfig::new(colour, 0.0)
                    };
                    match led.kind {
                        LedKind::Point => LedConfig {
                            radius_mm: Some(led.position.truncate().length()),
                            spread: led.spread,
                            falloff_mm: led.falloff_mm,
                            ..base
                        },
                        LedKind::Gel(b) => LedConfig {
                            kind: LedKindName::Gel,
                            width_mm: Some(b.width_mm),
                            widening: Some(b.widening),
                            attenuation_mm: Some(b.attenuation_mm),
                            relief: Some(b.relief),
                            ..base
                        },
                    }
                })
                .collect(),
        );
        c
    }
}

/// The colour matrix's entries off its diagonal, in the order a parameter vector holds them
/// (its diagonal is held at 1: each channel's own scale is the LEDs' colours').
pub const OFF_DIAGONAL: [(usize, usize); 6] = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];

/// Where `ray` meets the undeformed `finger`, as shading takes it.
fn hit_on(finger: &Finger, ray: DVec3) -> Option<(SkinHit, GelPlace)> {
    let s = finger.surface_along(ray)?;
    let hit = SkinHit {
        point: s.point,
        normal: s.normal,
        indentation: 0.0,
        ray,
    };
    Some((hit, GelPlace::of(finger, s.point, s.normal)))
}

/// An LED's kind by name.
pub fn kind_name(kind: LedKind) -> LedKindName {
    match kind {
        LedKind::Point => LedKindName::Point,
        LedKind::Gel(_) => LedKindName::Gel,
    }
}

/// 255 x^(1/gamma) of a linear value, not clipped above (a fit sees how far past full scale
/// a prediction lies).
fn unclipped_level(linear: f64, gamma: f64) -> f64 {
    255.0 * linear.max(0.0).powf(1.0 / gamma)
}

/// The 8-bit levels `camera` records for the vignetted linear light `light`, not clipped
/// above ([`unclipped_level`] of each mixed channel).
pub(super) fn recorded(camera: &CameraConfig, light: DVec3) -> [f64; 3] {
    let c = camera.mix(light);
    std::array::from_fn(|k| unclipped_level(c[k], camera.gamma[k]))
}
