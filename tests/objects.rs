//! Objects: the built-in solids' SDFs against their own meshes, the WGSL twin, mesh loading
//! (OBJ, glTF, GLB) and its errors, placement, baking, and the generated assets.

use geltip::object::{dims, write_builtin_objects, Mesh, Object, SdfGrid, Solid};
use geltip::GeltipError;
use glam::DVec3;
use std::path::{Path, PathBuf};

const SHADER: &str = "shaders/shared/object.wgsl";
const VOXEL: f64 = 0.25;

/// Distance from `p` to the nearest triangle of `mesh`, by brute force.
fn brute_distance(mesh: &Mesh, p: DVec3) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            point_triangle_distance(p, a, b, c)
        })
        .fold(f64::INFINITY, f64::min)
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(self.next(), self.next(), self.next())
    }
}

/// A fresh, empty temporary folder for one test.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-objects-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The box around a solid (and 1.5 mm more) in which test points are drawn.
fn test_box(s: Solid) -> (DVec3, DVec3) {
    let f = s.footprint_radius() + 1.5;
    let depth = s.bounding_radius() + 1.5;
    (DVec3::new(-f, -f, -depth), DVec3::new(f, f, 1.5))
}

// ---------------------------------------------------------------------------------------
// Analytic SDFs against the meshes.

#[test]
fn analytic_sdf_agrees_with_sdf_baked_from_its_mesh() {
    let mut rng = Rng(11);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let grid = SdfGrid::bake(&mesh, VOXEL).unwrap();
        let (lo, hi) = test_box(s);
        let (mut checked, mut worst) = (0, 0.0f64);
        while checked < 3000 {
            let p = rng.in_box(lo, hi);
            let exact = s.sdf(p);
            if exact.abs() > 1.0 {
                continue;
            }
            checked += 1;
            let err = (grid.sample(p) - exact).abs();
            worst = worst.max(err);
            assert!(
                err < 1.5 * VOXEL,
                "{s}: at {p} analytic {exact} but baked {}",
                grid.sample(p)
            );
        }
        // Away from the sharp features the agreement is much better than the bound.
        println!("{s}: worst |baked - analytic| near the surface = {worst:.4} mm");
    }
}

#[test]
fn baked_voxels_hold_exact_distances_to_the_mesh_everywhere() {
    // Not just in the exact band: the sweeps must find the nearest triangle far away too.
    let mut rng = Rng(17);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let grid = SdfGrid::bake(&mesh, VOXEL).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..800 {
            let v = [0, 1, 2].map(|a| (rng.next() * f64::from(grid.dims[a])) as u32);
            let p = grid.voxel_centre(v[0], v[1], v[2]);
            let brute = brute_distance(&mesh, p);
            let got = f64::from(grid.values[grid.index(v[0], v[1], v[2])]);
            // Within the exact band (2 voxels) exact up to f32; beyond it the distance to
            // the nearest triangle the sweeps found: never less than the truth, and at most
            // a few micrometres more where many triangles compete (inside the sphere).
            let err = got.abs() - brute;
            worst = worst.max(err.abs());
            let tol = if brute <= 2.0 * VOXEL { 1e-5 } else { 0.02 };
            assert!(
                err > -1e-5 && err < tol,
                "{s}: voxel {v:?} at {p}: |{got}| but the mesh is {brute} away"
            );
            if brute > 0.05 {
                assert_eq!(got < 0.0, s.sdf(p) < 0.0, "{s}: voxel {v:?} at {p}: sign");
            }
        }
        println!("{s}: worst voxel error {worst:.2e} mm");
    }
}

