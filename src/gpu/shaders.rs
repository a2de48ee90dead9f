//! WGSL shaders: stage files composed with shared files, validated with naga, made into
//! compute pipelines.
//!
//! Stage shaders live in `shaders/<stage>.wgsl`, shared code in `shaders/shared/*.wgsl`. A file
//! names the shared files it needs in its leading comment block, one per line, with paths
//! relative to `shaders/`:
//!
//! ```wgsl
//! //! use shared/common.wgsl
//! //! use shared/lens.wgsl
//! ```
//!
//! Composing prepends each needed shared file once (shared files may `//! use` other shared
//! files; they come first), each part behind a `// ---- geltip: <file> ----` marker line so
//! that [`validate`] can report errors as `file:line:column` of the original file.
//!
//! The shaders are embedded in the binary: **to add a stage, add a line to [`STAGES`]** (and a
//! shared file to [`SHARED`]); `tests/shaders.rs` fails until every file under `shaders/` is
//! registered there.

use std::borrow::Cow;
use std::collections::HashSet;
use std::path::Path;

use super::context::GpuContext;
use super::one_line;
use crate::error::{GeltipError, Result};

/// The embedded stage shaders: `(stage name, text of shaders/<stage name>.wgsl)`.
pub const STAGES: &[(&str, &str)] = &[
    ("start", include_str!("../../shaders/start.wgsl")),
    ("contact", include_str!("../../shaders/contact.wgsl")),
    ("elastomer", include_str!("../../shaders/elastomer.wgsl")),
    ("touched", include_str!("../../shaders/touched.wgsl")),
    ("camera", include_str!("../../shaders/camera.wgsl")),
    ("leds", include_str!("../../shaders/leds.wgsl")),
    // Test support (Renderer::unproject_pixels), not a stage of a frame.
    ("lens_rays", include_str!("../../shaders/lens_rays.wgsl")),
];

/// The embedded shared files: `(path relative to shaders/, text)`.
pub const SHARED: &[(&str, &str)] = &[
    (
        "shared/common.wgsl",
        include_str!("../../shaders/shared/common.wgsl"),
    ),
    (
        "shared/object.wgsl",
        include_str!("../../shaders/shared/object.wgsl"),
    ),
    (
        "shared/shading.wgsl",
        include_str!("../../shaders/shared/shading.wgsl"),
    ),
    (
        "shared/probes.wgsl",
        include_str!("../../shaders/shared/probes.wgsl"),
    ),
    (
        "shared/touched_list.wgsl",
        include_str!("../../shaders/shared/touched_list.wgsl"),
    ),
];

/// The `shaders/` directory of the source tree (for tests and development tools; the library
/// itself uses the embedded copies).
pub const SHADER_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders");

/// The directive naming a shared file: `//! use shared/common.wgsl`.
pub const USE_DIRECTIVE: &str = "//! use ";

/// Start of the marker line before each part of a composed shader.
const MARKER_START: &str = "// ---- geltip: ";
const MARKER_END: &str = " ----";

/// The embedded text of stage `name` (with or without `.wgsl`).
pub fn embedded_stage(name: &str) -> Option<&'static str> {
    let name = name.strip_suffix(".wgsl").unwrap_or(name);
    STAGES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// The embedded text of shared file `path` (e.g. `shared/common.wgsl`).
pub fn embedded_shared(path: &str) -> Option<&'static str> {
    SHARED.iter().find(|(p, _)| *p == path).map(|(_, t)| *t)
}

/// Composes embedded stage `stage_name` (e.g. `contact`) with the shared files it uses.
pub fn compose(stage_name: &str) -> Result<String> {
    let name = stage_name.strip_suffix(".wgsl").unwrap_or(stage_name);
    let file = format!("{name}.wgsl");
    let text = embedded_stage(name).ok_or_else(|| {
        let known: Vec<&str> = STAGES.iter().map(|(n, _)| *n).collect();
        GeltipError::Shader {
            file: file.clone(),
            reason: format!(
                "not a registered stage (registered: [{}]); add it to STAGES in src/gpu/shaders.rs",
                known.join(", ")
            ),
        }
    })?;
    compose_named(&file, text, |p| embedded_shared(p).map(str::to_string))
}

