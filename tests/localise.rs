//! The contact localisers on constructed images.
//!
//! No renderer is needed: the tests make their own frames of the paper's sensor. Imprints
//! are laid on the finger surface, not in the image: for each pixel the sensor's map m
//! gives the surface point it sees, and the imprint is a function of that point, so it is
//! distorted in the image exactly as the fisheye distorts it, and the truth is known.
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
//!
//! Tolerances are stated in every assert; the measured errors are printed (`--nocapture`).

use geltip::finger::SurfaceCoord;
use geltip::localise::paper::{
    self, area_filter, area_range, brightness, fit_ellipse, mean_filter, regions, threshold,
    weighted_centre, Blob,
};
use geltip::localise::raster::FloatImage;
use geltip::localise::{load_frame, load_image, localise, Detection, Localiser, Method};
use geltip::{GeltipError, Region, Sensor};
use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};
use std::f64::consts::{FRAC_PI_3, FRAC_PI_4, FRAC_PI_6};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------

fn sensor() -> &'static Sensor {
    static S: OnceLock<Sensor> = OnceLock::new();
    S.get_or_init(|| Sensor::preset("paper").unwrap())
}

fn localiser() -> &'static Localiser {
    static L: OnceLock<Localiser> = OnceLock::new();
    L.get_or_init(|| Localiser::new(sensor()))
}

