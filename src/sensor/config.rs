//! The sensor file as people write it (TOML), loaded with serde and validated field by field.

use super::lighting::{CameraConfig, Leds, LightConfig, Noise};
use super::shell_end::ShellEndConfig;
use crate::checks::{
    config_finite as finite, config_non_negative as non_negative,
    config_positive as finite_positive,
};
use crate::error::{GeltipError, Result};
use crate::lens::{Lens, LensModel};
use serde::{Deserialize, Serialize};

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

/// `[image]`: the picture's size in pixels, and where a camera's software cuts it to a
/// circle of its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageConfig {
    pub width: u32,
    pub height: u32,
    /// The image circle `[cx, cy, radius]` (px) when it is a mask of its own: pixels
    /// outside it are black whatever the lens sees. Absent, the lens's field of view about
    /// the principal point is the circle. A real sensor's mask need not be centred on the
    /// lens's principal point, so the two are held apart.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub circle: Option<[f64; 3]>,
}

/// `[elastomer]`: how the gel turns the object's penetration into a deformation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ElastomerConfig {
    /// Standard deviation (mm, along the surface) of the blur that blends the imprint's edge.
    pub blend_mm: f64,
    /// The tightest radius (mm) the skin can bend to: past an object's edge the skin falls away
    /// on a circle of this radius instead of a cliff. At least the shell thickness, so that
    /// even a full-depth press reaches back to the surface; a file that leaves it out gets
    /// [`default_drape_mm`] of its gel.
    pub drape_mm: f64,
    /// How much of the displaced gel bulges out around the imprint (0 = none): the bulge is
    /// this fraction of the difference between a blend twice as wide and the blend itself.
    pub bulge: f64,
}

/// The drape a sensor file gets when it gives none: 2 mm, or the gel's thickness when the gel
/// is thicker (a thick gel bends no tighter than it is thick).
pub fn default_drape_mm(shell_thickness_mm: f64) -> f64 {
    ElastomerConfig::default().drape_mm.max(shell_thickness_mm)
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

/// `[paint]`: the reflective coating on the elastomer's outer skin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PaintConfig {
    /// Linear RGB albedo multiplying all the light the paint reflects.
    #[serde(skip_serializing_if = "is_white")]
    pub colour: [f64; 3],
    pub diffuse: f64,
    pub specular: f64,
    pub shininess: f64,
}

impl Default for PaintConfig {
    fn default() -> Self {
        PaintConfig {
            colour: [1.0; 3],
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
    /// Standard deviation of additive sensor noise, in 8-bit levels (0 = none): one number,
    /// or one per channel.
    pub noise: Noise,
    /// Seed of the noise; the same seed gives the same bytes.
    pub noise_seed: u32,
}

impl Default for RenderConfig {
    fn default() -> Self {
        RenderConfig {
            heightfield_texels: 256,
            ray_steps: 4,
            blend_tap_spacing: 1.0,
            noise: Noise::NONE,
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
    pub leds: Leds,
    #[serde(default, skip_serializing_if = "LightConfig::is_default")]
    pub light: LightConfig,
    #[serde(default, skip_serializing_if = "CameraConfig::is_default")]
    pub camera: CameraConfig,
    /// A clear shell under the gel that ends, open, below the tip (none by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shell_end: Option<ShellEndConfig>,
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

fn is_white(colour: &[f64; 3]) -> bool {
    *colour == [1.0; 3]
}

/// Whether the TOML text sets `elastomer.drape_mm` (the text already parsed once).
fn drape_given(text: &str) -> bool {
    text.parse::<toml::Table>().is_ok_and(|t| {
        t.get("elastomer")
            .and_then(|e| e.as_table())
            .is_some_and(|e| e.contains_key("drape_mm"))
    })
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
        let mut config = config;
        if !drape_given(text) {
            config.elastomer.drape_mm = default_drape_mm(config.finger.shell_thickness_mm);
        }
        Ok(config)
    }

    /// Checks every field against what a real sensor can be; the error names the field.
    pub fn validate(&self) -> Result<()> {
        self.validate_finger()?;
        self.validate_image()?;
        self.validate_lens()?;
        self.validate_rendering()?;
        // Last: inverting the projection needs every field above sound.
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

    fn validate_finger(&self) -> Result<()> {
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
        Ok(())
    }

    fn validate_image(&self) -> Result<()> {
        let img = &self.image;
        for (field, v) in [("image.width", img.width), ("image.height", img.height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(GeltipError::config(
                    field,
                    format!("must be between 1 and {MAX_IMAGE_SIDE} pixels, got {v}"),
                ));
            }
        }
        if let Some([cx, cy, r]) = img.circle {
            for (i, v) in [cx, cy].into_iter().enumerate() {
                finite(&format!("image.circle[{i}]"), v)?;
            }
            finite_positive("image.circle[2]", r)?;
            let (w, h) = (img.width as f64, img.height as f64);
            if cx < 0.0 || cx > w || cy < 0.0 || cy > h {
                return Err(GeltipError::config(
                    "image.circle",
                    format!("centre ({cx}, {cy}) is outside the image ({w} x {h})"),
                ));
            }
        }
        Ok(())
    }

    /// The lens's own fields (whether its projection can be inverted is checked last).
    fn validate_lens(&self) -> Result<()> {
        let (l, img) = (&self.lens, &self.image);
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
            finite(field, v)?;
            if v < 0.0 || v > side as f64 {
                return Err(GeltipError::config(
                    field,
                    format!("principal point is outside the image (0..{side}), got {v}"),
                ));
            }
        }
        for (i, k) in l.k.iter().enumerate() {
            finite(&format!("lens.k[{i}]"), *k)?;
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
        Ok(())
    }

    fn validate_rendering(&self) -> Result<()> {
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
        let f = &self.finger;
        self.leds.validate(f.radius_mm, f.cylinder_length_mm)?;
        self.light.validate()?;
        self.camera.validate()?;
        if let Some(end) = &self.shell_end {
            end.validate(f.radius_mm, f.cylinder_length_mm + f.radius_mm)?;
        }
        if let Leds::List(list) = &self.leds {
            let spread_set = self.shell_end.is_some_and(|e| e.led_glow_deg.is_some());
            if let Some(i) = list.iter().position(|l| l.end_glow != [0.0; 3]) {
                if !spread_set {
                    return Err(GeltipError::config(
                        format!("leds[{i}].end_glow"),
                        "needs a [shell_end] with led_glow_deg (how far round the end it spreads)",
                    ));
                }
            }
        }
        for (k, c) in self.paint.colour.iter().enumerate() {
            non_negative(&format!("paint.colour[{k}]"), *c)?;
        }
        non_negative("paint.diffuse", self.paint.diffuse)?;
        non_negative("paint.specular", self.paint.specular)?;
        finite_positive("paint.shininess", self.paint.shininess)?;
        self.render.noise.validate()?;
        if self.camera.blurs() && self.render.noise.any() {
            // The renderer adds its noise before the frame reaches the camera's blur.
            return Err(GeltipError::config(
                "camera.blur_px",
                "cannot be combined with render.noise (the noise would be blurred); add noise afterwards, e.g. `dataset --noise`",
            ));
        }
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

    pub(super) fn lens(&self) -> Lens {
        Lens {
            model: self.lens.model,
            focal_px: self.lens.focal_px,
            k: self.lens.k,
            max_theta: 0.5 * self.lens.fov_deg.to_radians(),
        }
    }
}
