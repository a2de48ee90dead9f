//! A sensor: finger geometry + lens + image + light, loaded from TOML ([`config`], with the
//! light in [`lighting`]), validated, and the projection map m between pixels and points on
//! the finger surface.
//!
//! Pixel coordinates follow OpenCV: u to the right, v down, integer coordinates at pixel
//! centres, so a `width` x `height` image spans u in [-0.5, width - 0.5]. The image x axis is
//! the world x axis and the image v axis the world y axis; the optical axis is +z.

pub mod config;
pub mod lighting;
pub mod shell_end;

pub use config::{
    ElastomerConfig, FingerConfig, ImageConfig, LensConfig, PaintConfig, RenderConfig,
    SensorConfig, MAX_FINGER_MM, MAX_IMAGE_SIDE,
};
pub use lighting::{
    CameraConfig, GelSpread, Led, LedColours, LedConfig, LedKind, LedKindName, Leds, LedsConfig,
    LightConfig, Lighting, Noise, MAX_LEDS,
};
pub use shell_end::ShellEndConfig;

use crate::error::{GeltipError, Result};
use crate::finger::{Finger, SurfacePoint};
use crate::lens::Lens;
use glam::{DVec2, DVec3};
use std::path::Path;

/// The presets shipped in `assets/sensors/`, compiled in so the binary works from anywhere.
pub const PRESETS: [(&str, &str); 5] = [
    ("paper", include_str!("../../assets/sensors/paper.toml")),
    (
        "webcam70",
        include_str!("../../assets/sensors/webcam70.toml"),
    ),
    ("tube13", include_str!("../../assets/sensors/tube13.toml")),
    ("tube21", include_str!("../../assets/sensors/tube21.toml")),
    (
        "allsight",
        include_str!("../../assets/sensors/allsight.toml"),
    ),
];

/// Why a point has no pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NotVisible {
    /// Outside the finger: the opaque paint hides it.
    OutsideFinger { distance_mm: f64 },
    /// At the camera centre itself.
    AtCamera,
    /// Beyond the edge of the lens's field of view.
    OutsideFov { theta_deg: f64, half_fov_deg: f64 },
    /// The lens sees it but the image sensor does not cover that pixel.
    OutsideImage { u: f64, v: f64 },
    /// It lands on the image outside the image circle the camera cuts it to.
    OutsideCircle { u: f64, v: f64 },
    /// A coordinate is NaN or infinite.
    NotFinite,
}

impl std::fmt::Display for NotVisible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotVisible::OutsideFinger { distance_mm } => {
                write!(f, "outside the finger ({distance_mm:.6} mm beyond the surface): the paint hides it")
            }
            NotVisible::AtCamera => write!(f, "at the camera's optical centre"),
            NotVisible::OutsideFov { theta_deg, half_fov_deg } => write!(
                f,
                "{theta_deg:.4} degrees off the optical axis, beyond the lens's {half_fov_deg:.4} degree half field of view"
            ),
            NotVisible::OutsideImage { u, v } => {
                write!(f, "lands at pixel ({u:.3}, {v:.3}), outside the image")
            }
            NotVisible::OutsideCircle { u, v } => {
                write!(f, "lands at pixel ({u:.3}, {v:.3}), outside the image circle")
            }
            NotVisible::NotFinite => write!(f, "a coordinate is not a finite number"),
        }
    }
}

/// Points this close to the surface (mm) count as on it, to absorb rounding.
pub const SURFACE_TOLERANCE_MM: f64 = 1e-6;

/// A validated sensor: the finger, the lens and the image it forms.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    pub name: String,
    pub config: SensorConfig,
    pub finger: Finger,
    pub lens: Lens,
    /// Principal point (px).
    pub principal: DVec2,
    pub width: u32,
    pub height: u32,
}

impl Sensor {
    /// Builds a sensor from a configuration, validating it first.
    pub fn from_config(name: impl Into<String>, config: SensorConfig) -> Result<Self> {
        config.validate()?;
        Ok(Sensor {
            name: name.into(),
            finger: Finger {
                radius: config.finger.radius_mm,
                cylinder_length: config.finger.cylinder_length_mm,
                shell_thickness: config.finger.shell_thickness_mm,
            },
            lens: config.lens(),
            principal: DVec2::new(config.lens.cx, config.lens.cy),
            width: config.image.width,
            height: config.image.height,
            config,
        })
    }

    /// Parses and validates TOML text.
    pub fn from_toml(name: &str, text: &str) -> Result<Self> {
        Sensor::from_config(name, SensorConfig::from_toml(text, name)?)
    }

