//! `[shell_end]`: where a clear rigid shell under the gel ends, open, below the tip (the
//! AllSight's). The camera sees most of the skin through the shell's wall, which carries the
//! LEDs' light up like a light pipe, and the tip through its open end, where that light does
//! not reach: in the picture a darker, even disc inside a bright rim. Shading mirror:
//! `shell_end_light` in `shaders/shared/shading.wgsl` and `src/render/leds.rs`.

use crate::checks::{
    config_finite as finite, config_non_negative as non_negative,
    config_positive as finite_positive,
};
use crate::error::{GeltipError, Result};
use serde::{Deserialize, Serialize};

/// How sharp the open end's edge is: the width (mm, across the end's plane) over which a
/// ray's light turns from the shell's to the tip's. About a pixel at the AllSight's end, and
/// smooth, so a fit can move the end.
pub const SHELL_EDGE_MM: f64 = 0.08;

/// The shell's open end and the light on either side of it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShellEndConfig {
    /// Height of the open end along the optical axis (mm; the camera is at 0).
    pub z_mm: f64,
    /// The shell's inner radius there (mm): rays passing inside it see the tip.
    pub inner_radius_mm: f64,
    /// Linear light the skin beyond the end shows whatever the LEDs' pattern (RGB, >= 0).
    pub tip_colour: [f64; 3],
    /// The share of the LEDs' light that still reaches the skin beyond the end.
    pub tip_transmit: f64,
    /// How much brighter the skin seen through the shell is just outside the end's edge
    /// (the light the shell carries leaving it): x (1 + rim_glow exp(-d / rim_width_mm)), d
    /// the ray's distance outside the edge in the end's plane (> -1).
    pub rim_glow: f64,
    pub rim_width_mm: f64,
    /// How far round the end each LED's own glow spreads (degrees, one standard deviation
    /// of a Gaussian in azimuth about the LED's): set, each LED's `end_glow` tints the rim
    /// per channel; unset, the rim's glow is the same all round and in every channel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub led_glow_deg: Option<f64>,
}

impl ShellEndConfig {
    /// Checks every field; `radius_mm` and `top_mm` are the finger's radius and the height
    /// of its tip.
    pub fn validate(&self, radius_mm: f64, top_mm: f64) -> Result<()> {
        finite_positive("shell_end.z_mm", self.z_mm)?;
        if self.z_mm >= top_mm {
            return Err(GeltipError::config(
                "shell_end.z_mm",
                format!(
                    "the shell ends inside the finger (z_mm < {top_mm}), got {}",
                    self.z_mm
                ),
            ));
        }
        finite_positive("shell_end.inner_radius_mm", self.inner_radius_mm)?;
        if self.inner_radius_mm >= radius_mm {
            return Err(GeltipError::config(
                "shell_end.inner_radius_mm",
                format!(
                    "the shell lies inside the finger (inner_radius_mm < {radius_mm}), got {}",
                    self.inner_radius_mm
                ),
            ));
        }
        for (k, c) in self.tip_colour.iter().enumerate() {
            non_negative(&format!("shell_end.tip_colour[{k}]"), *c)?;
        }
        non_negative("shell_end.tip_transmit", self.tip_transmit)?;
        finite("shell_end.rim_glow", self.rim_glow)?;
        if self.rim_glow <= -1.0 {
            return Err(GeltipError::config(
                "shell_end.rim_glow",
                format!(
                    "must be greater than -1 (the rim cannot take more light than there is), got {}",
                    self.rim_glow
                ),
            ));
        }
        finite_positive("shell_end.rim_width_mm", self.rim_width_mm)?;
        if let Some(spread) = self.led_glow_deg {
            finite_positive("shell_end.led_glow_deg", spread)?;
            if spread > 180.0 {
                return Err(GeltipError::config(
                    "shell_end.led_glow_deg",
                    format!("must be at most 180, got {spread}"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn end() -> ShellEndConfig {
        ShellEndConfig {
            z_mm: 14.4,
            inner_radius_mm: 7.9,
            tip_colour: [0.0, 0.1, 0.3],
            tip_transmit: 0.5,
            rim_glow: 0.3,
            rim_width_mm: 2.0,
            led_glow_deg: Some(30.0),
        }
    }

    #[test]
    fn a_sound_end_passes_and_each_bad_field_is_named() {
        end().validate(12.9, 27.3).unwrap();
        let cases: [(&str, ShellEndConfig); 8] = [
            (
                "shell_end.z_mm",
                ShellEndConfig {
                    z_mm: 30.0,
                    ..end()
                },
            ),
            (
                "shell_end.z_mm",
                ShellEndConfig {
                    z_mm: f64::NAN,
                    ..end()
                },
            ),
            (
                "shell_end.inner_radius_mm",
                ShellEndConfig {
                    inner_radius_mm: 13.0,
                    ..end()
                },
            ),
            (
                "shell_end.tip_colour[1]",
                ShellEndConfig {
                    tip_colour: [0.0, -0.1, 0.0],
                    ..end()
                },
            ),
            (
                "shell_end.rim_glow",
                ShellEndConfig {
                    rim_glow: -1.0,
                    ..end()
                },
            ),
            (
                "shell_end.rim_width_mm",
                ShellEndConfig {
                    rim_width_mm: 0.0,
                    ..end()
                },
            ),
            (
                "shell_end.led_glow_deg",
                ShellEndConfig {
                    led_glow_deg: Some(0.0),
                    ..end()
                },
            ),
            (
                "shell_end.led_glow_deg",
                ShellEndConfig {
                    led_glow_deg: Some(200.0),
                    ..end()
                },
            ),
        ];
        for (field, bad) in cases {
            let e = bad.validate(12.9, 27.3).unwrap_err().to_string();
            assert!(e.contains(field), "{field}: {e}");
        }
    }
}
