//! The light a sensor file describes: its LEDs (the paper's ring of three, `[leds]`, or any
//! list, `[[leds]]`), the ambient light and the camera's vignetting (`[light]`), the paint's
//! colour, and the sensor's noise; resolved into one [`Lighting`] that the renderer and its
//! CPU mirror shade with.

use crate::checks::{
    config_finite as finite, config_non_negative as non_negative,
    config_positive as finite_positive,
};
use crate::error::{GeltipError, Result};
use crate::finger::Finger;
use glam::DVec3;
use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// The most LEDs a sensor may have (the GPU's uniform holds this many).
pub const MAX_LEDS: usize = 16;

/// LED colours of the ring: one red, one green and one blue LED, or three white ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LedColours {
    Rgb,
    White,
}

/// `[leds]` as a table: three point lights at the base of the finger, 120 degrees apart.
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

/// How an LED's light reaches the skin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LedKindName {
    /// Straight from the LED to the skin: a point light inside the finger.
    #[default]
    Point,
    /// Into the gel at the base and carried up it (a light-pipe ring feeding a clear gel, as
    /// in the AllSight): the skin glows in a band above the LED that widens and fades with
    /// the distance along the finger.
    Gel,
}

impl LedKindName {
    fn is_point(&self) -> bool {
        *self == LedKindName::Point
    }

    /// The kind named `name` ("point" or "gel").
    pub fn from_name(name: &str) -> Result<LedKindName> {
        match name {
            "point" => Ok(LedKindName::Point),
            "gel" => Ok(LedKindName::Gel),
            other => Err(GeltipError::option(
                "led_kind",
                format!("unknown LED kind '{other}'; choose point or gel"),
            )),
        }
    }
}

/// One LED of a `[[leds]]` list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LedConfig {
    /// `"point"` (default) or `"gel"`.
    #[serde(default, skip_serializing_if = "LedKindName::is_point")]
    pub kind: LedKindName,
    /// Linear RGB colour (each channel >= 0; multiplied by `intensity`).
    pub colour: [f64; 3],
    /// Angle about the finger's axis, degrees (0 is image +x, 90 image +y).
    pub azimuth_deg: f64,
    /// Height along the optical axis (mm; the camera is at 0).
    #[serde(default = "default_led_z")]
    pub z_mm: f64,
    /// Distance from the axis (mm); by default the ring's, 0.8 x (radius - shell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_mm: Option<f64>,
    #[serde(default = "default_led_intensity")]
    pub intensity: f64,
    /// Emission falls as cos(angle off +z)^spread.
    #[serde(default = "default_led_spread")]
    pub spread: f64,
    /// 1 / (1 + (dist / falloff)^2).
    #[serde(default = "default_led_falloff")]
    pub falloff_mm: f64,
    /// A gel LED's band: its width across the finger at the LED's height (mm along the
    /// surface, one standard deviation; default [`GelSpread::DEFAULT`]'s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_mm: Option<f64>,
    /// How much wider the band grows per mm up the finger.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub widening: Option<f64>,
    /// The distance up the finger (mm) over which the gel's light falls to 1/e.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attenuation_mm: Option<f64>,
    /// How strongly the skin's tilt against the light's path brightens or darkens it (what
    /// makes an imprint visible in light that runs along the skin): the glow is multiplied
    /// by max(0, 1 + relief n.t), n the skin's normal, t the way up the finger.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relief: Option<f64>,
    /// How much brighter, per channel, this LED makes the skin seen just outside a clear
    /// shell's open end round its azimuth: the light it sends up the shell leaving the end
    /// in its own tint. Added to `[shell_end]`'s `rim_glow` there, spread round the end over
    /// `shell_end.led_glow_deg`; needs that set. Default none.
    #[serde(default, skip_serializing_if = "is_zero3")]
    pub end_glow: [f64; 3],
}

fn is_zero3(v: &[f64; 3]) -> bool {
    *v == [0.0; 3]
}

impl LedConfig {
    /// An LED of `colour` at `azimuth_deg` with the ring's height, distance, intensity,
    /// spread and fall-off (the defaults a `[[leds]]` entry gets).
    pub fn new(colour: [f64; 3], azimuth_deg: f64) -> LedConfig {
        LedConfig {
            colour,
            azimuth_deg,
            z_mm: default_led_z(),
            radius_mm: None,
            intensity: default_led_intensity(),
            spread: default_led_spread(),
            falloff_mm: default_led_falloff(),
            kind: LedKindName::Point,
            width_mm: None,
            widening: None,
            attenuation_mm: None,
            relief: None,
            end_glow: [0.0; 3],
        }
    }

