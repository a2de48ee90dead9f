//! A sensor: finger geometry + lens + image, loaded from TOML, validated, and the projection
//! map m between pixels and points on the finger surface.
//!
//! Pixel coordinates follow OpenCV: u to the right, v down, integer coordinates at pixel
//! centres, so a `width` x `height` image spans u in [-0.5, width - 0.5]. The image x axis is
//! the world x axis and the image v axis the world y axis; the optical axis is +z.

use crate::error::{GeltipError, Result};
use crate::finger::{Finger, SurfacePoint};
use crate::lens::{Lens, LensModel};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `[finger]`: the finger's geometry in millimetres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerConfig {
    /// r
    pub radius_mm: f64,
    /// d: camera centre to the hemisphere's centre.
    pub cylinder_length_mm: f64,
    /// Elastomer thickness.
    pub shell_thickness_mm: f64,
}

/// `[lens]`: projection model and intrinsics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LensConfig {
    pub model: LensModel,
    /// alpha for the pinhole, f for the fisheye models (pixels).
    pub focal_px: f64,
    /// Full cone the lens passes (degrees).
    pub fov_deg: f64,
    pub cx: f64,
    pub cy: f64,
    /// Kannala-Brandt k1..k4; must be zero for the other models.
    #[serde(default)]
    pub k: [f64; 4],
}

/// `[image]`: the picture's size in pixels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageConfig {
    pub width: u32,
    pub height: u32,
}

/// `[elastomer]`: how the gel turns the object's penetration into a deformation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ElastomerConfig {
    /// Standard deviation (mm, along the surface) of the blur that blends the imprint's edge.
    pub blend_mm: f64,
    /// The tightest radius (mm) the skin can bend to: past an object's edge the skin falls away
    /// on a circle of this radius instead of a cliff. At least the shell thickness, so that
    /// even a full-depth press reaches back to the surface.
    pub drape_mm: f64,
    /// How much of the displaced gel bulges out around the imprint (0 = none): the bulge is
    /// this fraction of the difference between a blend twice as wide and the blend itself.
    pub bulge: f64,
}

impl Default for ElastomerConfig {
    fn default() -> Self {
        ElastomerConfig {
            blend_mm: 0.5,
            drape_mm: 2.0,
            bulge: 0.3,
        }
    }
}

/// LED colours: one red, one green and one blue LED, or three white ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LedColours {
    Rgb,
    White,
}

/// `[leds]`: three point lights at the base of the finger, 120 degrees apart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LedsConfig {
    pub colours: LedColours,
    /// Height of the LED ring (mm, along the optical axis; the camera is at 0).
    pub z_mm: f64,
    /// Azimuth of the first (red) LED in degrees; the others follow at +120 and +240.
    pub azimuth_deg: f64,
    /// Radiant intensity scale.
    pub intensity: f64,
    /// Distance (mm) at which the light has fallen to half: 1 / (1 + (dist / falloff)^2).
    pub falloff_mm: f64,
    /// The LEDs shine up the finger (+z): emission falls as cos(angle off +z)^spread
    /// (0 = the same in every direction).
    pub spread: f64,
    /// Light reaching every point regardless of the LEDs.
    pub ambient: f64,
}

impl Default for LedsConfig {
    fn default() -> Self {
        LedsConfig {
            colours: LedColours::Rgb,
            z_mm: -2.0,
            azimuth_deg: 90.0,
            intensity: 2.0,
            falloff_mm: 10.0,
            spread: 2.0,
            ambient: 0.06,
        }
    }
}

/// `[paint]`: the reflective coating on the elastomer's outer skin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PaintConfig {
    pub diffuse: f64,
    pub specular: f64,
    pub shininess: f64,
}

impl Default for PaintConfig {
    fn default() -> Self {
        PaintConfig {
            diffuse: 0.9,
            specular: 0.35,
            shininess: 24.0,
        }
    }
}

/// `[render]`: the knobs that trade speed for accuracy, and sensor noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    /// Texels per side of the unrolled-disc heightfield.
    pub heightfield_texels: u32,
    /// March steps of each camera ray through the elastomer shell (then bisection).
    pub ray_steps: u32,
    /// Spacing of the elastomer kernels' taps, in standard deviations of each kernel's own
    /// Gaussian (the narrow blend's is `elastomer.blend_mm`, the wide one's twice that);
    /// never closer than one heightfield texel.
    pub blend_tap_spacing: f64,
    /// Standard deviation of additive sensor noise, in 8-bit grey levels (0 = none).
    pub noise: f64,
    /// Seed of the noise; the same seed gives the same bytes.
    pub noise_seed: u32,
}

impl Default for RenderConfig {
    fn default() -> Self {
        RenderConfig {
            heightfield_texels: 256,
            ray_steps: 4,
            blend_tap_spacing: 1.0,
            noise: 0.0,
            noise_seed: 0,
        }
    }
}