/// Composes stage `stage_name` read from `dir` (e.g. [`SHADER_DIR`]), its shared files read
/// from `dir` too. For tests and shader development.
pub fn compose_from_dir(dir: &Path, stage_name: &str) -> Result<String> {
    let name = stage_name.strip_suffix(".wgsl").unwrap_or(stage_name);
    let file = format!("{name}.wgsl");
    let path = dir.join(&file);
    let text = std::fs::read_to_string(&path).map_err(|e| GeltipError::io(&path, e))?;
    compose_named(&file, &text, |p| std::fs::read_to_string(dir.join(p)).ok())
}

/// Composes `stage_text` with the shared files its `//! use` lines name, looked up with
/// `resolve_shared` (path relative to `shaders/` → text, `None` when missing).
pub fn compose_source(
    stage_text: &str,
    resolve_shared: impl Fn(&str) -> Option<String>,
) -> Result<String> {
    compose_named("stage", stage_text, resolve_shared)
}

/// [`compose_source`] for a stage called `file` in error messages and markers.
pub fn compose_named(
    file: &str,
    stage_text: &str,
    resolve_shared: impl Fn(&str) -> Option<String>,
) -> Result<String> {
    let mut order: Vec<(String, String)> = Vec::new();
    let mut done: HashSet<String> = HashSet::new();
    let mut stack: Vec<String> = Vec::new();
    for used in uses(file, stage_text)? {
        add_shared(
            file,
            &used,
            &resolve_shared,
            &mut order,
            &mut done,
            &mut stack,
        )?;
    }
    let mut out = String::with_capacity(
        stage_text.len() + order.iter().map(|(_, t)| t.len() + 64).sum::<usize>() + 64,
    );
    for (path, text) in order.iter().map(|(p, t)| (p.as_str(), t.as_str())) {
        push_part(&mut out, path, text);
    }
    push_part(&mut out, file, stage_text);
    Ok(out)
}

/// Appends `path`'s shared dependencies (depth first) and then `path` itself to `order`.
fn add_shared(
    user: &str,
    path: &str,
    resolve: &impl Fn(&str) -> Option<String>,
    order: &mut Vec<(String, String)>,
    done: &mut HashSet<String>,
    stack: &mut Vec<String>,
) -> Result<()> {
    if done.contains(path) {
        return Ok(());
    }
    if stack.iter().any(|p| p == path) {
        let mut cycle = stack.clone();
        cycle.push(path.to_string());
        return Err(GeltipError::Shader {
            file: user.to_string(),
            reason: format!("`//! use` cycle: {}", cycle.join(" -> ")),
        });
    }
    let text = resolve(path).ok_or_else(|| GeltipError::Shader {
        file: user.to_string(),
        reason: format!("`{USE_DIRECTIVE}{path}`: no such shared file"),
    })?;
    stack.push(path.to_string());
    for used in uses(path, &text)? {
        add_shared(path, &used, resolve, order, done, stack)?;
    }
    stack.pop();
    done.insert(path.to_string());
    order.push((path.to_string(), text));
    Ok(())
}

fn push_part(out: &mut String, path: &str, text: &str) {
    out.push_str(MARKER_START);
    out.push_str(path);
    out.push_str(MARKER_END);
    out.push('\n');
    out.push_str(text);
    if !text.ends_with('\n') {
        out.push('\n');
    }
}

/// The shared files `text` (file `file`) names in `//! use` lines of its leading comment block.
///
/// A `//! use` line after the first line of code is an error (it would be silently ignored).
pub fn uses(file: &str, text: &str) -> Result<Vec<String>> {
    let mut found = Vec::new();
    let mut in_header = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        let directive = line
            .strip_prefix(USE_DIRECTIVE.trim_end())
            .filter(|rest| rest.is_empty() || rest.starts_with(char::is_whitespace));
        if in_header && !(line.is_empty() || line.starts_with("//")) {
            in_header = false;
        }
        let Some(rest) = directive else { continue };
        let path = rest.trim();
        let bad = |reason: String| GeltipError::Shader {
            file: file.to_string(),
            reason: format!("line {}: {reason}", i + 1),
        };
        if !in_header {
            return Err(bad(format!(
                "`{line}` must be in the leading comment block, before any code"
            )));
        }
        if path.is_empty() || path.contains(char::is_whitespace) {
            return Err(bad(format!(
                "`{line}`: expected `{USE_DIRECTIVE}shared/<file>.wgsl`"
            )));
        }
        if !found.iter().any(|f| f == path) {
            found.push(path.to_string());
        }
    }
    Ok(found)
}