    /// A gel LED of `colour` at `azimuth_deg`, with the default band.
    pub fn gel(colour: [f64; 3], azimuth_deg: f64) -> LedConfig {
        LedConfig {
            kind: LedKindName::Gel,
            ..LedConfig::new(colour, azimuth_deg)
        }
    }

    /// The band of a gel LED (its values or the defaults).
    pub fn gel_spread(&self) -> GelSpread {
        let d = GelSpread::DEFAULT;
        GelSpread {
            width_mm: self.width_mm.unwrap_or(d.width_mm),
            widening: self.widening.unwrap_or(d.widening),
            attenuation_mm: self.attenuation_mm.unwrap_or(d.attenuation_mm),
            relief: self.relief.unwrap_or(d.relief),
        }
    }
}

/// The band of skin a gel LED lights ([`LedKindName::Gel`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GelSpread {
    pub width_mm: f64,
    pub widening: f64,
    pub attenuation_mm: f64,
    pub relief: f64,
}

impl GelSpread {
    pub const DEFAULT: GelSpread = GelSpread {
        width_mm: 3.0,
        widening: 0.2,
        attenuation_mm: 15.0,
        relief: 1.0,
    };
}

/// What kind of light an LED gives ([`LedKindName`]), resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LedKind {
    Point,
    Gel(GelSpread),
}

fn default_led_z() -> f64 {
    LedsConfig::default().z_mm
}
fn default_led_intensity() -> f64 {
    LedsConfig::default().intensity
}
fn default_led_spread() -> f64 {
    LedsConfig::default().spread
}
fn default_led_falloff() -> f64 {
    LedsConfig::default().falloff_mm
}

/// The sensor file's LEDs: the table `[leds]` (a ring of three) or the list `[[leds]]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Leds {
    Ring(LedsConfig),
    List(Vec<LedConfig>),
}

impl Default for Leds {
    fn default() -> Self {
        Leds::Ring(LedsConfig::default())
    }
}

// By hand rather than `untagged`, so that an error inside either form keeps its field path
// and message (untagged would only say that no form matched).
impl<'de> Deserialize<'de> for Leds {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct LedsVisitor;
        impl<'de> Visitor<'de> for LedsVisitor {
            type Value = Leds;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a [leds] table (a ring of three) or a [[leds]] list")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> std::result::Result<Leds, A::Error> {
                LedsConfig::deserialize(de::value::MapAccessDeserializer::new(map)).map(Leds::Ring)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Leds, A::Error> {
                Vec::<LedConfig>::deserialize(de::value::SeqAccessDeserializer::new(seq))
                    .map(Leds::List)
            }
        }
        deserializer.deserialize_any(LedsVisitor)
    }
}

/// `[light]`: what reaches the picture besides the LEDs' direct light.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightConfig {
    /// Ambient light as linear RGB; replaces the ring's grey `leds.ambient` when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ambient: Option<[f64; 3]>,
    /// The camera's vignetting: every pixel's light is multiplied by 1 + a x^2 + b x^4, x its
    /// distance from the principal point over the lens's image-circle radius.
    pub vignetting: [f64; 2],
    /// How the ambient light shades with the skin's tilt, per channel (R, G, B): each is
    /// multiplied by max(0, 1 + k n.t), n the skin's normal and t the way up the finger, as a
    /// gel LED's light is by its `relief` (in a sensor lit through its gel the ambient light
    /// is carried in the gel too). 0, the default, leaves it flat.
    #[serde(skip_serializing_if = "is_flat")]
    pub ambient_relief: [f64; 3],
}

fn is_flat(k: &[f64; 3]) -> bool {
    *k == [0.0; 3]
}

/// `render.noise`: one standard deviation for every channel, or one per channel (R, G, B), in
/// 8-bit levels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "a number or [r, g, b] (8-bit levels, >= 0)")]
pub enum Noise {
    Grey(f64),
    Rgb([f64; 3]),
}

impl Noise {
    pub const NONE: Noise = Noise::Grey(0.0);

    /// The standard deviation of each channel.
    pub fn rgb(self) -> [f64; 3] {
        match self {
            Noise::Grey(s) => [s; 3],
            Noise::Rgb(s) => s,
        }
    }

    /// Whether any channel has noise.
    pub fn any(self) -> bool {
        self.rgb().iter().any(|&s| s > 0.0)
    }

