//! Contact scenes: several objects in one frame, rigid poses against at/spin/tilt, the
//! labels' fields, and contacts that cannot touch or cannot be seen.

mod presses;

use geltip::object::{Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{contact, Frame, GroundTruth, Hold, Place, Press};
use geltip::sensor::Sensor;
use glam::DVec3;
use presses::*;
use std::sync::Arc;

fn px(f: &Frame, i: usize) -> &[u8] {
    &f.rgba[4 * i..4 * i + 4]
}

/// Two spheres at once: two imprints, two labels, each pixel away from the other's imprint
/// identical to the single render; overlapping presses keep the deepest.
#[test]
fn two_spheres_render_as_two_imprints() {
    let mut r = paper();
    let reference = r.reference().clone();
    let a = press(Solid::Sphere, Place::Rotation(30.0), 0.0, 1.0);
    let b = press(Solid::Sphere, Place::Translation(8.0), 180.0, 0.8);
    let (fa, ta) = render_one(&mut r, &a);
    let (fb, tb) = render_one(&mut r, &b);
    let (scene, truths) = r.render_scene(&[a.clone(), b.clone()]).unwrap();
    assert_eq!(truths.len(), 2);
    assert_eq!(truths[0].contact_centre, ta.contact_centre);
    assert_eq!(truths[1].contact_centre, tb.contact_centre);
    assert_eq!(truths[0].mask_pixels, ta.mask_pixels);
    assert_eq!(truths[1].mask_pixels, tb.mask_pixels);
    let (mut only_a, mut only_b) = (0, 0);
    for i in 0..(scene.width * scene.height) as usize {
        let (in_a, in_b) = (
            px(&fa, i) != px(&reference, i),
            px(&fb, i) != px(&reference, i),
        );
        assert!(!(in_a && in_b), "the imprints should not overlap here");
        let want = if in_a { px(&fa, i) } else { px(&fb, i) };
        assert!(px(&scene, i) == want, "pixel {i}");
        let want = if fa.indentation[i] != 0.0 {
            fa.indentation[i]
        } else {
            fb.indentation[i]
        };
        assert!(scene.indentation[i] == want, "pixel {i}");
        only_a += in_a as u32;
        only_b += in_b as u32;
    }
    assert!(only_a > 1000 && only_b > 1000);
    assert_eq!(scene.mask().0, ta.mask_pixels + tb.mask_pixels);
    // The same place twice: the deeper press wins whatever the order.
    let deep = press(Solid::Sphere, Place::Rotation(45.0), 90.0, 1.0);
    let shallow = press(Solid::Sphere, Place::Rotation(45.0), 90.0, 0.5);
    let (fd, _) = render_one(&mut r, &deep);
    for order in [
        [deep.clone(), shallow.clone()],
        [shallow.clone(), deep.clone()],
    ] {
        let (f, _) = r.render_scene(&order).unwrap();
        assert!(f.rgba == fd.rgba);
    }
}

/// A pose given as a matrix (and as position + quaternion) renders exactly as the same pose
/// given by at/spin/tilt, and implies the same depth.
#[test]
fn matrix_pose_equals_at_spin_tilt() {
    let sensor = Sensor::preset("paper").unwrap();
    let mut r = paper();
    let p = tilted(
        Solid::Cylinder,
        Place::Rotation(40.0),
        25.0,
        30.0,
        15.0,
        60.0,
        0.7,
    );
    let (frame, truth) = render_one(&mut r, &p);
    let posed = Press {
        object: p.object.clone(),
        hold: Hold::from_pose(&truth.pose).unwrap(),
    };
    let pose = posed.pose(&sensor).unwrap();
    let (frame2, truth2) = render_one(&mut r, &posed);
    assert!(frame2.rgba == frame.rgba);
    assert_eq!(truth2.pose, truth.pose);
    assert!(pose.depth_mm > 0.0);
    assert!((truth2.indentation_reached_mm - truth.indentation_reached_mm).abs() < 1e-9);
    // Position + quaternion: the same pose as its matrix, to rounding.
    let q = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 2.5);
    let m = glam::DMat3::from_quat(q);
    let c = DVec3::new(1.0, -2.0, 30.0);
    let Hold::Pose {
        world_from_object,
        origin,
        ..
    } = Hold::from_pose(&[c.x, c.y, c.z, q.w, q.x, q.y, q.z]).unwrap()
    else {
        panic!("not a pose")
    };
    assert!(world_from_object.abs_diff_eq(m, 1e-12) && origin == c);
    let rows = m.transpose().to_cols_array();
    let matrix = [
        rows[0], rows[1], rows[2], c.x, rows[3], rows[4], rows[5], c.y, rows[6], rows[7], rows[8],
        c.z, 0.0, 0.0, 0.0, 1.0,
    ];
    let Hold::Pose {
        world_from_object, ..
    } = Hold::from_pose(&matrix).unwrap()
    else {
        panic!("not a pose")
    };
    assert!(world_from_object.abs_diff_eq(m, 1e-12));
    // Bad poses are one-line errors naming the field.
    let diagonal = |d: [f64; 3], last: f64| {
        [
            d[0], 0.0, 0.0, 0.0, 0.0, d[1], 0.0, 0.0, 0.0, 0.0, d[2], 0.0, last, 0.0, 0.0, 1.0,
        ]
    };
    for (bad, says) in [
        (vec![1.0, 2.0, 3.0], "expected 16 numbers"),
        (diagonal([1.0, 1.0, 2.0], 0.0).to_vec(), "not a rotation"),
        (diagonal([1.0, 1.0, 1.0], 1.0).to_vec(), "last row"),
        (vec![0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0], "length 1"),
        (
            vec![0.0, 0.0, f64::INFINITY, 1.0, 0.0, 0.0, 0.0],
            "inf is not a finite number",
        ),
    ] {
        let e = Hold::from_pose(&bad).unwrap_err().to_string();
        assert!(
            e.starts_with("pose: ") && e.contains(says) && !e.contains('\n'),
            "{bad:?}: {e}"
        );
    }
}

