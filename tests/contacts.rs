//! Contacts defined by first touch: objects whose top is not a single point on the
//! contact normal (a ring, a flat disc on the cylinder, a tilted cylinder), rigid poses
//! against at/spin/tilt, several objects in one frame, and contacts that cannot touch
//! or cannot be seen.

use geltip::object::{dims, Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{contact, Frame, GroundTruth, Hold, Place, Press};
use geltip::sensor::Sensor;
use glam::DVec3;
use std::sync::{Arc, Mutex, OnceLock};

fn paper() -> std::sync::MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    R.get_or_init(|| {
        Mutex::new(
            Renderer::new(&Sensor::preset("paper").unwrap())
                .expect("renderer (is lavapipe installed?)"),
        )
    })
    .lock()
    .unwrap_or_else(|e| e.into_inner())
}

fn press(solid: Solid, place: Place, azimuth: f64, depth: f64) -> Press {
    tilted(solid, place, azimuth, 0.0, 0.0, 0.0, depth)
}

fn tilted(
    solid: Solid,
    place: Place,
    azimuth: f64,
    spin: f64,
    tilt: f64,
    towards: f64,
    depth: f64,
) -> Press {
    Press {
        object: Arc::new(Object::Solid(solid)),
        hold: Hold::Surface {
            place,
            azimuth_deg: azimuth,
            spin_deg: spin,
            tilt_deg: tilt,
            tilt_towards_deg: towards,
            depth_mm: depth,
        },
    }
}

fn render_one(r: &mut Renderer, p: &Press) -> (Frame, GroundTruth) {
    let (frame, mut truths) = r.render_scene(std::slice::from_ref(p)).unwrap();
    (frame, truths.remove(0))
}

fn rgb_at(frame: &Frame, px: glam::DVec2) -> [u8; 4] {
    let (u, v) = (px.x.round() as usize, px.y.round() as usize);
    let i = (v * frame.width as usize + u) * 4;
    frame.rgba[i..i + 4].try_into().unwrap()
}

/// First touch against analytic answers: a top point on the normal touches at offset 0
/// exactly (so the paper's seven solids sit with their tops at the place); the torus at the tip comes
/// in by exactly its minor radius (its tube's centre circle, radius 4, meets the 7.5 mm
/// hemisphere grown by 1 mm at sqrt(8.5^2 - 4^2) = 7.5 above the centre); the tube's inner
/// rim (radius 2) touches sqrt(7.5^2 - 2^2) - 7.5 mm in.
#[test]
fn first_touch_offsets_match_the_geometry() {
    let sensor = Sensor::preset("paper").unwrap();
    for solid in Solid::ALL {
        if solid == Solid::Tube {
            continue;
        }
        for place in [
            Place::Rotation(0.0),
            Place::Rotation(45.0),
            Place::Translation(5.0),
        ] {
            let pose = press(solid, place, 30.0, 1.0).pose(&sensor).unwrap();
            assert_eq!(pose.first_touch_offset_mm, 0.0, "{solid:?} at {place:?}");
            assert_eq!(pose.origin, pose.point - 1.0 * pose.normal);
        }
    }
    let r = sensor.finger.radius;
    let torus = press(Solid::Torus, Place::Rotation(0.0), 0.0, 0.6)
        .pose(&sensor)
        .unwrap();
    let want = -dims::TORUS_MINOR_RADIUS;
    assert!(
        (torus.first_touch_offset_mm - want).abs() < 1e-5,
        "torus at the tip: {} vs {want}",
        torus.first_touch_offset_mm
    );
    let tube = press(Solid::Tube, Place::Rotation(0.0), 0.0, 1.0)
        .pose(&sensor)
        .unwrap();
    let want = (r * r - dims::TUBE_INNER_RADIUS.powi(2)).sqrt() - r;
    assert!(
        (tube.first_touch_offset_mm - want).abs() < 1e-5,
        "tube at the tip: {} vs {want}",
        tube.first_touch_offset_mm
    );
    // On the cylinder's side the tube's flat rim meets the straight meridian at offset 0.
    let tube = press(Solid::Tube, Place::Translation(8.0), 0.0, 1.0)
        .pose(&sensor)
        .unwrap();
    assert!(tube.first_touch_offset_mm.abs() < 1e-5);
}

