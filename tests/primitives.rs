//! Sized primitives (`geltip::object::primitive`): their WGSL twin (constants and SDFs on
//! the GPU against Rust), renders on the GPU against the CPU mirror and against the built-in
//! solids of the same sizes, first touch, rigid poses along an approach, and bad sizes.

mod common;
mod object_support;
mod support;

use geltip::gpu::GpuContext;
use geltip::object::primitive::FIRST_PRIMITIVE_KIND;
use geltip::object::{Object, Primitive, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{cpu, Hold, Place, Press};
use geltip::sensor::Sensor;
use glam::{DMat3, DVec3};
use object_support::{compute_f32, repo_path, Rng};
use std::sync::Arc;
use support::{close_enough, diff, rgb, small_sensor};

const SHADER: &str = "shaders/shared/object.wgsl";

fn primitive(text: &str) -> Arc<Object> {
    Arc::new(Object::from_arg(text).unwrap_or_else(|e| panic!("{text}: {e}")))
}

fn shape(text: &str) -> Primitive {
    match *primitive(text) {
        Object::Primitive { shape, .. } => shape,
        _ => panic!("{text}: not a primitive"),
    }
}

/// One of each kind, and an ellipsoid with its axes in another order.
const SHAPES: [&str; 6] = [
    "sphere:r=4",
    "capsule:r=2,l=6",
    "cylinder:r=2.5,l=8",
    "box:x=9,y=5,z=3",
    "ellipsoid:x=8,y=5,z=4",
    "ellipsoid:x=4,y=7,z=9",
];

#[test]
fn wgsl_kinds_equal_the_rust_kinds() {
    let source = std::fs::read_to_string(repo_path(SHADER)).unwrap();
    for (k, name) in Primitive::NAMES.iter().enumerate() {
        let line = format!(
            "const OBJ_PRIMITIVE_{}: u32 = {}u;",
            name.to_uppercase(),
            FIRST_PRIMITIVE_KIND + k as u32
        );
        assert!(source.contains(&line), "{SHADER} lacks `{line}`");
    }
    for text in SHAPES {
        let p = shape(text);
        assert_eq!(
            Primitive::NAMES[(p.kind() - FIRST_PRIMITIVE_KIND) as usize],
            p.name()
        );
    }
    // The kinds lie between the built-in solids' ids and the mesh grid's.
    let last = FIRST_PRIMITIVE_KIND + Primitive::NAMES.len() as u32;
    assert!(Solid::ALL
        .iter()
        .chain(&Solid::EXTRA)
        .all(|s| s.id() < FIRST_PRIMITIVE_KIND));
    assert!(last <= geltip::render::uniforms::GRID_OBJECT);
}

/// `primitive_sdf` in WGSL against `Primitive::sdf`, on the GPU, at points within 2 mm of
/// each surface (how far out the skin's drape traces) and inside.
#[test]
fn wgsl_primitive_sdf_matches_rust_on_the_gpu() {
    let ctx = GpuContext::shared().unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Rng(5);
    let mut points = Vec::new();
    for (k, text) in SHAPES.iter().enumerate() {
        let p = shape(text);
        let r = p.bounding_radius() + 2.0;
        let mut n = 0;
        while n < 2048 {
            let q = rng.in_box(DVec3::new(-r, -r, -r), DVec3::new(r, r, 2.0));
            if p.sdf(q) > 2.0 {
                continue;
            }
            n += 1;
            points.push((k, q));
        }
        // On the axes and the planes of symmetry on purpose (the ellipsoid's special cases).
        for q in [
            DVec3::new(0.0, 0.0, -p.top()),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, -p.top()),
            DVec3::new(0.0, 1.5, -p.top()),
            DVec3::new(0.3, 0.2, -p.top()),
            DVec3::new(0.0, 0.7, -p.top() + 0.4),
        ] {
            points.push((k, q));
        }
    }
    let got = wgsl_sdf(ctx, &points);
    let mut worst = 0.0f64;
    for ((k, q), g) in points.iter().zip(&got) {
        let want = shape(SHAPES[*k]).sdf(*q);
        let err = (f64::from(*g) - want).abs();
        worst = worst.max(err);
        assert!(err < 1e-4, "{} at {q}: WGSL {g}, Rust {want}", SHAPES[*k]);
    }
    println!(
        "WGSL vs Rust over {} points: worst {worst:.2e} mm",
        points.len()
    );
}