/// The surface point each pixel sees (None outside the lens circle), row-major.
fn surface_table() -> &'static Vec<Option<DVec3>> {
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
fn positions() -> Vec<(&'static str, f64)> {
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
const AZIMUTHS: [f64; 4] = [0.0, 2.3, -std::f64::consts::FRAC_PI_2, -0.7];

/// A smooth reference: a radial colour gradient inside the lens circle, black outside.
fn gradient_reference() -> &'static RgbImage {
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
enum Paint {
    /// exp(-d^2 / 2 sigma^2): a blob.
    Blob { sigma_mm: f64 },
    /// exp(-(d - radius)^2 / 2 width^2): a ring, like the shading change at an imprint's rim.
    Ring { radius_mm: f64, width_mm: f64 },
}

/// The reference with an imprint of `amplitude` grey levels painted on the surface around
/// `p`: red darkens, green and blue brighten.
fn paint(reference: &RgbImage, p: DVec3, shape: Paint, amplitude: f64) -> RgbImage {
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
fn mm_per_px(p: DVec3) -> f64 {
    let s = sensor();
    let px = s.project(p).unwrap();
    let at = |d: DVec2| s.unproject(px + d).unwrap().point;
    let du = (at(DVec2::new(0.5, 0.0)) - at(DVec2::new(-0.5, 0.0))).length();
    let dv = (at(DVec2::new(0.0, 0.5)) - at(DVec2::new(0.0, -0.5))).length();
    (du * dv).sqrt()
}

/// An inward displacement field on the tangent plane at the contact, tabulated on a grid:
/// an object's penetration (compact) smoothed by a Gaussian like a soft elastomer layer.
struct Profile {
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
struct Dimple {
    p: DVec3,
    e_s: DVec3,
    e_phi: DVec3,
    normal: DVec3,
    profile: Profile,
}

impl Dimple {
    /// A Gaussian dimple: standard deviations `w_s` along the meridian and `w_phi` along
    /// the azimuth (mm), `depth` deep.
    fn new(coord: SurfaceCoord, w_s: f64, w_phi: f64, depth: f64) -> Self {
        Dimple::with_profile(
            coord,
            Profile::new(
                |a, b| depth * (-(a * a / (2.0 * w_s * w_s) + b * b / (2.0 * w_phi * w_phi))).exp(),
                0.0,
            ),
        )
    }

    fn with_profile(coord: SurfaceCoord, profile: Profile) -> Self {
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
fn object_profile(name: &str, depth: f64, cylinder: bool) -> Profile {
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
fn lights() -> [DVec3; 3] {
    let at = |deg: f64| {
        let a = deg.to_radians();
        DVec3::new(6.0 * a.cos(), 6.0 * a.sin(), 1.0)
    };
    [at(90.0), at(210.0), at(330.0)]
}

/// How the gel is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Lighting {
    /// Three point LEDs at the base, red, green and blue (the sensor's design).
    Leds,
    /// One white light at the camera: a different pattern of shading changes, to check
    /// that the surface detector is not tuned to one lighting.
    Headlight,
}

/// Colour of a point of the gel with unit normal `inward` (towards the inside of the finger).
fn shade(point: DVec3, inward: DVec3, lighting: Lighting) -> [f64; 3] {
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
struct Noise(u64);

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
fn render(dimple: Option<&Dimple>, noise: Option<(f64, u64)>, lighting: Lighting) -> RgbImage {
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
fn rendered_reference() -> &'static RgbImage {
    static R: OnceLock<RgbImage> = OnceLock::new();
    R.get_or_init(|| render(None, None, Lighting::Leds))
}

// ---------------------------------------------------------------------------------------
// Scoring
// ---------------------------------------------------------------------------------------

/// Distance (mm) from the detection's point to the truth; panics if not detected or if the
/// detection is malformed (point off the surface, pixel not the point's projection).
fn error_mm(d: &Detection, truth: DVec3, what: &str) -> f64 {
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
fn report(label: &str, errors: &[(String, f64)]) -> (f64, f64) {
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
fn expected_region(s: f64) -> Option<Region> {
    let j = sensor().finger.junction_s();
    if (s - j).abs() < 0.5 {
        None
    } else if s < j {
        Some(Region::Hemisphere)
    } else {
        Some(Region::Cylinder)
    }
}

// ---------------------------------------------------------------------------------------
// A single clear contact on the hemisphere, at the junction and on the cylinder
// ---------------------------------------------------------------------------------------

/// `shape(mm_per_px)` painted at every position and azimuth, located by `method`.
fn painted_errors(method: Method, shape: impl Fn(f64) -> Paint) -> Vec<(String, f64)> {
    let f = sensor().finger;
    let mut out = Vec::new();
    for (name, s) in positions() {
        for phi in AZIMUTHS {
            let truth = f.point_at(SurfaceCoord { s, phi }).point;
            let frame = paint(gradient_reference(), truth, shape(mm_per_px(truth)), 60.0);
            let d = localiser()
                .localise(gradient_reference(), &frame, method)
                .unwrap();
            let what = format!("{} at {name}, phi {phi}", method.name());
            let e = error_mm(&d, truth, &what);
            if let Some(want) = expected_region(s) {
                assert_eq!(d.region, Some(want), "{what}: wrong region");
            }
            out.push((what, e));
        }
    }
    out
}

#[test]
fn paper_finds_a_ring_imprint_on_hemisphere_junction_and_cylinder() {
    // A thin ring 4.5 px in radius: after the 15x15 filter its brightest part is a small
    // peak, and the part above 60% of it is one region of 90..120 px, inside the area
    // filter (37..123 px). Smooth blobs never are (see the next test).
    let errors = painted_errors(Method::Paper, |mm| Paint::Ring {
        radius_mm: 4.5 * mm,
        width_mm: 0.45 * mm,
    });
    let (mean, worst) = report("paper, painted rings", &errors);
    assert!(mean < 0.1, "paper: mean error {mean:.3} mm, allowed 0.1 mm");
    assert!(
        worst < 0.3,
        "paper: worst error {worst:.3} mm, allowed 0.3 mm"
    );
}

#[test]
fn paper_area_filter_rejects_every_single_smooth_blob() {
    // After the 15x15 mean filter, the part of a lone blob above 60% of its peak is never
    // smaller than about 118 px (contour area): a small blob becomes the kernel's 15x15
    // square, a large one stays large. So the paper's detector only ever keeps fragments,
    // rings and secondary peaks, never one clean blob; this is the paper's algorithm, not
    // a bug here.
    let truth = sensor().finger.tip();
    let (lo, hi) = area_range(640.0 * 480.0);
    for sigma_px in [0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0] {
        let shape = Paint::Blob {
            sigma_mm: sigma_px * mm_per_px(truth),
        };
        let frame = paint(gradient_reference(), truth, shape, 60.0);
        let diff = paper::difference(gradient_reference(), &frame).unwrap();
        let b = threshold(&brightness(&mean_filter(&diff, paper::KERNEL)), 0.6);
        let r = regions(&b);
        assert_eq!(r.len(), 1, "blob {sigma_px} px: {} regions", r.len());
        assert!(
            r[0].area > hi,
            "blob {sigma_px} px: area {} inside {lo}..{hi}",
            r[0].area
        );
        let d = localiser()
            .localise(gradient_reference(), &frame, Method::Paper)
            .unwrap();
        assert!(!d.detected, "blob {sigma_px} px detected");
        let note = d.note.unwrap();
        assert!(note.contains("area filter"), "note: {note}");
        assert_eq!(d.regions_found, 1);
    }
}

#[test]
fn surface_finds_painted_blobs_and_rings_on_hemisphere_junction_and_cylinder() {
    for (label, shape) in [
        ("blob 2.5 px", Paint::Blob { sigma_mm: 2.5 }),
        ("blob 6 px", Paint::Blob { sigma_mm: 6.0 }),
        (
            "ring 4.5 px",
            Paint::Ring {
                radius_mm: 4.5,
                width_mm: 0.45,
            },
        ),
    ] {
        let errors = painted_errors(Method::Surface, |mm| match shape {
            Paint::Blob { sigma_mm } => Paint::Blob {
                sigma_mm: sigma_mm * mm,
            },
            Paint::Ring {
                radius_mm,
                width_mm,
            } => Paint::Ring {
                radius_mm: radius_mm * mm,
                width_mm: width_mm * mm,
            },
        });
        let (mean, worst) = report(&format!("surface, painted {label}"), &errors);
        // The outline is found to the pixel (up to 0.3 mm per pixel where the finger is
        // seen obliquely) and measured on the tangent plane, which near the junction is
        // not quite symmetric (sphere on one side, cylinder on the other): ~0.1 mm.
        assert!(
            mean < 0.06,
            "{label}: mean error {mean:.3} mm, allowed 0.06"
        );
        assert!(
            worst < 0.15,
            "{label}: worst error {worst:.3} mm, allowed 0.15"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Object-shaped imprints, shaded
// ---------------------------------------------------------------------------------------

const OBJECTS: [&str; 7] = [
    "sphere", "cone", "cylinder", "edge", "tube", "slab", "gaussian",
];

struct Case {
    what: String,
    truth: DVec3,
    reference: RgbImage,
    frame: RgbImage,
}

/// Every object at every position (56 taps like the paper's experiment, azimuths varied),
/// pressed 1 mm; `every` > 1 keeps one case in `every`.
fn object_cases(noise: Option<f64>, lighting: Lighting, every: usize) -> Vec<Case> {
    let f = sensor().finger;
    let reference = match lighting {
        Lighting::Leds => rendered_reference().clone(),
        Lighting::Headlight => render(None, None, lighting),
    };
    let mut cases = Vec::new();
    for (i, (name, s)) in positions().into_iter().enumerate() {
        for (j, obj) in OBJECTS.iter().enumerate() {
            let k = i * OBJECTS.len() + j;
            if !k.is_multiple_of(every) {
                continue;
            }
            let phi = AZIMUTHS[(i + j) % AZIMUTHS.len()];
            let coord = SurfaceCoord { s, phi };
            let dimple = if *obj == "gaussian" {
                Dimple::new(coord, 1.5, 1.5, 1.0)
            } else {
                Dimple::with_profile(coord, object_profile(obj, 1.0, s > f.junction_s()))
            };
            let seed = k as u64 + 1;
            let reference = match noise {
                Some(n) => render(None, Some((n, 1000 + seed)), lighting),
                None => reference.clone(),
            };
            let frame = render(Some(&dimple), noise.map(|n| (n, seed)), lighting);
            cases.push(Case {
                what: format!("{obj} at {name}, phi {phi}"),
                truth: dimple.p,
                reference,
                frame,
            });
        }
    }
    cases
}

/// Errors of `method` on `cases`, and the cases it missed.
fn case_errors(cases: &[Case], method: Method) -> (Vec<(String, f64)>, Vec<String>) {
    let mut errors = Vec::new();
    let mut missed = Vec::new();
    for c in cases {
        let d = localiser()
            .localise(&c.reference, &c.frame, method)
            .unwrap();
        if d.detected {
            let what = format!("{} {}", method.name(), c.what);
            errors.push((what.clone(), error_mm(&d, c.truth, &what)));
        } else {
            missed.push(format!("{}: {}", c.what, d.note.unwrap_or_default()));
        }
    }
    (errors, missed)
}

#[test]
fn object_imprints_surface_within_half_a_millimetre_and_better_than_paper() {
    let cases = object_cases(None, Lighting::Leds, 1);
    assert_eq!(cases.len(), 56);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects", &errors);
    assert!(
        mean < 0.3,
        "surface: mean error {mean:.3} mm, allowed 0.3 mm"
    );
    assert!(
        worst < 1.0,
        "surface: worst error {worst:.3} mm, allowed 1.0 mm"
    );

    let (paper_errors, paper_missed) = case_errors(&cases, Method::Paper);
    eprintln!("paper missed {} of 56", paper_missed.len());
    let paper_mean = if paper_errors.is_empty() {
        f64::INFINITY
    } else {
        report("paper, shaded objects (detected ones)", &paper_errors).0
    };
    assert!(
        mean < paper_mean,
        "surface mean {mean:.3} mm is not below paper's {paper_mean:.3} mm"
    );
}

#[test]
fn object_imprints_in_sensor_noise() {
    // Gaussian noise of 2 grey levels in every channel of both frames.
    let cases = object_cases(Some(2.0), Lighting::Leds, 2);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects, noise 2", &errors);
    assert!(
        mean < 0.35,
        "surface: mean error {mean:.3} mm, allowed 0.35 mm"
    );
    assert!(
        worst < 1.0,
        "surface: worst error {worst:.3} mm, allowed 1.0 mm"
    );
}

#[test]
fn object_imprints_under_other_lighting() {
    let cases = object_cases(None, Lighting::Headlight, 2);
    let (errors, missed) = case_errors(&cases, Method::Surface);
    assert!(missed.is_empty(), "surface missed {missed:#?}");
    let (mean, worst) = report("surface, shaded objects, headlight", &errors);
    assert!(
        mean < 0.35,
        "surface: mean error {mean:.3} mm, allowed 0.35 mm"
    );
    assert!(
        worst < 1.2,
        "surface: worst error {worst:.3} mm, allowed 1.2 mm"
    );
}

// ---------------------------------------------------------------------------------------
// No contact
// ---------------------------------------------------------------------------------------

fn assert_not_detected(d: &Detection, what: &str) {
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

#[test]
fn a_frame_identical_to_the_reference_is_no_contact() {
    for reference in [gradient_reference(), rendered_reference()] {
        for method in Method::ALL {
            let d = localise(sensor(), reference, reference, method).unwrap();
            assert_not_detected(&d, method.name());
            assert!(d.note.unwrap().contains("does not differ"));
        }
    }
}

#[test]
fn noise_alone_is_no_contact_for_the_surface_detector() {
    for (sigma, seed) in [(1.0, 1u64), (2.0, 2), (5.0, 3), (5.0, 4)] {
        let reference = render(None, Some((sigma, seed)), Lighting::Leds);
        let frame = render(None, Some((sigma, seed + 100)), Lighting::Leds);
        let d = localiser()
            .localise(&reference, &frame, Method::Surface)
            .unwrap();
        assert_not_detected(&d, &format!("noise {sigma}"));
        assert!(d.note.unwrap().contains("below the detection level"));
    }
}

#[test]
fn a_weak_contact_is_found_at_a_coarser_scale() {
    // A shallow dimple (0.1 mm deep, 1.5 mm wide) under noise of 5 grey levels: too faint
    // for the 5x5 scale, found at 9x9.
    let f = sensor().finger;
    let coord = SurfaceCoord {
        s: f.s_of_translation(5.0),
        phi: 0.4,
    };
    let dimple = Dimple::new(coord, 1.5, 1.5, 0.1);
    let reference = render(None, Some((5.0, 11)), Lighting::Leds);
    let frame = render(Some(&dimple), Some((5.0, 12)), Lighting::Leds);
    let fine = Localiser::with_config(
        sensor(),
        geltip::localise::surface::SurfaceConfig {
            scales: vec![5],
            ..Default::default()
        },
    );
    let d = fine.localise(&reference, &frame, Method::Surface).unwrap();
    assert!(
        !d.detected,
        "the 5x5 scale alone should miss it: {:?}",
        d.point
    );
    let d = localiser()
        .localise(&reference, &frame, Method::Surface)
        .unwrap();
    let e = error_mm(&d, dimple.p, "weak contact");
    eprintln!("weak contact: {e:.3} mm, confidence {:.2}", d.confidence);
    assert!(e < 1.0, "weak contact: error {e:.3} mm, allowed 1.0 mm");
}

// ---------------------------------------------------------------------------------------
// The paper's steps on constructed images
// ---------------------------------------------------------------------------------------

fn gray(width: u32, height: u32, f: impl Fn(u32, u32) -> f64) -> FloatImage {
    let data = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| f(x, y))
        .collect();
    FloatImage::from_gray(width, height, data).unwrap()
}

#[test]
fn difference_is_absolute_per_channel() {
    let a = RgbImage::from_pixel(3, 2, Rgb([10, 200, 50]));
    let mut b = a.clone();
    b.put_pixel(1, 1, Rgb([30, 150, 50]));
    let d = paper::difference(&a, &b).unwrap();
    assert_eq!(d.channels, 3);
    assert_eq!(d.get(1, 1, 0), 20.0);
    assert_eq!(d.get(1, 1, 1), 50.0);
    assert_eq!(d.get(1, 1, 2), 0.0);
    assert_eq!(d.get(0, 0, 1), 0.0);
    let err = paper::difference(&a, &RgbImage::new(2, 3))
        .unwrap_err()
        .to_string();
    assert!(err.contains("2x3") && err.contains("3x2"), "{err}");
}

#[test]
fn mean_filter_keeps_a_constant_image_constant() {
    let img = gray(40, 30, |_, _| 7.25);
    let out = mean_filter(&img, 15);
    for v in &out.data {
        assert!((v - 7.25).abs() < 1e-12, "{v}");
    }
}

#[test]
fn mean_filter_spreads_an_impulse_over_a_15x15_box() {
    let (w, h) = (50u32, 40u32);
    let k = 1.0 / 225.0;
    // Inside: a 15x15 box of 1/225 centred on the impulse, zero elsewhere.
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 20 && y == 18)), 15);
    for y in 0..h {
        for x in 0..w {
            let inside = (13..=27).contains(&x) && (11..=25).contains(&y);
            let want = if inside { k } else { 0.0 };
            assert!((out.get(x, y, 0) - want).abs() < 1e-15, "({x}, {y})");
        }
    }
    // Borders are BORDER_REFLECT_101 (OpenCV's default for blur): the edge pixel is not
    // repeated, so an impulse on the corner is counted once (the sum is not preserved)...
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 0 && y == 0)), 15);
    assert!((out.get(0, 0, 0) - k).abs() < 1e-15);
    assert!((out.get(7, 7, 0) - k).abs() < 1e-15);
    assert!(out.get(8, 0, 0).abs() < 1e-15);
    // ...while one pixel in from the corner is mirrored across each edge: twice per axis.
    let out = mean_filter(&gray(w, h, |x, y| f64::from(x == 1 && y == 1)), 15);
    assert!((out.get(0, 0, 0) - 4.0 * k).abs() < 1e-15);
    assert!((out.get(0, 8, 0) - 2.0 * k).abs() < 1e-15);
    assert!((out.get(8, 8, 0) - k).abs() < 1e-15);
    assert!(out.get(9, 9, 0).abs() < 1e-15);
}

#[test]
fn threshold_zeroes_pixels_under_60_percent_of_the_brightest() {
    // Brightness is the mean of the channels: (90 + 120 + 90) / 3 = 100 at the peak.
    let mut diff = FloatImage::zeros(5, 1, 3);
    let pixels = [
        [90.0, 120.0, 90.0],
        [60.0, 60.0, 60.0],
        [59.0, 59.0, 59.5],
        [61.0; 3],
        [0.0; 3],
    ];
    for (x, p) in pixels.iter().enumerate() {
        for (c, &v) in p.iter().enumerate() {
            diff.set(x as u32, 0, c, v);
        }
    }
    let b = brightness(&diff);
    assert_eq!(b.data, vec![100.0, 60.0, 59.166666666666664, 61.0, 0.0]);
    let t = threshold(&b, 0.6);
    assert_eq!(t.data, vec![100.0, 60.0, 0.0, 61.0, 0.0]);
    // An all-zero image stays zero; scaling the image does not move the cut.
    assert!(threshold(&gray(4, 4, |_, _| 0.0), 0.6)
        .data
        .iter()
        .all(|&v| v == 0.0));
    let scaled = gray(5, 1, |x, _| b.data[x as usize] * 0.1);
    let t2 = threshold(&scaled, 0.6);
    for (a, b) in t2.data.iter().zip(&t.data) {
        assert!((a - b * 0.1).abs() < 1e-12);
    }
}

/// A filled disc of `radius` px centred at (cx, cy) on a 100x100 image.
fn disc(cx: f64, cy: f64, radius: f64) -> FloatImage {
    gray(100, 100, |x, y| {
        f64::from(DVec2::new(x as f64 - cx, y as f64 - cy).length() <= radius)
    })
}

#[test]
fn regions_are_8_connected_with_outer_contours_and_opencv_areas() {
    // A filled 10x6 rectangle: contour through the border pixel centres, area 9 x 5.
    let img = gray(30, 20, |x, y| {
        f64::from((5..15).contains(&x) && (3..9).contains(&y))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].pixel_count(), 60);
    assert_eq!(r[0].area, 45.0);
    assert_eq!(r[0].contour.len(), 2 * (9 + 5));
    assert_eq!(r[0].contour[0], DVec2::new(5.0, 3.0));
    // Diagonal neighbours join; a gap splits; a lone pixel has area 0.
    let img = gray(10, 10, |x, y| {
        f64::from((x == 1 && y == 1) || (x == 2 && y == 2) || (x == 6 && y == 6))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 2);
    assert_eq!(r[0].pixel_count(), 2);
    assert_eq!(r[1].pixel_count(), 1);
    assert_eq!(r[1].area, 0.0);
    // A ring is one region; its hole is not a region of its own.
    let img = gray(40, 40, |x, y| {
        let d = DVec2::new(x as f64 - 20.0, y as f64 - 20.0).length();
        f64::from((5.0..9.0).contains(&d))
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    assert!(r[0].area > 200.0, "outer contour area {}", r[0].area);
}

#[test]
fn area_filter_keeps_80_px_and_rejects_20_and_300_px() {
    let picture = 640.0 * 480.0;
    let (lo, hi) = area_range(picture);
    assert!((lo - 36.864).abs() < 1e-9 && (hi - 122.88).abs() < 1e-9);
    let img = {
        let a = disc(15.0, 15.0, 2.6);
        let b = disc(50.0, 20.0, 5.1);
        let c = disc(50.0, 65.0, 9.8);
        gray(100, 100, |x, y| {
            a.get(x, y, 0) + b.get(x, y, 0) + c.get(x, y, 0)
        })
    };
    let r = regions(&img);
    let counts: Vec<usize> = r.iter().map(Blob::pixel_count).collect();
    assert_eq!(r.len(), 3, "{counts:?}");
    for (n, want) in counts.iter().zip([21usize, 81, 301]) {
        assert!(n.abs_diff(want) <= 12, "pixel counts {counts:?}");
    }
    let kept = area_filter(r, picture);
    assert_eq!(
        kept.len(),
        1,
        "kept {:?}",
        kept.iter().map(|b| b.area).collect::<Vec<_>>()
    );
    assert!(kept[0].pixel_count().abs_diff(81) <= 12);
    assert!((lo..=hi).contains(&kept[0].area));
}

#[test]
fn ellipse_fit_recovers_centre_axes_and_angle() {
    // Points exactly on an ellipse: exact recovery.
    let (c, a, b, t) = (DVec2::new(40.3, 27.8), 12.0, 5.0, 0.5f64);
    let rot = DVec2::from_angle(t);
    let pts: Vec<DVec2> = (0..40)
        .map(|i| {
            let u = i as f64 * std::f64::consts::TAU / 40.0;
            c + rot.rotate(DVec2::new(a * u.cos(), b * u.sin()))
        })
        .collect();
    let e = fit_ellipse(&pts).expect("fit");
    assert!((e.centre - c).length() < 1e-9, "centre {}", e.centre);
    assert!(
        (e.semi_axes - DVec2::new(a, b)).length() < 1e-9,
        "{}",
        e.semi_axes
    );
    assert!((e.angle - t).abs() < 1e-9, "angle {}", e.angle);
    // A rasterised ellipse: its contour runs through border pixel centres, about half a
    // pixel inside the true outline.
    let img = gray(100, 70, |x, y| {
        let q = DVec2::from_angle(-t).rotate(DVec2::new(x as f64, y as f64) - c);
        f64::from((q.x / a).powi(2) + (q.y / b).powi(2) <= 1.0)
    });
    let r = regions(&img);
    assert_eq!(r.len(), 1);
    let e = fit_ellipse(&r[0].contour).expect("fit");
    assert!((e.centre - c).length() < 0.2, "centre {} vs {c}", e.centre);
    assert!((e.semi_axes.x - a).abs() < 1.0, "major {}", e.semi_axes.x);
    assert!((e.semi_axes.y - b).abs() < 1.0, "minor {}", e.semi_axes.y);
    assert!((e.angle - t).abs() < 0.05, "angle {}", e.angle);
    // Too few or collinear points: no fit (the detector falls back to the centroid).
    assert!(fit_ellipse(&pts[..4]).is_none());
    let line: Vec<DVec2> = (0..10)
        .map(|i| DVec2::new(i as f64, 2.0 * i as f64))
        .collect();
    assert!(fit_ellipse(&line).is_none());
    let mut with_nan = pts.clone();
    with_nan[3] = DVec2::NAN;
    assert!(fit_ellipse(&with_nan).is_none());
}

#[test]
fn centres_are_averaged_by_area() {
    let img = {
        let a = disc(20.0, 20.0, 5.0);
        let b = disc(70.0, 60.0, 3.0);
        gray(100, 100, |x, y| a.get(x, y, 0) + b.get(x, y, 0))
    };
    let r = regions(&img);
    assert_eq!(r.len(), 2);
    let (wa, wb) = (r[0].area, r[1].area);
    let want = (wa * DVec2::new(20.0, 20.0) + wb * DVec2::new(70.0, 60.0)) / (wa + wb);
    let got = weighted_centre(&r).unwrap();
    assert!((got - want).length() < 1e-6, "{got} vs {want}");
    assert!(weighted_centre(&[]).is_none());
}

// ---------------------------------------------------------------------------------------
// Interface: errors, names, JSON, files
// ---------------------------------------------------------------------------------------

#[test]
fn wrong_sizes_are_errors_naming_both_sizes() {
    let small = RgbImage::new(320, 240);
    let big = RgbImage::new(640, 480);
    for method in Method::ALL {
        let err = localise(sensor(), &small, &small, method).unwrap_err();
        assert!(matches!(err, GeltipError::InvalidInput { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
        assert!(!msg.contains('\n'));
        let msg = localise(sensor(), &big, &small, method)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
        let msg = localise(sensor(), &small, &big, method)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("320x240") && msg.contains("640x480"), "{msg}");
    }
}

#[test]
fn method_names_round_trip() {
    assert_eq!(Method::ALL.len(), 2);
    for m in Method::ALL {
        assert_eq!(Method::from_name(m.name()).unwrap(), m);
    }
    let msg = Method::from_name("sobel").unwrap_err().to_string();
    assert!(
        msg.contains("sobel") && msg.contains("paper") && msg.contains("surface"),
        "{msg}"
    );
}

#[test]
fn detection_json_has_every_field_and_no_nan() {
    let f = sensor().finger;
    let truth = f.point_at(SurfaceCoord { s: 4.0, phi: 1.0 }).point;
    let frame = paint(
        gradient_reference(),
        truth,
        Paint::Blob { sigma_mm: 0.6 },
        60.0,
    );
    let d = localiser()
        .localise(gradient_reference(), &frame, Method::Surface)
        .unwrap();
    let j = d.to_json();
    assert_eq!(j["detected"], true);
    assert_eq!(j["pixel"].as_array().unwrap().len(), 2);
    let p = j["point"].as_array().unwrap();
    assert_eq!(p.len(), 3);
    assert!((p[2].as_f64().unwrap() - d.point.unwrap().z).abs() < 1e-12);
    assert_eq!(j["region"], "hemisphere");
    assert!(j["confidence"].as_f64().unwrap() > 0.5);
    assert_eq!(j["regions_found"], 1);
    assert!(j["note"].is_null());
    // A pixel that sees no part of the finger (the image corner, outside the lens circle)
    // is "not detected" with a note, never NaN.
    let d = Detection::at_pixel(sensor(), DVec2::new(0.0, 0.0), 0.7, 2);
    assert_not_detected(&d, "corner");
    assert_eq!(d.regions_found, 2);
    let j = d.to_json();
    assert!(j["pixel"].is_null() && j["point"].is_null() && j["region"].is_null());
    let d = Detection::at_pixel(sensor(), DVec2::new(f64::NAN, 3.0), f64::NAN, 0);
    assert_not_detected(&d, "NaN pixel");
}

#[test]
fn images_load_and_bad_files_are_one_line_errors() {
    let dir = std::env::temp_dir().join(format!("geltip-localise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("frame.png");
    gradient_reference().save(&good).unwrap();
    let img = load_image(&good).unwrap();
    assert_eq!(&img, gradient_reference());
    assert_eq!(&load_frame(sensor(), &good).unwrap(), gradient_reference());

    let small = dir.join("small.png");
    RgbImage::new(32, 24).save(&small).unwrap();
    let err = load_frame(sensor(), &small).unwrap_err();
    assert!(matches!(err, GeltipError::InvalidImage { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("32x24") && msg.contains("640x480") && msg.contains("small.png"),
        "{msg}"
    );

    let garbage = dir.join("garbage.png");
    std::fs::write(&garbage, b"not a png\nat all").unwrap();
    for path in [garbage, dir.join("missing.png")] {
        let err = load_image(&path).unwrap_err();
        assert!(matches!(err, GeltipError::InvalidImage { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(
            msg.contains(path.file_name().unwrap().to_str().unwrap()),
            "{msg}"
        );
        assert!(!msg.contains('\n'), "{msg}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
