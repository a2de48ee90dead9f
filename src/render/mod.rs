//! The renderer: "this object pressed this deep at this place" -> the image the GelTip
//! camera would see. Four stages, each a WGSL file in `shaders/` and a Rust module here with
//! a CPU mirror under the same names, so tests can compare them:
//! 1. [`contact`]: penetration of the object along the surface normal, on the heightfield;
//! 2. [`elastomer`]: the gel's blend of that penetration, capped at the shell thickness;
//! 3. [`camera`]: each pixel's lens ray meets the deformed skin inside the shell;
//! 4. [`leds`]: three LEDs at the base light the painted skin.
//!
//! The heightfield lives on the unrolled disc (see [`crate::finger`]); only the object's
//! footprint on it, and the pixels that can see that footprint, are computed per contact:
//! the rest of every frame is the no-contact reference, rendered once per sensor.

pub mod camera;
pub mod contact;
pub mod cpu;
pub mod elastomer;
pub mod gpu;
pub mod leds;
pub mod uniforms;

use crate::error::{GeltipError, Result};
use crate::finger::{Region, SurfaceCoord};
use crate::object::Object;
use crate::sensor::Sensor;
use glam::{DMat3, DVec2, DVec3};
use std::sync::Arc;

/// Where on the finger a contact is placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Place {
    /// The paper's rotation about the tip, in degrees: 0 = the tip, 90 = the junction.
    Rotation(f64),
    /// The paper's translation along the side, in mm below the junction.
    Translation(f64),
    /// Arc length from the tip along a meridian, in mm.
    ArcLength(f64),
}

impl Place {
    /// Parses the CLI's `rotation=<deg>`, `translation=<mm>` or `s=<mm>`.
    pub fn parse(text: &str) -> Result<Place> {
        let bad = |reason: &str| GeltipError::input(format!("--at {text}"), reason.to_string());
        let (key, value) = text
            .split_once('=')
            .ok_or_else(|| bad("expected rotation=<deg>, translation=<mm> or s=<mm>"))?;
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| bad("the value is not a number"))?;
        if !v.is_finite() {
            return Err(bad("the value is not a finite number"));
        }
        match key.trim() {
            "rotation" => Ok(Place::Rotation(v)),
            "translation" => Ok(Place::Translation(v)),
            "s" => Ok(Place::ArcLength(v)),
            _ => Err(bad("expected rotation=<deg>, translation=<mm> or s=<mm>")),
        }
    }

    /// Arc length from the tip on `sensor`'s finger.
    pub fn arc_length(self, sensor: &Sensor) -> f64 {
        let f = &sensor.finger;
        match self {
            Place::Rotation(deg) => f.s_of_rotation(deg.to_radians()),
            Place::Translation(mm) => f.s_of_translation(mm),
            Place::ArcLength(s) => s,
        }
    }

    /// Human-readable label, as the experiment's tables use.
    pub fn label(self) -> String {
        match self {
            Place::Rotation(d) => format!("rotation {d} deg"),
            Place::Translation(mm) => format!("translation {mm} mm"),
            Place::ArcLength(s) => format!("s {s} mm"),
        }
    }
}

/// One object pressed into the finger.
#[derive(Debug, Clone)]
pub struct Contact {
    pub object: Arc<Object>,
    pub place: Place,
    /// Azimuth of the contact about the finger's axis, degrees (0 = image +x).
    pub azimuth_deg: f64,
    /// The object's own rotation about the contact normal, degrees.
    pub spin_deg: f64,
    /// How far the object is pressed in along the normal, mm.
    pub depth_mm: f64,
}

/// Where a contact sits and how its object is oriented, in the camera frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPose {
    /// Contact point on the undeformed surface.
    pub point: DVec3,
    /// Outward surface normal there.
    pub normal: DVec3,
    pub coord: SurfaceCoord,
    pub region: Region,
    /// Rotation taking object-local vectors to the camera frame. Object-local +z points into
    /// the finger (along -normal): objects stand on their base with their top at the origin.
    pub world_from_object: DMat3,
    /// The object's origin (its top) in the camera frame: the contact point pushed in by depth.
    pub origin: DVec3,
    pub depth_mm: f64,
}

impl ContactPose {
    /// Object-local coordinates of a camera-frame point.
    pub fn to_object(&self, p: DVec3) -> DVec3 {
        self.world_from_object.transpose() * (p - self.origin)
    }
}