/// `primitive_sdf` of each point, evaluated by the WGSL on the GPU.
fn wgsl_sdf(ctx: &GpuContext, points: &[(usize, DVec3)]) -> Vec<f32> {
    let source = std::fs::read_to_string(repo_path(SHADER)).unwrap();
    let source = format!(
        "{source}\n\
         struct PrimTest {{ q: vec4<f32>, kind: vec4<u32>, size: vec4<f32> }}\n\
         @group(0) @binding(0) var<storage, read> prim_in: array<PrimTest>;\n\
         @group(0) @binding(1) var<storage, read_write> prim_out: array<f32>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
             if gid.x < arrayLength(&prim_out) {{\n\
                 let t = prim_in[gid.x];\n\
                 prim_out[gid.x] = primitive_sdf(t.kind.x, t.size, t.q.xyz);\n\
             }}\n\
         }}\n"
    );
    let mut input: Vec<u32> = Vec::new();
    for (k, q) in points {
        let p = shape(SHAPES[*k]);
        let q = [q.x as f32, q.y as f32, q.z as f32, 0.0];
        input.extend(q.map(f32::to_bits));
        input.extend([p.kind(), 0, 0, 0]);
        input.extend(p.gpu_size().map(f32::to_bits));
    }
    compute_f32(
        ctx,
        "primitive",
        &source,
        bytemuck::cast_slice(&input),
        points.len(),
    )
}

/// Each kind rendered on the GPU against the CPU mirror of every stage, within the one
/// image tolerance; and a primitive 0.3 mm bigger is outside it (the comparison can fail).
#[test]
fn gpu_renders_primitives_as_the_cpu_mirror_does() {
    let sensor = small_sensor();
    let mut r = Renderer::new(&sensor).unwrap();
    for (text, place) in [
        ("sphere:r=4", Place::Rotation(30.0)),
        ("capsule:r=2,l=6", Place::Rotation(0.0)),
        ("cylinder:r=2.5,l=8", Place::Translation(4.0)),
        ("box:x=9,y=5,z=3", Place::Rotation(60.0)),
        ("ellipsoid:x=8,y=5,z=4", Place::Translation(2.0)),
    ] {
        let press = Press::at(primitive(text), place, 30.0, 1.0).spun(20.0);
        let (gpu, truth) = r.render(&press).unwrap();
        let cpu = cpu::render(&sensor, Some(&press)).unwrap();
        let d = diff(&rgb(&gpu), &rgb(&cpu.frame), 3);
        assert!(close_enough(&d), "{text} at {place:?}: {d:?}");
        assert!(
            cpu.frame.indentation.iter().any(|&d| d > 0.2),
            "{text}: no imprint"
        );
        assert!(
            truth.mask_pixels > 50,
            "{text}: {} pixels",
            truth.mask_pixels
        );
        assert_eq!(truth.object, text);
        // Perturbed: the same contact 1 mm further from the tip fails the comparison.
        let moved = Place::ArcLength(place.arc_length(&sensor) + 1.0);
        let other = Press::at(primitive(text), moved, 30.0, 1.0).spun(20.0);
        let (moved, _) = r.render(&other).unwrap();
        let d = diff(&rgb(&moved), &rgb(&cpu.frame), 3);
        assert!(!close_enough(&d), "{text} moved 1 mm passes: {d:?}");
    }
}

