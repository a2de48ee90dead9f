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

/// Each stage composed and parsed (not validated: `all_shaders_compose_and_validate` does).
fn stage_modules() -> Vec<(&'static str, naga::Module)> {
    STAGES
        .iter()
        .map(|(name, _)| {
            let source = geltip::gpu::shaders::compose(name).expect("composes");
            let module = naga::front::wgsl::parse_str(&source).expect("parses");
            (*name, module)
        })
        .collect()
}

/// The integer a WGSL constant holds, if it holds one.
fn integer_constant(module: &naga::Module, name: &str) -> Option<i64> {
    use naga::{Expression as E, Literal as L};
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?;
    match module.global_expressions[c.init] {
        E::Literal(L::U32(v)) => Some(v.into()),
        E::Literal(L::I32(v)) => Some(v.into()),
        E::Literal(L::AbstractInt(v)) => Some(v),
        _ => None,
    }
}

/// The renderer's mirrors of where the shaders put things
/// (`geltip::render::gpu::layout`) hold the shaders' own values: every constant (the
/// counters' words, the probes' strides, the tile size), and the workgroup size of every
/// compute entry point of every stage, which the renderer sizes its dispatches by. All
/// mismatches are reported together.
#[test]
fn layout_mirrors_equal_the_shaders() {
    use geltip::render::gpu::layout::{WGSL_CONSTANTS, WORKGROUP_SIZES};
    let modules = stage_modules();
    let mut failures = Vec::new();
    for &(name, value) in WGSL_CONSTANTS {
        let found: Vec<(&str, i64)> = modules
            .iter()
            .filter_map(|(stage, m)| Some((*stage, integer_constant(m, name)?)))
            .collect();
        if found.is_empty() {
            failures.push(format!(
                "{name}: no stage declares it as an integer constant"
            ));
        }
        let differ: Vec<String> = found
            .iter()
            .filter(|&&(_, wgsl)| wgsl != i64::from(value))
            .map(|(stage, wgsl)| format!("{stage}.wgsl {wgsl}"))
            .collect();
        if !differ.is_empty() {
            failures.push(format!("{name}: Rust {value}, WGSL {}", differ.join(", ")));
        }
    }
    for (stage, module) in &modules {
        for ep in &module.entry_points {
            let size = WORKGROUP_SIZES
                .iter()
                .find(|(s, e, _)| s == stage && *e == ep.name)
                .map(|(_, _, size)| *size);
            match size {
                None => failures.push(format!(
                    "{stage}.wgsl {}: not in layout::WORKGROUP_SIZES",
                    ep.name
                )),
                Some(size) if size != ep.workgroup_size => failures.push(format!(
                    "{stage}.wgsl {}: @workgroup_size {:?}, Rust {size:?}",
                    ep.name, ep.workgroup_size
                )),
                Some(_) => {}
            }
        }
    }
    for (stage, entry, _) in WORKGROUP_SIZES {
        let declared = modules
            .iter()
            .any(|(s, m)| s == stage && m.entry_points.iter().any(|ep| ep.name == *entry));
        if !declared {
            failures.push(format!("{stage}.wgsl has no entry point {entry}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every binding any stage declares is the renderer's binding table's
/// (`geltip::render::gpu::bindings::BINDINGS`, from which its layout and bind groups are
/// made) at that number: the same name and kind, in group 0; and every binding of the table
/// is declared.
#[test]
fn bindings_table_equals_the_shaders() {
    use geltip::render::gpu::bindings::{Kind, BINDINGS};
    use naga::{AddressSpace, StorageAccess, TypeInner};
    let mut failures = Vec::new();
    let mut declared = vec![false; BINDINGS.len()];
    for (stage, module) in stage_modules() {
        for (_, g) in module.global_variables.iter() {
            let Some(rb) = &g.binding else { continue };
            let name = g.name.as_deref().unwrap_or("?");
            let kind = match (g.space, &module.types[g.ty].inner) {
                (AddressSpace::Uniform, _) => Some(Kind::Uniform),
                (AddressSpace::Storage { access }, _) => Some(Kind::Storage {
                    read_only: !access.contains(StorageAccess::STORE),
                }),
                (AddressSpace::Handle, TypeInner::Image { arrayed, class, .. }) => {
                    match (arrayed, class) {
                        (
                            _,
                            naga::ImageClass::Sampled {
                                kind: naga::ScalarKind::Uint,
                                ..
                            },
                        ) => Some(Kind::UintTexture),
                        (true, _) => Some(Kind::TextureArray),
                        (false, _) => Some(Kind::Texture),
                    }
                }
                (AddressSpace::Handle, TypeInner::Sampler { .. }) => Some(Kind::Sampler),
                _ => None,
            };
            let Some(b) = BINDINGS.get(rb.binding as usize).filter(|_| rb.group == 0) else {
                failures.push(format!(
                    "{stage}.wgsl {name}: @group({}) @binding({}) is not in the table",
                    rb.group, rb.binding
                ));
                continue;
            };
            declared[rb.binding as usize] = true;
            if b.wgsl_name() != name || Some(b.kind()) != kind {
                failures.push(format!(
                    "{stage}.wgsl @binding({}): {name} {kind:?}, the table's {} {:?}",
                    rb.binding,
                    b.wgsl_name(),
                    b.kind()
                ));
            }
        }
    }
    for (b, seen) in BINDINGS.iter().zip(declared) {
        if !seen {
            failures.push(format!("{b:?}: no stage declares it"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `(name, offset, size)` of a field of a `#[repr(C)]` struct, or of one element of an
/// array field, named as its WGSL member.
macro_rules! member {
    ($t:ty, $f:ident) => {
        member!($t, $f as stringify!($f))
    };
    ($t:ty, $f:ident as $w:expr) => {{
        let z: $t = bytemuck::Zeroable::zeroed();
        (
            $w.to_string(),
            std::mem::offset_of!($t, $f),
            std::mem::size_of_val(&z.$f),
        )
    }};
    ($t:ty, $f:ident [$i:literal] as $w:expr) => {{
        let z: $t = bytemuck::Zeroable::zeroed();
        let one = std::mem::size_of_val(&z.$f[0]);
        ($w.to_string(), std::mem::offset_of!($t, $f) + $i * one, one)
    }};
}

/// The members of WGSL struct `name` in `module`: `(name, offset, size)`, and its size.
fn wgsl_struct(module: &naga::Module, name: &str) -> (Vec<(String, usize, usize)>, usize) {
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"))
        .1;
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let members = members
        .iter()
        .map(|m| {
            let size = module.types[m.ty].inner.size(module.to_ctx());
            (
                m.name.clone().unwrap_or_default(),
                m.offset as usize,
                size as usize,
            )
        })
        .collect();
    (members, *span as usize)
}

/// The uniforms' Rust structs (`geltip::render::uniforms`) lay out their fields where the
/// WGSL structs `Sensor` and `Frame` read them: every member's offset and size, and the
/// structs' sizes.
#[test]
fn uniform_structs_equal_the_shaders() {
    use geltip::render::uniforms::{FrameUniform as F, SensorUniform as S};
    let sensor = vec![
        member!(S, radius),
        member!(S, cylinder_length),
        member!(S, shell_thickness),
        member!(S, junction_s),
        member!(S, lens_model),
        member!(S, focal_px),
        member!(S, max_theta),
        member!(S, max_rho),
        member!(S, k),
        member!(S, principal),
        member!(S, image_size),
        member!(S, texels),
        member!(S, ray_steps),
        member!(S, half_size_mm),
        member!(S, texel_mm),
        member!(S, blend_mm),
        member!(S, bulge),
        member!(S, diffuse),
        member!(S, specular),
        member!(S, shininess),
        member!(S, led_count),
        member!(S, spread),
        member!(S, drape_mm),
        member!(S, narrow_step_mm),
        member!(S, wide_step_mm),
        member!(S, narrow_taps),
        member!(S, wide_taps),
        member!(S, noise),
        member!(S, ambient),
        member!(S, paint_colour),
        member!(S, vignetting),
        member!(S, led_position),
        member!(S, led_colour),
        member!(S, led_light),
        member!(S, led_band),
        member!(S, led_end_glow),
        member!(S, colour_matrix),
        member!(S, inverse_gamma),
        member!(S, gel_leds),
        member!(S, camera_response),
        member!(S, has_shell_end),
        member!(S, pad),
        member!(S, image_circle),
        member!(S, shell_end),
        member!(S, shell_tip),
        member!(S, ambient_relief),
        member!(S, shell_glow),
        member!(S, blend_weights),
    ];
    let frame = vec![
        member!(F, texel_rect),
        member!(F, pixel_rect),
        member!(F, object_x),
        member!(F, object_y),
        member!(F, object_z),
        member!(F, origin),
        member!(F, object_kind),
        member!(F, grid_dims[0] as "grid_dims_x"),
        member!(F, grid_dims[1] as "grid_dims_y"),
        member!(F, grid_dims[2] as "grid_dims_z"),
        member!(F, grid_origin),
        member!(F, noise_seed),
        member!(F, image_origin[0] as "image_x"),
        member!(F, image_origin[1] as "image_y"),
        member!(F, image_pitch),
        member!(F, pressed_rect),
        member!(F, meridian_rect),
        member!(F, object_size),
        member!(F, lane),
        member!(F, image_at),
        member!(F, counters_at),
        member!(F, field_at),
        member!(F, listed_frames),
        member!(F, image_size[0] as "image_w"),
        member!(F, image_size[1] as "image_h"),
        member!(F, list_at),
        member!(F, group_base),
        member!(F, group_items),
    ];
    let source = geltip::gpu::shaders::compose("contact").unwrap();
    let module = naga::front::wgsl::parse_str(&source).unwrap();
    let mut failures = Vec::new();
    for (name, rust, size) in [
        ("Sensor", sensor, std::mem::size_of::<S>()),
        ("Frame", frame, std::mem::size_of::<F>()),
    ] {
        let (wgsl, span) = wgsl_struct(&module, name);
        if span != size {
            failures.push(format!("{name}: WGSL {span} bytes, Rust {size}"));
        }
        if wgsl != rust {
            failures.push(format!(
                "{name}: WGSL members (name, offset, size)\n  {wgsl:?}\nRust\n  {rust:?}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