#[test]
fn signs_at_known_inside_and_outside_points() {
    use Solid::*;
    let inside: [(Solid, [f64; 3]); 7] = [
        (Cone, [0.0, 0.0, -8.0]),
        (Sphere, [0.0, 0.0, -5.0]),
        (IrregularPrism, [0.0, 0.0, -5.0]),
        (Cylinder, [0.0, 0.0, -5.0]),
        (Edge, [0.0, 0.0, -4.0]),
        (Tube, [2.5, 0.0, -5.0]),
        (Slab, [0.0, 0.0, -1.5]),
    ];
    let outside: [(Solid, [f64; 3]); 7] = [
        (Cone, [4.0, 0.0, -2.0]),
        (Sphere, [4.0, 4.0, -1.0]),
        (IrregularPrism, [3.4, 3.2, -5.0]),
        (Cylinder, [2.5, 0.0, -5.0]),
        (Edge, [0.0, 2.5, -1.0]),
        (Tube, [0.0, 0.0, -5.0]),
        (Slab, [0.0, 0.0, -4.0]),
    ];
    for s in Solid::ALL {
        let grid = SdfGrid::bake(&s.mesh(), VOXEL).unwrap();
        let above = DVec3::new(0.0, 0.0, 1.0);
        assert!(s.sdf(above) > 0.9 && grid.sample(above) > 0.9, "{s}: above");
        for (t, p) in inside {
            if t == s {
                let p = DVec3::from(p);
                assert!(s.sdf(p) < -0.4, "{s}: {p} should be inside");
                assert!(grid.sample(p) < -0.4, "{s}: {p} should be inside the bake");
            }
        }
        for (t, p) in outside {
            if t == s {
                let p = DVec3::from(p);
                assert!(s.sdf(p) > 0.2, "{s}: {p} should be outside");
                assert!(grid.sample(p) > 0.2, "{s}: {p} should be outside the bake");
            }
        }
    }
}

#[test]
fn every_solid_touches_the_origin_from_below() {
    for s in Solid::ALL {
        let mesh = s.mesh();
        let max_z = mesh.positions.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        assert_eq!(max_z, 0.0, "{s}: mesh top");
        assert_eq!(mesh.top(), DVec3::ZERO, "{s}: the mesh's top is the origin");
        assert_eq!(mesh.placed_for_contact(), mesh, "{s}: already placed");
        let at_origin = s.sdf(DVec3::ZERO);
        if s == Solid::Tube {
            // A ring: the origin is the centre of the hole, the rim is at z = 0.
            assert_eq!(at_origin, dims::TUBE_INNER_RADIUS);
            assert_eq!(s.sdf(DVec3::new(2.5, 0.0, 0.0)), 0.0);
        } else {
            assert!(at_origin.abs() < 1e-12, "{s}: sdf(origin) = {at_origin}");
        }
        // Nothing of the solid is above z = 0.
        let mut rng = Rng(5);
        let (lo, hi) = test_box(s);
        for _ in 0..2000 {
            let p = rng.in_box(DVec3::new(lo.x, lo.y, 1e-3), hi);
            assert!(s.sdf(p) >= p.z - 1e-12, "{s}: {p}");
        }
    }
}

#[test]
fn analytic_sdfs_are_1_lipschitz() {
    let mut rng = Rng(23);
    for s in Solid::ALL {
        let (lo, hi) = test_box(s);
        for k in 0..20000 {
            let a = rng.in_box(lo, hi);
            // Half the pairs close together, where a kink in the field would show.
            let b = if k % 2 == 0 {
                a + (rng.in_box(DVec3::splat(-1.0), DVec3::splat(1.0))) * 0.05
            } else {
                rng.in_box(lo, hi)
            };
            let (da, db) = (s.sdf(a), s.sdf(b));
            assert!(
                (da - db).abs() <= (a - b).length() * (1.0 + 1e-9) + 1e-12,
                "{s}: |sdf({a}) - sdf({b})| = {} > {}",
                (da - db).abs(),
                (a - b).length()
            );
        }
    }
}

#[test]
fn analytic_sdfs_are_exact_distances_to_the_mesh_surface() {
    // Outside points: the SDF equals the distance to the (finely tessellated) mesh, up to
    // the tessellation's chord error. Brute force over all triangles.
    let mut rng = Rng(31);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let (lo, hi) = test_box(s);
        let mut n = 0;
        while n < 60 {
            let p = rng.in_box(lo, hi);
            let d = s.sdf(p);
            if d.abs() > 1.2 {
                continue;
            }
            n += 1;
            let brute = brute_distance(&mesh, p);
            // Chord error of 64 segments (and 32 rings) on radius 5: below 0.02 mm.
            assert!(
                (brute - d.abs()).abs() < 0.02,
                "{s}: at {p} |sdf| = {} but mesh distance {brute}",
                d.abs()
            );
        }
    }
}

