//! The GPU renderer on lavapipe: its images against committed references (with a tolerance
//! that a perturbed image fails), and its ground truth, monotonicity and determinism. Its
//! stages against their CPU mirrors: tests/mirrors.rs.
//!
//! Reference images live in tests/reference/; `GELTIP_BLESS=1 cargo test --test render`
//! rewrites them (then look at them before committing).

mod common;
mod support;

use geltip::object::{Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{self, elastomer};
use geltip::render::{Frame, Place, Press};
use geltip::sensor::Sensor;
use glam::DVec2;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};
use support::{close_enough, contact, diff, rgb};

/// One renderer for the paper's sensor, shared by the tests of this file.
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

fn reference_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/reference")
        .join(name)
}

/// Compares with a committed PNG (or writes it when blessing); returns the committed image.
fn check_against_reference(name: &str, frame: &Frame) -> Vec<u8> {
    let path = reference_path(name);
    if std::env::var_os("GELTIP_BLESS").is_some() {
        frame.to_rgb().save(&path).unwrap();
    }
    let expected = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (GELTIP_BLESS=1 writes it)", path.display()))
        .to_rgb8();
    assert_eq!(
        (expected.width(), expected.height()),
        (frame.width, frame.height)
    );
    let d = diff(&rgb(frame), expected.as_raw(), 3);
    assert!(close_enough(&d), "{name}: {d:?}");
    expected.into_raw()
}

/// Perturbations a real regression could cause; each must fail the tolerance.
fn assert_perturbations_fail(name: &str, image: &[u8], width: u32, around: DVec2) {
    let (cx, cy) = (around.x as i64, around.y as i64);
    let mut brighter_patch = image.to_vec();
    let mut shifted = image.to_vec();
    let mut swapped = image.to_vec();
    for y in 0..(image.len() as i64 / 3 / width as i64) {
        for x in 0..width as i64 {
            let i = ((y * width as i64 + x) * 3) as usize;
            if (x - cx).abs() < 20 && (y - cy).abs() < 20 {
                for c in 0..3 {
                    brighter_patch[i + c] = brighter_patch[i + c].saturating_add(40);
                }
            }
            if x >= 2 {
                let j = ((y * width as i64 + x - 2) * 3) as usize;
                shifted[i..i + 3].copy_from_slice(&image[j..j + 3]);
            }
            swapped.swap(i, i + 2);
        }
    }
    for (what, p) in [
        ("brighter 40x40 patch", &brighter_patch),
        ("2 px shift", &shifted),
        ("red/blue swap", &swapped),
    ] {
        let d = diff(image, p, 3);
        assert!(
            !close_enough(&d),
            "{name}: a {what} passes the tolerance: {d:?}"
        );
    }
}

#[test]
fn reference_frame_matches_committed_image() {
    let r = paper();
    let committed = check_against_reference("paper_reference.png", r.reference());
    let s = r.sensor();
    assert_perturbations_fail(
        "paper_reference.png",
        &committed,
        s.width,
        s.principal + DVec2::new(60.0, 20.0),
    );
}

#[test]
fn contact_frame_matches_committed_image() {
    let mut r = paper();
    let (frame, truth) = r
        .render(&contact(Solid::Sphere, Place::Rotation(45.0), 1.0))
        .unwrap();
    let committed = check_against_reference("paper_sphere_rot45.png", &frame);
    let px = truth.pixel.unwrap();
    assert_perturbations_fail("paper_sphere_rot45.png", &committed, frame.width, px);
}

