//! Sized primitives: a sphere, capsule, cylinder, box or ellipsoid of any size, with exact
//! analytic SDFs. Physics engines describe most of their shapes this way (MuJoCo's geoms),
//! and a command line or scene file names one as text: `box:x=10,y=6,z=4`
//! ([`Primitive::parse`], [`PRIMITIVE_SYNTAX`]).
//!
//! Placement: like every object, a primitive lies in the object frame with its top at the
//! origin and its body in `z <= 0`, its own axis (a capsule's or cylinder's, an ellipsoid's
//! or box's z) along z: its centre is at `(0, 0, -top)` ([`Primitive::top`]). Whoever holds
//! it by its centre (a physics engine's geom frame) moves it by that much along its z.
//!
//! Twin: `primitive_sdf(kind, size, p)` in `shaders/shared/object.wgsl`, with the kinds
//! ([`Primitive::kind`], `OBJ_PRIMITIVE_*`) and the sizes in the frame uniform's
//! `object_size` ([`Primitive::gpu_size`]); `tests/primitives.rs` holds the two together.

use super::solids::{sd_box2, sd_box3};
use crate::error::{quoted, GeltipError, Result};
use glam::{DVec2, DVec3};

/// The smallest and largest size (mm) a primitive may have along any of its dimensions: a
/// micrometre, and ten metres (a physics scene's table or floor slab; the shader's f32
/// still resolves half a micrometre on a surface that far from the object's centre).
pub const MIN_PRIMITIVE_MM: f64 = 1e-3;
pub const MAX_PRIMITIVE_MM: f64 = 10_000.0;

/// The text forms, one example each, for messages and help.
pub const PRIMITIVE_SYNTAX: &str =
    "sphere:r=5, capsule:r=2,l=8, cylinder:r=2,l=10, box:x=10,y=6,z=4, ellipsoid:x=8,y=6,z=4";

/// Object kind (FrameUniform `object_kind`, WGSL `OBJ_PRIMITIVE_*`) of the first primitive;
/// the others follow in [`Primitive::NAMES`]' order.
pub const FIRST_PRIMITIVE_KIND: u32 = 10;

/// Bisection steps at most in the ellipsoid's closest-point root (each halves the bracket:
/// f64 converges within about 110).
const ELLIPSOID_MAX_STEPS: u32 = 200;

/// A primitive with its sizes in millimetres (full lengths, not MuJoCo's half-sizes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// A ball of radius `r`.
    Sphere { r: f64 },
    /// A cylinder of radius `r` and length `l` capped by two half-balls: `l + 2r` long.
    Capsule { r: f64, l: f64 },
    /// A flat-ended cylinder of radius `r` and length `l`.
    Cylinder { r: f64, l: f64 },
    /// A box of edge lengths `size` (x, y, z).
    Box { size: DVec3 },
    /// An ellipsoid whose axes are `size` long (its diameters along x, y, z).
    Ellipsoid { size: DVec3 },
}

