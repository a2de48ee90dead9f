//! The GPU renderer on lavapipe: its lens rays against the CPU projection map, its images
//! against committed references (with a tolerance that a perturbed image fails), against the
//! CPU mirrors of its stages, and its ground truth, monotonicity and determinism.
//!
//! Reference images live in tests/reference/; `GELTIP_BLESS=1 cargo test --test render`
//! rewrites them (then look at them before committing).

mod common;

use geltip::object::{Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::{self, cpu, elastomer, touched};
use geltip::render::{Contact, Frame, Place};
use geltip::sensor::Sensor;
use glam::DVec2;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

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

fn contact(solid: Solid, place: Place, depth: f64) -> Contact {
    Contact {
        object: Arc::new(Object::Solid(solid)),
        place,
        azimuth_deg: 30.0,
        spin_deg: 0.0,
        depth_mm: depth,
    }
}

/// A small sensor for CPU-vs-GPU comparisons (the CPU mirror is slow at full size). 150 px
/// wide: a row of its rays' probes (150 x 32 bytes) is not a whole number of 256-byte copy
/// rows, so the renderer copies them row by row.
fn small_sensor() -> Sensor {
    let mut c = common::paper_config();
    c.image.width = 150;
    c.image.height = 120;
    c.lens.cx = 75.0;
    c.lens.cy = 60.0;
    c.lens.focal_px = 45.0;
    c.render.heightfield_texels = 256;
    Sensor::from_config("small", c).unwrap()
}

/// Per-channel differences between two images.
#[derive(Debug)]
struct Diff {
    mean_abs: f64,
    /// Fraction of channel values that differ by more than `loose` levels.
    frac_over: f64,
}

fn diff(a: &[u8], b: &[u8], loose: u8) -> Diff {
    assert_eq!(a.len(), b.len());
    let (mut sum, mut over) = (0u64, 0u64);
    for (x, y) in a.iter().zip(b) {
        let d = x.abs_diff(*y);
        sum += d as u64;
        if d > loose {
            over += 1;
        }
    }
    Diff {
        mean_abs: sum as f64 / a.len() as f64,
        frac_over: over as f64 / a.len() as f64,
    }
}

/// The tolerance every image comparison uses: small rounding differences everywhere are fine,
/// a changed region is not.
fn close_enough(d: &Diff) -> bool {
    d.mean_abs < 0.5 && d.frac_over < 0.002
}

fn reference_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/reference")
        .join(name)
}

