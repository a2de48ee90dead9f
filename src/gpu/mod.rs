//! Headless wgpu: context, shader loading and validation, readback.
//!
//! - [`context`]: one [`GpuContext`] (device + queue) per process, error scopes that turn
//!   wgpu validation errors into [`crate::GeltipError::Gpu`], and [`GpuContext::wait`], the one
//!   place that blocks on the GPU (with a timeout).
//! - [`shaders`]: WGSL stage files composed with their shared files, validated with naga
//!   before wgpu sees them.
//! - [`readback`]: copying textures and buffers back to the CPU (row padding handled).

pub mod context;
pub mod readback;
pub mod shaders;

pub use context::GpuContext;
pub use readback::{padded_bytes_per_row, read_buffer, read_texture, Readback};
pub use shaders::{compose, compose_source, create_compute_pipeline, validate};

/// Flattens a (possibly multi-line, indented) error text into one line.
///
/// wgpu and naga format nested errors as indented lines; the crate's error messages are one
/// line each, so lines are trimmed and joined with ": ".
pub(crate) fn one_line(text: &str) -> String {
    let parts: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let mut joined = parts.join(": ");
    // Collapse the `x: : y` left behind by lines that already end with a colon.
    while joined.contains(":: ") {
        joined = joined.replace(":: ", ": ");
    }
    joined
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn one_line_flattens_nested_errors() {
        let text = "Validation Error\n\nCaused by:\n  In Device::create_buffer\n    bad size\n";
        assert_eq!(
            one_line(text),
            "Validation Error: Caused by: In Device::create_buffer: bad size"
        );
    }
}
