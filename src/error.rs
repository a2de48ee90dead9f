//! The library's one error type. Every message is a single line that names what is wrong.

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

    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
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

    /// An `Io` error for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        GeltipError::Io {
            path: path.into(),
            source,
        }
    }
}