fn rgb(frame: &Frame) -> Vec<u8> {
    frame.to_rgb().into_raw()
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
fn gpu_lens_rays_agree_with_the_cpu_map() {
    for sensor in common::all_sensors() {
        let mut r = Renderer::new(&sensor).unwrap();
        let mut pixels = Vec::new();
        for v in (0..sensor.height).step_by(7) {
            for u in (0..sensor.width).step_by(7) {
                pixels.push(DVec2::new(u as f64 + 0.25, v as f64 + 0.5));
            }
        }
        // The centre, the junction ring and the lens edge on purpose.
        let rho_j = sensor.lens.project(sensor.finger.junction_theta());
        let rho_e = sensor.lens.max_rho();
        for rho in [0.0, rho_j - 1e-3, rho_j + 1e-3, rho_e * (1.0 - 1e-5)] {
            let px = sensor.principal + DVec2::new(rho, 0.0);
            if sensor.in_image(px) {
                pixels.push(px);
            }
        }
        let gpu = r.unproject_pixels(&pixels).unwrap();
        let (mut worst, mut compared) = (0.0f64, 0);
        for (px, g) in pixels.iter().zip(&gpu) {
            let c = sensor.unproject(*px);
            match (c, g) {
                (Some(c), Some(g)) => {
                    worst = worst.max((c.point - *g).length());
                    compared += 1;
                }
                (None, None) => {}
                // Pixels within a hair of the lens edge may fall either side in f32.
                (c, g) => {
                    let rho = (*px - sensor.principal).length();
                    assert!(
                        (rho / rho_e - 1.0).abs() < 1e-5,
                        "{}: {px}: cpu {c:?} gpu {g:?}",
                        sensor.name
                    );
                }
            }
        }
        assert!(
            compared > 500,
            "{}: only {compared} pixels compared",
            sensor.name
        );
        assert!(
            worst < 1e-3,
            "{}: GPU and CPU disagree by {worst} mm",
            sensor.name
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
fn gpu_matches_the_cpu_pipeline() {
    gpu_matches_cpu(&small_sensor());
    // Other ray steps and kernel taps (the shaders take them as pipeline constants).
    let mut c = small_sensor().config.clone();
    c.render.ray_steps = 7;
    c.render.blend_tap_spacing = 0.5;
    gpu_matches_cpu(&Sensor::from_config("small-fine", c.clone()).unwrap());
    // Taps a texel apart for both kernels: the wide taps do not lie on every other
    // narrow one, and the meridians pass samples each kernel's own (WIDE_TAPS_NESTED off).
    c.render.blend_tap_spacing = 0.25;
    let apart = Sensor::from_config("small-apart", c).unwrap();
    let nested = |s: &Sensor| {
        let grid = render::HeightfieldGrid::for_sensor(s);
        render::uniforms::SensorUniform::new(s, &grid)
            .pipeline_constants()
            .iter()
            .find(|(name, _)| *name == "WIDE_TAPS_NESTED")
            .map(|&(_, v)| v)
    };
    assert_eq!(nested(&small_sensor()), Some(1.0));
    assert_eq!(nested(&apart), Some(0.0));
    gpu_matches_cpu(&apart);
}

fn gpu_matches_cpu(sensor: &Sensor) {
    let sensor = sensor.clone();
    let mut r = Renderer::new(&sensor).unwrap();
    let reference = cpu::render(&sensor, None).unwrap();
    let d = diff(&rgb(r.reference()), &rgb(&reference.frame), 3);
    assert!(close_enough(&d), "reference: {d:?}");
    for (solid, place) in [
        (Solid::Sphere, Place::Rotation(0.0)),
        (Solid::Cone, Place::Rotation(60.0)),
        (Solid::Slab, Place::Translation(5.0)),
        (Solid::Edge, Place::Rotation(90.0)),
    ] {
        let c = contact(solid, place, 1.0);
        let (gpu, _) = r.render(&c).unwrap();
        let cpu = cpu::render(&sensor, Some(&c)).unwrap();
        // The pixels re-rendered: the GPU's touched list against the CPU mirror's (f32 and
        // f64 may part on a probe at the very edge of the deformation).
        let touched =
            touched::select_touched(&sensor, r.grid(), &cpu.height, cpu.pixel_rect.unwrap());
        let (gpu_touched, cpu_touched) = (r.timings().touched_pixels as f64, touched.len() as f64);
        assert!(
            cpu_touched > 100.0 && (gpu_touched - cpu_touched).abs() <= 0.01 * cpu_touched,
            "{solid:?}: touched pixels GPU {gpu_touched}, CPU {cpu_touched}"
        );
        let d = diff(&rgb(&gpu), &rgb(&cpu.frame), 3);
        assert!(close_enough(&d), "{solid:?} at {place:?}: {d:?}");
        // The CPU pipeline over the footprint alone (the reference's pixels elsewhere): as
        // the full CPU render but for a pixel or two at the footprint's edge whose probes see
        // no deformation (measured: at most 4e-5 of the channel values, mean 5e-4 levels).
        let footprint = cpu::render_contact(&sensor, r.grid(), &reference.frame, &c).unwrap();
        let d = diff(&rgb(&footprint), &rgb(&cpu.frame), 3);
        assert!(close_enough(&d), "{solid:?}: CPU footprint render {d:?}");
        let worst = gpu
            .indentation
            .iter()
            .zip(&cpu.frame.indentation)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 0.05, "{solid:?}: indentation differs by {worst} mm");
        // The CPU pipeline must see a real imprint, or this comparison proves nothing.
        assert!(
            cpu.frame.indentation.iter().any(|&d| d > 0.2),
            "{solid:?}: no imprint"
        );
    }
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

/// The footprint bounds the work of a contact frame, so it must never cut an imprint short:
/// over the whole heightfield (not just the footprint), every texel the object pushes in
/// lies inside the pressed rectangle (where the contact stage traces), every texel the object
/// pushes in or the elastomer then moves inside the texel rectangle, and every pixel
/// that sees such a texel (at the undeformed surface or at the moved skin) inside the pixel
/// rectangle. Seven solids at the paper's eight positions, at three azimuths and spins, on
/// the paper's sensor and on a softer gel whose imprints spread and bulge further.
#[test]
fn footprints_hold_every_moved_texel_and_its_pixels() {
    let mut soft = common::paper_config();
    soft.elastomer.blend_mm = 1.0;
    soft.elastomer.bulge = 1.0;
    soft.elastomer.drape_mm = 3.0;
    // Every tap on the paper's sensor; on the soft one (its kernels are slow on the CPU) the
    // taps along the side, whose imprints run to the lens's edge.
    footprints_hold_moved_texels(&Sensor::preset("paper").unwrap(), 0);
    footprints_hold_moved_texels(&Sensor::from_config("soft", soft).unwrap(), 4);
}

/// Checks the taps at the paper's positions from index `first` on; and that the tiles the
/// renderer selects touched pixels from (`touched::select_tiles`, from their probes' texels)
/// hold every touched pixel of the pixel rectangle, while most of its tiles are left out.
fn footprints_hold_moved_texels(sensor: &Sensor, first: usize) {
    let sensor = sensor.clone();
    let grid = render::HeightfieldGrid::for_sensor(&sensor);
    let tiles = touched::probe_tiles(&sensor, &grid);
    let mut tally = TileTally::default();
    let reach = elastomer::Kernel::for_config(&sensor.config, &grid).reach_mm;
    let mut checked = 0;
    for (k, solid) in Solid::ALL.into_iter().enumerate() {
        for (m, (place, _)) in geltip::jobs::experiment::POSITIONS.iter().enumerate() {
            if m < first {
                continue;
            }
            let c = Contact {
                object: Arc::new(Object::Solid(solid)),
                place: *place,
                azimuth_deg: [0.0, 77.0, 200.0][(k + m) % 3],
                spin_deg: [0.0, 35.0, 110.0][(k + 2 * m) % 3],
                depth_mm: [1.0, 1.5][m % 2],
            };
            let what = format!("{}: {solid:?} at {place:?}", sensor.name);
            let pose = c.pose(&sensor).unwrap();
            let fp = render::contact::footprint(&sensor, &grid, &pose, &c.object, reach)
                .unwrap_or_else(|| panic!("{what}: no footprint"));
            let whole = render::Rect {
                x: 0,
                y: 0,
                w: grid.texels,
                h: grid.texels,
            };
            let p = render::contact::penetration_field(&sensor, &grid, &pose, &c.object, whole);
            let h = assert_blends_within(&what, &sensor, &grid, &p, &fp);
            assert_moved_within(&what, &sensor, &grid, &p, &h, &fp);
            tally.add(&what, &sensor, &grid, &h, &tiles, &fp);
            checked += 1;
        }
    }
    assert_eq!(checked, 7 * (8 - first));
    let TileTally {
        rect_tiles,
        listed_tiles,
        missed_by_middle,
    } = tally;
    assert!(
        missed_by_middle > 0,
        "{}: tiles by their middle probes alone held every touched pixel",
        sensor.name
    );
    assert!(
        (listed_tiles as f64) < 0.7 * rect_tiles as f64,
        "{}: {listed_tiles} of the pixel rectangles' {rect_tiles} tiles listed",
        sensor.name
    );
    eprintln!(
        "{}: {listed_tiles} of the pixel rectangles' {rect_tiles} tiles listed",
        sensor.name
    );
}

fn within(r: render::Rect, i: u32, j: u32) -> bool {
    i >= r.x && i < r.x + r.w && j >= r.y && j < r.y + r.h
}

/// The elastomer's passes over the footprint grown by 30 texels (8 mm) each side, from the
/// penetration `p`: every blend along a meridian that is not zero lies in the meridian rect
/// (the meridians pass runs over it alone). Returns the skin's displacement.
fn assert_blends_within(
    what: &str,
    sensor: &Sensor,
    grid: &render::HeightfieldGrid,
    p: &[f32],
    fp: &render::contact::Footprint,
) -> Vec<f32> {
    let (n, t) = (grid.texels, fp.texels);
    let grown = render::Rect {
        x: t.x.saturating_sub(30),
        y: t.y.saturating_sub(30),
        w: (t.x + t.w + 30).min(n) - t.x.saturating_sub(30),
        h: (t.y + t.h + 30).min(n) - t.y.saturating_sub(30),
    };
    let config = &sensor.config.elastomer;
    let kernel = elastomer::Kernel::for_config(&sensor.config, grid);
    let meridian = elastomer::blend_meridian(grid, config, kernel, p, grown);
    let mut blended = 0;
    for j in 0..n {
        for i in 0..n {
            let v = meridian[(j * n + i) as usize];
            if v != DVec2::ZERO {
                blended += 1;
                assert!(
                    within(fp.meridians, i, j),
                    "{what}: texel ({i}, {j}) blends {v} outside {:?}",
                    fp.meridians
                );
            }
        }
    }
    assert!(blended > 20, "{what}: only {blended} texels blend");
    let finger = &sensor.finger;
    elastomer::blend_azimuth(finger, grid, config, kernel, p, &meridian, grown).0
}

/// Every texel the object pushes in (`p`) lies in the pressed rect, every texel it pushes
/// in or the elastomer moves (`h`) in the texel rect, and every pixel that sees such a
/// texel (at the undeformed surface or at the moved skin) in the pixel rect.
fn assert_moved_within(
    what: &str,
    sensor: &Sensor,
    grid: &render::HeightfieldGrid,
    p: &[f32],
    h: &[f32],
    fp: &render::contact::Footprint,
) {
    let (n, t, pressed, px) = (grid.texels, fp.texels, fp.pressed, fp.pixels.unwrap());
    let mut moved = 0;
    for j in 0..n {
        for i in 0..n {
            let idx = (j * n + i) as usize;
            if p[idx] == 0.0 && h[idx] == 0.0 {
                continue;
            }
            moved += 1;
            assert!(
                p[idx] == 0.0 || within(pressed, i, j),
                "{what}: texel ({i}, {j}) is pressed ({}) outside {pressed:?}",
                p[idx]
            );
            assert!(
                within(t, i, j),
                "{what}: texel ({i}, {j}) moves (p {}, h {}) outside {t:?}",
                p[idx],
                h[idx]
            );
            let coord = geltip::finger::SurfaceCoord::from_disc(grid.texel_centre(i, j));
            let sp = sensor.finger.point_at(coord);
            for depth in [0.0, h[idx] as f64] {
                if let Ok(q) = sensor.project(sp.point - depth * sp.normal) {
                    assert!(
                        q.x >= px.x as f64 - 0.5
                            && q.x <= (px.x + px.w) as f64 - 0.5
                            && q.y >= px.y as f64 - 0.5
                            && q.y <= (px.y + px.h) as f64 - 0.5,
                        "{what}: texel ({i}, {j}) is seen at {q} outside {px:?}"
                    );
                }
            }
        }
    }
    assert!(moved > 20, "{what}: only {moved} texels move");
}

/// Tiles over the taps: those of the pixel rects, those listed, and the touched pixels
/// whose tiles a cull by the tiles' middle probes alone leaves out (a cull that must miss
/// some, or the check could not tell a good cull from a bad one).
#[derive(Default)]
struct TileTally {
    rect_tiles: usize,
    listed_tiles: usize,
    missed_by_middle: usize,
}

impl TileTally {
    /// Checks that the tiles listed for the skin `h` hold every touched pixel of the
    /// footprint's pixel rect, and counts them.
    fn add(
        &mut self,
        what: &str,
        sensor: &Sensor,
        grid: &render::HeightfieldGrid,
        h: &[f32],
        tiles: &[[touched::TexelRange; 3]],
        fp: &render::contact::Footprint,
    ) {
        let (t, px) = (fp.texels, fp.pixels.unwrap());
        let empty = [1, 1, 0, 0];
        let middle_only: Vec<_> = tiles.iter().map(|r| [empty, r[1], empty]).collect();
        let (across, _) = touched::tile_grid(sensor.width, sensor.height);
        let listed = touched::select_tiles(sensor, grid, h, tiles, px, t);
        let by_middle = touched::select_tiles(sensor, grid, h, &middle_only, px, t);
        let touched_pixels = touched::select_touched(sensor, grid, h, px);
        assert!(!touched_pixels.is_empty(), "{what}: no pixel touched");
        for &i in &touched_pixels {
            let (x, y) = (i % sensor.width, i / sensor.width);
            let tile = (y / touched::PIXEL_TILE) * across + x / touched::PIXEL_TILE;
            assert!(
                listed.contains(&tile),
                "{what}: touched pixel ({x}, {y}) lies in tile {tile}, not listed"
            );
            self.missed_by_middle += !by_middle.contains(&tile) as usize;
        }
        let (columns, rows) = touched::tiles_over(px);
        self.rect_tiles += columns.len() * rows.len();
        self.listed_tiles += listed.len();
    }
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

/// A small contact (a cone 0.3 mm deep) and its frame from a fresh renderer of `sensor`:
/// what a renderer that rendered other frames first must give for it.
fn small_contact_alone(sensor: &Sensor) -> (Contact, Frame) {
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
    let refused = render::Press::from(&contact(Solid::Sphere, Place::Rotation(45.0), -1.0));
    let e = r.render_scene(&[refused]).unwrap_err().to_string();
    assert!(e.contains("--depth"), "{e}");
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
    c.render.noise = 2.0;
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
    c.render.noise = 2.0;
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
            "--depth",
        ),
        (
            contact(Solid::Sphere, Place::Rotation(0.0), f64::NAN),
            "--depth",
        ),
        (
            contact(Solid::Sphere, Place::Translation(40.0), 1.0),
            "--at",
        ),
        (contact(Solid::Sphere, Place::Rotation(-5.0), 1.0), "--at"),
    ] {
        let err = r.render(&c).unwrap_err().to_string();
        assert!(err.contains(what), "{err}");
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
        let loaded = Contact {
            object: mesh,
            ..analytic.clone()
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
