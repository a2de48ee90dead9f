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
//! [`background`] puts a frame's change from that reference on a real sensor's empty frame.

pub mod background;
pub mod camera;
pub mod contact;
pub mod cpu;
pub mod elastomer;
pub mod gpu;
pub mod leds;
pub mod pool;
pub mod softness;
pub mod touched;
pub mod uniforms;

use crate::finger::Region;
use crate::sensor::Sensor;
use glam::{DVec2, DVec3};

/// The contact types the renderer's callers name with it (defined in [`crate::scene`]).
pub use crate::scene::{ContactPose, Hold, Place, Press};

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
    /// The object's tilt away from the normal and its direction (degrees; 0 for a rigid pose).
    pub tilt_deg: f64,
    pub tilt_towards_deg: f64,
    /// The object's pose: camera-frame point = M (object point, 1), M row-major.
    pub pose: [f64; 16],
    /// How far from its top's place on the normal the object first touched (mm, outward
    /// positive; 0 for a top point on the normal, -1 for the torus at the tip).
    pub first_touch_offset_mm: f64,
    /// Surface points touched first (a ring's circle), the refined first point first.
    pub first_touch: Vec<DVec3>,
    /// The deepest penetration of the object into the undeformed skin (mm), and where.
    pub indentation_reached_mm: f64,
    pub deepest_point: Option<DVec3>,
    /// Centroid of the indented area on the surface (weighted by indentation): **the label
    /// detectors are scored against** (see [`GroundTruth::scoring_point`]).
    pub contact_centre: Option<DVec3>,
    /// Surface area of the indented region (mm²).
    pub indented_area_mm2: f64,
}

/// Indentation (mm) above which a pixel belongs to the contact mask.
pub const MASK_THRESHOLD_MM: f64 = 0.01;

impl GroundTruth {
    /// The point a contact detector should be scored against: the centre of the indented
    /// region on the surface ([`GroundTruth::contact_centre`]), or the contact point when
    /// nothing is indented. For a single-point top pressed along the normal of a smooth
    /// finger it lies at the contact point up to the imprint's asymmetry.
    pub fn scoring_point(&self) -> DVec3 {
        self.contact_centre.unwrap_or(self.point)
    }

    /// The labels file: one JSON object.
    pub fn to_json(&self) -> serde_json::Value {
        let v = |p: &DVec3| p.to_array();
        // A ring's first-touch band can hold hundreds of samples: at most 64, evenly spread.
        let stride = self.first_touch.len().div_ceil(64).max(1);
        let first_touch: Vec<[f64; 3]> = self.first_touch.iter().step_by(stride).map(v).collect();
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
            "tilt_deg": self.tilt_deg,
            "tilt_towards_deg": self.tilt_towards_deg,
            "pose": self.pose,
            "first_touch_offset_mm": self.first_touch_offset_mm,
            "first_touch_point": self.first_touch.first().map(v),
            "first_touch": first_touch,
            "indentation_reached_mm": self.indentation_reached_mm,
            "deepest_point": self.deepest_point.as_ref().map(v),
            "contact_centre": self.contact_centre.as_ref().map(v),
            "indented_area_mm2": self.indented_area_mm2,
            "score_against": "contact_centre",
        })
    }
}