#[test]
fn contact_region_contains_the_true_pixel() {
    let mut r = paper();
    for (solid, place) in [
        (Solid::Cone, Place::Rotation(0.0)),
        (Solid::Sphere, Place::Rotation(30.0)),
        (Solid::Cylinder, Place::Rotation(90.0)),
        (Solid::Tube, Place::Translation(10.0)),
        (Solid::IrregularPrism, Place::Translation(15.0)),
    ] {
        let (frame, truth) = r.render(&contact(solid, place, 1.0)).unwrap();
        let px = truth
            .pixel
            .clone()
            .unwrap_or_else(|e| panic!("{solid:?}: truth not visible: {e}"));
        let [u0, v0, u1, v1] = truth
            .mask_bbox
            .unwrap_or_else(|| panic!("{solid:?} at {place:?}: empty mask"));
        assert!(
            px.x >= u0 as f64 - 0.5
                && px.x <= u1 as f64 + 0.5
                && px.y >= v0 as f64 - 0.5
                && px.y <= v1 as f64 + 0.5,
            "{solid:?} at {place:?}: truth pixel {px} outside mask {:?}",
            truth.mask_bbox
        );
        // The tube touches in a ring: its centre is not pressed.
        if solid != Solid::Tube {
            let (u, v) = (px.x.round() as u32, px.y.round() as u32);
            let d = frame.indentation[(v * frame.width + u) as usize];
            assert!(
                d > 0.1,
                "{solid:?} at {place:?}: indentation {d} at the truth pixel"
            );
        }
        let changed = diff(&rgb(&frame), &rgb(r.reference()), 0);
        assert!(changed.frac_over > 0.0);
        assert!(!truth.over_pressed);
    }
}

#[test]
fn deeper_press_changes_the_image_more() {
    let mut r = paper();
    let reference = rgb(r.reference());
    let mut last = 0.0;
    for depth in [0.1, 0.3, 0.6, 1.0, 1.4] {
        let (frame, _) = r
            .render(&contact(Solid::Sphere, Place::Translation(5.0), depth))
            .unwrap();
        let total: u64 = rgb(&frame)
            .iter()
            .zip(&reference)
            .map(|(a, b)| a.abs_diff(*b) as u64)
            .sum();
        let total = total as f64;
        assert!(
            total > last,
            "depth {depth}: difference {total} not above {last}"
        );
        last = total;
    }
}

#[test]
fn a_press_too_shallow_to_move_the_skin_renders_the_empty_finger() {
    let mut r = paper();
    // 4 µm of penetration has a footprint (the passes run) but blends to less than the 5 µm
    // the elastomer counts as movement: the touched list stays empty and the passes over it
    // dispatch no work.
    let shallow = contact(Solid::Sphere, Place::Rotation(30.0), 0.004);
    let pose = shallow.pose(r.sensor()).unwrap();
    let reach = elastomer::blend_reach_mm(&r.sensor().config.elastomer);
    let footprint = render::contact::footprint(r.sensor(), r.grid(), &pose, &shallow.object, reach);
    assert!(
        footprint.is_some_and(|f| f.pixels.is_some()),
        "no footprint: the test would not reach the touched-pixel passes"
    );
    let (frame, truth) = r.render(&shallow).unwrap();
    assert_eq!(r.timings().touched_pixels, 0);
    assert!(truth.pixel.is_ok());
    assert!(
        frame.rgba == r.reference().rgba,
        "the frame differs from the empty finger"
    );
    assert!(frame.indentation.iter().all(|&d| d == 0.0));
    // And the renderer is fine afterwards: a real press touches pixels again.
    let (frame, _) = r
        .render(&contact(Solid::Sphere, Place::Rotation(30.0), 1.0))
        .unwrap();
    assert!(r.timings().touched_pixels > 1000);
    assert!(frame.rgba != r.reference().rgba);
}

#[test]
fn over_pressing_is_reported() {
    let mut r = paper();
    let (_, truth) = r
        .render(&contact(Solid::Sphere, Place::Rotation(30.0), 2.5))
        .unwrap();
    assert!(truth.over_pressed, "2.5 mm into a 1.5 mm shell: {truth:?}");
}

#[test]
fn same_inputs_give_identical_bytes() {
    let mut r = paper();
    let c = contact(Solid::Edge, Place::Rotation(60.0), 0.8);
    let (a, ta) = r.render(&c).unwrap();
    let batch = r
        .render_batch(&[
            c.clone(),
            contact(Solid::Cone, Place::Rotation(0.0), 1.0),
            c.clone(),
        ])
        .unwrap();
    assert_eq!(a.rgba, batch[0].0.rgba);
    assert_eq!(a.rgba, batch[2].0.rgba);
    assert_ne!(a.rgba, batch[1].0.rgba);
    assert_eq!(ta, batch[0].1);
    let fresh = Renderer::new(r.sensor()).unwrap();
    assert_eq!(fresh.reference().rgba, r.reference().rgba);
}