    /// The largest channel's standard deviation.
    pub fn max(self) -> f64 {
        self.rgb().into_iter().fold(0.0, f64::max)
    }
}

impl Default for Noise {
    fn default() -> Self {
        Noise::NONE
    }
}

impl From<f64> for Noise {
    fn from(sigma: f64) -> Self {
        Noise::Grey(sigma)
    }
}

/// One LED, resolved: where it is and what it emits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Led {
    /// Position in the camera frame (mm).
    pub position: DVec3,
    /// Linear RGB colour.
    pub colour: DVec3,
    pub intensity: f64,
    pub spread: f64,
    pub falloff_mm: f64,
    pub kind: LedKind,
    /// Per channel, the rim glow this LED adds round its azimuth at a clear shell's open
    /// end ([`LedConfig::end_glow`]).
    pub end_glow: DVec3,
}

/// A sensor's light, resolved from either form of the file: what shading needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Lighting {
    pub leds: Vec<Led>,
    pub ambient: DVec3,
    /// Per channel, how the ambient light shades with the skin's tilt
    /// ([`LightConfig::ambient_relief`]).
    pub ambient_relief: DVec3,
    /// The paint's colour (linear RGB albedo, multiplying all reflected light).
    pub paint_colour: DVec3,
    /// 1 + a x^2 + b x^4 (see [`LightConfig::vignetting`]).
    pub vignetting: [f64; 2],
    /// The finger the gel carries light along (its radius and the hemisphere's height).
    pub finger: Finger,
    /// How the camera turns light into pixel values.
    pub camera: CameraConfig,
    /// Where a clear shell under the gel ends below the tip, if it does.
    pub shell_end: Option<super::ShellEndConfig>,
}

/// `[camera]`: how the camera turns the light reaching it into 8-bit values: a colour
/// matrix (the camera's own mixing of its channels, off-diagonal terms negative in most
/// cameras' colour correction) applied to the vignetted linear light, then each channel
/// encoded as 255 x^(1/gamma).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Rows: output R, G, B from input (R, G, B).
    pub colour_matrix: [[f64; 3]; 3],
    pub gamma: [f64; 3],
    /// The camera's softness: each recorded frame blurred by a Gaussian of this many
    /// pixels (standard deviation) over the pixels the lens sees; 0, none.
    #[serde(skip_serializing_if = "is_zero")]
    pub blur_px: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            colour_matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            gamma: [2.2; 3],
            blur_px: 0.0,
        }
    }
}

/// The largest camera blur a sensor file may ask for (pixels).
pub const MAX_BLUR_PX: f64 = 20.0;

impl CameraConfig {
    /// Whether this is the default (no `[camera]` table): left out when a config is written.
    pub fn is_default(&self) -> bool {
        *self == CameraConfig::default()
    }

    /// Whether the camera blurs what it records (`blur_px` above 0): the renderer's noise,
    /// added before the blur, would be blurred with it, so such a sensor takes none.
    pub fn blurs(&self) -> bool {
        self.blur_px > 0.0
    }

    /// Whether the colour response is the default (identity mixing, gamma 2.2 on every
    /// channel): the renderer then takes its plain gamma-2.2 path.
    pub fn has_default_response(&self) -> bool {
        let d = CameraConfig::default();
        self.colour_matrix == d.colour_matrix && self.gamma == d.gamma
    }

    /// The linear light `c` as the camera records it, before the gamma: mixed by the matrix.
    pub fn mix(&self, c: DVec3) -> DVec3 {
        let m = &self.colour_matrix;
        DVec3::new(
            m[0][0] * c.x + m[0][1] * c.y + m[0][2] * c.z,
            m[1][0] * c.x + m[1][1] * c.y + m[1][2] * c.z,
            m[2][0] * c.x + m[2][1] * c.y + m[2][2] * c.z,
        )
    }

    pub fn validate(&self) -> Result<()> {
        for (i, row) in self.colour_matrix.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                finite(&format!("camera.colour_matrix[{i}][{j}]"), *v)?;
            }
        }
        for (k, g) in self.gamma.iter().enumerate() {
            let field = format!("camera.gamma[{k}]");
            finite_positive(&field, *g)?;
            if !(0.2..=5.0).contains(g) {
                return Err(GeltipError::config(
                    field,
                    format!("must be between 0.2 and 5, got {g}"),
                ));
            }
        }
        finite("camera.blur_px", self.blur_px)?;
        if !(0.0..=MAX_BLUR_PX).contains(&self.blur_px) {
            return Err(GeltipError::config(
                "camera.blur_px",
                format!(
                    "must be between 0 and {MAX_BLUR_PX} px, got {}",
                    self.blur_px
                ),
            ));
        }
        Ok(())
    }
}