/// Objects that cannot touch say so; over-presses are labelled; contacts the lens cannot see
/// still say why.
#[test]
fn untouchable_and_invisible_contacts_say_so() {
    let sensor = Sensor::preset("paper").unwrap();
    // Posed 3 mm above the tip, pointing at it: short of touching.
    let above = Press {
        object: Arc::new(Object::Solid(Solid::Sphere)),
        hold: Hold::Pose {
            world_from_object: glam::DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0)),
            origin: sensor.finger.tip() + DVec3::new(0.0, 0.0, 3.0),
            approach: None,
        },
    };
    let e = above.pose(&sensor).unwrap_err().to_string();
    assert!(e.contains("3.000 mm short of touching"), "{e}");
    // Beside the finger, moving parallel to it: never touches.
    let beside = Press {
        object: Arc::new(Object::Solid(Solid::Sphere)),
        hold: Hold::Pose {
            world_from_object: glam::DMat3::from_cols(DVec3::Z, DVec3::Y, -DVec3::X),
            origin: DVec3::new(40.0, 0.0, 10.0),
            approach: None,
        },
    };
    let e = beside.pose(&sensor).unwrap_err().to_string();
    assert!(e.contains("does not touch"), "{e}");
    // Pressed through the shell: labelled.
    let mut r = paper();
    let (_, truth) = render_one(
        &mut r,
        &press(Solid::Sphere, Place::Rotation(20.0), 0.0, 2.5),
    );
    assert!(truth.over_pressed && truth.indentation_reached_mm > sensor.finger.shell_thickness);
    drop(r);
    // The webcam's 70 degree lens cannot see 15 mm down the side: no pixel, with the reason.
    let webcam = Sensor::preset("webcam70").unwrap();
    let mut w = Renderer::new(&webcam).unwrap();
    let p = press(Solid::Sphere, Place::Translation(18.0), 0.0, 0.6);
    let (frame, truths) = w.render_scene(&[p]).unwrap();
    let why = truths[0].pixel.clone().unwrap_err();
    assert!(why.contains("field of view"), "{why}");
    assert!(frame.rgba == w.reference().rgba);
    assert_eq!(truths[0].mask_pixels, 0);
}

