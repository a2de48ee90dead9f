//! The solids' WGSL twin (shaders/shared/object.wgsl): it validates, its constants equal the
//! Rust dimensions, and its SDFs match the Rust ones on the GPU.

mod object_support;

use geltip::gpu::GpuContext;
use geltip::object::{dims, Solid};
use glam::DVec3;
use object_support::*;

const SHADER: &str = "shaders/shared/object.wgsl";

fn parse_shader() -> (String, naga::Module) {
    let source = std::fs::read_to_string(repo_path(SHADER)).unwrap();
    // An entry point that calls solid_sdf, so the whole file is reachable.
    let full = format!(
        "{source}\n\
         @group(0) @binding(0) var<storage, read_write> obj_test_out: array<f32>;\n\
         @compute @workgroup_size(64)\n\
         fn obj_test_main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
             let p = vec3<f32>(f32(gid.x) * 0.1 - 5.0, f32(gid.y) * 0.1 - 5.0, -1.0);\n\
             obj_test_out[gid.x] = solid_sdf(gid.y % 7u, p);\n\
         }}\n"
    );
    let module = match naga::front::wgsl::parse_str(&full) {
        Ok(m) => m,
        Err(e) => panic!("{SHADER} does not parse:\n{}", e.emit_to_string(&full)),
    };
    (full, module)
}

#[test]
fn object_wgsl_validates_with_naga() {
    let (full, module) = parse_shader();
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    if let Err(e) = validator.validate(&module) {
        panic!("{SHADER} does not validate:\n{}", e.emit_to_string(&full));
    }
    assert!(module
        .functions
        .iter()
        .any(|(_, f)| f.name.as_deref() == Some("solid_sdf")));
    // No bindings in the shared file itself: the only global is the test's.
    assert_eq!(module.global_variables.len(), 1);
}

/// The numbers a constant expression holds, flattened (vectors and arrays in order).
fn flatten(module: &naga::Module, h: naga::Handle<naga::Expression>) -> Vec<f64> {
    use naga::{Expression as E, Literal as L};
    match &module.global_expressions[h] {
        E::Literal(L::F32(v)) => vec![f64::from(*v)],
        E::Literal(L::U32(v)) => vec![f64::from(*v)],
        E::Compose { components, .. } => components
            .iter()
            .flat_map(|&c| flatten(module, c))
            .collect(),
        E::Constant(c) => flatten(module, module.constants[*c].init),
        other => panic!("unexpected constant expression {other:?}"),
    }
}

#[test]
fn wgsl_constants_equal_the_rust_dimensions() {
    use dims::*;
    let expected: Vec<(&str, Vec<f64>)> = vec![
        ("CONE_RADIUS", vec![CONE_RADIUS]),
        ("CONE_HEIGHT", vec![CONE_HEIGHT]),
        ("SPHERE_RADIUS", vec![SPHERE_RADIUS]),
        ("PRISM_HEIGHT", vec![PRISM_HEIGHT]),
        (
            "PRISM_PENTAGON",
            PRISM_PENTAGON.iter().flatten().copied().collect(),
        ),
        ("CYLINDER_RADIUS", vec![CYLINDER_RADIUS]),
        ("CYLINDER_HEIGHT", vec![CYLINDER_HEIGHT]),
        ("EDGE_LENGTH", vec![EDGE_LENGTH]),
        ("EDGE_WIDTH", vec![EDGE_WIDTH]),
        ("EDGE_HEIGHT", vec![EDGE_HEIGHT]),
        ("TUBE_OUTER_RADIUS", vec![TUBE_OUTER_RADIUS]),
        ("TUBE_INNER_RADIUS", vec![TUBE_INNER_RADIUS]),
        ("TUBE_HEIGHT", vec![TUBE_HEIGHT]),
        ("SLAB_X", vec![SLAB_X]),
        ("SLAB_Y", vec![SLAB_Y]),
        ("SLAB_Z", vec![SLAB_Z]),
        ("TORUS_MAJOR_RADIUS", vec![TORUS_MAJOR_RADIUS]),
        ("TORUS_MINOR_RADIUS", vec![TORUS_MINOR_RADIUS]),
        ("DISC_RADIUS", vec![DISC_RADIUS]),
        ("DISC_THICKNESS", vec![DISC_THICKNESS]),
    ];
    let (_, module) = parse_shader();
    let mut found = std::collections::BTreeMap::new();
    for (_, c) in module.constants.iter() {
        if let Some(name) = c.name.as_deref().and_then(|n| n.strip_prefix("OBJ_")) {
            found.insert(name.to_string(), flatten(&module, c.init));
        }
    }
    for (name, values) in &expected {
        let got = found
            .remove(*name)
            .unwrap_or_else(|| panic!("{SHADER} lacks OBJ_{name}"));
        let want: Vec<f64> = values.iter().map(|&v| f64::from(v as f32)).collect();
        assert_eq!(got, want, "OBJ_{name} differs from dims::{name}");
    }
    for s in Solid::ALL.into_iter().chain(Solid::EXTRA) {
        let name = format!("SOLID_{}", s.name().to_uppercase().replace('-', "_"));
        let got = found
            .remove(&name)
            .unwrap_or_else(|| panic!("{SHADER} lacks OBJ_{name}"));
        assert_eq!(got, vec![f64::from(s.id())], "OBJ_{name} != Solid::id");
    }
    found.remove("FAR");
    // The sized primitives' kinds and the ellipsoid's steps: tests/primitives.rs.
    found.retain(|name, _| !name.starts_with("PRIMITIVE_") && name != "ELLIPSOID_MAX_STEPS");
    assert!(
        found.is_empty(),
        "WGSL constants without a Rust twin: {:?}",
        found.keys().collect::<Vec<_>>()
    );
}