/// The labels of a frame of several contacts (or none), as `geltip render --scene` writes
/// them: each contact's labels, the union mask's pixel count and box, and whether any
/// object pressed the gel against the shell.
pub fn scene_labels(frame: &Frame, truths: &[GroundTruth]) -> serde_json::Value {
    let (count, bbox) = frame.mask();
    serde_json::json!({
        "contacts": truths.iter().map(GroundTruth::to_json).collect::<Vec<_>>(),
        "mask_pixels": count,
        "mask_bbox": bbox,
        "over_pressed": truths.iter().any(|t| t.over_pressed),
    })
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

    /// Pixel count and bounding box of the contact mask inside `rect`.
    pub fn mask_in(&self, rect: Rect) -> (u64, Option<[u32; 4]>) {
        let pressed = |d: &f32| *d as f64 > MASK_THRESHOLD_MM;
        let (u0, u1) = (rect.x.min(self.width), (rect.x + rect.w).min(self.width));
        let mut count = 0;
        let mut bbox: Option<[u32; 4]> = None;
        // Row by row: a count and the first and last pressed pixel (loops the compiler
        // vectorises; this runs on every rendered frame).
        for v in rect.y..(rect.y + rect.h).min(self.height) {
            let start = (v * self.width) as usize;
            let row = &self.indentation[start + u0 as usize..start + u1 as usize];
            let Some(first) = row.iter().position(pressed) else {
                continue;
            };
            let last = row.iter().rposition(pressed).unwrap_or(first);
            count += row[first..=last].iter().filter(|d| pressed(d)).count() as u64;
            let (a, b) = (u0 + first as u32, u0 + last as u32);
            bbox = Some(match bbox {
                None => [a, v, b, v],
                Some([x0, y0, x1, _]) => [x0.min(a), y0, x1.max(b), v],
            });
        }
        (count, bbox)
    }

    /// Pixel count and bounding box of the contact mask.
    pub fn mask(&self) -> (u64, Option<[u32; 4]>) {
        self.mask_in(Rect {
            x: 0,
            y: 0,
            w: self.width,
            h: self.height,
        })
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

    /// `self` grown by `cells` each side, clipped to `within`; `None` when they do not meet.
    pub fn grown_within(&self, cells: u32, within: Rect) -> Option<Rect> {
        let x0 = self.x.saturating_sub(cells).max(within.x);
        let y0 = self.y.saturating_sub(cells).max(within.y);
        let x1 = (self.x + self.w + cells).min(within.x + within.w);
        let y1 = (self.y + self.h + cells).min(within.y + within.h);
        (x1 > x0 && y1 > y0).then_some(Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        })
    }

    /// The part of `self` outside `other`, as up to four disjoint rectangles.
    pub fn minus(self, other: Rect) -> Vec<Rect> {
        let (ax1, ay1) = (self.x + self.w, self.y + self.h);
        let (bx1, by1) = (other.x + other.w, other.y + other.h);
        let (ix0, iy0) = (self.x.max(other.x), self.y.max(other.y));
        let (ix1, iy1) = (ax1.min(bx1), ay1.min(by1));
        if ix0 >= ix1 || iy0 >= iy1 {
            return vec![self];
        }
        let mut out = Vec::new();
        let mut push = |x0: u32, y0: u32, x1: u32, y1: u32| {
            if x1 > x0 && y1 > y0 {
                out.push(Rect {
                    x: x0,
                    y: y0,
                    w: x1 - x0,
                    h: y1 - y0,
                });
            }
        };
        push(self.x, self.y, ax1, iy0); // above
        push(self.x, iy1, ax1, ay1); // below
        push(self.x, iy0, ix0, iy1); // left
        push(ix1, iy0, ax1, iy1); // right
        out
    }

    /// The union of `rects` as disjoint rectangles (each cell covered once).
    pub fn disjoint(rects: impl IntoIterator<Item = Rect>) -> Vec<Rect> {
        let mut out: Vec<Rect> = Vec::new();
        for r in rects {
            let mut pieces = vec![r];
            for q in &out {
                pieces = pieces.into_iter().flat_map(|p| p.minus(*q)).collect();
            }
            out.extend(pieces);
        }
        out
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
    fn disjoint_rects_cover_the_union_once() {
        let rects = [
            Rect {
                x: 0,
                y: 0,
                w: 10,
                h: 8,
            },
            Rect {
                x: 5,
                y: 4,
                w: 10,
                h: 10,
            },
            Rect {
                x: 30,
                y: 30,
                w: 3,
                h: 3,
            },
            Rect {
                x: 2,
                y: 2,
                w: 3,
                h: 3,
            },
        ];
        let pieces = Rect::disjoint(rects);
        let mut cover = vec![0u32; 40 * 40];
        for p in &pieces {
            for y in p.y..p.y + p.h {
                for x in p.x..p.x + p.w {
                    cover[y as usize * 40 + x as usize] += 1;
                }
            }
        }
        for y in 0..40u32 {
            for x in 0..40u32 {
                let inside = rects
                    .iter()
                    .any(|r| (r.x..r.x + r.w).contains(&x) && (r.y..r.y + r.h).contains(&y));
                assert_eq!(cover[(y * 40 + x) as usize], inside as u32, "cell {x},{y}");
            }
        }
        let area: u64 = pieces.iter().map(|p| p.area()).sum();
        // The second overlaps the first by 5 x 4; the fourth lies inside the first.
        assert_eq!(area, 80 + 100 - 20 + 9);
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
        // Inside a rect: pixels outside it do not count; a rect past the frame is clipped.
        let rect = |x, y, w, h| Rect { x, y, w, h };
        assert_eq!(f.mask_in(rect(2, 0, 10, 3)), (2, Some([4, 1, 5, 2])));
        assert_eq!(f.mask_in(rect(0, 3, 2, 1)), (1, Some([1, 3, 1, 3])));
        assert_eq!(f.mask_in(rect(0, 0, 1, 9)), (0, None));
    }
}