/// An edge's knife-sharp ridge lying across the finger at a slant: random dataset poses
/// (seed 2), where a search along the meridian and the parallel alone creeps along the
/// ridge and stops short (up to 0.046 mm, with 84 000 traces for one pose). Placed at its
/// first touch, no point of the ridge may be inside the finger, and the nearest must touch
/// it.
#[test]
fn first_touch_follows_a_slanted_ridge_to_its_top() {
    use geltip::jobs::dataset;
    let sensor = Sensor::preset("paper").unwrap();
    let objects = vec![Arc::new(Object::Solid(Solid::Edge))];
    let depths = dataset::default_depth_range(sensor.finger.shell_thickness);
    for k in 0..100 {
        let contact = dataset::sample_contact(&sensor, &objects, depths, 2, k).unwrap();
        let pose = contact.pose(&sensor).unwrap();
        let touching = pose.origin + pose.depth_mm * pose.normal;
        // The ridge: along x at the object's top (z = 0), 2001 points.
        let half = 0.5 * dims::EDGE_LENGTH;
        let deepest = (0..=2000)
            .map(|i| {
                let q = DVec3::new(-half + half * i as f64 / 1000.0, 0.0, 0.0);
                sensor
                    .finger
                    .signed_distance(touching + pose.world_from_object * q)
            })
            .fold(f64::INFINITY, f64::min);
        // The ridge need not touch at all (a face's corner may come first): then it stays
        // outside. Where the ridge touches, it touches to the search's tolerance.
        assert!(
            deepest > -1e-5,
            "sample {k}: the ridge is {deepest} mm inside at first touch"
        );
        if pose
            .first_touch
            .iter()
            .all(|p| pose.to_object(*p).z.abs() < 1e-6)
        {
            assert!(
                deepest < 1e-4,
                "sample {k}: the ridge stops {deepest} mm short"
            );
        }
    }
}

/// A torus: a ring (4 mm major radius) pressed 0.6 mm at rotation 60 changes the
/// image where the ring touches and not in its hole, and its labels report the ring.
#[test]
fn torus_marks_its_ring_not_its_hole() {
    let sensor = Sensor::preset("paper").unwrap();
    let mut r = paper();
    for place in [
        Place::Rotation(60.0),
        Place::Rotation(0.0),
        Place::Translation(6.0),
    ] {
        let p = press(Solid::Torus, place, 20.0, 0.6);
        let (frame, truth) = render_one(&mut r, &p);
        let reference = r.reference().clone();
        // Its top circle sits on a straight meridian of the cylinder (offset 0) but has to
        // come in to meet the hemisphere.
        if matches!(place, Place::Translation(_)) {
            assert_eq!(truth.first_touch_offset_mm, 0.0);
        } else {
            assert!(truth.first_touch_offset_mm < -0.3, "{place:?}");
        }
        // Pressed 0.6 mm along the contact normal; the ring meets skin whose normal leans
        // away from it, so the indentation along that skin's normal is about 0.6 cos(lean).
        let touch = truth.first_touch[0];
        let lean = sensor
            .finger
            .point_at(sensor.finger.coord_of(touch))
            .normal
            .dot(truth.normal);
        assert!(
            (truth.indentation_reached_mm - 0.6 * lean).abs() < 0.03,
            "{place:?}: reached {} against {}",
            truth.indentation_reached_mm,
            0.6 * lean
        );
        // The ring: touched first along (part of) a circle about 4 mm from the axis...
        assert!(!truth.first_touch.is_empty());
        for q in &truth.first_touch {
            let d = (*q - truth.point).length();
            assert!(
                (2.5..5.5).contains(&d),
                "{place:?}: first touch {d} mm off the axis"
            );
        }
        let deepest = truth.deepest_point.unwrap();
        let d = (deepest - truth.point).length();
        assert!((2.5..5.5).contains(&d), "{place:?}: deepest {d} mm off");
        // ... its centre in the hole (the ring's middle, within a millimetre).
        let centre = truth.contact_centre.unwrap();
        assert!((centre - truth.point).length() < 1.0, "{place:?}: {centre}");
        // The image: changed where the ring touches, unchanged in the hole.
        let hole = sensor.project(truth.point).unwrap();
        assert_eq!(
            rgb_at(&frame, hole),
            rgb_at(&reference, hole),
            "{place:?}: hole"
        );
        let touched = sensor.project(deepest).unwrap();
        let at = |f: &Frame, du: f64, dv: f64| rgb_at(f, touched + glam::DVec2::new(du, dv));
        let changed = (-3..=3)
            .flat_map(|du| (-3..=3).map(move |dv| (du as f64, dv as f64)))
            .filter(|&(du, dv)| at(&frame, du, dv) != at(&reference, du, dv))
            .count();
        assert!(
            changed > 10,
            "{place:?}: ring: {changed} of 49 pixels changed"
        );
        let index = |p: glam::DVec2| (p.y.round() * frame.width as f64 + p.x.round()) as usize;
        assert!(frame.indentation[index(touched)] > 0.3, "{place:?}");
        // In the hole the gel bulges out a few µm at most: not pressed.
        assert!(frame.indentation[index(hole)] < 0.01, "{place:?}");
        assert!(truth.mask_pixels > 100);
        // And the single-contact API gives the same frame.
        let contact = Press::at(p.object.clone(), place, 20.0, 0.6);
        let (single, truth1) = r.render(&contact).unwrap();
        assert!(single.rgba == frame.rgba);
        assert_eq!(truth1.first_touch_offset_mm, truth.first_touch_offset_mm);
    }
}