/// Parses and validates WGSL `source` with naga (all validation flags, default capabilities).
///
/// Errors are one line: `GeltipError::Shader { file: name, reason }` where the reason starts
/// with `file:line:column` (of the original file when `source` was composed here).
pub fn validate(name: &str, source: &str) -> Result<naga::Module> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| GeltipError::Shader {
        file: name.to_string(),
        reason: parse_error_reason(name, source, &e),
    })?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    );
    validator
        .validate(&module)
        .map_err(|e| GeltipError::Shader {
            file: name.to_string(),
            reason: validation_error_reason(name, source, &e),
        })?;
    Ok(module)
}

/// Composes embedded stage `stage_name`, validates it, and creates a compute pipeline for
/// `entry_point` (`layout` `None`: layout derived from the shader).
pub fn create_compute_pipeline(
    ctx: &GpuContext,
    stage_name: &str,
    entry_point: &str,
    layout: Option<&wgpu::PipelineLayout>,
) -> Result<wgpu::ComputePipeline> {
    create_compute_pipeline_with(ctx, stage_name, entry_point, layout, &[])
}

/// [`create_compute_pipeline`] with values for the shader's pipeline-overridable constants
/// (`override` declarations, by name).
pub fn create_compute_pipeline_with(
    ctx: &GpuContext,
    stage_name: &str,
    entry_point: &str,
    layout: Option<&wgpu::PipelineLayout>,
    constants: &[(&str, f64)],
) -> Result<wgpu::ComputePipeline> {
    let name = stage_name.strip_suffix(".wgsl").unwrap_or(stage_name);
    let source = compose(name)?;
    create_pipeline(
        ctx,
        &format!("{name}.wgsl"),
        &source,
        entry_point,
        layout,
        constants,
    )
}

/// [`create_compute_pipeline`] for WGSL `source` (already composed) called `name`.
///
/// Validates with naga first (clear errors with line numbers), checks that `entry_point` is a
/// `@compute` entry point, then creates the module and pipeline inside [`GpuContext::scoped`]
/// so that wgpu validation errors (e.g. a layout that does not match) come back as `Err`.
pub fn create_compute_pipeline_from_source(
    ctx: &GpuContext,
    name: &str,
    source: &str,
    entry_point: &str,
    layout: Option<&wgpu::PipelineLayout>,
) -> Result<wgpu::ComputePipeline> {
    create_pipeline(ctx, name, source, entry_point, layout, &[])
}

fn create_pipeline(
    ctx: &GpuContext,
    name: &str,
    source: &str,
    entry_point: &str,
    layout: Option<&wgpu::PipelineLayout>,
    constants: &[(&str, f64)],
) -> Result<wgpu::ComputePipeline> {
    let module = validate(name, source)?;
    let computes: Vec<&str> = module
        .entry_points
        .iter()
        .filter(|ep| ep.stage == naga::ShaderStage::Compute)
        .map(|ep| ep.name.as_str())
        .collect();
    if !computes.contains(&entry_point) {
        return Err(GeltipError::Shader {
            file: name.to_string(),
            reason: format!(
                "no @compute entry point `{entry_point}` (found: [{}])",
                computes.join(", ")
            ),
        });
    }
    let label = format!("{name}:{entry_point}");
    ctx.scoped(&format!("creating compute pipeline {label}"), || {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(source)),
            });
        ctx.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&label),
                layout,
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            })
    })
}

/// Where a composed line came from: `(file, line in that file)`; the name and the line itself
/// when `source` has no markers.
fn locate<'a>(name: &'a str, source: &'a str, line: u32) -> (&'a str, u32) {
    let mut file = name;
    let mut marker_line = 0u32;
    for (i, text) in source
        .lines()
        .enumerate()
        .take(line.saturating_sub(1) as usize)
    {
        let n = i as u32 + 1;
        if let Some(path) = text
            .strip_prefix(MARKER_START)
            .and_then(|r| r.strip_suffix(MARKER_END))
        {
            file = path;
            marker_line = n;
        }
    }
    (file, line - marker_line)
}

fn position(name: &str, source: &str, loc: &naga::SourceLocation) -> String {
    let (file, line) = locate(name, source, loc.line_number);
    format!("{file}:{line}:{}", loc.line_position)
}