impl Primitive {
    /// The kinds' names, in the order of their kinds (from [`FIRST_PRIMITIVE_KIND`]).
    pub const NAMES: [&'static str; 5] = ["sphere", "capsule", "cylinder", "box", "ellipsoid"];

    /// The primitive `text` describes (`box:x=10,y=6,z=4`), `None` when it is not a
    /// primitive's text at all (no `kind:` prefix naming one). A primitive's text with bad
    /// sizes is an error naming the size, with `what` naming the text.
    pub fn parse(text: &str) -> Result<Option<Primitive>> {
        let Some((kind, sizes)) = text.split_once(':') else {
            return Ok(None);
        };
        let kind = kind.trim();
        if !Self::NAMES.contains(&kind) {
            return Ok(None);
        }
        let bad = |reason: String| GeltipError::input(format!("object {}", quoted(text)), reason);
        let keys = Self::keys(kind);
        let mut values: [Option<f64>; 3] = [None; 3];
        for item in sizes.split(',') {
            let item = item.trim();
            let Some((key, value)) = item.split_once('=') else {
                return Err(bad(format!(
                    "expected sizes as key=value (e.g. {}), got {}",
                    Self::example(kind),
                    quoted(item)
                )));
            };
            let key = key.trim();
            let Some(slot) = keys.iter().position(|k| *k == key) else {
                return Err(bad(format!(
                    "unknown size {} for a {kind} (it takes {})",
                    quoted(key),
                    keys.join(", ")
                )));
            };
            if values[slot].is_some() {
                return Err(bad(format!("{key} is given twice")));
            }
            let v: f64 = value
                .trim()
                .parse()
                .map_err(|_| bad(format!("{key}: {} is not a number", quoted(value.trim()))))?;
            values[slot] = Some(v);
        }
        let mut got = [0.0; 3];
        for (slot, key) in keys.iter().enumerate() {
            got[slot] = values[slot].ok_or_else(|| {
                bad(format!(
                    "a {kind} needs {} ({}); {key} is missing",
                    keys.join(", "),
                    Self::meaning(kind)
                ))
            })?;
        }
        let p = match kind {
            "sphere" => Primitive::Sphere { r: got[0] },
            "capsule" => Primitive::Capsule {
                r: got[0],
                l: got[1],
            },
            "cylinder" => Primitive::Cylinder {
                r: got[0],
                l: got[1],
            },
            "box" => Primitive::Box {
                size: DVec3::from_array(got),
            },
            _ => Primitive::Ellipsoid {
                size: DVec3::from_array(got),
            },
        };
        p.check().map_err(bad)?;
        Ok(Some(p))
    }

    /// Each size within [`MIN_PRIMITIVE_MM`]..=[`MAX_PRIMITIVE_MM`]: the error names it.
    pub fn check(&self) -> std::result::Result<(), String> {
        for (key, v) in Self::keys(self.name()).iter().zip(self.sizes()) {
            if !(MIN_PRIMITIVE_MM..=MAX_PRIMITIVE_MM).contains(&v) {
                return Err(format!(
                    "{key} must be a size from {MIN_PRIMITIVE_MM} to {MAX_PRIMITIVE_MM} mm, got {v}"
                ));
            }
        }
        Ok(())
    }

    /// The kind's name (`box`).
    pub fn name(&self) -> &'static str {
        Self::NAMES[(self.kind() - FIRST_PRIMITIVE_KIND) as usize]
    }

    /// Its object kind (FrameUniform `object_kind`, WGSL `OBJ_PRIMITIVE_*`).
    pub fn kind(&self) -> u32 {
        FIRST_PRIMITIVE_KIND
            + match self {
                Primitive::Sphere { .. } => 0,
                Primitive::Capsule { .. } => 1,
                Primitive::Cylinder { .. } => 2,
                Primitive::Box { .. } => 3,
                Primitive::Ellipsoid { .. } => 4,
            }
    }

    /// The size keys of a kind, in the order [`Primitive::sizes`] gives them.
    fn keys(kind: &str) -> &'static [&'static str] {
        match kind {
            "sphere" => &["r"],
            "capsule" | "cylinder" => &["r", "l"],
            _ => &["x", "y", "z"],
        }
    }

    /// What a kind's sizes mean, for messages.
    fn meaning(kind: &str) -> &'static str {
        match kind {
            "sphere" => "its radius, mm",
            "capsule" => "its radius and the length between its caps' centres, mm",
            "cylinder" => "its radius and length, mm",
            "box" => "its edge lengths, mm",
            _ => "its diameters along x, y and z, mm",
        }
    }

    /// A kind's example text, for messages.
    fn example(kind: &str) -> &'static str {
        PRIMITIVE_SYNTAX
            .split(", ")
            .find(|e| e.starts_with(&format!("{kind}:")))
            .unwrap_or(PRIMITIVE_SYNTAX)
    }

    /// The sizes in the order of the text's keys (`r`, `l` or `x`, `y`, `z`).
    pub fn sizes(&self) -> Vec<f64> {
        match *self {
            Primitive::Sphere { r } => vec![r],
            Primitive::Capsule { r, l } | Primitive::Cylinder { r, l } => vec![r, l],
            Primitive::Box { size } | Primitive::Ellipsoid { size } => size.to_array().to_vec(),
        }
    }

    /// How far its top lies above its centre: where the centre sits below the object
    /// frame's origin, along -z.
    pub fn top(&self) -> f64 {
        match *self {
            Primitive::Sphere { r } => r,
            Primitive::Capsule { r, l } => r + l / 2.0,
            Primitive::Cylinder { l, .. } => l / 2.0,
            Primitive::Box { size } | Primitive::Ellipsoid { size } => size.z / 2.0,
        }
    }

    /// The sizes the shader reads (FrameUniform `object_size`): sphere (r), capsule and
    /// cylinder (r, l), box and ellipsoid their half-sizes (x, y, z).
    pub fn gpu_size(&self) -> [f32; 4] {
        let s = match *self {
            Primitive::Sphere { r } => [r, 0.0, 0.0],
            Primitive::Capsule { r, l } | Primitive::Cylinder { r, l } => [r, l, 0.0],
            Primitive::Box { size } | Primitive::Ellipsoid { size } => (size / 2.0).to_array(),
        };
        [s[0] as f32, s[1] as f32, s[2] as f32, 0.0]
    }

    /// Exact signed distance (mm, negative inside) from `p` in the object frame.
    ///
    /// Twin: `primitive_sdf` in `shaders/shared/object.wgsl`.
    pub fn sdf(&self, p: DVec3) -> f64 {
        let top = self.top();
        let c = p + DVec3::new(0.0, 0.0, top);
        match *self {
            Primitive::Sphere { r } => c.length() - r,
            Primitive::Capsule { r, l } => {
                (c - DVec3::new(0.0, 0.0, c.z.clamp(-l / 2.0, l / 2.0))).length() - r
            }
            Primitive::Cylinder { r, l } => sd_box2(
                DVec2::new(c.truncate().length(), c.z),
                DVec2::ZERO,
                DVec2::new(r, l / 2.0),
            ),
            Primitive::Box { size } => sd_box3(c, DVec3::ZERO, size / 2.0),
            Primitive::Ellipsoid { size } => sd_ellipsoid(c, size / 2.0),
        }
    }

    /// The largest distance from the origin (its top) to any of its points (for the
    /// ellipsoid a bound: its top to its centre plus its longest semi-axis).
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Primitive::Sphere { r } => 2.0 * r,
            Primitive::Capsule { r, l } => 2.0 * r + l,
            Primitive::Cylinder { r, l } => r.hypot(l),
            Primitive::Box { size } => DVec3::new(size.x / 2.0, size.y / 2.0, size.z).length(),
            Primitive::Ellipsoid { size } => size.z / 2.0 + size.max_element() / 2.0,
        }
    }

    /// The largest distance from the z axis to any of its points.
    pub fn footprint_radius(&self) -> f64 {
        match *self {
            Primitive::Sphere { r }
            | Primitive::Capsule { r, .. }
            | Primitive::Cylinder { r, .. } => r,
            Primitive::Box { size } => (size.x / 2.0).hypot(size.y / 2.0),
            Primitive::Ellipsoid { size } => size.x.max(size.y) / 2.0,
        }
    }
}