impl Contact {
    /// Checks the contact's numbers and places it on `sensor`'s finger.
    pub fn pose(&self, sensor: &Sensor) -> Result<ContactPose> {
        let f = &sensor.finger;
        for (what, v) in [
            ("--azimuth", self.azimuth_deg),
            ("--spin", self.spin_deg),
            ("--depth", self.depth_mm),
        ] {
            if !v.is_finite() {
                return Err(GeltipError::input(
                    what,
                    format!("must be a finite number, got {v}"),
                ));
            }
        }
        if self.depth_mm < 0.0 {
            return Err(GeltipError::input(
                "--depth",
                format!("a press depth cannot be negative, got {} mm", self.depth_mm),
            ));
        }
        let reach = contact::max_trace_depth(f, self.depth_mm) + sensor.config.elastomer.drape_mm;
        if self.object.exact_reach_mm() < reach {
            return Err(GeltipError::input(
                format!("object {}", self.object.name()),
                format!(
                    "its baked SDF is exact only {:.2} mm around it; this sensor's drape and press need {reach:.2} mm",
                    self.object.exact_reach_mm()
                ),
            ));
        }
        let s = self.place.arc_length(sensor);
        // The finger runs from the tip down to the camera's plane (further where the lens sees
        // behind it). A contact the lens cannot see renders as the empty finger, and its
        // ground truth says why it has no pixel.
        let s_max = (heightfield_extent(sensor) - margin_mm(sensor))
            .max(f.junction_s() + f.cylinder_length);
        if !(0.0..=s_max).contains(&s) {
            return Err(GeltipError::input(
                "--at",
                format!(
                    "{} is {s:.3} mm from the tip along the surface; the finger runs 0..{s_max:.3} mm",
                    self.place.label()
                ),
            ));
        }
        let coord = SurfaceCoord {
            s,
            phi: self.azimuth_deg.to_radians(),
        };
        let sp = f.point_at(coord);
        let (e_s, e_phi) = f.tangents_at(coord);
        // Object x along the meridian (away from the tip), y along the azimuth, z inward;
        // then the object's spin about its own z.
        let (sin, cos) = self.spin_deg.to_radians().sin_cos();
        let x = cos * e_s + sin * e_phi;
        let y = -sin * e_s + cos * e_phi;
        let z = -sp.normal;
        Ok(ContactPose {
            point: sp.point,
            normal: sp.normal,
            coord,
            region: sp.region,
            world_from_object: DMat3::from_cols(x, y, z),
            origin: sp.point - self.depth_mm * sp.normal,
            depth_mm: self.depth_mm,
        })
    }
}

/// Ground truth of one rendered contact.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    pub object: String,
    pub place: String,
    pub point: DVec3,
    /// The contact point's pixel, or `None` with the reason when the camera cannot see it.
    pub pixel: std::result::Result<DVec2, String>,
    pub normal: DVec3,
    pub depth_mm: f64,
    pub region: Region,
    pub s_mm: f64,
    pub azimuth_deg: f64,
    pub spin_deg: f64,
    /// Pixels whose skin is pressed in by more than [`MASK_THRESHOLD_MM`].
    pub mask_pixels: u64,
    /// Bounding box of those pixels: [u0, v0, u1, v1] inclusive.
    pub mask_bbox: Option<[u32; 4]>,
    /// Whether the object pushed the gel against the rigid shell (penetration > thickness).
    pub over_pressed: bool,
    /// How far the skin is pushed in at the contact point itself (mm): the press depth for
    /// a solid top, 0 in a tube's hole.
    pub contact_indentation_mm: f64,
}

/// Indentation (mm) above which a pixel belongs to the contact mask.
pub const MASK_THRESHOLD_MM: f64 = 0.01;

impl GroundTruth {
    /// The labels file: one JSON object.
    pub fn to_json(&self) -> serde_json::Value {
        let (pixel, reason) = match &self.pixel {
            Ok(px) => (serde_json::json!([px.x, px.y]), serde_json::Value::Null),
            Err(why) => (serde_json::Value::Null, serde_json::json!(why)),
        };
        serde_json::json!({
            "object": self.object,
            "place": self.place,
            "point": self.point.to_array(),
            "pixel": pixel,
            "pixel_reason": reason,
            "normal": self.normal.to_array(),
            "depth_mm": self.depth_mm,
            "region": self.region.name(),
            "s_mm": self.s_mm,
            "azimuth_deg": self.azimuth_deg,
            "spin_deg": self.spin_deg,
            "mask_pixels": self.mask_pixels,
            "mask_bbox": self.mask_bbox,
            "over_pressed": self.over_pressed,
            "contact_indentation_mm": self.contact_indentation_mm,
        })
    }
}

/// A rendered frame: RGBA8 pixels (row-major, tightly packed) and the indentation (mm)
/// each pixel sees.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub indentation: Vec<f32>,
}

impl Frame {
    /// The RGB image (alpha dropped), as the localiser and PNG files use.
    pub fn to_rgb(&self) -> image::RgbImage {
        let rgb = self
            .rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        image::RgbImage::from_raw(self.width, self.height, rgb)
            .expect("frame size matches its pixels")
    }

    /// Pixel count and bounding box of the contact mask.
    pub fn mask(&self) -> (u64, Option<[u32; 4]>) {
        let pressed = |d: &f32| *d as f64 > MASK_THRESHOLD_MM;
        // The mask is a small part of the frame: find where it starts and ends first.
        let Some(first) = self.indentation.iter().position(pressed) else {
            return (0, None);
        };
        let last = self.indentation.iter().rposition(pressed).unwrap_or(first);
        let mut count = 0;
        let mut bbox: Option<[u32; 4]> = None;
        for (i, &d) in self
            .indentation
            .iter()
            .enumerate()
            .take(last + 1)
            .skip(first)
        {
            if pressed(&d) {
                count += 1;
                let (u, v) = (i as u32 % self.width, i as u32 / self.width);
                bbox = Some(match bbox {
                    None => [u, v, u, v],
                    Some([u0, v0, u1, v1]) => [u0.min(u), v0.min(v), u1.max(u), v1.max(v)],
                });
            }
        }
        (count, bbox)
    }
}