impl Lighting {
    /// The vignetting gain at `x`, the distance from the principal point over the image
    /// circle's radius.
    pub fn vignette(&self, x: f64) -> f64 {
        let x2 = x * x;
        1.0 + self.vignetting[0] * x2 + self.vignetting[1] * x2 * x2
    }

    /// Whether any LED is a gel LED (shading then needs each skin point's [`GelPlace`]).
    ///
    /// [`GelPlace`]: crate::render::leds::GelPlace
    pub fn has_gel_leds(&self) -> bool {
        self.leds.iter().any(|l| matches!(l.kind, LedKind::Gel(_)))
    }

    /// Whether the ambient light shades with the skin's tilt (shading then needs each skin
    /// point's [`GelPlace`] too).
    ///
    /// [`GelPlace`]: crate::render::leds::GelPlace
    pub fn has_ambient_relief(&self) -> bool {
        self.ambient_relief != DVec3::ZERO
    }

    /// The spread every LED shares, if they share one.
    pub fn shared_spread(&self) -> Option<f64> {
        let first = self.leds.first()?.spread;
        self.leds.iter().all(|l| l.spread == first).then_some(first)
    }
}

/// The ring's distance from the axis (mm): just inside the elastomer.
pub fn ring_radius(radius_mm: f64, shell_mm: f64) -> f64 {
    0.8 * (radius_mm - shell_mm)
}

impl Leds {
    /// The LEDs in the camera frame, for a finger of `radius_mm` with a `shell_mm` gel.
    pub fn resolve(&self, radius_mm: f64, shell_mm: f64) -> Vec<Led> {
        let ring = ring_radius(radius_mm, shell_mm);
        match self {
            Leds::Ring(c) => {
                let colours = match c.colours {
                    LedColours::Rgb => [DVec3::X, DVec3::Y, DVec3::Z],
                    LedColours::White => [DVec3::splat(0.5); 3],
                };
                (0..3)
                    .map(|i| {
                        let a = (c.azimuth_deg + 120.0 * i as f64).to_radians();
                        Led {
                            position: DVec3::new(ring * a.cos(), ring * a.sin(), c.z_mm),
                            colour: colours[i],
                            intensity: c.intensity,
                            spread: c.spread,
                            falloff_mm: c.falloff_mm,
                            kind: LedKind::Point,
                            end_glow: DVec3::ZERO,
                        }
                    })
                    .collect()
            }
            Leds::List(list) => list
                .iter()
                .map(|l| {
                    let a = l.azimuth_deg.to_radians();
                    let r = l.radius_mm.unwrap_or(ring);
                    Led {
                        position: DVec3::new(r * a.cos(), r * a.sin(), l.z_mm),
                        colour: DVec3::from_array(l.colour),
                        intensity: l.intensity,
                        spread: l.spread,
                        falloff_mm: l.falloff_mm,
                        kind: match l.kind {
                            LedKindName::Point => LedKind::Point,
                            LedKindName::Gel => LedKind::Gel(l.gel_spread()),
                        },
                        end_glow: DVec3::from_array(l.end_glow),
                    }
                })
                .collect(),
        }
    }

    /// The ring's grey ambient light (the list form has none of its own).
    pub fn ring_ambient(&self) -> Option<f64> {
        match self {
            Leds::Ring(c) => Some(c.ambient),
            Leds::List(_) => None,
        }
    }