/// The canonical text: `box:x=10,y=6,z=4` (numbers in Rust's shortest exact form), which
/// [`Primitive::parse`] reads back as the same primitive.
impl std::fmt::Display for Primitive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:", self.name())?;
        for (k, (key, v)) in Self::keys(self.name()).iter().zip(self.sizes()).enumerate() {
            let sep = if k == 0 { "" } else { "," };
            write!(f, "{sep}{key}={v}")?;
        }
        Ok(())
    }
}

/// The objects of a comma-separated list (`--objects sphere,box:x=10,y=6,z=4,cone.obj`):
/// a primitive's own commas stay in it. A piece `key=value` (a lowercase key, no path)
/// continues the primitive before it.
pub fn split_objects(list: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for piece in list.split(',') {
        let continues = out.last().is_some_and(|last| {
            let kind = last.split_once(':').map(|(k, _)| k.trim());
            let key = piece.split_once('=').map(|(k, _)| k.trim());
            kind.is_some_and(|k| Primitive::NAMES.contains(&k))
                && key.is_some_and(|k| !k.is_empty() && k.chars().all(|c| c.is_ascii_lowercase()))
        });
        match out.last_mut() {
            Some(last) if continues => {
                last.push(',');
                last.push_str(piece);
            }
            _ => out.push(piece.to_string()),
        }
    }
    out
}

/// Exact signed distance from `c` (relative to the centre) to the ellipsoid of semi-axes
/// `e`: the distance to the closest point on its surface (Eberly's robust bisection for
/// the closest point, "Distance from a Point to an Ellipse, an Ellipsoid, or a
/// Hyperellipsoid"), signed by whether `c` lies inside. Twin: `obj_sd_ellipsoid`.
pub fn sd_ellipsoid(c: DVec3, e: DVec3) -> f64 {
    // By symmetry, the first octant with the axes sorted longest first.
    let mut a = [(e.x, c.x.abs()), (e.y, c.y.abs()), (e.z, c.z.abs())];
    if a[0].0 < a[1].0 {
        a.swap(0, 1);
    }
    if a[1].0 < a[2].0 {
        a.swap(1, 2);
    }
    if a[0].0 < a[1].0 {
        a.swap(0, 1);
    }
    let [(e0, y0), (e1, y1), (e2, y2)] = a;
    let g = (y0 / e0).powi(2) + (y1 / e1).powi(2) + (y2 / e2).powi(2) - 1.0;
    let d = distance_to_ellipsoid(e0, e1, e2, y0, y1, y2);
    if g < 0.0 {
        -d
    } else {
        d
    }
}

