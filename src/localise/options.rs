//! What a user may set of the detectors: the change method's decision threshold and the
//! sensor's noise, and the limits on a contact's area on the finger (mm^2, from the sensor
//! model, so that one setting means the same on every sensor's pixels).

use super::change::ChangeConfig;
use super::Method;
use crate::checks;
use crate::error::{GeltipError, Result};

/// The smallest and largest area on the finger a contact's region may have, mm^2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaWindow {
    pub min_mm2: f64,
    pub max_mm2: f64,
}

impl AreaWindow {
    /// Parses "MIN,MAX" (mm^2; MAX may be "inf"): both >= 0, MIN <= MAX. The error names the
    /// option and says what is wrong.
    pub fn parse(text: &str) -> Result<AreaWindow> {
        let bad = |reason: &str| GeltipError::option_value("area_mm2", text, reason);
        let (lo, hi) = text
            .split_once(',')
            .ok_or_else(|| bad("expected MIN,MAX in mm^2, e.g. 2,80"))?;
        let number = |s: &str| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(&format!("'{}' is not a number", s.trim())))
        };
        AreaWindow::new(number(lo)?, number(hi)?)
    }

    /// The window [min, max] mm^2; refused unless min is finite and >= 0, max is not NaN
    /// and min <= max.
    pub fn new(min_mm2: f64, max_mm2: f64) -> Result<AreaWindow> {
        let bad = |reason: String| {
            GeltipError::option_value("area_mm2", format!("{min_mm2},{max_mm2}"), reason)
        };
        checks::finite(min_mm2).map_err(|r| bad(format!("MIN {r}")))?;
        if min_mm2 < 0.0 || max_mm2.is_nan() || max_mm2 < min_mm2 {
            return Err(bad("needs 0 <= MIN <= MAX".into()));
        }
        Ok(AreaWindow { min_mm2, max_mm2 })
    }

    /// Whether `area_mm2` lies in the window (both ends included).
    pub fn holds(&self, area_mm2: f64) -> bool {
        area_mm2 >= self.min_mm2 && area_mm2 <= self.max_mm2
    }
}

/// The detectors' options; each `None` keeps the method's default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DetectorOptions {
    /// The change method: how many noise spreads the strongest change must stand out
    /// (default 20).
    pub threshold: Option<f64>,
    /// The change method: the sensor's noise, standard deviation in 8-bit levels; the noise
    /// the pair is credited with is its own estimate or this, whichever is larger (default 1).
    pub noise: Option<f64>,
    /// The change and paper methods: the contact region's area on the finger. Defaults:
    /// change, at least [`ChangeConfig::default`]'s `area_mm2.min_mm2`; paper, the paper's
    /// 0.012%..0.04% of the picture (in pixels: one sensor's objects).
    pub area_mm2: Option<AreaWindow>,
}

impl DetectorOptions {
    /// Whether anything is set.
    pub fn any(&self) -> bool {
        self.threshold.is_some() || self.noise.is_some() || self.area_mm2.is_some()
    }

    /// Refuses an option `method` does not take, or a threshold or noise not finite and > 0
    /// (the error names the option).
    pub fn check(&self, method: Method) -> Result<()> {
        let takes = |name: &str, methods: &[Method]| {
            if methods.contains(&method) {
                Ok(())
            } else {
                let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
                Err(GeltipError::option(
                    name,
                    format!(
                        "applies to method '{}', not '{method}'",
                        names.join("' or '")
                    ),
                ))
            }
        };
        if self.threshold.is_some() {
            takes("threshold", &[Method::Change])?;
        }
        if self.noise.is_some() {
            takes("noise", &[Method::Change])?;
        }
        if self.area_mm2.is_some() {
            takes("area_mm2", &[Method::Change, Method::Paper])?;
        }
        for (name, value) in [("threshold", self.threshold), ("noise", self.noise)] {
            if let Some(v) = value {
                checks::positive(v).map_err(|reason| GeltipError::option(name, reason))?;
            }
        }
        Ok(())
    }

    /// The change method's constants: the defaults with what is set (checked as
    /// [`Self::check`] for the change method).
    pub fn change_config(&self) -> Result<ChangeConfig> {
        self.check(Method::Change)?;
        let mut c = ChangeConfig::default();
        if let Some(t) = self.threshold {
            c.score_threshold = t;
        }
        if let Some(n) = self.noise {
            c.noise_floor = n;
        }
        if let Some(a) = self.area_mm2 {
            c.area_mm2 = a;
        }
        Ok(c)
    }

    /// How reports name the settings: "threshold 12, noise 3, area 2..80 mm^2", or "" for
    /// none.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(t) = self.threshold {
            parts.push(format!("threshold {t}"));
        }
        if let Some(n) = self.noise {
            parts.push(format!("noise {n}"));
        }
        if let Some(a) = self.area_mm2 {
            parts.push(format!("area {}..{} mm^2", a.min_mm2, a.max_mm2));
        }
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_area_window_parses_and_bad_ones_name_what_is_wrong() {
        let w = AreaWindow::parse("2, 80").unwrap();
        assert_eq!((w.min_mm2, w.max_mm2), (2.0, 80.0));
        assert!(AreaWindow::parse("0,inf").unwrap().holds(1e9));
        for (text, says) in [
            ("80", "MIN,MAX"),
            ("a,3", "'a' is not a number"),
            ("5,2", "0 <= MIN <= MAX"),
            ("-1,2", "0 <= MIN <= MAX"),
            ("nan,2", "MIN"),
            ("1,nan", "0 <= MIN <= MAX"),
        ] {
            let e = AreaWindow::parse(text).unwrap_err().to_string();
            assert!(e.contains("area_mm2") && e.contains(says), "{text}: {e}");
        }
    }

    #[test]
    fn options_a_method_does_not_take_are_refused_by_name() {
        let area = Some(AreaWindow::new(1.0, 9.0).unwrap());
        let o = DetectorOptions {
            area_mm2: area,
            ..Default::default()
        };
        assert!(o.check(Method::Paper).is_ok() && o.check(Method::Change).is_ok());
        let e = o.check(Method::Surface).unwrap_err().to_string();
        assert!(e.contains("area_mm2") && e.contains("'surface'"), "{e}");
        let t = DetectorOptions {
            threshold: Some(5.0),
            ..Default::default()
        };
        let e = t.check(Method::Paper).unwrap_err().to_string();
        assert!(e.contains("threshold") && e.contains("'paper'"), "{e}");
        let bad = DetectorOptions {
            noise: Some(-1.0),
            ..Default::default()
        };
        assert!(bad
            .change_config()
            .unwrap_err()
            .to_string()
            .contains("noise"));
        let c = o.change_config().unwrap();
        assert_eq!((c.area_mm2.min_mm2, c.area_mm2.max_mm2), (1.0, 9.0));
    }
}