#[test]
fn batches_of_any_size_give_the_frames_of_one_at_a_time() {
    // A submission of many frames (the next prepared while one renders, the frame uniforms
    // in one buffer, the frames unpacked side by side) gives, frame for frame and label for
    // label, what one frame a submission gives; so do scenes of two contacts.
    let mut r = paper();
    let default = (r.batch_frames(), r.lanes());
    let solids = [
        Solid::Sphere,
        Solid::Cone,
        Solid::Edge,
        Solid::Slab,
        Solid::Tube,
    ];
    let list: Vec<Press> = (0..11)
        .map(|k| {
            let place = if k % 2 == 0 {
                Place::Rotation(10.0 * k as f64)
            } else {
                Place::Translation(k as f64)
            };
            let mut c = contact(solids[k % solids.len()], place, 0.4 + 0.1 * k as f64);
            if let render::Hold::Surface { azimuth_deg, .. } = &mut c.hold {
                *azimuth_deg = 33.0 * k as f64;
            }
            c
        })
        .collect();
    let one: Vec<_> = list.iter().map(|c| r.render(c).unwrap()).collect();
    let mut scenes: Vec<Vec<Press>> = list.chunks(2).map(|c| c.to_vec()).collect();
    // Among them a press too shallow to move the skin: its passes run, its lists stay
    // empty, so a wave holds a frame of no touched pixels between others.
    scenes.insert(
        2,
        vec![contact(Solid::Sphere, Place::Rotation(30.0), 0.004)],
    );
    let each: Vec<_> = scenes.iter().map(|s| r.render_scene(s).unwrap()).collect();
    // Frames recorded side by side (lanes: each stage of each frame before the next
    // stage, each frame on a heightfield of its own) or one after the other.
    for (n, lanes) in [(4, 1), (4, 3), (64, 16)] {
        r.set_batch_frames(n).unwrap();
        r.set_lanes(lanes).unwrap();
        assert_eq!((r.batch_frames(), r.lanes()), (n, lanes));
        let batch = r.render_batch(&list).unwrap();
        assert_eq!(batch.len(), list.len());
        for (k, ((a, ta), (b, tb))) in one.iter().zip(&batch).enumerate() {
            assert!(a.rgba == b.rgba, "batch {n}: frame {k}'s image differs");
            assert!(
                a.indentation == b.indentation,
                "batch {n}: frame {k}'s depth"
            );
            assert_eq!(ta.to_json(), tb.to_json(), "batch {n}: frame {k}'s labels");
        }
        let batched = r.render_scenes(&scenes, false).unwrap();
        for (k, ((a, ta), (b, tb))) in each.iter().zip(&batched).enumerate() {
            assert!(a.rgba == b.rgba, "batch {n}: scene {k}'s image differs");
            assert!(
                a.indentation == b.indentation,
                "batch {n}: scene {k}'s depth"
            );
            let tb: Vec<_> = tb.iter().map(|(_, t)| t.to_json()).collect();
            let ta: Vec<_> = ta.iter().map(|t| t.to_json()).collect();
            assert_eq!(ta, tb, "batch {n}: scene {k}'s labels");
        }
    }
    // Distinct frames: each slot of a submission holds its own.
    assert_ne!(one[0].0.rgba, one[1].0.rgba);
    for bad in [0, geltip::render::gpu::MAX_BATCH + 1] {
        let e = r.set_batch_frames(bad).unwrap_err().to_string();
        assert!(e.starts_with("batch: ") && e.contains("1 to"), "{e}");
        let e = r.set_lanes(bad).unwrap_err().to_string();
        assert!(e.starts_with("lanes: ") && e.contains("1 to"), "{e}");
    }
    r.set_batch_frames(default.0).unwrap();
    r.set_lanes(default.1).unwrap();
}

/// A small contact (a cone 0.3 mm deep) and its frame from a fresh renderer of `sensor`:
/// what a renderer that rendered other frames first must give for it.
fn small_contact_alone(sensor: &Sensor) -> (Press, Frame) {
    let small = contact(Solid::Cone, Place::Rotation(62.0), 0.3);
    let (alone, _) = Renderer::new(sensor).unwrap().render(&small).unwrap();
    (small, alone)
}