/// The labels the renderer reads back from the GPU's own penetration (each contact's field
/// copied out before the elastomer reuses the buffer) equal the CPU's, computed from
/// `contact::penetration_field` over the same texel rect: in a batch (each slot its own
/// field), and in a scene of two presses at the same place (each label its own object's
/// field, not the deeper one's).
#[test]
fn labels_from_the_gpu_field_match_the_cpu_field() {
    let mut r = paper();
    let sensor = r.sensor().clone();
    let grid = *r.grid();
    let n = grid.texels as usize;
    let reach = geltip::render::elastomer::blend_reach_mm(&sensor.config.elastomer);
    let cpu_labels = |p: &Press| {
        let pose = p.pose(&sensor).unwrap();
        let rect = contact::footprint(&sensor, &grid, &pose, &p.object, reach)
            .unwrap()
            .texels;
        let field = contact::penetration_field(&sensor, &grid, &pose, &p.object, rect);
        contact::indentation_labels(&sensor.finger, &grid, &field[rect.y as usize * n..], rect)
    };
    let check = |what: &str, t: &GroundTruth, p: &Press| {
        let want = cpu_labels(p);
        assert!(want.reached_mm > 0.1, "{what}: the CPU field is empty");
        assert!(
            (t.indentation_reached_mm - want.reached_mm).abs() < 1e-3,
            "{what}: reached {} vs CPU {}",
            t.indentation_reached_mm,
            want.reached_mm
        );
        let centre = t.contact_centre.expect("a centre");
        assert!(
            (centre - want.centre.unwrap()).length() < 1e-2,
            "{what}: centre {centre} vs CPU {}",
            want.centre.unwrap()
        );
        let rel = (t.indented_area_mm2 - want.area_mm2).abs() / want.area_mm2;
        assert!(
            rel < 0.02,
            "{what}: area {} vs CPU {}",
            t.indented_area_mm2,
            want.area_mm2
        );
    };
    let contact = |solid, place, azimuth_deg, depth_mm| {
        Press::at(Arc::new(Object::Solid(solid)), place, azimuth_deg, depth_mm)
    };
    let plain = [
        contact(Solid::Sphere, Place::Rotation(0.0), 0.0, 1.0),
        contact(Solid::Cone, Place::Rotation(60.0), 45.0, 0.8),
        contact(Solid::Slab, Place::Translation(10.0), 200.0, 0.6),
    ];
    let contacts: Vec<Press> = plain.to_vec();
    let batch = r.render_batch(&plain).unwrap();
    for ((_, t), p) in batch.iter().zip(&contacts) {
        check(&format!("batch {}", t.place), t, p);
    }
    let deep = press(Solid::Sphere, Place::Rotation(45.0), 90.0, 1.0);
    let shallow = press(Solid::Sphere, Place::Rotation(45.0), 90.0, 0.5);
    let (_, truths) = r.render_scene(&[deep.clone(), shallow.clone()]).unwrap();
    check("scene, deep", &truths[0], &deep);
    check("scene, shallow", &truths[1], &shallow);
    assert!(truths[1].indentation_reached_mm < truths[0].indentation_reached_mm - 0.3);
}