/// A sensor configuration file, as written by people and scripts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    /// Free text shown by `geltip sensors`.
    #[serde(default)]
    pub description: String,
    pub finger: FingerConfig,
    pub lens: LensConfig,
    pub image: ImageConfig,
    #[serde(default)]
    pub elastomer: ElastomerConfig,
    #[serde(default)]
    pub leds: LedsConfig,
    #[serde(default)]
    pub paint: PaintConfig,
    #[serde(default)]
    pub render: RenderConfig,
}

/// The largest image side geltip accepts (GPU texture limits start at 8192 on some devices).
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// The largest finger radius and length (mm) geltip accepts: a metre, far beyond any
/// GelTip, and small enough that the finger's geometry stays finite (a radius of 1e308 mm
/// squares to infinity).
pub const MAX_FINGER_MM: f64 = 1000.0;

/// A finger size: finite, positive, at most [`MAX_FINGER_MM`].
fn finger_size(field: &str, v: f64) -> Result<()> {
    finite_positive(field, v)?;
    if v > MAX_FINGER_MM {
        return Err(GeltipError::config(
            field,
            format!("must be at most {MAX_FINGER_MM} mm, got {v}"),
        ));
    }
    Ok(())
}

fn finite_positive(field: &str, v: f64) -> Result<()> {
    if !v.is_finite() {
        return Err(GeltipError::config(
            field,
            format!("must be a finite number, got {v}"),
        ));
    }
    if v <= 0.0 {
        return Err(GeltipError::config(
            field,
            format!("must be greater than 0, got {v}"),
        ));
    }
    Ok(())
}