/// A flat disc on the cylinder's side touches along the straight meridian through the
/// contact point and indents the skin by the given depth all along that line.
#[test]
fn flat_disc_indents_its_first_touch_line_by_the_depth() {
    let sensor = Sensor::preset("paper").unwrap();
    let f = &sensor.finger;
    let depth = 0.4;
    let p = press(Solid::Disc, Place::Translation(8.0), 45.0, depth);
    let pose = p.pose(&sensor).unwrap();
    assert_eq!(pose.first_touch_offset_mm, 0.0);
    // The first-touch band is the meridian: same azimuth, several mm long.
    let phi = 45f64.to_radians();
    let zs: Vec<f64> = pose.first_touch.iter().map(|q| q.z).collect();
    for q in &pose.first_touch {
        // Within 10 µm of the tangent plane: 7.5 (1 - cos dphi) <= 0.01.
        assert!((q.y.atan2(q.x) - phi).abs() < 0.055, "{q}");
    }
    let span =
        zs.iter().cloned().fold(f64::MIN, f64::max) - zs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 6.0, "first-touch line {span} mm long");
    // The indentation at the surface point nearest `q`, traced to `tolerance`.
    let pen_near = |q: DVec3, tolerance: f64| {
        let at = f.point_at(f.coord_of(q));
        contact::penetration(&pose, &p.object, &at, pose.trace_depth_mm, 0.0, tolerance)
    };
    for dz in [-4.0, -2.0, 0.0, 2.0, 4.0] {
        let pen = pen_near(
            pose.point + DVec3::new(0.0, 0.0, dz),
            contact::TRACE_EPSILON_MM,
        );
        assert!((pen - depth).abs() < 2e-3, "at dz {dz}: {pen}");
    }
    // Across the line the cylinder falls away: less indentation 3 mm to the side.
    let pen = pen_near(
        pose.point + 3.0 * DVec3::new(-phi.sin(), phi.cos(), 0.0),
        1e-3,
    );
    assert!(pen < depth - 0.2, "{pen}");
    let (_, truth) = render_one(&mut paper(), &p);
    assert!((truth.indentation_reached_mm - depth).abs() < 0.01);
}

/// A cylinder tilted 20 degrees touches with its rim first, not its face's centre.
#[test]
fn tilted_cylinder_touches_with_its_rim() {
    let sensor = Sensor::preset("paper").unwrap();
    for (place, towards) in [
        (Place::Rotation(30.0), 0.0),
        (Place::Translation(5.0), 90.0),
        (Place::Rotation(60.0), 200.0),
    ] {
        let p = tilted(Solid::Cylinder, place, 10.0, 0.0, 20.0, towards, 0.5);
        let pose = p.pose(&sensor).unwrap();
        // The object where it first touched, in its own frame.
        let at_touch = pose.origin + (pose.depth_mm) * pose.normal;
        let q = pose.world_from_object.transpose() * (pose.first_touch[0] - at_touch);
        let rim = q.truncate().length();
        assert!(
            (rim - dims::CYLINDER_RADIUS).abs() < 0.02 && q.z.abs() < 0.02,
            "{place:?}: first touch at r {rim}, z {}",
            q.z
        );
        // Tilted about the face's centre, the rim dips into the finger: it backs off.
        assert!(pose.first_touch_offset_mm > 0.0);
        // Untilted, the face's centre (the contact point) touches first.
        let flat = tilted(Solid::Cylinder, place, 10.0, 0.0, 0.0, towards, 0.5)
            .pose(&sensor)
            .unwrap();
        assert_eq!(flat.first_touch_offset_mm, 0.0);
    }
}

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
/// block that contains a point `contact::penetration` finds pressed (the old scan's sphere
/// trace could step over a thin band within its tolerance; `may_touch` traces the grown
/// object instead). Checked on points around several contacts, blocks of 2.2 mm.
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
        },
    };
    let e = inside.pose(&sensor).unwrap_err().to_string();
    assert!(e.starts_with("pose: ") && e.contains("only up to"), "{e}");
}
