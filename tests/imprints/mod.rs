//! Constructed frames of the paper's sensor for the localiser tests, and how they are scored.
//!
//! No renderer is needed: imprints are laid on the finger surface, not in the image: for each
//! pixel the sensor's map m gives the surface point it sees, and the imprint is a function of
//! that point, so it is distorted in the image exactly as the fisheye distorts it, and the
//! truth is known.
//!
//! - Painted imprints: a colour change that depends only on the 3D distance to the contact
//!   (a blob, or a ring like the shading change at an imprint's rim), on a smooth radial
//!   gradient reference with black outside the lens circle.
//! - Shaded imprints: a small ray tracer presses an object-shaped dimple into the finger
//!   (sphere, cone, cylinder, edge, tube, slab, or a Gaussian; the object's penetration
//!   blurred like a soft elastomer), finds where each pixel's ray meets the deformed
//!   surface and shades it under three coloured LEDs at the base, optionally with sensor
//!   noise. This gives the lobed, lighting- and view-dependent differences of real
//!   imprints: the flank facing the light or the camera changes more than the other.
#![allow(dead_code)]

use geltip::finger::SurfaceCoord;
use geltip::localise::{Detection, Localiser};
use geltip::{Region, Sensor};
use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};
use std::f64::consts::{FRAC_PI_3, FRAC_PI_4, FRAC_PI_6};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------

pub fn sensor() -> &'static Sensor {
    static S: OnceLock<Sensor> = OnceLock::new();
    S.get_or_init(|| Sensor::preset("paper").unwrap())
}

pub fn localiser() -> &'static Localiser {
    static L: OnceLock<Localiser> = OnceLock::new();
    L.get_or_init(|| Localiser::new(sensor()))
}

/// The surface point each pixel sees (None outside the lens circle), row-major.
pub fn surface_table() -> &'static Vec<Option<DVec3>> {
    static T: OnceLock<Vec<Option<DVec3>>> = OnceLock::new();
    T.get_or_init(|| {
        let s = sensor();
        (0..s.height)
            .flat_map(|v| (0..s.width).map(move |u| (u, v)))
            .map(|(u, v)| {
                s.unproject(DVec2::new(u as f64, v as f64))
                    .map(|sp| sp.point)
            })
            .collect()
    })
}

/// Where a contact is: the paper's eight tap positions and the junction.
pub fn positions() -> Vec<(&'static str, f64)> {
    let f = sensor().finger;
    vec![
        ("rot 0", f.s_of_rotation(0.0)),
        ("rot pi/6", f.s_of_rotation(FRAC_PI_6)),
        ("rot pi/4", f.s_of_rotation(FRAC_PI_4)),
        ("rot pi/3", f.s_of_rotation(FRAC_PI_3)),
        ("junction", f.junction_s()),
        ("trans 5", f.s_of_translation(5.0)),
        ("trans 10", f.s_of_translation(10.0)),
        ("trans 15", f.s_of_translation(15.0)),
    ]
}

/// Azimuths the positions are tried at: right, down-left, up, up-right (image v is down).
pub const AZIMUTHS: [f64; 4] = [0.0, 2.3, -std::f64::consts::FRAC_PI_2, -0.7];

/// A smooth reference: a radial colour gradient inside the lens circle, black outside.
pub fn gradient_reference() -> &'static RgbImage {
    static R: OnceLock<RgbImage> = OnceLock::new();
    R.get_or_init(|| {
        let s = sensor();
        let table = surface_table();
        let edge = s.lens.project(s.lens.max_theta);
        RgbImage::from_fn(s.width, s.height, |u, v| {
            if table[(v * s.width + u) as usize].is_none() {
                return Rgb([0, 0, 0]);
            }
            let off = DVec2::new(u as f64, v as f64) - s.principal;
            let t = off.length() / edge;
            let a = off.y.atan2(off.x);
            Rgb([
                (70.0 + 90.0 * (1.0 - t)) as u8,
                (90.0 + 40.0 * a.cos() * t) as u8,
                (100.0 + 40.0 * a.sin() * t) as u8,
            ])
        })
    })
}

/// How a painted imprint changes the colour with the 3D distance d to the contact.
#[derive(Debug, Clone, Copy)]
pub enum Paint {
    /// exp(-d^2 / 2 sigma^2): a blob.
    Blob { sigma_mm: f64 },
    /// exp(-(d - radius)^2 / 2 width^2): a ring, like the shading change at an imprint's rim.
    Ring { radius_mm: f64, width_mm: f64 },
}