/// A primitive of a built-in solid's sizes renders its very bytes (the same SDF in f32, in a
/// pipeline of its own).
#[test]
fn primitives_of_builtin_sizes_render_the_builtin_bytes() {
    let sensor = Sensor::preset("paper").unwrap();
    let mut r = Renderer::new(&sensor).unwrap();
    for (solid, text) in [
        (Solid::Sphere, "sphere:r=5"),
        (Solid::Slab, "box:x=10,y=6,z=3"),
        (Solid::Cylinder, "cylinder:r=2,l=10"),
    ] {
        for (place, spin) in [
            (Place::Rotation(45.0), 0.0),
            (Place::Translation(6.0), 35.0),
        ] {
            let a = Press::at(Arc::new(Object::Solid(solid)), place, 120.0, 1.0).spun(spin);
            let b = Press::at(primitive(text), place, 120.0, 1.0).spun(spin);
            let (fa, ta) = r.render(&a).unwrap();
            let (fb, tb) = r.render(&b).unwrap();
            assert!(
                fa.rgba == fb.rgba,
                "{text} at {place:?} differs from the {solid}"
            );
            assert_eq!(ta.pose, tb.pose);
            assert_eq!(ta.contact_centre, tb.contact_centre);
        }
    }
}

/// Every primitive lies below the tangent plane at its top (its body in z <= 0) and the
/// finger is convex: held at a place, each first touches at its top, offset 0.
#[test]
fn first_touch_of_primitives_is_at_their_top() {
    let sensor = Sensor::preset("paper").unwrap();
    for text in SHAPES {
        for place in [
            Place::Rotation(0.0),
            Place::Rotation(50.0),
            Place::Translation(7.0),
        ] {
            let pose = Press::at(primitive(text), place, 75.0, 0.8)
                .pose(&sensor)
                .unwrap_or_else(|e| panic!("{text} at {place:?}: {e}"));
            assert_eq!(pose.first_touch_offset_mm, 0.0, "{text} at {place:?}");
            assert_eq!(pose.origin, pose.point - 0.8 * pose.normal);
        }
    }
}

/// A rigid pose measures its depth along its approach: a sphere held beside the cylinder,
/// its own axes along the camera's, pressed `depth` mm in along -x.
#[test]
fn rigid_poses_measure_depth_along_their_approach() {
    let sensor = Sensor::preset("paper").unwrap();
    let r_f = sensor.finger.radius;
    let ball = primitive("sphere:r=5");
    let posed = |depth: f64, approach: Option<DVec3>| {
        // The centre 5 mm beyond the surface less the depth; the top (origin) 5 mm above it
        // along the object's +z, which is the camera's +z here.
        let centre = DVec3::new(r_f + 5.0 - depth, 0.0, 10.0);
        Press {
            object: ball.clone(),
            hold: Hold::Pose {
                world_from_object: DMat3::IDENTITY,
                origin: centre + DVec3::new(0.0, 0.0, 5.0),
                approach,
            },
        }
    };
    for depth in [0.3, 1.0, 1.4] {
        let pose = posed(depth, Some(-DVec3::X)).pose(&sensor).unwrap();
        assert!(
            (pose.depth_mm - depth).abs() < 1e-6,
            "{depth}: {}",
            pose.depth_mm
        );
        assert!((pose.point - DVec3::new(r_f, 0.0, 10.0)).length() < 1e-3);
        // Backing off along its own +z instead is not the penetration: that is what the
        // approach is for.
        let along_z = posed(depth, None).pose_if_touching(&sensor);
        if let Ok(Some(p)) = along_z {
            assert!((p.depth_mm - depth).abs() > 0.1, "{depth}: {}", p.depth_mm);
        }
    }
    // Short of touching: an error for a pose, nothing for pose_if_touching.
    let short = posed(-0.5, Some(-DVec3::X));
    let e = short.pose(&sensor).unwrap_err().to_string();
    assert!(
        e.contains("0.500 mm short of touching along its approach"),
        "{e}"
    );
    assert!(short.pose_if_touching(&sensor).unwrap().is_none());
    // Beside the finger, moving parallel to its axis: never touches.
    let beside = posed(-20.0, Some(DVec3::Z));
    assert!(beside.pose_if_touching(&sensor).unwrap().is_none());
    let e = beside.pose(&sensor).unwrap_err().to_string();
    assert!(e.contains("nor would it moving along its approach"), "{e}");
    // Facing away, it would have come through the finger from the far side: not a
    // contact that skips, an error saying so.
    let e = posed(-0.5, Some(DVec3::X))
        .pose_if_touching(&sensor)
        .unwrap_err();
    assert!(e.to_string().contains("has gone through"), "{e}");
}

