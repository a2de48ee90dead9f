//! Every WGSL file under `shaders/` composes and validates with naga; all failures are
//! collected and reported together. Also checks that the embedded registry matches the files.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use geltip::gpu::shaders::{compose_named, validate, SHADER_DIR, SHARED, STAGES};

/// `*.wgsl` files directly in `dir`, by file name.
fn wgsl_files(dir: &Path) -> BTreeMap<String, PathBuf> {
    let mut files = BTreeMap::new();
    let Ok(read) = fs::read_dir(dir) else {
        return files;
    };
    for entry in read {
        let path = entry.unwrap().path();
        if path.is_file() && path.extension().is_some_and(|e| e == "wgsl") {
            files.insert(
                path.file_name().unwrap().to_string_lossy().into_owned(),
                path,
            );
        }
    }
    files
}

/// Validates a shared file on its own, adding a dummy entry point if it has none.
fn validate_shared(name: &str, text: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(text);
    let has_entry = module.is_ok_and(|m| !m.entry_points.is_empty());
    let source = if has_entry {
        text.to_string()
    } else {
        format!("{text}\n@compute @workgroup_size(1)\nfn geltip_shared_check_main() {{}}\n")
    };
    validate(name, &source)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Checks every stage in `dir` (composed with its shared files from `dir`) and every shared
/// file in `dir/shared` on its own. Returns one line per failure.
fn check_shader_dir(dir: &Path) -> (usize, Vec<String>) {
    let mut failures = Vec::new();
    let mut checked = 0;
    let read_shared = |p: &str| fs::read_to_string(dir.join(p)).ok();
    for (file, path) in wgsl_files(dir) {
        checked += 1;
        let text = match fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) => {
                failures.push(format!("{file}: cannot read: {e}"));
                continue;
            }
        };
        let result = compose_named(&file, &text, read_shared).and_then(|s| validate(&file, &s));
        if let Err(e) = result {
            failures.push(e.to_string());
        }
    }
    for (file, path) in wgsl_files(&dir.join("shared")) {
        checked += 1;
        let name = format!("shared/{file}");
        let result = fs::read_to_string(&path)
            .map_err(|e| format!("{name}: cannot read: {e}"))
            .and_then(|text| {
                compose_named(&name, &text, read_shared)
                    .map_err(|e| e.to_string())
                    .and_then(|composed| validate_shared(&name, &composed))
            });
        if let Err(e) = result {
            failures.push(e);
        }
    }
    (checked, failures)
}