#[test]
fn a_frame_does_not_depend_on_the_frames_before_it() {
    // The renderer keeps the heightfield between frames and clears only what the last
    // contact touched: a contact rendered after a larger one that overlaps it must come out
    // exactly as from a fresh renderer.
    // (With the clear limited to the current rect, a few hundred bytes differ and this fails.)
    let mut r = paper();
    let (small, alone) = small_contact_alone(r.sensor());
    let batch = r
        .render_batch(&[
            contact(Solid::Slab, Place::Rotation(60.0), 1.5),
            small.clone(),
            contact(Solid::Edge, Place::Rotation(65.0), 1.2),
        ])
        .unwrap();
    assert_eq!(alone.rgba, batch[1].0.rgba);
    assert_eq!(alone.indentation, batch[1].0.indentation);
    let (after, _) = r.render(&small).unwrap();
    assert_eq!(alone.rgba, after.rgba);
}

#[test]
fn a_refused_scene_leaves_the_next_frame_as_from_a_fresh_renderer() {
    // After a failed frame the renderer clears its whole heightfield at the next one (what
    // a failed submission left there is unknown): that frame still comes out exactly.
    let mut r = paper();
    let (small, alone) = small_contact_alone(r.sensor());
    r.render(&contact(Solid::Slab, Place::Rotation(60.0), 1.5))
        .unwrap();
    let refused = contact(Solid::Sphere, Place::Rotation(45.0), -1.0);
    let e = r.render_scene(&[refused]).unwrap_err().to_string();
    assert!(e.starts_with("depth: "), "{e}");
    let (after, _) = r.render(&small).unwrap();
    assert!(
        after.rgba == alone.rgba,
        "the frame after a refused scene differs"
    );
    assert_eq!(after.indentation, alone.indentation);
}

#[test]
fn renderers_on_their_own_devices_render_the_same_frames_at_once() {
    // `geltip dataset --streams` renders batches on several devices at the same time and
    // promises the files do not depend on which stream rendered a sample: a second
    // device's frames, rendered while the shared device renders, equal the shared one's.
    use geltip::gpu::context::MAX_STREAMS;
    use geltip::gpu::GpuContext;
    let contacts = [
        contact(Solid::Sphere, Place::Rotation(45.0), 1.0),
        contact(Solid::Edge, Place::Rotation(62.0), 0.8),
    ];
    let mut shared = paper();
    let sensor = shared.sensor().clone();
    let second = GpuContext::stream(1).unwrap();
    assert!(!std::ptr::eq(second, GpuContext::shared().unwrap()));
    assert!(std::ptr::eq(second, GpuContext::stream(1).unwrap()));
    assert!(std::ptr::eq(
        GpuContext::stream(0).unwrap(),
        GpuContext::shared().unwrap()
    ));
    let e = GpuContext::stream(MAX_STREAMS).unwrap_err().to_string();
    assert!(e.contains("render streams") && e.contains("at most"), "{e}");
    let mut other = Renderer::on(&sensor, second).unwrap();
    let (mine, theirs) = std::thread::scope(|scope| {
        let theirs = scope.spawn(|| other.render_batch(&contacts).unwrap());
        (
            shared.render_batch(&contacts).unwrap(),
            theirs.join().unwrap(),
        )
    });
    for ((a, ta), (b, tb)) in mine.iter().zip(&theirs) {
        assert!(a.rgba == b.rgba, "the two devices' images differ");
        assert_eq!(a.indentation, b.indentation);
        assert_eq!(ta.to_json(), tb.to_json());
    }
    assert_ne!(
        mine[0].0.rgba,
        shared.reference().rgba,
        "no contact rendered"
    );
}