    /// Checks every LED; `radius_mm` and `cylinder_length_mm` are the finger's.
    pub fn validate(&self, radius_mm: f64, cylinder_length_mm: f64) -> Result<()> {
        match self {
            Leds::Ring(c) => {
                check_height("leds.z_mm", c.z_mm, cylinder_length_mm)?;
                finite("leds.azimuth_deg", c.azimuth_deg)?;
                non_negative("leds.intensity", c.intensity)?;
                finite_positive("leds.falloff_mm", c.falloff_mm)?;
                non_negative("leds.spread", c.spread)?;
                non_negative("leds.ambient", c.ambient)
            }
            Leds::List(list) => {
                if list.is_empty() || list.len() > MAX_LEDS {
                    return Err(GeltipError::config(
                        "leds",
                        format!("a sensor has 1 to {MAX_LEDS} LEDs, got {}", list.len()),
                    ));
                }
                for (i, l) in list.iter().enumerate() {
                    let field = |name: &str| format!("leds[{i}].{name}");
                    for (k, c) in l.colour.iter().enumerate() {
                        non_negative(&format!("leds[{i}].colour[{k}]"), *c)?;
                    }
                    finite(&field("azimuth_deg"), l.azimuth_deg)?;
                    check_height(&field("z_mm"), l.z_mm, cylinder_length_mm)?;
                    if let Some(r) = l.radius_mm {
                        non_negative(&field("radius_mm"), r)?;
                        if r >= radius_mm {
                            return Err(GeltipError::config(
                                field("radius_mm"),
                                format!(
                                    "the LEDs sit inside the finger (radius_mm < {radius_mm}), got {r}"
                                ),
                            ));
                        }
                    }
                    non_negative(&field("intensity"), l.intensity)?;
                    non_negative(&field("spread"), l.spread)?;
                    finite_positive(&field("falloff_mm"), l.falloff_mm)?;
                    validate_gel(l, &field)?;
                    for (k, g) in l.end_glow.iter().enumerate() {
                        let field = format!("leds[{i}].end_glow[{k}]");
                        finite(&field, *g)?;
                        if *g <= -1.0 {
                            return Err(GeltipError::config(
                                field,
                                format!("must be above -1, got {g}"),
                            ));
                        }
                    }
                }
                Ok(())
            }
        }
    }
}

impl LightConfig {
    /// Whether this is the default (no `[light]` table): left out when a config is written.
    pub fn is_default(&self) -> bool {
        *self == LightConfig::default()
    }

    pub fn validate(&self) -> Result<()> {
        if let Some(a) = self.ambient {
            for (k, c) in a.iter().enumerate() {
                non_negative(&format!("light.ambient[{k}]"), *c)?;
            }
        }
        for (k, v) in self.vignetting.iter().enumerate() {
            finite(&format!("light.vignetting[{k}]"), *v)?;
        }
        for (k, v) in self.ambient_relief.iter().enumerate() {
            finite(&format!("light.ambient_relief[{k}]"), *v)?;
        }
        // The gain must stay positive across the image circle: at its lowest (x = 1 or the
        // quartic's turning point) it decides whether a ring of pixels turns black or negative.
        let [a, b] = self.vignetting;
        let mut lowest = (1.0 + a + b).min(1.0);
        if b > 0.0 && a < 0.0 && -a < 2.0 * b {
            let x2 = -a / (2.0 * b);
            lowest = lowest.min(1.0 + a * x2 + b * x2 * x2);
        }
        if lowest <= 0.0 {
            return Err(GeltipError::config(
                "light.vignetting",
                format!(
                    "1 + a x^2 + b x^4 falls to {lowest:.3} inside the image circle; it must stay above 0"
                ),
            ));
        }
        Ok(())
    }
}

impl Noise {
    pub fn validate(self) -> Result<()> {
        match self {
            Noise::Grey(s) => non_negative("render.noise", s),
            Noise::Rgb(s) => {
                for (k, v) in s.iter().enumerate() {
                    non_negative(&format!("render.noise[{k}]"), *v)?;
                }
                Ok(())
            }
        }
    }
}

/// A gel LED's band; a point LED must not give one.
fn validate_gel(l: &LedConfig, field: &dyn Fn(&str) -> String) -> Result<()> {
    let given = [
        ("width_mm", l.width_mm),
        ("widening", l.widening),
        ("attenuation_mm", l.attenuation_mm),
        ("relief", l.relief),
    ];
    if l.kind == LedKindName::Point {
        if let Some((name, _)) = given.iter().find(|(_, v)| v.is_some()) {
            return Err(GeltipError::config(
                field(name),
                "only a gel LED (kind = \"gel\") has a band; a point LED takes spread and falloff_mm",
            ));
        }
        return Ok(());
    }
    let g = l.gel_spread();
    finite_positive(&field("width_mm"), g.width_mm)?;
    non_negative(&field("widening"), g.widening)?;
    finite_positive(&field("attenuation_mm"), g.attenuation_mm)?;
    finite(&field("relief"), g.relief)
}

fn check_height(field: &str, z: f64, cylinder_length_mm: f64) -> Result<()> {
    finite(field, z)?;
    if z >= cylinder_length_mm {
        return Err(GeltipError::config(
            field,
            format!(
                "the LEDs sit at the base, below the hemisphere (z < {cylinder_length_mm}), got {z}"
            ),
        ));
    }
    Ok(())
}