#[test]
fn all_shaders_compose_and_validate() {
    let dir = Path::new(SHADER_DIR);
    let (checked, failures) = check_shader_dir(dir);
    assert!(checked > 0, "no shaders found under {}", dir.display());
    assert!(
        failures.is_empty(),
        "{} of {checked} shader files failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn harness_reports_every_failure_without_panicking() {
    let dir = std::env::temp_dir().join(format!("geltip-shader-harness-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("shared")).unwrap();
    let write = |p: &str, t: &str| fs::write(dir.join(p), t).unwrap();
    write(
        "shared/ok.wgsl",
        "fn twice(x: f32) -> f32 { return 2.0 * x; }\n",
    );
    write(
        "shared/broken.wgsl",
        "fn half(x: f32) -> f32 { return x / ; }\n",
    );
    write(
        "good.wgsl",
        "//! use shared/ok.wgsl\n@compute @workgroup_size(1)\nfn main() { let y = twice(1.0); }\n",
    );
    write(
        "type_error.wgsl",
        "//! use shared/ok.wgsl\n\n@compute @workgroup_size(1)\nfn main() {\n    let y: i32 = twice(1.0);\n}\n",
    );
    write(
        "missing_use.wgsl",
        "//! use shared/nowhere.wgsl\n@compute @workgroup_size(1)\nfn main() {}\n",
    );
    write(
        "uses_broken.wgsl",
        "//! use shared/broken.wgsl\n@compute @workgroup_size(1)\nfn main() {}\n",
    );

    let (checked, failures) = check_shader_dir(&dir);
    fs::remove_dir_all(&dir).unwrap();
    let report = failures.join("\n");
    eprintln!("{report}");
    assert_eq!(checked, 6, "{report}");
    assert_eq!(failures.len(), 4, "{report}");
    let find = |needle: &str| {
        failures
            .iter()
            .find(|f| f.contains(needle))
            .unwrap_or_else(|| panic!("no failure mentions {needle:?} in:\n{report}"))
    };
    // The type error is reported at its line in the stage file, not in the composed text.
    assert!(
        find("type_error.wgsl").contains("type_error.wgsl:5:"),
        "{report}"
    );
    assert!(
        find("missing_use.wgsl").contains("shared/nowhere.wgsl"),
        "{report}"
    );
    // A broken shared file is reported for its user and on its own, at its own line.
    assert!(
        find("shader uses_broken.wgsl").contains("shared/broken.wgsl:1:"),
        "{report}"
    );
    assert!(
        find("shader shared/broken.wgsl").contains("shared/broken.wgsl:1:"),
        "{report}"
    );
    for f in &failures {
        assert!(!f.contains('\n'), "multi-line failure: {f:?}");
    }
}

#[test]
fn embedded_registry_matches_the_files() {
    let dir = Path::new(SHADER_DIR);
    let mut problems = Vec::new();

    let stage_files = wgsl_files(dir);
    for (file, path) in &stage_files {
        let name = file.trim_end_matches(".wgsl");
        match STAGES.iter().find(|(n, _)| *n == name) {
            None => problems.push(format!(
                "shaders/{file} is not registered: add (\"{name}\", include_str!(\"../../shaders/{file}\")) to STAGES in src/gpu/shaders.rs"
            )),
            Some((_, text)) => {
                if fs::read_to_string(path).unwrap() != *text {
                    problems.push(format!("STAGES entry {name} differs from shaders/{file}"));
                }
            }
        }
    }
    for (name, _) in STAGES {
        if !stage_files.contains_key(&format!("{name}.wgsl")) {
            problems.push(format!(
                "STAGES entry {name} has no file shaders/{name}.wgsl"
            ));
        }
    }

    let shared_files = wgsl_files(&dir.join("shared"));
    for (file, path) in &shared_files {
        let key = format!("shared/{file}");
        match SHARED.iter().find(|(p, _)| *p == key) {
            None => problems.push(format!(
                "shaders/{key} is not registered: add (\"{key}\", include_str!(\"../../shaders/{key}\")) to SHARED in src/gpu/shaders.rs"
            )),
            Some((_, text)) => {
                if fs::read_to_string(path).unwrap() != *text {
                    problems.push(format!("SHARED entry {key} differs from shaders/{key}"));
                }
            }
        }
    }
    for (key, _) in SHARED {
        let file = key.strip_prefix("shared/").unwrap_or(key);
        if !shared_files.contains_key(file) {
            problems.push(format!("SHARED entry {key} has no file shaders/{key}"));
        }
    }

    // Every embedded stage composes from the embedded shared files.
    for (name, _) in STAGES {
        if let Err(e) = geltip::gpu::compose(name) {
            problems.push(e.to_string());
        }
    }

    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every stage fits WebGPU's guaranteed limits on bindings a shader stage may use (the
/// renderer asks for no more): 8 storage buffers, 16 sampled textures, 12 uniform buffers,
/// 16 samplers. One stage over a limit would keep the renderer off devices that offer just
/// those. A module with a ninth storage buffer fails the check.
#[test]
fn stages_fit_webgpus_guaranteed_binding_limits() {
    use naga::{AddressSpace, TypeInner};
    let limits = wgpu::Limits::defaults();
    let over = |source: &str| -> Vec<String> {
        let module = naga::front::wgsl::parse_str(source).expect("parses");
        let (mut storage, mut uniform, mut textures, mut samplers) = (0, 0, 0, 0);
        for (_, g) in module.global_variables.iter() {
            match (g.space, &module.types[g.ty].inner) {
                (AddressSpace::Storage { .. }, _) => storage += 1,
                (AddressSpace::Uniform, _) => uniform += 1,
                (AddressSpace::Handle, TypeInner::Image { .. }) => textures += 1,
                (AddressSpace::Handle, TypeInner::Sampler { .. }) => samplers += 1,
                _ => {}
            }
        }
        [
            (
                "storage buffers",
                storage,
                limits.max_storage_buffers_per_shader_stage,
            ),
            (
                "uniform buffers",
                uniform,
                limits.max_uniform_buffers_per_shader_stage,
            ),
            (
                "sampled textures",
                textures,
                limits.max_sampled_textures_per_shader_stage,
            ),
            ("samplers", samplers, limits.max_samplers_per_shader_stage),
        ]
        .into_iter()
        .filter(|&(_, n, max)| n > max)
        .map(|(what, n, max)| format!("{what}: {n} > {max}"))
        .collect()
    };
    let mut failures = Vec::new();
    for (name, _) in STAGES {
        let source = geltip::gpu::shaders::compose(name).expect("composes");
        for f in over(&source) {
            failures.push(format!("{name}.wgsl: {f}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The check can fail: one more storage buffer than the limit.
    let extra: String = (0..=limits.max_storage_buffers_per_shader_stage)
        .map(|i| format!("@group(1) @binding({i}) var<storage, read_write> b{i}: array<u32>;\n"))
        .collect();
    assert!(!over(&extra).is_empty());
}