#[test]
fn profiling_a_frame_times_every_stage_and_leaves_the_renderer_as_rendering_does() {
    // The profiler records the same stages as a frame (in one submission with timestamps
    // where the device has them): every stage named once, the GPU's share positive, and the
    // next frame exactly as from a fresh renderer (the profiled contact's texels are cleared).
    let mut r = paper();
    let (small, alone) = small_contact_alone(r.sensor());
    let stages = r
        .profile_stages(&contact(Solid::Slab, Place::Rotation(60.0), 1.5))
        .unwrap();
    let names: Vec<&str> = stages.iter().map(|s| s.0).collect();
    assert_eq!(
        names,
        [
            "copy reference + clear",
            "contact",
            "elastomer: meridians",
            "elastomer: parallels",
            "elastomer: skin normals",
            "touched: select",
            "camera + leds: touched pixels",
            "readback"
        ]
    );
    let gpu: std::time::Duration = stages[..7].iter().map(|s| s.1).sum();
    assert!(gpu > std::time::Duration::ZERO, "{stages:?}");
    let (after, _) = r.render(&small).unwrap();
    assert_eq!(alone.rgba, after.rgba);
}

#[test]
fn noise_is_seeded() {
    let mut c = common::paper_config();
    c.render.noise = 2.0.into();
    c.render.noise_seed = 7;
    let sensor = Sensor::from_config("noisy", c).unwrap();
    let contact = contact(Solid::Sphere, Place::Rotation(0.0), 0.5);
    let mut a = Renderer::new(&sensor).unwrap();
    let mut b = Renderer::new(&sensor).unwrap();
    let (fa, _) = a.render(&contact).unwrap();
    let (fb, _) = b.render(&contact).unwrap();
    assert_eq!(fa.rgba, fb.rgba, "same seed, same bytes");
    let (fa2, _) = a.render(&contact).unwrap();
    assert_ne!(fa.rgba, fa2.rgba, "each frame draws fresh noise");
    let d = diff(&rgb(&fa), &rgb(a.reference()), 0);
    assert!(
        d.mean_abs > 0.5 && d.mean_abs < 3.0,
        "noise of 2 levels: {d:?}"
    );
    // An empty frame has noise too, fresh each time, and nothing else.
    let (e1, e2) = (a.render_empty().unwrap(), a.render_empty().unwrap());
    assert_ne!(e1.rgba, e2.rgba);
    let d = diff(&rgb(&e1), &rgb(a.reference()), 0);
    assert!(
        d.mean_abs > 0.5 && d.mean_abs < 3.0,
        "empty frame noise: {d:?}"
    );
    // Without noise, the empty frame is the reference itself.
    let mut quiet = paper();
    let empty = quiet.render_empty().unwrap();
    assert_eq!(&empty, quiet.reference());
}

#[test]
fn sensor_noise_is_gaussian_with_the_configured_spread() {
    let mut c = common::paper_config();
    c.render.noise = 2.0.into();
    c.render.noise_seed = 11;
    let mut r = Renderer::new(&Sensor::from_config("noisy", c).unwrap()).unwrap();
    let reference = r.reference().rgba.clone();
    // Four empty frames: noise minus the noise-free reference, where no clipping bites.
    let mut d: Vec<[f64; 3]> = Vec::new();
    let width = r.sensor().width as usize;
    let mut right_neighbour: Vec<(f64, f64)> = Vec::new();
    for _ in 0..4 {
        let e = r.render_empty().unwrap();
        let px = |i: usize| -> Option<[f64; 3]> {
            let (n, q) = (&e.rgba[i * 4..i * 4 + 3], &reference[i * 4..i * 4 + 3]);
            q.iter()
                .all(|&v| (12..=243).contains(&v))
                .then(|| std::array::from_fn(|c| n[c] as f64 - q[c] as f64))
        };
        for i in 0..reference.len() / 4 {
            if let Some(v) = px(i) {
                d.push(v);
                if (i + 1) % width != 0 {
                    if let Some(w) = px(i + 1) {
                        right_neighbour.push((v[0], w[0]));
                    }
                }
            }
        }
    }
    assert!(d.len() > 500_000, "only {} noisy samples", d.len());
    let n = d.len() as f64;
    for c in 0..3 {
        let mean = d.iter().map(|v| v[c]).sum::<f64>() / n;
        let var = d.iter().map(|v| (v[c] - mean).powi(2)).sum::<f64>() / n;
        let kurtosis = d.iter().map(|v| (v[c] - mean).powi(4)).sum::<f64>() / n / var.powi(2);
        // 2 levels of noise, then rounding to whole levels (variance + 1/12).
        let expected = (4.0f64 + 1.0 / 12.0).sqrt();
        assert!(mean.abs() < 0.02, "channel {c}: mean {mean}");
        assert!(
            (var.sqrt() - expected).abs() < 0.04,
            "channel {c}: std {} (expected {expected})",
            var.sqrt()
        );
        // A Gaussian's kurtosis is 3 (a uniform's 1.8, a sum of four uniforms' 2.7).
        assert!(
            (kurtosis - 3.0).abs() < 0.1,
            "channel {c}: kurtosis {kurtosis}"
        );
    }
    let corr = |pairs: &[(f64, f64)]| {
        let m = pairs.len() as f64;
        let (ma, mb) = (
            pairs.iter().map(|p| p.0).sum::<f64>() / m,
            pairs.iter().map(|p| p.1).sum::<f64>() / m,
        );
        let cov = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).sum::<f64>() / m;
        let va = pairs.iter().map(|p| (p.0 - ma).powi(2)).sum::<f64>() / m;
        let vb = pairs.iter().map(|p| (p.1 - mb).powi(2)).sum::<f64>() / m;
        cov / (va * vb).sqrt()
    };
    let channels: Vec<(f64, f64)> = d.iter().map(|v| (v[0], v[1])).collect();
    let pair_b: Vec<(f64, f64)> = d.iter().map(|v| (v[1], v[2])).collect();
    for (what, r) in [
        ("neighbouring pixels", corr(&right_neighbour)),
        ("red and green", corr(&channels)),
        ("green and blue", corr(&pair_b)),
    ] {
        assert!(r.abs() < 0.01, "{what} correlate: {r}");
    }
}