    /// A preset shipped with geltip, by name.
    pub fn preset(name: &str) -> Result<Self> {
        let (_, text) =
            PRESETS
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| GeltipError::UnknownSensor {
                    name: name.to_string(),
                    presets: preset_names(),
                })?;
        Sensor::from_toml(name, text)
    }

    /// `--sensor` semantics: an existing file path, else a preset name.
    pub fn load(name_or_path: &str) -> Result<Self> {
        let path = Path::new(name_or_path);
        if path.is_file() {
            let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
            return Sensor::from_toml(name_or_path, &text);
        }
        if PRESETS.iter().any(|(n, _)| *n == name_or_path) {
            return Sensor::preset(name_or_path);
        }
        Err(GeltipError::UnknownSensor {
            name: name_or_path.to_string(),
            presets: preset_names(),
        })
    }

    /// The sensor's light, resolved from either form of its file.
    pub fn lighting(&self) -> Lighting {
        let c = &self.config;
        let ambient = match (c.light.ambient, c.leds.ring_ambient()) {
            (Some(rgb), _) => DVec3::from_array(rgb),
            (None, Some(grey)) => DVec3::splat(grey),
            (None, None) => DVec3::ZERO,
        };
        Lighting {
            leds: c
                .leds
                .resolve(c.finger.radius_mm, c.finger.shell_thickness_mm),
            ambient,
            ambient_relief: DVec3::from_array(c.light.ambient_relief),
            paint_colour: DVec3::from_array(c.paint.colour),
            vignetting: c.light.vignetting,
            finger: self.finger,
            camera: c.camera,
            shell_end: c.shell_end,
        }
    }

    /// Whether the continuous pixel position lies on the image (OpenCV convention).
    pub fn in_image(&self, pixel: DVec2) -> bool {
        pixel.x >= -0.5
            && pixel.y >= -0.5
            && pixel.x <= self.width as f64 - 0.5
            && pixel.y <= self.height as f64 - 0.5
    }

    /// The image circle's centre and radius (px): the mask's where the sensor file gives one
    /// (`image.circle`), else the principal point and the edge of the lens's field of view.
    pub fn image_circle(&self) -> (DVec2, f64) {
        match self.config.image.circle {
            Some([cx, cy, r]) => (DVec2::new(cx, cy), r),
            None => (self.principal, self.lens.max_rho()),
        }
    }

    /// Whether the pixel lies inside the image circle, where the sensor file gives one as a
    /// mask (`image.circle`); always true without one. Compared in f32 as the shaders do,
    /// so the CPU and the GPU cut the same pixels.
    pub fn in_circle(&self, pixel: DVec2) -> bool {
        match self.config.image.circle {
            None => true,
            Some([cx, cy, r]) => {
                let d = pixel.as_vec2() - glam::Vec2::new(cx as f32, cy as f32);
                d.length_squared() <= (r as f32) * (r as f32)
            }
        }
    }

    /// Unit direction of the lens ray through `pixel`, or `None` outside the image or the
    /// lens's field of view.
    pub fn ray_direction(&self, pixel: DVec2) -> Option<DVec3> {
        if !pixel.is_finite() || !self.in_image(pixel) || !self.in_circle(pixel) {
            return None;
        }
        self.lens.ray(pixel - self.principal)
    }

    /// The map m: the surface point a pixel sees, or `None` when it sees no part of the
    /// finger (outside the image or beyond the lens's field of view).
    pub fn unproject(&self, pixel: DVec2) -> Option<SurfacePoint> {
        self.finger.surface_along(self.ray_direction(pixel)?)
    }

    /// The pixel where a point inside or on the finger appears: the inverse of m on the
    /// surface, and the camera's projection for points inside the finger.
    pub fn project(&self, point: DVec3) -> Result<DVec2, NotVisible> {
        if !point.is_finite() {
            return Err(NotVisible::NotFinite);
        }
        let distance = self.finger.signed_distance(point);
        if distance > SURFACE_TOLERANCE_MM {
            return Err(NotVisible::OutsideFinger {
                distance_mm: distance,
            });
        }
        let lateral = point.x.hypot(point.y);
        if lateral == 0.0 && point.z == 0.0 {
            return Err(NotVisible::AtCamera);
        }
        let theta = lateral.atan2(point.z);
        // The lens edge itself is inside, up to rounding (as in `Lens::unproject`).
        if theta > self.lens.max_theta * (1.0 + 1e-12) {
            return Err(NotVisible::OutsideFov {
                theta_deg: theta.to_degrees(),
                half_fov_deg: self.lens.max_theta.to_degrees(),
            });
        }
        let rho = self.lens.project(theta.min(self.lens.max_theta));
        let pixel = if lateral == 0.0 {
            self.principal
        } else {
            self.principal + rho * DVec2::new(point.x, point.y) / lateral
        };
        if !self.in_image(pixel) {
            return Err(NotVisible::OutsideImage {
                u: pixel.x,
                v: pixel.y,
            });
        }
        if !self.in_circle(pixel) {
            return Err(NotVisible::OutsideCircle {
                u: pixel.x,
                v: pixel.y,
            });
        }
        Ok(pixel)
    }
}

/// The preset names, comma separated.
pub fn preset_names() -> String {
    PRESETS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}