/// Unsigned distance from (y0, y1, y2) >= 0 to the ellipsoid of semi-axes e0 >= e1 >= e2.
fn distance_to_ellipsoid(e0: f64, e1: f64, e2: f64, y0: f64, y1: f64, y2: f64) -> f64 {
    if y2 > 0.0 {
        if y1 > 0.0 && y0 > 0.0 {
            let z = DVec3::new(y0 / e0, y1 / e1, y2 / e2);
            let g = z.length_squared() - 1.0;
            if g == 0.0 {
                return 0.0;
            }
            let r = DVec2::new((e0 / e2).powi(2), (e1 / e2).powi(2));
            let s = ellipsoid_root(r, z, g);
            let x = DVec3::new(r.x * y0 / (s + r.x), r.y * y1 / (s + r.y), y2 / (s + 1.0));
            return (x - DVec3::new(y0, y1, y2)).length();
        }
        if y1 > 0.0 {
            return distance_to_ellipse(e1, e2, y1, y2);
        }
        if y0 > 0.0 {
            return distance_to_ellipse(e0, e2, y0, y2);
        }
        return (y2 - e2).abs();
    }
    // On the plane of the two longest axes: inside the region whose closest point lies off
    // that plane, or else the ellipse's problem.
    let (d0, d1) = (e0 * e0 - e2 * e2, e1 * e1 - e2 * e2);
    let (n0, n1) = (e0 * y0, e1 * y1);
    if n0 < d0 && n1 < d1 {
        let (q0, q1) = (n0 / d0, n1 / d1);
        let discr = 1.0 - q0 * q0 - q1 * q1;
        if discr > 0.0 {
            let x = DVec3::new(e0 * q0, e1 * q1, e2 * discr.sqrt());
            return (x - DVec3::new(y0, y1, 0.0)).length();
        }
    }
    distance_to_ellipse(e0, e1, y0, y1)
}

/// Unsigned distance from (y0, y1) >= 0 to the ellipse of semi-axes e0 >= e1.
fn distance_to_ellipse(e0: f64, e1: f64, y0: f64, y1: f64) -> f64 {
    if y1 > 0.0 {
        if y0 > 0.0 {
            let z = DVec2::new(y0 / e0, y1 / e1);
            let g = z.length_squared() - 1.0;
            if g == 0.0 {
                return 0.0;
            }
            let r0 = (e0 / e1).powi(2);
            let s = ellipse_root(r0, z, g);
            let x = DVec2::new(r0 * y0 / (s + r0), y1 / (s + 1.0));
            return (x - DVec2::new(y0, y1)).length();
        }
        return (y1 - e1).abs();
    }
    let (n0, d0) = (e0 * y0, e0 * e0 - e1 * e1);
    if n0 < d0 {
        let q0 = n0 / d0;
        let x = DVec2::new(e0 * q0, e1 * (1.0 - q0 * q0).sqrt());
        return (x - DVec2::new(y0, 0.0)).length();
    }
    (y0 - e0).abs()
}

/// The root s of sum((r_i z_i / (s + r_i))^2) - 1 (r = 1 for the last axis) by bisection
/// of its bracket, for an ellipsoid; `g` is its value at s = 0.
fn ellipsoid_root(r: DVec2, z: DVec3, g: f64) -> f64 {
    let n = DVec2::new(r.x * z.x, r.y * z.y);
    let hi = if g < 0.0 {
        0.0
    } else {
        DVec3::new(n.x, n.y, z.z).length() - 1.0
    };
    bisect(z.z - 1.0, hi, |s| {
        (n.x / (s + r.x)).powi(2) + (n.y / (s + r.y)).powi(2) + (z.z / (s + 1.0)).powi(2) - 1.0
    })
}

/// As [`ellipsoid_root`], for an ellipse.
fn ellipse_root(r0: f64, z: DVec2, g: f64) -> f64 {
    let n0 = r0 * z.x;
    let hi = if g < 0.0 {
        0.0
    } else {
        DVec2::new(n0, z.y).length() - 1.0
    };
    bisect(z.y - 1.0, hi, |s| {
        (n0 / (s + r0)).powi(2) + (z.y / (s + 1.0)).powi(2) - 1.0
    })
}

/// The root of the decreasing `f` in [lo, hi], by bisection to the precision of f64.
fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let mut s = 0.5 * (lo + hi);
    for _ in 0..ELLIPSOID_MAX_STEPS {
        s = 0.5 * (lo + hi);
        if s == lo || s == hi {
            break;
        }
        let g = f(s);
        if g > 0.0 {
            lo = s;
        } else if g < 0.0 {
            hi = s;
        } else {
            break;
        }
    }
    s
}

#[cfg(test)]
mod tests;