/// The reference with an imprint of `amplitude` grey levels painted on the surface around
/// `p`: red darkens, green and blue brighten.
pub fn paint(reference: &RgbImage, p: DVec3, shape: Paint, amplitude: f64) -> RgbImage {
    let s = sensor();
    let table = surface_table();
    let mut out = reference.clone();
    for (u, v, px) in out.enumerate_pixels_mut() {
        let Some(q) = table[(v * s.width + u) as usize] else {
            continue;
        };
        let d = (q - p).length();
        let g = amplitude
            * match shape {
                Paint::Blob { sigma_mm } => (-(d * d) / (2.0 * sigma_mm * sigma_mm)).exp(),
                Paint::Ring {
                    radius_mm,
                    width_mm,
                } => (-(d - radius_mm).powi(2) / (2.0 * width_mm * width_mm)).exp(),
            };
        let change = [-g, 0.8 * g, 0.5 * g];
        for (v, dv) in px.0.iter_mut().zip(change) {
            *v = (*v as f64 + dv).round().clamp(0.0, 255.0) as u8;
        }
    }
    out
}

/// Millimetres of surface per pixel around the pixel where `p` appears (geometric mean of
/// the two directions), from the sensor's own map.
pub fn mm_per_px(p: DVec3) -> f64 {
    let s = sensor();
    let px = s.project(p).unwrap();
    let at = |d: DVec2| s.unproject(px + d).unwrap().point;
    let du = (at(DVec2::new(0.5, 0.0)) - at(DVec2::new(-0.5, 0.0))).length();
    let dv = (at(DVec2::new(0.0, 0.5)) - at(DVec2::new(0.0, -0.5))).length();
    (du * dv).sqrt()
}

/// An inward displacement field on the tangent plane at the contact, tabulated on a grid:
/// an object's penetration (compact) smoothed by a Gaussian like a soft elastomer layer.
pub struct Profile {
    /// Largest distance from the centre (mm) with a displacement over 1 nm.
    reach: f64,
    half: f64,
    step: f64,
    n: usize,
    values: Vec<f64>,
}

impl Profile {
    /// `pen(a, b)`: penetration (mm, >= 0) at tangent-plane coordinates a (along the
    /// meridian) and b (along the azimuth); `smooth`: the elastomer's blur (mm).
    fn new(pen: impl Fn(f64, f64) -> f64, smooth: f64) -> Self {
        let (half, step) = (10.0, 0.05);
        let n = (2.0 * half / step) as usize + 1;
        let at = |i: usize| -half + i as f64 * step;
        let mut values: Vec<f64> = (0..n * n)
            .map(|k| pen(at(k % n), at(k / n)).max(0.0))
            .collect();
        if smooth > 0.0 {
            let r = (3.0 * smooth / step).ceil() as isize;
            let kernel: Vec<f64> = (-r..=r)
                .map(|i| (-((i as f64 * step).powi(2)) / (2.0 * smooth * smooth)).exp())
                .collect();
            let norm: f64 = kernel.iter().sum();
            for pass in 0..2 {
                let src = values.clone();
                for y in 0..n {
                    for x in 0..n {
                        let mut acc = 0.0;
                        for (j, kv) in kernel.iter().enumerate() {
                            let o = j as isize - r;
                            let (sx, sy) = if pass == 0 {
                                (x as isize + o, y as isize)
                            } else {
                                (x as isize, y as isize + o)
                            };
                            if sx >= 0 && sy >= 0 && (sx as usize) < n && (sy as usize) < n {
                                acc += kv * src[sy as usize * n + sx as usize];
                            }
                        }
                        values[y * n + x] = acc / norm;
                    }
                }
            }
        }
        let reach = (0..n * n)
            .filter(|&k| values[k] > 1e-6)
            .map(|k| at(k % n).hypot(at(k / n)))
            .fold(0.0, f64::max);
        Profile {
            reach,
            half,
            step,
            n,
            values,
        }
    }

    /// Bilinear sample; 0 outside the grid.
    fn sample(&self, a: f64, b: f64) -> f64 {
        let (fx, fy) = ((a + self.half) / self.step, (b + self.half) / self.step);
        if fx < 0.0 || fy < 0.0 || fx >= (self.n - 1) as f64 || fy >= (self.n - 1) as f64 {
            return 0.0;
        }
        let (x, y) = (fx as usize, fy as usize);
        let (tx, ty) = (fx - x as f64, fy - y as f64);
        let v = |x: usize, y: usize| self.values[y * self.n + x];
        (1.0 - ty) * ((1.0 - tx) * v(x, y) + tx * v(x + 1, y))
            + ty * ((1.0 - tx) * v(x, y + 1) + tx * v(x + 1, y + 1))
    }
}

/// A dimple pressed into the finger around the surface point `p`.
pub struct Dimple {
    pub p: DVec3,
    e_s: DVec3,
    e_phi: DVec3,
    normal: DVec3,
    profile: Profile,
}