/// Appends ` [file:line:col: label]` for each labelled span (without the position when it is
/// the primary one).
fn push_labels<'l>(
    reason: &mut String,
    name: &str,
    source: &str,
    primary: Option<&str>,
    labels: impl Iterator<Item = (naga::Span, &'l str)>,
) {
    for (span, label) in labels {
        if label.is_empty() || !span.is_defined() {
            continue;
        }
        let pos = position(name, source, &span.location(source));
        if primary == Some(pos.as_str()) {
            reason.push_str(&format!(" [{label}]"));
        } else {
            reason.push_str(&format!(" [{pos}: {label}]"));
        }
    }
}

fn parse_error_reason(name: &str, source: &str, e: &naga::front::wgsl::ParseError) -> String {
    let primary = e.location(source).map(|loc| position(name, source, &loc));
    let mut reason = match &primary {
        Some(pos) => format!("{pos}: {}", e.message()),
        None => e.message().to_string(),
    };
    push_labels(&mut reason, name, source, primary.as_deref(), e.labels());
    for note in e.notes() {
        reason.push_str("; note: ");
        reason.push_str(note);
    }
    one_line(&reason)
}

fn validation_error_reason(
    name: &str,
    source: &str,
    e: &naga::WithSpan<naga::valid::ValidationError>,
) -> String {
    let mut message = e.as_inner().to_string();
    let mut cause = std::error::Error::source(e.as_inner());
    while let Some(c) = cause {
        message.push_str(": ");
        message.push_str(&c.to_string());
        cause = c.source();
    }
    // naga lists the enclosing item (function, global) first and the culprit last.
    let culprit = e.spans().filter(|(span, _)| span.is_defined()).last();
    let primary = culprit.map(|(span, _)| position(name, source, &span.location(source)));
    let mut reason = match &primary {
        Some(pos) => format!("{pos}: {message}"),
        None => message,
    };
    let labels = e.spans().map(|(span, label)| (*span, label.as_str()));
    push_labels(&mut reason, name, source, primary.as_deref(), labels);
    one_line(&reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(path: &str) -> Option<String> {
        match path {
            "shared/a.wgsl" => Some("//! use shared/b.wgsl\nconst A: f32 = B;\n".into()),
            "shared/b.wgsl" => Some("const B: f32 = 1.0;\n".into()),
            "shared/loop.wgsl" => Some("//! use shared/loop.wgsl\n".into()),
            _ => None,
        }
    }

    #[test]
    fn shared_files_come_first_once_in_dependency_order() {
        let stage = "// stage\n//! use shared/a.wgsl\n//! use shared/b.wgsl\n\n@compute @workgroup_size(1)\nfn main() { let x = A; }\n";
        let out = compose_named("s.wgsl", stage, files).unwrap();
        let b = out.find("const B").unwrap();
        let a = out.find("const A").unwrap();
        let main = out.find("fn main").unwrap();
        assert!(b < a && a < main, "{out}");
        assert_eq!(out.matches("const B").count(), 1);
        validate("s.wgsl", &out).unwrap();
    }

    #[test]
    fn missing_and_cyclic_uses_are_errors() {
        let e = compose_named("s.wgsl", "//! use shared/nope.wgsl\n", files).unwrap_err();
        assert!(e.to_string().contains("shared/nope.wgsl"), "{e}");
        let e = compose_named("s.wgsl", "//! use shared/loop.wgsl\n", files).unwrap_err();
        assert!(e.to_string().contains("cycle"), "{e}");
        let e = compose_named(
            "s.wgsl",
            "const X: i32 = 1;\n//! use shared/b.wgsl\n",
            files,
        )
        .unwrap_err();
        assert!(e.to_string().contains("leading comment block"), "{e}");
    }

    #[test]
    fn errors_point_into_the_original_file() {
        let stage = "//! use shared/b.wgsl\n\nfn f() -> f32 {\n    return B +;\n}\n";
        let out = compose_named("s.wgsl", stage, files).unwrap();
        let e = validate("s.wgsl", &out).unwrap_err().to_string();
        assert!(e.contains("s.wgsl:4:"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        let e = validate("raw", "fn f() -> f32 {\n  return true;\n}\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("shader raw: raw:2:"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn registry_is_consistent() {
        for (path, _) in SHARED {
            assert!(
                path.starts_with("shared/") && path.ends_with(".wgsl"),
                "{path}"
            );
        }
        for (name, _) in STAGES {
            assert!(!name.contains('/') && !name.ends_with(".wgsl"), "{name}");
            compose(name).unwrap();
        }
        assert!(compose("no-such-stage").is_err());
    }
}