#[test]
fn bad_contacts_are_refused() {
    let mut r = paper();
    for (c, what) in [
        (
            contact(Solid::Sphere, Place::Rotation(0.0), -1.0),
            "depth: ",
        ),
        (
            contact(Solid::Sphere, Place::Rotation(0.0), f64::NAN),
            "depth: ",
        ),
        (
            contact(Solid::Sphere, Place::Translation(40.0), 1.0),
            "at: ",
        ),
        (contact(Solid::Sphere, Place::Rotation(-5.0), 1.0), "at: "),
    ] {
        let err = r.render(&c).unwrap_err().to_string();
        assert!(err.starts_with(what), "{err}");
    }
}

#[test]
fn a_contact_the_lens_cannot_see_renders_the_empty_finger() {
    let sensor = Sensor::preset("webcam70").unwrap();
    let mut r = Renderer::new(&sensor).unwrap();
    let (frame, truth) = r
        .render(&contact(Solid::Cone, Place::Translation(15.0), 1.0))
        .unwrap();
    assert_eq!(&frame, r.reference());
    let why = truth.pixel.unwrap_err();
    assert!(why.contains("field of view"), "{why}");
    assert_eq!(truth.mask_pixels, 0);
}

#[test]
fn a_loaded_mesh_renders_like_its_analytic_solid() {
    let mut r = paper();
    let reference = rgb(r.reference());
    for solid in [Solid::Sphere, Solid::Tube, Solid::Edge] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(format!("assets/objects/{}.obj", solid.name()));
        let mesh = Arc::new(Object::from_arg(path.to_str().unwrap()).unwrap());
        let place = Place::Rotation(40.0);
        let analytic = contact(solid, place, 1.0);
        let loaded = Press {
            object: mesh,
            hold: analytic.hold,
        };
        let (a, ta) = r.render(&analytic).unwrap();
        let (b, tb) = r.render(&loaded).unwrap();
        // Both press the same shape: the baked SDF is within a voxel (0.25 mm) of the truth.
        let d = diff(&rgb(&a), &rgb(&b), 8);
        assert!(d.frac_over < 0.002, "{solid:?}: {d:?}");
        let changed = diff(&rgb(&b), &reference, 8);
        assert!(
            changed.frac_over > 0.0005,
            "{solid:?}: the mesh left no imprint"
        );
        assert_eq!(ta.point, tb.point);
        assert!(
            (ta.mask_pixels as f64 - tb.mask_pixels as f64).abs() < 0.1 * ta.mask_pixels as f64
        );
    }
}