/// Independent point-triangle distance for the brute-force test: the closest of the
/// interior projection (when it falls inside) and the three edges.
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let seg = |a: DVec3, b: DVec3| {
        let e = b - a;
        let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        (p - (a + e * t)).length()
    };
    let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let n = n.normalize();
        let q = p - n * (p - a).dot(n);
        let inside = (b - a).cross(q - a).dot(n) >= 0.0
            && (c - b).cross(q - b).dot(n) >= 0.0
            && (a - c).cross(q - c).dot(n) >= 0.0;
        if inside {
            best = best.min((p - q).length());
        }
    }
    best
}

// ---------------------------------------------------------------------------------------
// The WGSL twin.

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
    use geltip::gpu::shaders::create_compute_pipeline_from_source;
    use geltip::gpu::{read_buffer, GpuContext};
    use wgpu::util::DeviceExt;

    let ctx = GpuContext::shared().unwrap_or_else(|e| panic!("{e}"));
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
    // Points around every solid, half of them within 1 mm of its surface, plus an unknown id.
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
    let pipeline =
        create_compute_pipeline_from_source(ctx, "object-test.wgsl", &source, "main", None)
            .unwrap_or_else(|e| panic!("{e}"));
    let input = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("object test points"),
            contents: bytemuck::cast_slice(&points),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("object test sdf"),
        size: 4 * points.len() as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("object test"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("object test"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    ctx.submit_and_wait("object test", encoder)
        .unwrap_or_else(|e| panic!("{e}"));
    let got: Vec<f32> =
        read_buffer(ctx, &output, 0, points.len()).unwrap_or_else(|e| panic!("{e}"));
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

// ---------------------------------------------------------------------------------------
// Loading, writing, placing.

#[test]
fn obj_round_trips() {
    let dir = temp_dir("roundtrip");
    for s in Solid::ALL {
        let mesh = s.mesh();
        assert_eq!(mesh.compacted(), mesh, "{s}: mesh not in first-use order");
        let path = dir.join(format!("{}.obj", s.name()));
        mesh.write_obj(&path).unwrap();
        let back = Mesh::load(&path).unwrap();
        assert_eq!(back.triangles, mesh.triangles, "{s}");
        assert_eq!(back.positions.len(), mesh.positions.len(), "{s}");
        for (a, b) in back.positions.iter().zip(&mesh.positions) {
            // Six decimals in the file, f32 in the loader.
            assert!((*a - *b).abs().max_element() < 2e-6, "{s}: {a} vs {b}");
        }
        // Writing what was read gives the same file.
        let again = dir.join(format!("{}-again.obj", s.name()));
        back.write_obj(&again).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&again).unwrap(),
            "{s}"
        );
    }
    // Any mesh comes back compacted: unused vertices dropped, first-use order.
    let shuffled = Mesh {
        positions: vec![
            DVec3::new(9.0, 9.0, 9.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::ZERO,
            DVec3::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[3, 1, 2], [3, 2, 4], [3, 4, 1], [1, 4, 2]],
    };
    let path = dir.join("shuffled.obj");
    shuffled.write_obj(&path).unwrap();
    let back = Mesh::load(&path).unwrap();
    assert_eq!(back, shuffled.compacted());
    assert_eq!(back.positions.len(), 4);
    assert_eq!(back.positions[0], DVec3::ZERO);
    // No temporary file is left behind.
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(name.ends_with(".obj") && !name.starts_with('.'), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn obj_with_polygons_and_groups_is_triangulated() {
    let dir = temp_dir("quads");
    let path = dir.join("two.obj");
    std::fs::write(
        &path,
        "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
         o b\nv 0 0 1\nv 1 0 1\nv 1 1 1\nf 5 6 7\n",
    )
    .unwrap();
    let mesh = Mesh::load(&path).unwrap();
    assert_eq!(mesh.triangles.len(), 3);
    assert_eq!(mesh.positions.len(), 7);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF document for `mesh` (f32 positions, u32 indices): a parent node translated by
/// `parent_t` with a child node that holds the mesh, scaled by `child_scale`. With `glb`,
/// the buffer is the GLB's binary chunk; without, an embedded base64 data URI.
fn gltf_json(
    mesh: &Mesh,
    parent_t: [f64; 3],
    child_scale: [f64; 3],
    glb: bool,
) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &mesh.positions {
        for (k, v) in [p.x as f32, p.y as f32, p.z as f32].into_iter().enumerate() {
            bin.extend_from_slice(&v.to_le_bytes());
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    let pos_len = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let uri = if glb {
        String::new()
    } else {
        format!(
            r#","uri":"data:application/octet-stream;base64,{}""#,
            base64(&bin)
        )
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"translation":{pt:?},"children":[1]}},{{"mesh":0,"scale":{cs:?}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],
"buffers":[{{"byteLength":{len}{uri}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len},"target":34962}},
{{"buffer":0,"byteOffset":{pos_len},"byteLength":{idx_len},"target":34963}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{nv},"type":"VEC3","min":{lo:?},"max":{hi:?}}},
{{"bufferView":1,"componentType":5125,"count":{ni},"type":"SCALAR"}}]}}"#,
        pt = parent_t,
        cs = child_scale,
        len = bin.len(),
        idx_len = bin.len() - pos_len,
        nv = mesh.positions.len(),
        ni = 3 * mesh.triangles.len(),
    );
    (json, bin)
}