/// Extra arc length (mm) the heightfield covers beyond what the lens sees.
pub fn margin_mm(sensor: &Sensor) -> f64 {
    1.0 + 4.0 * sensor.config.elastomer.blend_mm
}

/// Half the side of the heightfield's square on the unrolled disc (mm): the arc length of the
/// farthest surface point the lens can see, plus a margin for the elastomer's blend.
pub fn heightfield_extent(sensor: &Sensor) -> f64 {
    let t = sensor.lens.max_theta;
    let f = &sensor.finger;
    let edge = f
        .surface_along(DVec3::new(t.sin(), 0.0, t.cos()))
        .map(|sp| f.coord_of(sp.point).s)
        .unwrap_or(f.junction_s());
    // The inner skin (pressed to the full thickness) is seen a little further out.
    let inner = edge + f.shell_thickness;
    inner + margin_mm(sensor)
}

/// The heightfield grid: `texels` x `texels` square on the unrolled disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightfieldGrid {
    pub texels: u32,
    pub half_size_mm: f64,
}

impl HeightfieldGrid {
    pub fn for_sensor(sensor: &Sensor) -> Self {
        HeightfieldGrid {
            texels: sensor.config.render.heightfield_texels,
            half_size_mm: heightfield_extent(sensor),
        }
    }

    /// Size of one texel on the disc, mm.
    pub fn texel_mm(&self) -> f64 {
        2.0 * self.half_size_mm / self.texels as f64
    }

    /// Disc coordinates of texel (i, j)'s centre.
    pub fn texel_centre(&self, i: u32, j: u32) -> DVec2 {
        DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * self.texel_mm()
            - DVec2::splat(self.half_size_mm)
    }

    /// Continuous texel coordinates of a disc point (texel centres at integer + 0.5).
    pub fn texel_of(&self, disc: DVec2) -> DVec2 {
        (disc + DVec2::splat(self.half_size_mm)) / self.texel_mm()
    }
}

/// A rectangle of texels or pixels: origin and size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl Rect {
    /// The rectangle covering continuous coordinates [lo, hi], grown by `pad` cells (x, y)
    /// and clipped to a `size.0` x `size.1` grid; `None` when nothing is left.
    pub fn covering(lo: DVec2, hi: DVec2, pad: DVec2, size: (u32, u32)) -> Option<Rect> {
        let x0 = (lo.x - pad.x).floor().max(0.0);
        let y0 = (lo.y - pad.y).floor().max(0.0);
        let x1 = (hi.x + pad.x).ceil().min(size.0 as f64);
        let y1 = (hi.y + pad.y).ceil().min(size.1 as f64);
        if !(x1 > x0 && y1 > y0) {
            return None;
        }
        Some(Rect {
            x: x0 as u32,
            y: y0 as u32,
            w: (x1 - x0) as u32,
            h: (y1 - y0) as u32,
        })
    }

    pub fn area(&self) -> u64 {
        self.w as u64 * self.h as u64
    }

    /// The smallest rectangle covering both.
    pub fn union(&self, other: &Rect) -> Rect {
        let (x0, y0) = (self.x.min(other.x), self.y.min(other.y));
        let x1 = (self.x + self.w).max(other.x + other.w);
        let y1 = (self.y + self.h).max(other.y + other.h);
        Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(pressed: &[(u32, u32, f32)]) -> Frame {
        let (width, height) = (7, 5);
        let mut indentation = vec![0.0; (width * height) as usize];
        for &(x, y, d) in pressed {
            indentation[(y * width + x) as usize] = d;
        }
        Frame {
            width,
            height,
            rgba: vec![0; (width * height * 4) as usize],
            indentation,
        }
    }

    #[test]
    fn mask_counts_pressed_pixels_and_bounds_them() {
        assert_eq!(frame(&[]).mask(), (0, None));
        // At the threshold is not pressed; just past it is.
        assert_eq!(frame(&[(3, 2, MASK_THRESHOLD_MM as f32)]).mask(), (0, None));
        assert_eq!(frame(&[(3, 2, 0.02)]).mask(), (1, Some([3, 2, 3, 2])));
        // First and last pixels of the frame, a bump out (negative) ignored, in between.
        let f = frame(&[
            (0, 0, 0.5),
            (6, 4, 0.3),
            (5, 1, -0.4),
            (2, 3, 0.2),
            (6, 0, 0.1),
        ]);
        assert_eq!(f.mask(), (4, Some([0, 0, 6, 4])));
        let f = frame(&[(4, 1, 0.5), (1, 3, 0.3), (5, 2, 0.2)]);
        assert_eq!(f.mask(), (3, Some([1, 1, 5, 3])));
    }
}