impl SensorConfig {
    /// Parses TOML text; `origin` names the file (or preset) in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self> {
        let parse_err = |e: toml::de::Error| {
            let line = e
                .span()
                .map(|s| {
                    format!(
                        " (line {})",
                        text[..s.start.min(text.len())].lines().count().max(1)
                    )
                })
                .unwrap_or_default();
            GeltipError::ConfigParse {
                path: origin.to_string(),
                reason: format!("{}{line}", e.message().trim().replace('\n', " ")),
            }
        };
        let de = toml::de::Deserializer::parse(text).map_err(parse_err)?;
        let config: SensorConfig = serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            let inner = e.into_inner();
            GeltipError::ConfigParse {
                path: origin.to_string(),
                reason: format!("{field}: {}", inner.message().trim().replace('\n', " ")),
            }
        })?;
        Ok(config)
    }

    /// Checks every field against what a real sensor can be; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let f = &self.finger;
        finger_size("finger.radius_mm", f.radius_mm)?;
        finger_size("finger.cylinder_length_mm", f.cylinder_length_mm)?;
        finite_positive("finger.shell_thickness_mm", f.shell_thickness_mm)?;
        if f.shell_thickness_mm >= f.radius_mm {
            return Err(GeltipError::config(
                "finger.shell_thickness_mm",
                format!(
                    "must be less than finger.radius_mm ({}), got {}",
                    f.radius_mm, f.shell_thickness_mm
                ),
            ));
        }
        let img = &self.image;
        for (field, v) in [("image.width", img.width), ("image.height", img.height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(GeltipError::config(
                    field,
                    format!("must be between 1 and {MAX_IMAGE_SIDE} pixels, got {v}"),
                ));
            }
        }
        let l = &self.lens;
        finite_positive("lens.focal_px", l.focal_px)?;
        finite_positive("lens.fov_deg", l.fov_deg)?;
        if l.fov_deg >= 360.0 {
            return Err(GeltipError::config(
                "lens.fov_deg",
                format!("a lens cannot pass 360 degrees or more, got {}", l.fov_deg),
            ));
        }
        if l.model == LensModel::Pinhole && l.fov_deg >= 180.0 {
            return Err(GeltipError::config(
                "lens.fov_deg",
                format!(
                    "a pinhole lens (rho = alpha tan theta) cannot pass 180 degrees or more, got {}; use a fisheye model",
                    l.fov_deg
                ),
            ));
        }
        for (field, v, side) in [("lens.cx", l.cx, img.width), ("lens.cy", l.cy, img.height)] {
            if !v.is_finite() {
                return Err(GeltipError::config(
                    field,
                    format!("must be a finite number, got {v}"),
                ));
            }
            if v < 0.0 || v > side as f64 {
                return Err(GeltipError::config(
                    field,
                    format!("principal point is outside the image (0..{side}), got {v}"),
                ));
            }
        }
        for (i, k) in l.k.iter().enumerate() {
            if !k.is_finite() {
                return Err(GeltipError::config(
                    format!("lens.k[{i}]"),
                    format!("must be a finite number, got {k}"),
                ));
            }
        }
        if l.model != LensModel::KannalaBrandt && l.k.iter().any(|&k| k != 0.0) {
            return Err(GeltipError::config(
                "lens.k",
                format!(
                    "only the kannala-brandt model uses k, but the model is {}",
                    l.model.name()
                ),
            ));
        }
        self.validate_rendering()?;
        if let Some(theta) = self.lens().first_non_increasing_theta() {
            return Err(GeltipError::config(
                "lens.k",
                format!(
                    "the projection stops increasing at {:.2} degrees off axis, inside the field of view; it cannot be inverted",
                    theta.to_degrees()
                ),
            ));
        }
        Ok(())
    }

    fn validate_rendering(&self) -> Result<()> {
        let non_negative = |field: &str, v: f64| -> Result<()> {
            if !v.is_finite() || v < 0.0 {
                return Err(GeltipError::config(
                    field,
                    format!("must be a finite number >= 0, got {v}"),
                ));
            }
            Ok(())
        };
        non_negative("elastomer.blend_mm", self.elastomer.blend_mm)?;
        non_negative("elastomer.bulge", self.elastomer.bulge)?;
        finite_positive("elastomer.drape_mm", self.elastomer.drape_mm)?;
        if self.elastomer.drape_mm < self.finger.shell_thickness_mm {
            return Err(GeltipError::config(
                "elastomer.drape_mm",
                format!(
                    "must be at least finger.shell_thickness_mm ({}), got {}",
                    self.finger.shell_thickness_mm, self.elastomer.drape_mm
                ),
            ));
        }
        if self.elastomer.bulge > 1.0 {
            return Err(GeltipError::config(
                "elastomer.bulge",
                format!("must be at most 1, got {}", self.elastomer.bulge),
            ));
        }
        if !self.leds.z_mm.is_finite() {
            return Err(GeltipError::config(
                "leds.z_mm",
                format!("must be a finite number, got {}", self.leds.z_mm),
            ));
        }
        if self.leds.z_mm >= self.finger.cylinder_length_mm {
            return Err(GeltipError::config(
                "leds.z_mm",
                format!(
                    "the LEDs sit at the base, below the hemisphere (z < {}), got {}",
                    self.finger.cylinder_length_mm, self.leds.z_mm
                ),
            ));
        }
        if !self.leds.azimuth_deg.is_finite() {
            return Err(GeltipError::config(
                "leds.azimuth_deg",
                format!("must be a finite number, got {}", self.leds.azimuth_deg),
            ));
        }
        non_negative("leds.intensity", self.leds.intensity)?;
        finite_positive("leds.falloff_mm", self.leds.falloff_mm)?;
        non_negative("leds.spread", self.leds.spread)?;
        non_negative("leds.ambient", self.leds.ambient)?;
        non_negative("paint.diffuse", self.paint.diffuse)?;
        non_negative("paint.specular", self.paint.specular)?;
        finite_positive("paint.shininess", self.paint.shininess)?;
        non_negative("render.noise", self.render.noise)?;
        let r = &self.render;
        if !(16..=4096).contains(&r.heightfield_texels) {
            return Err(GeltipError::config(
                "render.heightfield_texels",
                format!("must be between 16 and 4096, got {}", r.heightfield_texels),
            ));
        }
        if !(1..=256).contains(&r.ray_steps) {
            return Err(GeltipError::config(
                "render.ray_steps",
                format!("must be between 1 and 256, got {}", r.ray_steps),
            ));
        }
        finite_positive("render.blend_tap_spacing", r.blend_tap_spacing)?;
        if r.blend_tap_spacing > 6.0 {
            return Err(GeltipError::config(
                "render.blend_tap_spacing",
                format!(
                    "must be at most 6 (the kernels reach 6 blend_mm), got {}",
                    r.blend_tap_spacing
                ),
            ));
        }
        Ok(())
    }

    fn lens(&self) -> Lens {
        Lens {
            model: self.lens.model,
            focal_px: self.lens.focal_px,
            k: self.lens.k,
            max_theta: 0.5 * self.lens.fov_deg.to_radians(),
        }
    }
}

/// The presets shipped in `assets/sensors/`, compiled in so the binary works from anywhere.
pub const PRESETS: [(&str, &str); 4] = [
    ("paper", include_str!("../assets/sensors/paper.toml")),
    ("webcam70", include_str!("../assets/sensors/webcam70.toml")),
    ("tube13", include_str!("../assets/sensors/tube13.toml")),
    ("tube21", include_str!("../assets/sensors/tube21.toml")),
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

    /// Whether the continuous pixel position lies on the image (OpenCV convention).
    pub fn in_image(&self, pixel: DVec2) -> bool {
        pixel.x >= -0.5
            && pixel.y >= -0.5
            && pixel.x <= self.width as f64 - 0.5
            && pixel.y <= self.height as f64 - 0.5
    }

    /// Unit direction of the lens ray through `pixel`, or `None` outside the image or the
    /// lens's field of view.
    pub fn ray_direction(&self, pixel: DVec2) -> Option<DVec3> {
        if !pixel.is_finite() || !self.in_image(pixel) {
            return None;
        }
        let offset = pixel - self.principal;
        let rho = offset.length();
        let theta = self.lens.unproject(rho)?;
        if rho == 0.0 {
            return Some(DVec3::Z);
        }
        let (sin_t, cos_t) = theta.sin_cos();
        Some(DVec3::new(
            sin_t * offset.x / rho,
            sin_t * offset.y / rho,
            cos_t,
        ))
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
