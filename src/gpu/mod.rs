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

/// The host a speed figure comes from, in one line: CPU model and cores, then the adapter and
/// its driver (for lavapipe the adapter name carries LLVM's version and vector width), e.g.
/// `CPU AMD EPYC (2 cores); adapter llvmpipe (LLVM 15.0.6, 256 bits), driver llvmpipe Mesa
/// 22.3.6`. The same renderer has run 5x apart on machines of one nominal kind, so every
/// benchmark prints this first.
pub fn host_description(adapter: &wgpu::AdapterInfo) -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, model)| model.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let driver = [adapter.driver.as_str(), adapter.driver_info.as_str()]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    format!(
        "CPU {cpu} ({cores} cores); adapter {} ({:?}), driver {driver}",
        adapter.name, adapter.backend
    )
}

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