impl Dimple {
    /// A Gaussian dimple: standard deviations `w_s` along the meridian and `w_phi` along
    /// the azimuth (mm), `depth` deep.
    pub fn new(coord: SurfaceCoord, w_s: f64, w_phi: f64, depth: f64) -> Self {
        Dimple::with_profile(
            coord,
            Profile::new(
                |a, b| depth * (-(a * a / (2.0 * w_s * w_s) + b * b / (2.0 * w_phi * w_phi))).exp(),
                0.0,
            ),
        )
    }

    pub fn with_profile(coord: SurfaceCoord, profile: Profile) -> Self {
        let f = sensor().finger;
        let sp = f.point_at(coord);
        let (e_s, e_phi) = f.tangents_at(coord);
        Dimple {
            p: sp.point,
            e_s,
            e_phi,
            normal: sp.normal,
            profile,
        }
    }

    /// Inward displacement of the undeformed surface point `q`.
    fn delta(&self, q: DVec3) -> f64 {
        let d = q - self.p;
        if d.dot(self.normal) < -4.0 {
            return 0.0;
        }
        self.profile.sample(d.dot(self.e_s), d.dot(self.e_phi))
    }

    /// How far from `p` (mm) the displacement reaches, plus a margin for oblique rays.
    fn reach(&self) -> f64 {
        self.profile.reach + 3.0
    }

    /// Implicit function of the deformed surface: negative in the air inside the finger.
    fn field(&self, x: DVec3) -> f64 {
        let f = sensor().finger;
        let foot = f.point_at(f.coord_of(x)).point;
        f.signed_distance(x) + self.delta(foot)
    }
}

/// Objects like the paper's, as penetration fields (mm) pressed `depth` deep at tangent-plane
/// coordinates (a, b), for a contact on the hemisphere (`cylinder` false) or the cylinder.
pub fn object_profile(name: &str, depth: f64, cylinder: bool) -> Profile {
    let r = sensor().finger.radius;
    let smooth = 0.6;
    let pen: Box<dyn Fn(f64, f64) -> f64> = match name {
        "sphere" => Box::new(move |a, b| depth - (a * a + b * b) / (2.0 * 4.0)),
        "cone" => Box::new(move |a, b| depth - a.hypot(b)),
        "cylinder" => Box::new(move |a, b| {
            if b.abs() < 4.0 {
                depth - a * a / (2.0 * 3.0)
            } else {
                0.0
            }
        }),
        "edge" => Box::new(move |a, b| if b.abs() < 5.0 { depth - a.abs() } else { 0.0 }),
        "tube" => Box::new(move |a, b| {
            if (a.hypot(b) - 2.5).abs() < 0.4 {
                depth
            } else {
                0.0
            }
        }),
        "slab" if cylinder => Box::new(move |a, b| {
            if a.abs() < 4.0 {
                depth - b * b / (2.0 * r)
            } else {
                0.0
            }
        }),
        "slab" => Box::new(move |a, b| depth - (a * a + b * b) / (2.0 * r)),
        other => panic!("no object {other}"),
    };
    Profile::new(pen, smooth)
}

/// Three LEDs at the base: red, green, blue, 120 degrees apart.
pub fn lights() -> [DVec3; 3] {
    let at = |deg: f64| {
        let a = deg.to_radians();
        DVec3::new(6.0 * a.cos(), 6.0 * a.sin(), 1.0)
    };
    [at(90.0), at(210.0), at(330.0)]
}

/// How the gel is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lighting {
    /// Three point LEDs at the base, red, green and blue (the sensor's design).
    Leds,
    /// One white light at the camera: a different pattern of shading changes, to check
    /// that the surface detector is not tuned to one lighting.
    Headlight,
}

/// Colour of a point of the gel with unit normal `inward` (towards the inside of the finger).
pub fn shade(point: DVec3, inward: DVec3, lighting: Lighting) -> [f64; 3] {
    if lighting == Lighting::Headlight {
        let v = inward.dot(-point.normalize()).max(0.0);
        return [
            255.0 * (0.1 + 0.6 * v),
            255.0 * (0.1 + 0.5 * v),
            255.0 * (0.1 + 0.4 * v),
        ];
    }
    let ls = lights();
    std::array::from_fn(|c| {
        let to = ls[c] - point;
        let dist = to.length();
        let lambert = inward.dot(to / dist).max(0.0);
        let falloff = 1.0 / (1.0 + (dist / 12.0).powi(2));
        255.0 * (0.08 + 0.9 * lambert * falloff)
    })
}

