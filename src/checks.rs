//! The number checks that every input shares (sensor files, scenes, options): each says what
//! a value must be, in the words every error uses, and the sensor file's forms name its field.

use crate::error::{GeltipError, Result};

/// A finite number.
pub fn finite(v: f64) -> std::result::Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("must be a finite number, got {v}"))
    }
}

/// A finite number greater than 0.
pub fn positive(v: f64) -> std::result::Result<(), String> {
    finite(v)?;
    if v <= 0.0 {
        return Err(format!("must be greater than 0, got {v}"));
    }
    Ok(())
}

/// A finite number, 0 or more.
pub fn non_negative(v: f64) -> std::result::Result<(), String> {
    if !v.is_finite() || v < 0.0 {
        return Err(format!("must be a finite number >= 0, got {v}"));
    }
    Ok(())
}

/// [`finite`] for a sensor file's `field`.
pub fn config_finite(field: &str, v: f64) -> Result<()> {
    finite(v).map_err(|reason| GeltipError::config(field, reason))
}

/// [`positive`] for a sensor file's `field`.
pub fn config_positive(field: &str, v: f64) -> Result<()> {
    positive(v).map_err(|reason| GeltipError::config(field, reason))
}

/// [`non_negative`] for a sensor file's `field`.
pub fn config_non_negative(field: &str, v: f64) -> Result<()> {
    non_negative(v).map_err(|reason| GeltipError::config(field, reason))
}
