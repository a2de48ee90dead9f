//! The library's one error type. Every message is a single line that names what is wrong
//! and says why, cause included: no variant reports a `source()`, so printing an error's
//! chain (`{:#}`) shows each cause once.

use std::path::PathBuf;

/// Everything that can go wrong in geltip's library code.
#[derive(Debug, thiserror::Error)]
pub enum GeltipError {
    /// A sensor configuration field holds a value the sensor cannot have.
    #[error("sensor config: {field}: {reason}")]
    InvalidConfig { field: String, reason: String },

    /// A sensor configuration file could not be parsed (syntax, missing or unknown key).
    #[error("sensor config {path}: {reason}")]
    ConfigParse { path: String, reason: String },

    /// `--sensor` named neither a preset nor a readable file.
    #[error("unknown sensor '{name}': not a preset ({presets}) and no such file")]
    UnknownSensor { name: String, presets: String },

    /// A value given on the command line or through the API is out of range.
    #[error("{what}: {reason}")]
    InvalidInput { what: String, reason: String },

    /// A contact's field holds a value no press can have; `field` is the name it has in
    /// [`crate::scene::ContactSpec`] (`depth`, `at`, `pose`...), so a front end can name
    /// its own flag or argument instead.
    #[error("{field}: {reason}")]
    InvalidContact { field: String, reason: String },

    /// A mesh file that cannot be used as an object.
    #[error("mesh {path}: {reason}")]
    InvalidMesh { path: PathBuf, reason: String },

    /// An image that cannot be used (unreadable, wrong size).
    #[error("image {path}: {reason}")]
    InvalidImage { path: PathBuf, reason: String },

    /// No GPU adapter (or no software Vulkan driver) could be found.
    #[error("{0}")]
    NoAdapter(String),

    /// The GPU device failed, ran out of memory or did not finish in time.
    #[error("gpu: {0}")]
    Gpu(String),

    /// A WGSL shader failed to parse or validate.
    #[error("shader {file}: {reason}")]
    Shader { file: String, reason: String },

    /// Reading or writing a file failed: the message is the path and the system's reason;
    /// `cause` keeps the error itself (its kind, its OS code).
    #[error("{path}: {cause}")]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
}

/// Shorthand for results of geltip's library.
pub type Result<T, E = GeltipError> = std::result::Result<T, E>;

impl GeltipError {
    /// An `InvalidConfig` error for `field`.
    pub fn config(field: impl Into<String>, reason: impl Into<String>) -> Self {
        GeltipError::InvalidConfig {
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// An `InvalidInput` error about `what`.
    pub fn input(what: impl Into<String>, reason: impl Into<String>) -> Self {
        GeltipError::InvalidInput {
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// An `InvalidContact` error about the contact field `field`.
    pub fn contact(field: impl Into<String>, reason: impl Into<String>) -> Self {
        GeltipError::InvalidContact {
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// An `Io` error for `path`.
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        GeltipError::Io {
            path: path.into(),
            cause,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One of every variant (the match below fails to compile when one is added).
    fn every_variant() -> Vec<GeltipError> {
        let all = vec![
            GeltipError::config("finger.radius_mm", "must be positive"),
            GeltipError::ConfigParse {
                path: "x.toml".into(),
                reason: "line 1".into(),
            },
            GeltipError::UnknownSensor {
                name: "nope".into(),
                presets: "paper".into(),
            },
            GeltipError::input("--count", "must be at least 1"),
            GeltipError::contact("depth", "a press depth cannot be negative"),
            GeltipError::InvalidMesh {
                path: "m.obj".into(),
                reason: "no triangles".into(),
            },
            GeltipError::InvalidImage {
                path: "i.png".into(),
                reason: "10x10".into(),
            },
            GeltipError::NoAdapter("no adapter".into()),
            GeltipError::Gpu("timeout".into()),
            GeltipError::Shader {
                file: "contact.wgsl".into(),
                reason: "parse".into(),
            },
            GeltipError::io("/out/x.png", std::io::Error::from_raw_os_error(28)),
        ];
        for e in &all {
            match e {
                GeltipError::InvalidConfig { .. }
                | GeltipError::ConfigParse { .. }
                | GeltipError::UnknownSensor { .. }
                | GeltipError::InvalidInput { .. }
                | GeltipError::InvalidContact { .. }
                | GeltipError::InvalidMesh { .. }
                | GeltipError::InvalidImage { .. }
                | GeltipError::NoAdapter(_)
                | GeltipError::Gpu(_)
                | GeltipError::Shader { .. }
                | GeltipError::Io { .. } => {}
            }
        }
        all
    }

    #[test]
    fn every_message_says_its_cause_once() {
        for e in every_variant() {
            let message = e.to_string();
            assert!(!message.contains('\n'), "{message}");
            // The message is the whole chain: printed as the binary prints it (`{:#}`, each
            // cause after a colon), nothing is added, so nothing is said twice.
            assert!(std::error::Error::source(&e).is_none(), "{message}");
            assert_eq!(format!("{:#}", anyhow::Error::from(e)), message);
        }
        let cause = std::io::Error::from_raw_os_error(28).to_string();
        let e = GeltipError::io("/out/x.png", std::io::Error::from_raw_os_error(28));
        assert_eq!(
            format!("{:#}", anyhow::Error::from(e)),
            format!("/out/x.png: {cause}")
        );
    }
}
