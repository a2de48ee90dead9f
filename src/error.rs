//! The library's one error type. Every message is a single line that names what is wrong
//! and says why, cause included: no variant reports a `source()`, so printing an error's
//! chain (`{:#}`) shows each cause once. Text a user gave (a name, a place, a key of a
//! file) is written with its control characters escaped ([`OneLine`]), so that no input
//! can break a message over lines; [`quoted`] also shortens it.

use std::path::PathBuf;

/// Everything that can go wrong in geltip's library code.
#[derive(Debug, thiserror::Error)]
pub enum GeltipError {
    /// A sensor configuration field holds a value the sensor cannot have.
    #[error("sensor config: {}: {}", OneLine(.field), OneLine(.reason))]
    InvalidConfig { field: String, reason: String },

    /// A sensor configuration file could not be parsed (syntax, missing or unknown key).
    #[error("sensor config {}: {}", OneLine(.path), OneLine(.reason))]
    ConfigParse { path: String, reason: String },

    /// `--sensor` named neither a preset nor a readable file.
    #[error("unknown sensor '{}': not a preset ({presets}) and no such file", OneLine(.name))]
    UnknownSensor { name: String, presets: String },

    /// A value given on the command line or through the API is out of range.
    #[error("{}: {}", OneLine(.what), OneLine(.reason))]
    InvalidInput { what: String, reason: String },

    /// A contact's field holds a value no press can have; `field` is the name it has in
    /// [`crate::scene::ContactSpec`] (`depth`, `at`, `pose`...), so a front end can name
    /// its own flag or argument instead.
    #[error("{}: {}", OneLine(.field), OneLine(.reason))]
    InvalidContact { field: String, reason: String },

    /// An option of a job holds a value the job cannot run with; `option` is the name the
    /// library gives it (a field of the job's spec or an argument of its function: `count`,
    /// `depth_range`, `out`...), so a front end can name its own flag or argument instead,
    /// and `value` is the value as given, when the message shows it.
    #[error("{}: {}", OneLine(named(.option, .value.as_deref())), OneLine(.reason))]
    InvalidOption {
        option: String,
        value: Option<String>,
        reason: String,
    },

    /// A mesh file that cannot be used as an object.
    #[error("mesh {}: {}", OneLine(.path.display()), OneLine(.reason))]
    InvalidMesh { path: PathBuf, reason: String },

    /// An image that cannot be used (unreadable, wrong size).
    #[error("image {}: {}", OneLine(.path.display()), OneLine(.reason))]
    InvalidImage { path: PathBuf, reason: String },

    /// No GPU adapter (or no software Vulkan driver) could be found.
    #[error("{}", OneLine(.0))]
    NoAdapter(String),

    /// The GPU device failed, ran out of memory or did not finish in time.
    #[error("gpu: {}", OneLine(.0))]
    Gpu(String),

    /// A WGSL shader failed to parse or validate.
    #[error("shader {}: {}", OneLine(.file), OneLine(.reason))]
    Shader { file: String, reason: String },

    /// Reading or writing a file failed: the message is the path and the system's reason;
    /// `cause` keeps the error itself (its kind, its OS code).
    #[error("{}: {}", OneLine(.path.display()), OneLine(.cause))]
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

    /// An `InvalidOption` error about the job option `option`.
    pub fn option(option: impl Into<String>, reason: impl Into<String>) -> Self {
        GeltipError::InvalidOption {
            option: option.into(),
            value: None,
            reason: reason.into(),
        }
    }

    /// An `InvalidOption` error about the job option `option` given as `value`.
    pub fn option_value(
        option: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        GeltipError::InvalidOption {
            option: option.into(),
            value: Some(value.to_string()),
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

/// An option's name, followed by its value when there is one (`shard 3/3`).
fn named(option: &str, value: Option<&str>) -> String {
    match value {
        Some(v) => format!("{option} {v}"),
        None => option.to_string(),
    }
}

/// Text written on one line: line breaks, tabs and other control characters as escapes
/// (`\n`), everything else as it is.
pub struct OneLine<T>(pub T);

impl<T: std::fmt::Display> std::fmt::Display for OneLine<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use std::fmt::Write as _;
        for c in self.0.to_string().chars() {
            if c.is_control() {
                write!(f, "{}", c.escape_default())?;
            } else {
                f.write_char(c)?;
            }
        }
        Ok(())
    }
}

/// A user's text for a message: in single quotes, on one line ([`OneLine`]), cut to its
/// first 60 characters and an ellipsis when longer.
pub fn quoted(text: &str) -> String {
    const MAX: usize = 60;
    let mut short: String = text.chars().take(MAX).collect();
    if text.chars().nth(MAX).is_some() {
        short.push_str("...");
    }
    format!("'{}'", OneLine(short))
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
            GeltipError::input("sample 3", "no visible contact"),
            GeltipError::option("count", "must be at least 1"),
            GeltipError::option_value("shard", "3/3", "the index must be below the count"),
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
                | GeltipError::InvalidOption { .. }
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
        // Whatever a field holds (here a user's key with a line break in it), one line.
        let e = GeltipError::input("contacts[0].line\nbreak", "unknown field\r\n");
        assert_eq!(
            e.to_string(),
            "contacts[0].line\\nbreak: unknown field\\r\\n"
        );
        let e = GeltipError::option_value("out", "set\n2", "holds another set");
        assert_eq!(e.to_string(), "out set\\n2: holds another set");
        assert_eq!(
            GeltipError::option("count", "must be at least 1").to_string(),
            "count: must be at least 1"
        );
        assert_eq!(quoted("s=1\ns=2"), "'s=1\\ns=2'");
        assert_eq!(quoted(&"x".repeat(100)), format!("'{}...'", "x".repeat(60)));
        let cause = std::io::Error::from_raw_os_error(28).to_string();
        let e = GeltipError::io("/out/x.png", std::io::Error::from_raw_os_error(28));
        assert_eq!(
            format!("{:#}", anyhow::Error::from(e)),
            format!("/out/x.png: {cause}")
        );
    }
}