/// The footprint scan prunes blocks of cells with `contact::may_touch`: it must hold for every
/// block that contains a point `contact::penetration` finds pressed (a sphere trace of the
/// object itself can step over a thin band within its tolerance; `may_touch` traces the
/// grown object, which cannot). Checked on points around several contacts, blocks of 2.2 mm.
#[test]
fn may_touch_covers_every_pressed_point_of_its_block() {
    let sensor = Sensor::preset("paper").unwrap();
    let f = &sensor.finger;
    let drape = sensor.config.elastomer.drape_mm;
    let half = 2.2 * std::f64::consts::FRAC_1_SQRT_2;
    let mut checked = 0;
    for (solid, place) in [
        (Solid::Sphere, Place::Translation(0.0)),
        (Solid::Cone, Place::Rotation(30.0)),
        (Solid::Edge, Place::Translation(10.0)),
        (Solid::Tube, Place::Rotation(60.0)),
    ] {
        let p = press(solid, place, 30.0, 1.0);
        let pose = p.pose(&sensor).unwrap();
        let depth = pose.trace_depth_mm;
        let tolerance = half * (1.0 + (depth + drape) / f.radius) + contact::TRACE_EPSILON_MM;
        let centre = pose.coord.to_disc();
        for bj in -6..=6 {
            for bi in -6..=6 {
                let block = centre + glam::DVec2::new(bi as f64, bj as f64) * 2.2;
                let touched = contact::may_touch(
                    &pose,
                    &p.object,
                    &f.point_at_disc(block),
                    depth,
                    drape,
                    tolerance,
                );
                for k in 0..25 {
                    let offset = glam::DVec2::new((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0) * 0.5;
                    let at = f.point_at(geltip::SurfaceCoord::from_disc(block + offset));
                    let pressed = contact::penetration(
                        &pose,
                        &p.object,
                        &at,
                        depth,
                        drape,
                        contact::TRACE_EPSILON_MM,
                    ) > 0.0;
                    assert!(!pressed || touched, "{solid:?}: block {bi},{bj} point {k}");
                    checked += pressed as usize;
                }
            }
        }
    }
    assert!(checked > 200, "only {checked} pressed points");
}

/// How deep a press can go before the object has gone through the gel: the number the
/// refusal of a far deeper press says.
fn deepest(p: &Press, sensor: &Sensor) -> f64 {
    let mut far = p.clone();
    let Hold::Surface { depth_mm, .. } = &mut far.hold else {
        panic!("not a surface hold")
    };
    *depth_mm = 1e9;
    let e = far.pose(sensor).unwrap_err().to_string();
    assert!(e.starts_with("depth: ") && !e.contains('\n'), "{e}");
    e.split("only up to ")
        .nth(1)
        .and_then(|t| t.split(" mm").next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no limit in: {e}"))
}

/// A press deeper than the gel is an over-press, rendered and labelled, as long as the
/// object still reaches the gel; deeper, it has gone through the gel and the shell, and the
/// press is refused with how deep it can go instead of rendering an empty frame. Rigid
/// poses that deep are refused too. `over_pressed` says whether the skin is pushed beyond
/// the gel's thickness: for a top on the normal, untilted, that is every depth beyond it; a
/// ring or a tilted object pressed a little beyond it pushes the skin less deep along the
/// skin's own normals.
#[test]
fn presses_through_the_gel_are_refused_and_over_presses_labelled() {
    let sensor = Sensor::preset("paper").unwrap();
    let t = sensor.finger.shell_thickness;
    let mut r = paper();
    for (p, top_on_normal) in [
        (press(Solid::Sphere, Place::Rotation(0.0), 0.0, 1.0), true),
        (press(Solid::Cone, Place::Rotation(45.0), 30.0, 1.0), true),
        (press(Solid::Slab, Place::Translation(5.0), 0.0, 1.0), true),
        (press(Solid::Disc, Place::Translation(8.0), 90.0, 1.0), true),
        (press(Solid::Torus, Place::Rotation(60.0), 0.0, 1.0), false),
        (
            tilted(
                Solid::Cylinder,
                Place::Rotation(40.0),
                25.0,
                30.0,
                15.0,
                60.0,
                1.0,
            ),
            false,
        ),
    ] {
        let most = deepest(&p, &sensor);
        assert!(most > t + 0.5, "{}: {most}", p.name());
        for depth in [t + 0.05, 0.5 * (t + most), most - 1e-3] {
            let mut q = p.clone();
            if let Hold::Surface { depth_mm, .. } = &mut q.hold {
                *depth_mm = depth;
            }
            let (_, truth) = render_one(&mut r, &q);
            let what = format!(
                "{} at {depth} mm (at most {most}): {} pixels, over-pressed {}, reached {} mm",
                p.name(),
                truth.mask_pixels,
                truth.over_pressed,
                truth.indentation_reached_mm
            );
            assert!(truth.mask_pixels > 0, "{what}");
            assert_eq!(
                truth.over_pressed,
                truth.indentation_reached_mm > t,
                "{what}"
            );
            assert!(truth.over_pressed || !top_on_normal, "{what}");
            // At the deepest press the object holds the gel's traced depth, past the shell.
            assert!(truth.over_pressed || depth < 0.5 * (t + most), "{what}");
        }
        let mut q = p.clone();
        if let Hold::Surface { depth_mm, .. } = &mut q.hold {
            *depth_mm = most + 1e-2;
        }
        assert!(q.pose(&sensor).is_err(), "{} past {most}", p.name());
    }
    // A sphere posed 20 mm inside the tip, pointing at it.
    let inside = Press {
        object: Arc::new(Object::Solid(Solid::Sphere)),
        hold: Hold::Pose {
            world_from_object: glam::DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0)),
            origin: sensor.finger.tip() - DVec3::new(0.0, 0.0, 20.0),
            approach: None,
        },
    };
    let e = inside.pose(&sensor).unwrap_err().to_string();
    assert!(e.starts_with("pose: ") && e.contains("only up to"), "{e}");
}
