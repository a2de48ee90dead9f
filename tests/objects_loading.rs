//! Mesh loading (OBJ, glTF, GLB) and its errors, writing, placement, and objects from
//! command-line arguments.

mod object_support;

use geltip::object::{Mesh, Object, Solid};
use geltip::GeltipError;
use glam::DVec3;
use object_support::gltf::{glb_bytes, gltf_json};
use object_support::*;
use std::path::Path;

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
    bad_files_are_refused(&dir);
    bad_gltf_is_refused(&dir);
    a_mesh_too_big_to_bake_is_refused(&dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Missing, unknown, empty, non-finite and unparsable files, each refused with its reason.
fn bad_files_are_refused(dir: &Path) {
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
        let reason = invalid_reason(dir, file, contents.as_deref().map(str::as_bytes));
        assert!(reason.contains(want), "{file}: '{reason}' lacks '{want}'");
    }
}

/// glTF: an index past the vertices, a NaN vertex, no triangle primitive.
fn bad_gltf_is_refused(dir: &Path) {
    let mut m = Solid::Slab.mesh();
    m.triangles[3][1] = 99;
    let (json, _) = gltf_json(&m, [0.0; 3], [1.0; 3], false);
    let reason = invalid_reason(dir, "range.gltf", Some(json.as_bytes()));
    assert!(
        reason.contains("vertex index 99 but has only 8 vertices"),
        "{reason}"
    );

    let mut m = Solid::Slab.mesh();
    m.positions[5].y = f64::NAN;
    let (json, bin) = gltf_json(&m, [0.0; 3], [1.0; 3], true);
    let json = json.replace("NaN", "0.0"); // keep the min/max JSON valid
    let reason = invalid_reason(dir, "nan.glb", Some(&glb_bytes(&json, bin)));
    assert!(reason.contains("vertex 5 is not finite"), "{reason}");

    let (json, _) = gltf_json(&Solid::Slab.mesh(), [0.0; 3], [1.0; 3], false);
    let json = json.replace(r#""mode":4"#, r#""mode":1"#);
    let reason = invalid_reason(dir, "lines.gltf", Some(json.as_bytes()));
    assert!(reason.contains("no triangles"), "{reason}");
}

/// glTF files the gltf crate's reader panics on (in a build with overflow checks) or
/// misreads: each refused with a one-line reason instead.
#[test]
fn gltf_the_reader_cannot_take_is_refused() {
    let dir = temp_dir("reader");
    let (json, _) = gltf_json(&Solid::Slab.mesh(), [0.0; 3], [1.0; 3], false);
    let cases = [
        (
            r#""componentType":5125,"count":36"#,
            r#""componentType":5126,"count":36"#,
            "indices are Scalar of F32",
        ),
        (
            r#""count":8,"type":"VEC3""#,
            r#""count":8,"type":"SCALAR""#,
            "positions are Scalar of F32",
        ),
        (
            r#""count":8,"type":"VEC3""#,
            r#""count":0,"type":"VEC3""#,
            "has no positions",
        ),
        (
            r#""count":8,"type":"VEC3""#,
            r#""count":4294967295,"type":"VEC3""#,
            "positions (4294967295 of 12 bytes",
        ),
        (
            r#""byteOffset":0,"byteLength":96"#,
            r#""byteOffset":18446744073709551615,"byteLength":96"#,
            "",
        ),
        (
            r#"{"mesh":0,"scale""#,
            r#"{"mesh":0,"children":[0],"scale""#,
            "reached twice",
        ),
        (
            r#""POSITION":0"#,
            r#""POSITION":7"#,
            "names accessor 7 of 2",
        ),
    ];
    for (k, (from, to, says)) in cases.into_iter().enumerate() {
        assert!(json.contains(from), "{from}");
        let bad = json.replacen(from, to, 1);
        let reason = invalid_reason(&dir, &format!("reader{k}.gltf"), Some(bad.as_bytes()));
        assert!(reason.contains(says), "{to}: {reason}");
    }
    let mut glb = glb_bytes(&json, Vec::new());
    glb[8..12].copy_from_slice(&4u32.to_le_bytes());
    let reason = invalid_reason(&dir, "short.glb", Some(&glb));
    assert!(
        reason.contains("declares a length shorter than itself"),
        "{reason}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mesh far too big for the voxel size is refused by the bake, with the path.
fn a_mesh_too_big_to_bake_is_refused(dir: &Path) {
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

/// Every preset takes a loaded mesh pressed as deep as its gel is thick and tilted (the
/// contact stage then traces the whole gel grown by the skin's drape): the mesh's baked
/// distances reach that far, the `allsight` preset's 3.5 mm gel included.
#[test]
fn every_preset_takes_a_mesh_pressed_through_its_gel() {
    use geltip::render::{Hold, Place, Press};
    use geltip::sensor::{Sensor, PRESETS};
    use std::sync::Arc;
    let dir = temp_dir("mesh-reach");
    let path = dir.join("sphere.obj");
    Solid::Sphere.mesh().write_obj(&path).unwrap();
    let object = Arc::new(Object::from_arg(path.to_str().unwrap()).unwrap());
    for (name, _) in PRESETS {
        let sensor = Sensor::preset(name).unwrap();
        let gel = sensor.finger.shell_thickness;
        let need = gel + 0.5 + sensor.config.elastomer.drape_mm;
        assert!(
            object.exact_reach_mm() >= need,
            "{name}: the mesh is exact {} mm out, the press needs {need}",
            object.exact_reach_mm()
        );
        let mut press = Press::at(object.clone(), Place::Rotation(60.0), 30.0, gel);
        if let Hold::Surface { tilt_deg, .. } = &mut press.hold {
            *tilt_deg = 20.0;
        }
        let pose = press
            .pose(&sensor)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(pose.trace_depth_mm + sensor.config.elastomer.drape_mm <= object.exact_reach_mm());
    }
}