/// An approach is three numbers with a direction, given with a pose: otherwise an error
/// that names the field.
#[test]
fn bad_approaches_name_the_field() {
    let spec = |json: &str| -> geltip::Result<Hold> {
        serde_json::from_str::<geltip::scene::ContactSpec>(json)
            .unwrap()
            .hold()
    };
    let pose = "\"pose\": [0, 0, 30, 1, 0, 0, 0]";
    assert!(spec(&format!(
        "{{\"object\": \"sphere\", {pose}, \"approach\": [0, 0, -2]}}"
    ))
    .is_ok());
    for (json, says) in [
        (
            format!("{{\"object\": \"sphere\", {pose}, \"approach\": [0, 0]}}"),
            "approach: expected 3 numbers",
        ),
        (
            format!("{{\"object\": \"sphere\", {pose}, \"approach\": [0, 0, 0]}}"),
            "approach: [0, 0, 0] has no direction",
        ),
        (
            "{\"object\": \"sphere\", \"at\": \"s=1\", \"depth\": 1, \"approach\": [0, 0, 1]}"
                .to_string(),
            "approach: is for a pose",
        ),
    ] {
        let e = spec(&json).unwrap_err().to_string();
        assert!(e.starts_with(says), "{json}: {e}");
    }
}

/// A mesh made in memory is placed and baked exactly as the same vertices loaded from a file.
#[test]
fn a_mesh_in_memory_equals_its_file() {
    let path = repo_path("assets/objects/irregular-prism.obj");
    let from_file = Object::from_arg(path.to_str().unwrap()).unwrap();
    let mesh = geltip::object::Mesh::load(&path).unwrap();
    let (in_memory, top) = Object::from_mesh("prism", mesh.clone()).unwrap();
    assert_eq!(top, mesh.top());
    match (&from_file, &in_memory) {
        (
            Object::Mesh {
                mesh: a, grid: ga, ..
            },
            Object::Mesh {
                mesh: b,
                grid: gb,
                name,
            },
        ) => {
            assert_eq!(a, b);
            assert!(ga.values == gb.values && ga.origin == gb.origin && ga.dims == gb.dims);
            assert_eq!(name, "prism");
        }
        _ => panic!("not meshes"),
    }
    let bad = geltip::object::Mesh {
        positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)],
        triangles: vec![[0, 1, 2]],
    };
    let e = Object::from_mesh("bad", bad).unwrap_err().to_string();
    assert_eq!(e, "mesh 'bad': vertex 2 is not finite (NaN, 0, 0)");
    let e = Object::from_mesh("none", geltip::object::Mesh::default())
        .unwrap_err()
        .to_string();
    assert_eq!(e, "mesh 'none': no triangles");
}

/// Bad sizes and unknown keys are one-line errors naming them, through the object argument
/// every front end uses.
#[test]
fn bad_primitives_are_refused_naming_what_is_wrong() {
    for (text, says) in [
        (
            "box:x=10,y=6",
            "object 'box:x=10,y=6': a box needs x, y, z (its edge lengths, mm); z is missing",
        ),
        (
            "sphere:r=0",
            "object 'sphere:r=0': r must be a size from 0.001 to 10000 mm, got 0",
        ),
        (
            "capsule:r=2,l=-1",
            "object 'capsule:r=2,l=-1': l must be a size from 0.001 to 10000 mm, got -1",
        ),
        (
            "cylinder:r=2,h=3",
            "object 'cylinder:r=2,h=3': unknown size 'h' for a cylinder (it takes r, l)",
        ),
        (
            "ellipsoid:x=1,y=nan,z=1",
            "object 'ellipsoid:x=1,y=nan,z=1': y must be a size from 0.001 to 10000 mm, got NaN",
        ),
    ] {
        let e = Object::from_arg(text).unwrap_err().to_string();
        assert_eq!(e, says, "{text}");
    }
    let e = Object::from_arg("pyramid:h=2").unwrap_err().to_string();
    assert!(
        e.contains("a primitive (sphere:r=5, capsule:r=2,l=8"),
        "{e}"
    );
}