/// A binary glTF container around `json` and `bin`.
fn glb_bytes(json: &str, mut bin: Vec<u8>) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    out
}

fn assert_same_mesh_moved(loaded: &Mesh, mesh: &Mesh, offset: DVec3) {
    assert_eq!(loaded.triangles, mesh.triangles);
    assert_eq!(loaded.positions.len(), mesh.positions.len());
    for (a, b) in loaded.positions.iter().zip(&mesh.positions) {
        let want = b.as_vec3().as_dvec3() + offset;
        assert!((*a - want).abs().max_element() < 1e-9, "{a} vs {want}");
    }
}

#[test]
fn gltf_and_glb_load_with_node_transforms() {
    let dir = temp_dir("gltf");
    let mesh = Solid::IrregularPrism.mesh();
    let (json, _) = gltf_json(&mesh, [1.0, 2.0, 3.0], [1.0, 1.0, 1.0], false);
    let path = dir.join("prism.gltf");
    std::fs::write(&path, json).unwrap();
    let loaded = Mesh::load(&path).unwrap();
    assert_same_mesh_moved(&loaded, &mesh, DVec3::new(1.0, 2.0, 3.0));
    // Placed for contact, it is the solid again.
    assert_same_mesh_moved(&loaded.placed_for_contact(), &mesh, DVec3::ZERO);

    let (json, bin_chunk) = gltf_json(&mesh, [0.0, 0.0, -4.0], [1.0, 1.0, 1.0], true);
    let glb = dir.join("prism.GLB");
    std::fs::write(&glb, glb_bytes(&json, bin_chunk)).unwrap();
    assert_same_mesh_moved(
        &Mesh::load(&glb).unwrap(),
        &mesh,
        DVec3::new(0.0, 0.0, -4.0),
    );

    // A mirroring transform keeps the mesh wound outward.
    let (json, _) = gltf_json(&mesh, [0.0; 3], [1.0, 1.0, -1.0], false);
    let mirrored = dir.join("mirrored.gltf");
    std::fs::write(&mirrored, json).unwrap();
    let m = Mesh::load(&mirrored).unwrap();
    assert!(m.signed_volume() > 0.0);
    assert!((m.signed_volume() - mesh.signed_volume()).abs() < 1e-3);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Loads `file` (written with `contents` into a temp folder) and returns the InvalidMesh
/// reason, checking the message is one line and names the file.
fn invalid_reason(dir: &Path, file: &str, contents: Option<&[u8]>) -> String {
    let path = dir.join(file);
    if let Some(c) = contents {
        std::fs::write(&path, c).unwrap();
    }
    let err = Mesh::load(&path).expect_err(file);
    let text = err.to_string();
    assert!(!text.contains('\n'), "{file}: multi-line error: {text}");
    assert!(
        text.contains(file),
        "{file}: error does not name the file: {text}"
    );
    match err {
        GeltipError::InvalidMesh { reason, .. } => reason,
        other => panic!("{file}: not InvalidMesh: {other:?}"),
    }
}

#[test]
fn bad_meshes_give_one_line_errors_that_name_the_problem() {
    let dir = temp_dir("bad");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: Vec<(&str, Option<String>, &str)> = vec![
        ("missing.obj", None, "cannot read file"),
        (
            "mesh.stl",
            Some("solid x\n".into()),
            "unknown extension '.stl'",
        ),
        ("noext", Some(tri.into()), "no extension"),
        ("points.obj", Some(tri.into()), "no triangles"),
        (
            "lines.obj",
            Some(format!("{tri}l 1 2\nl 2 3\n")),
            "no triangles",
        ),
        ("empty.obj", Some(String::new()), "no triangles"),
        (
            "nan.obj",
            Some("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".into()),
            "vertex 0 is not finite",
        ),
        (
            "inf.obj",
            Some("v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n".into()),
            "vertex 1 is not finite",
        ),
        (
            "range.obj",
            Some(format!("{tri}f 1 2 9\n")),
            "index out of bounds",
        ),
        (
            "garbage.obj",
            Some("v 0 zero 0\n".into()),
            "cannot parse OBJ",
        ),
        ("bad.gltf", Some("{ not json".into()), "cannot parse glTF"),
        ("bad.glb", Some("glTF????".into()), "cannot parse glTF"),
    ];
    for (file, contents, want) in cases {
        let reason = invalid_reason(&dir, file, contents.as_deref().map(str::as_bytes));
        assert!(reason.contains(want), "{file}: '{reason}' lacks '{want}'");
    }

    // glTF: an index past the vertices, a NaN vertex, no triangle primitive.
    let mut m = Solid::Slab.mesh();
    m.triangles[3][1] = 99;
    let (json, _) = gltf_json(&m, [0.0; 3], [1.0; 3], false);
    let reason = invalid_reason(&dir, "range.gltf", Some(json.as_bytes()));
    assert!(
        reason.contains("vertex index 99 but has only 8 vertices"),
        "{reason}"
    );

    let mut m = Solid::Slab.mesh();
    m.positions[5].y = f64::NAN;
    let (json, bin) = gltf_json(&m, [0.0; 3], [1.0; 3], true);
    let json = json.replace("NaN", "0.0"); // keep the min/max JSON valid
    let reason = invalid_reason(&dir, "nan.glb", Some(&glb_bytes(&json, bin)));
    assert!(reason.contains("vertex 5 is not finite"), "{reason}");

    let (json, _) = gltf_json(&Solid::Slab.mesh(), [0.0; 3], [1.0; 3], false);
    let json = json.replace(r#""mode":4"#, r#""mode":1"#);
    let reason = invalid_reason(&dir, "lines.gltf", Some(json.as_bytes()));
    assert!(reason.contains("no triangles"), "{reason}");

    // A mesh far too big for the voxel size is refused by the bake, with the path.
    let big = Solid::Slab.mesh();
    let big = Mesh {
        positions: big.positions.iter().map(|p| *p * 10.0).collect(),
        triangles: big.triangles,
    };
    let path = dir.join("huge.obj");
    big.write_obj(&path).unwrap();
    let err = Object::from_arg(path.to_str().unwrap()).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, GeltipError::InvalidMesh { .. }), "{text}");
    assert!(
        text.contains("huge.obj") && text.contains("more than 256 per side"),
        "{text}"
    );
    assert!(!text.contains('\n'));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn placed_for_contact_puts_the_top_at_the_origin() {
    // A slab lying at an arbitrary place, top face at z = 7.
    let offset = DVec3::new(12.5, -3.0, 10.0);
    let slab = Solid::Slab.mesh().translated(offset);
    let placed = slab.placed_for_contact();
    assert_same_mesh_moved(&placed, &Solid::Slab.mesh(), DVec3::ZERO);
    // Only the vertices of the top count: a cone's apex, not its base's centre.
    let cone = Solid::Cone.mesh().translated(DVec3::new(1.0, 2.0, 3.0));
    assert!((cone.top() - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12);
    // Vertices within 1e-6 mm of the top count as top.
    let mut tri = Mesh {
        positions: vec![
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(4.0, 0.0, 1.0 - 5e-7),
            DVec3::new(0.0, 6.0, -3.0),
        ],
        triangles: vec![[0, 1, 2]],
    };
    assert_eq!(tri.top(), DVec3::new(2.0, 0.0, 1.0));
    tri.positions[1].z = 1.0 - 2e-6;
    assert_eq!(tri.top(), DVec3::new(0.0, 0.0, 1.0));
}

#[test]
fn objects_from_args() {
    for s in Solid::ALL {
        let o = Object::from_arg(s.name()).unwrap();
        assert_eq!(o.solid(), Some(s));
        assert_eq!(o.name(), s.name());
        assert_eq!(o.bounding_radius(), s.bounding_radius());
        assert_eq!(o.footprint_radius(), s.footprint_radius());
        let p = DVec3::new(0.3, -0.2, -1.0);
        assert_eq!(o.sdf(p), s.sdf(p));
    }
    let err = Object::from_arg("pyramid").unwrap_err().to_string();
    assert!(
        err.contains("pyramid") && err.contains("irregular-prism"),
        "{err}"
    );

    // A user mesh somewhere else in space is placed, baked and measured like the solid.
    let dir = temp_dir("from-arg");
    let path = dir.join("my-cone.obj");
    Solid::Cone
        .mesh()
        .translated(DVec3::new(20.0, -5.0, 30.0))
        .write_obj(&path)
        .unwrap();
    let o = Object::from_arg(path.to_str().unwrap()).unwrap();
    assert_eq!(o.name(), "my-cone");
    assert_eq!(o.solid(), None);
    assert!((o.bounding_radius() - Solid::Cone.bounding_radius()).abs() < 1e-4);
    assert!((o.footprint_radius() - Solid::Cone.footprint_radius()).abs() < 1e-4);
    let mut rng = Rng(41);
    let (lo, hi) = test_box(Solid::Cone);
    for _ in 0..500 {
        let p = rng.in_box(lo, hi);
        let d = Solid::Cone.sdf(p);
        if d.abs() < 1.0 {
            assert!((o.sdf(p) - d).abs() < 1.5 * VOXEL, "{p}");
        }
    }
    // Far outside the grid: positive and no more than the true distance.
    let far = DVec3::new(0.0, 40.0, -5.0);
    assert!(o.sdf(far) > 0.0 && o.sdf(far) <= Solid::Cone.sdf(far) + 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------
// Generated assets.

#[test]
fn builtin_object_assets_match_the_code() {
    let dir = temp_dir("assets");
    write_builtin_objects(&dir).unwrap();
    for s in Solid::ALL {
        let file = format!("{}.obj", s.name());
        let fresh = std::fs::read(dir.join(&file)).unwrap();
        let committed =
            std::fs::read(repo_path("assets/objects").join(&file)).unwrap_or_else(|e| {
                panic!(
                    "assets/objects/{file}: {e}; regenerate with \
                 `cargo test --test objects -- --ignored regenerate_builtin_object_assets`"
                )
            });
        assert!(
            fresh == committed,
            "assets/objects/{file} differs from what the code generates; regenerate with \
             `cargo test --test objects -- --ignored regenerate_builtin_object_assets`"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes `assets/objects/*.obj` from the code. Run on purpose only.
#[test]
#[ignore = "writes into assets/objects"]
fn regenerate_builtin_object_assets() {
    write_builtin_objects(&repo_path("assets/objects")).unwrap();
}

/// Prints bake timings (run with `--ignored --nocapture`, ideally `--release`).
#[test]
#[ignore = "timing report"]
fn bake_timings() {
    for s in Solid::ALL {
        let mesh = s.mesh();
        for voxel in [0.5, 0.25, 0.125] {
            let t = std::time::Instant::now();
            let grid = SdfGrid::bake(&mesh, voxel).unwrap();
            println!(
                "{s:>16}: {:5} triangles, voxel {voxel:5} mm, grid {:?} = {:8} voxels: {:7.1} ms",
                mesh.triangles.len(),
                grid.dims,
                grid.values.len(),
                t.elapsed().as_secs_f64() * 1e3
            );
        }
    }
}