/// `solid_sdf` in WGSL against `Solid::sdf` in Rust, on the GPU (lavapipe in CI; like
/// tests/gpu.rs, this fails without an adapter).
#[test]
fn wgsl_solid_sdf_matches_rust_on_the_gpu() {
    let ctx = GpuContext::shared().unwrap_or_else(|e| panic!("{e}"));
    let points = points_around_solids();
    let got = wgsl_solid_sdf(ctx, &points);
    let mut worst = 0.0f64;
    for (q, g) in points.iter().zip(&got) {
        let p = DVec3::new(q[0].into(), q[1].into(), q[2].into());
        let Some(s) = Solid::from_id(q[3] as u32) else {
            assert!(*g > 1e29, "unknown id: {g}");
            continue;
        };
        let want = s.sdf(p);
        worst = worst.max((f64::from(*g) - want).abs());
        assert!(
            (f64::from(*g) - want).abs() < 1e-4,
            "{s} at {p}: WGSL {g}, Rust {want}"
        );
    }
    println!(
        "WGSL vs Rust over {} points on {}: worst {worst:.2e} mm",
        points.len(),
        ctx.adapter_info.name
    );
}

/// Points (x, y, z, solid id) around every solid, half of them within 1 mm of its surface,
/// plus one with an unknown id.
fn points_around_solids() -> Vec<[f32; 4]> {
    let mut rng = Rng(77);
    let mut points: Vec<[f32; 4]> = Vec::new();
    for s in Solid::ALL {
        let (lo, hi) = test_box(s);
        let mut n = 0;
        while n < 2048 {
            let p = rng.in_box(lo, hi);
            if n % 2 == 0 && s.sdf(p).abs() > 1.0 {
                continue;
            }
            n += 1;
            points.push([p.x as f32, p.y as f32, p.z as f32, s.id() as f32]);
        }
    }
    points.push([0.0, 0.0, 0.0, 7.0]);
    points
}

/// `solid_sdf` of each point, evaluated by the WGSL on the GPU.
fn wgsl_solid_sdf(ctx: &GpuContext, points: &[[f32; 4]]) -> Vec<f32> {
    let source = std::fs::read_to_string(repo_path(SHADER)).unwrap();
    let source = format!(
        "{source}\n\
         @group(0) @binding(0) var<storage, read> obj_in: array<vec4<f32>>;\n\
         @group(0) @binding(1) var<storage, read_write> obj_out: array<f32>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
             if gid.x < arrayLength(&obj_out) {{\n\
                 let q = obj_in[gid.x];\n\
                 obj_out[gid.x] = solid_sdf(u32(q.w), q.xyz);\n\
             }}\n\
         }}\n"
    );
    compute_f32(
        ctx,
        "object",
        &source,
        bytemuck::cast_slice(points),
        points.len(),
    )
}