/// Deterministic Gaussian noise (xorshift64* and Box-Muller).
pub struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gauss(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

/// Renders the finger, pressed by `dimple` if any, with Gaussian noise of `noise.0` grey
/// levels (seed `noise.1`) if any.
pub fn render(dimple: Option<&Dimple>, noise: Option<(f64, u64)>, lighting: Lighting) -> RgbImage {
    let s = sensor();
    let f = s.finger;
    let table = surface_table();
    let mut rng = noise.map(|(_, seed)| Noise(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1));
    RgbImage::from_fn(s.width, s.height, |u, v| {
        let Some(q) = table[(v * s.width + u) as usize] else {
            return Rgb([0, 0, 0]);
        };
        let mut point = q;
        let mut inward = -f.point_at(f.coord_of(q)).normal;
        if let Some(d) = dimple {
            let reach = d.reach();
            if (q - d.p).length() < reach {
                let dir = q.normalize();
                let t0 = q.length();
                let mut t = t0;
                while f.signed_distance(t * dir) > -1.6 {
                    t -= 0.25;
                }
                let step = 0.02;
                while d.field((t + step) * dir) < 0.0 && t < t0 {
                    t += step;
                }
                let (mut lo, mut hi) = (t, t + step);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if d.field(mid * dir) < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                point = 0.5 * (lo + hi) * dir;
                let h = 1e-4;
                let grad = DVec3::new(
                    d.field(point + DVec3::X * h) - d.field(point - DVec3::X * h),
                    d.field(point + DVec3::Y * h) - d.field(point - DVec3::Y * h),
                    d.field(point + DVec3::Z * h) - d.field(point - DVec3::Z * h),
                );
                inward = -grad.normalize();
            }
        }
        let colour = shade(point, inward, lighting);
        Rgb(std::array::from_fn(|c| {
            let n = match (noise, rng.as_mut()) {
                (Some((sigma, _)), Some(r)) => sigma * r.gauss(),
                _ => 0.0,
            };
            (colour[c] + n).round().clamp(0.0, 255.0) as u8
        }))
    })
}

/// The noise-free rendered reference under the LEDs.
pub fn rendered_reference() -> &'static RgbImage {
    static R: OnceLock<RgbImage> = OnceLock::new();
    R.get_or_init(|| render(None, None, Lighting::Leds))
}

// ---------------------------------------------------------------------------------------
// Scoring
// ---------------------------------------------------------------------------------------

/// Distance (mm) from the detection's point to the truth; panics if not detected or if the
/// detection is malformed (point off the surface, pixel not the point's projection).
pub fn error_mm(d: &Detection, truth: DVec3, what: &str) -> f64 {
    assert!(d.detected, "{what}: not detected: {:?}", d.note);
    let p = d.point.expect("detected without a point");
    assert!(p.is_finite(), "{what}: non-finite point");
    assert!(
        sensor().finger.signed_distance(p).abs() < 1e-6,
        "{what}: point {p} is off the surface"
    );
    let px = d.pixel.expect("detected without a pixel");
    let back = sensor().project(p).unwrap();
    assert!(
        (px - back).length() < 1e-6,
        "{what}: pixel {px} is not where the point appears ({back})"
    );
    assert!((0.0..=1.0).contains(&d.confidence), "{what}: confidence");
    (p - truth).length()
}

/// Prints the errors; returns (mean, worst).
pub fn report(label: &str, errors: &[(String, f64)]) -> (f64, f64) {
    assert!(!errors.is_empty(), "{label}: nothing to report");
    let mean = errors.iter().map(|e| e.1).sum::<f64>() / errors.len() as f64;
    let worst = errors.iter().map(|e| e.1).fold(0.0, f64::max);
    eprintln!(
        "{label}: mean {mean:.3} mm, worst {worst:.3} mm over {}",
        errors.len()
    );
    for (what, e) in errors {
        eprintln!("    {what}: {e:.3} mm");
    }
    (mean, worst)
}

/// The region a surface arc length lies on, or None at the junction (either is right).
pub fn expected_region(s: f64) -> Option<Region> {
    let j = sensor().finger.junction_s();
    if (s - j).abs() < 0.5 {
        None
    } else if s < j {
        Some(Region::Hemisphere)
    } else {
        Some(Region::Cylinder)
    }
}

pub fn assert_not_detected(d: &Detection, what: &str) {
    assert!(!d.detected, "{what}: detected at {:?}", d.point);
    assert!(d.pixel.is_none() && d.point.is_none() && d.region.is_none());
    assert_eq!(d.confidence, 0.0, "{what}");
    let note = d.note.as_deref().unwrap_or("");
    assert!(
        !note.is_empty() && !note.contains('\n'),
        "{what}: note {note:?}"
    );
    let json = d.to_json().to_string();
    assert!(!json.contains("NaN") && !json.contains("nan"), "{json}");
    assert!(json.contains("\"detected\":false"), "{json}");
}
