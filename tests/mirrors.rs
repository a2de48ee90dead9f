//! The GPU renderer against the CPU mirrors of its stages: its lens rays against the CPU
//! projection map, its frames against the CPU pipeline's, and the footprints and tile lists
//! that bound a frame's work against every texel and pixel the CPU mirrors move.

mod common;
mod support;

use geltip::object::{Object, Solid};
use geltip::render::gpu::Renderer;
use geltip::render::softness::Softness;
use geltip::render::{self, cpu, elastomer, touched, Place, Press};
use geltip::sensor::Sensor;
use glam::DVec2;
use std::sync::Arc;
use support::{close_enough, contact, diff, rgb, small_sensor};

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

/// A calibrated sensor's light: five LEDs listed with their own colours, places, spreads
/// (so the shaders read each one's instead of a shared constant) and fall-offs, coloured
/// ambient light and paint, and vignetting.
#[test]
fn gpu_matches_the_cpu_pipeline_under_a_calibrated_light() {
    use geltip::sensor::{LedConfig, Leds};
    let mut c = small_sensor().config.clone();
    let led =
        |colour: [f64; 3], azimuth_deg: f64, z_mm: f64, spread: f64, falloff_mm: f64| LedConfig {
            colour,
            azimuth_deg,
            z_mm,
            radius_mm: Some(3.0 + azimuth_deg / 200.0),
            intensity: 1.5 + azimuth_deg / 360.0,
            spread,
            falloff_mm,
            ..LedConfig::new(colour, azimuth_deg)
        };
    c.leds = Leds::List(vec![
        led([1.0, 0.2, 0.7], 10.0, -2.0, 1.5, 8.0),
        led([0.3, 1.0, 0.2], 80.0, -4.0, 3.0, 12.0),
        led([0.2, 0.4, 1.0], 150.0, 1.0, 0.0, 6.0),
        led([0.9, 0.9, 0.9], 230.0, -1.0, 2.5, 20.0),
        led([0.5, 0.1, 1.0], 300.0, -6.0, 7.25, 9.0),
    ]);
    c.light.ambient = Some([0.08, 0.03, 0.12]);
    c.light.vignetting = [-0.35, 0.2];
    c.paint.colour = [0.95, 0.8, 1.0];
    c.paint.shininess = 17.5;
    let sensor = Sensor::from_config("small-calibrated", c).unwrap();
    let constants = |s: &Sensor| {
        let grid = render::HeightfieldGrid::for_sensor(s);
        render::uniforms::SensorUniform::new(s, &grid).pipeline_constants()
    };
    let value = |s: &Sensor, name: &str| {
        constants(s)
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, v)| v)
    };
    assert_eq!(value(&sensor, "LED_COUNT"), Some(5.0));
    assert_eq!(value(&sensor, "LED_SPREAD"), Some(-1.0));
    assert_eq!(value(&sensor, "VIGNETTING"), Some(1.0));
    assert_eq!(value(&small_sensor(), "VIGNETTING"), Some(0.0));
    gpu_matches_cpu(&sensor);
    // The light changes the picture: the CPU mirror with the paper's ring is far from it.
    let ring = cpu::render(&small_sensor(), None).unwrap();
    let listed = cpu::render(&sensor, None).unwrap();
    assert!(!close_enough(&diff(
        &rgb(&ring.frame),
        &rgb(&listed.frame),
        3
    )));
}

/// An image circle the camera cuts apart from the lens (`image.circle`: a mask off the
/// principal point, inside what the lens sees) and vignetting measured over it: the GPU
/// against the CPU mirror, black outside the mask and lit inside it, and the mask moved
/// by 3 px changes the picture.
#[test]
fn gpu_matches_the_cpu_pipeline_behind_an_image_circle_mask() {
    let masked = |cx: f64| {
        let mut c = small_sensor().config.clone();
        c.image.circle = Some([cx, 62.0, 50.0]);
        c.light.vignetting = [-0.35, 0.2];
        Sensor::from_config("small-masked", c).unwrap()
    };
    let sensor = masked(72.0);
    gpu_matches_cpu(&sensor);
    let picture = Renderer::new(&sensor).unwrap().reference().to_rgb();
    let (mut outside, mut lit) = (0, 0);
    for (x, y, p) in picture.enumerate_pixels() {
        let d = (x as f64 - 72.0).hypot(y as f64 - 62.0);
        if d > 50.5 {
            assert_eq!(p.0, [0, 0, 0], "({x}, {y}) outside the mask is lit");
            outside += 1;
        } else if d < 49.5 && p.0 != [0, 0, 0] {
            lit += 1;
        }
    }
    assert!(outside > 5000 && lit > 7000, "{outside} black, {lit} lit");
    let moved = Renderer::new(&masked(75.0)).unwrap().reference().to_rgb();
    assert!(!close_enough(&diff(picture.as_raw(), moved.as_raw(), 3)));
}

/// Light carried in the gel (gel LEDs, each with its own band, beside a point LED) and a
/// camera with its own colour matrix and gamma: the shaders' gel_light and encode_gamma
/// against the CPU mirror, on the reference and four contacts (whose flanks the relief
/// lights).
#[test]
fn gpu_matches_the_cpu_pipeline_under_gel_light_and_a_camera_response() {
    use geltip::sensor::{CameraConfig, LedConfig, Leds};
    let mut c = small_sensor().config.clone();
    let gel = |colour: [f64; 3], azimuth_deg: f64, width: f64, relief: f64| LedConfig {
        intensity: 1.2,
        z_mm: 0.5,
        width_mm: Some(width),
        widening: Some(0.15),
        attenuation_mm: Some(14.0),
        relief: Some(relief),
        ..LedConfig::gel(colour, azimuth_deg)
    };
    let mut leds: Vec<LedConfig> = (0..12)
        .map(|i| {
            let a = 30.0 * i as f64;
            let colour = [[1.0, 0.1, 0.2], [0.1, 1.0, 0.3], [0.2, 0.3, 1.0]][i % 3];
            gel(colour, a, 1.5 + 0.2 * i as f64, 0.5 + 0.25 * i as f64)
        })
        .collect();
    leds.push(LedConfig::new([0.4, 0.4, 0.4], 45.0));
    c.leds = Leds::List(leds);
    c.camera = CameraConfig {
        colour_matrix: [[1.0, -0.3, -0.1], [-0.2, 1.0, -0.05], [-0.1, -0.25, 1.0]],
        gamma: [2.5, 2.8, 3.3],
        ..CameraConfig::default()
    };
    c.light.ambient = Some([0.05, 0.04, 0.06]);
    let sensor = Sensor::from_config("small-gel", c.clone()).unwrap();
    let grid = render::HeightfieldGrid::for_sensor(&sensor);
    let constants = render::uniforms::SensorUniform::new(&sensor, &grid).pipeline_constants();
    let value = |name: &str| constants.iter().find(|(n, _)| *n == name).map(|&(_, v)| v);
    assert_eq!(value("GEL_LEDS"), Some(1.0));
    assert_eq!(value("CAMERA_RESPONSE"), Some(1.0));
    assert_eq!(value("LED_COUNT"), Some(13.0));
    gpu_matches_cpu(&sensor);
    // Each term changes the picture: without the camera's response, or with the gel LEDs'
    // relief off, the CPU mirror's frames are far from these.
    let with = cpu::render(&sensor, None).unwrap();
    let mut plain = c.clone();
    plain.camera = CameraConfig::default();
    let plain = cpu::render(&Sensor::from_config("plain", plain).unwrap(), None).unwrap();
    assert!(!close_enough(&diff(
        &rgb(&with.frame),
        &rgb(&plain.frame),
        3
    )));
    let press = contact(Solid::Sphere, Place::Rotation(60.0), 1.0);
    let pressed = cpu::render(&sensor, Some(&press)).unwrap();
    let mut flat = c;
    if let Leds::List(list) = &mut flat.leds {
        for l in list.iter_mut().filter(|l| l.relief.is_some()) {
            l.relief = Some(0.0);
        }
    }
    let flat = Sensor::from_config("flat", flat).unwrap();
    let flat_pressed = cpu::render(&flat, Some(&press)).unwrap();
    assert!(!close_enough(&diff(
        &rgb(&pressed.frame),
        &rgb(&flat_pressed.frame),
        3
    )));
}

/// Ambient light that shades with the skin's tilt (`light.ambient_relief`): the shaders'
/// ambient_light against the CPU mirror, on the reference and four contacts; the empty
/// finger (no tilt) keeps its light to the byte, an imprint's flanks change with the term
/// and with its channel.
#[test]
fn gpu_matches_the_cpu_pipeline_under_an_ambient_that_shades_with_tilt() {
    let mut c = small_sensor().config.clone();
    c.leds = geltip::sensor::Leds::List(gel_ring(6, 60.0));
    c.light.ambient = Some([0.3, 0.2, 0.25]);
    let flat = Sensor::from_config("small-flat-ambient", c.clone()).unwrap();
    c.light.ambient_relief = [2.0, -1.5, 0.0];
    let sensor = Sensor::from_config("small-ambient-relief", c.clone()).unwrap();
    let grid = render::HeightfieldGrid::for_sensor(&sensor);
    let constants = render::uniforms::SensorUniform::new(&sensor, &grid).pipeline_constants();
    assert!(constants.contains(&("AMBIENT_RELIEF", 1.0)));
    let flat_grid = render::HeightfieldGrid::for_sensor(&flat);
    assert!(render::uniforms::SensorUniform::new(&flat, &flat_grid)
        .pipeline_constants()
        .contains(&("AMBIENT_RELIEF", 0.0)));
    gpu_matches_cpu(&sensor);
    // The empty finger keeps the flat ambient's light to the byte, on both renderers; a
    // pressed flank does not, and only in the channels the term is given.
    let reference = |s: &Sensor| rgb(&cpu::render(s, None).unwrap().frame);
    assert_eq!(reference(&sensor), reference(&flat));
    let gpu_reference = |s: &Sensor| rgb(render::gpu::Renderer::new(s).unwrap().reference());
    assert_eq!(gpu_reference(&sensor), gpu_reference(&flat));
    let press = contact(Solid::Sphere, Place::Rotation(60.0), 1.0);
    let pressed = rgb(&cpu::render(&sensor, Some(&press)).unwrap().frame);
    let flat_pressed = rgb(&cpu::render(&flat, Some(&press)).unwrap().frame);
    assert!(!close_enough(&diff(&pressed, &flat_pressed, 3)));
    let most = |k: usize| {
        pressed
            .chunks(3)
            .zip(flat_pressed.chunks(3))
            .map(|(a, b)| a[k].abs_diff(b[k]))
            .max()
            .unwrap()
    };
    assert!(
        most(0) >= 4 && most(1) >= 4,
        "red {} green {}",
        most(0),
        most(1)
    );
    assert!(most(2) <= 1, "blue {}", most(2));
}

/// A clear shell ending below the tip (`[shell_end]`) over gel light: the shaders'
/// shell_end_light against the CPU mirror, on the reference and four contacts; the term
/// darkens the tip it is given and leaves a sensor without one as it was.
#[test]
fn gpu_matches_the_cpu_pipeline_past_a_shell_end() {
    let mut c = small_sensor().config.clone();
    c.leds = geltip::sensor::Leds::List(narrow_gel_ring());
    let plain = Sensor::from_config("small-gel", c.clone()).unwrap();
    c.shell_end = Some(small_shell_end(&c, None));
    let sensor = Sensor::from_config("small-shell-end", c).unwrap();
    let grid = render::HeightfieldGrid::for_sensor(&sensor);
    let constants = render::uniforms::SensorUniform::new(&sensor, &grid).pipeline_constants();
    assert!(constants.contains(&("SHELL_END", 1.0)));
    gpu_matches_cpu(&sensor);
    // The tip (the image's centre) is darker with the end than without; the picture's edge,
    // seen through the shell far from the end, is the same.
    let with = cpu::render(&sensor, None).unwrap();
    let without = cpu::render(&plain, None).unwrap();
    let level = |frame: &render::Frame, x: u32, y: u32| {
        let i = 4 * (y * frame.width + x) as usize;
        frame.rgba[i..i + 3].iter().map(|&v| v as u32).sum::<u32>()
    };
    assert!(level(&with.frame, 75, 60) + 30 < level(&without.frame, 75, 60));
    assert!(!close_enough(&diff(
        &rgb(&with.frame),
        &rgb(&without.frame),
        3
    )));
    let ring = sensor.principal + DVec2::new(sensor.lens.max_rho() * 0.98, 0.0);
    let (x, y) = (ring.x.round() as u32, ring.y.round() as u32);
    assert!(level(&with.frame, x, y).abs_diff(level(&without.frame, x, y)) <= 3);
}

/// The LEDs' own glow at a shell's end (`leds[*].end_glow`, `shell_end.led_glow_deg`): the
/// shaders' end_glow against the CPU mirror, on the reference and four contacts; it tints
/// the rim round each glowing LED and leaves the tip and the rest of the picture as they
/// were, and an end without `led_glow_deg` renders as before.
#[test]
fn gpu_matches_the_cpu_pipeline_with_the_leds_glowing_at_a_shell_end() {
    use geltip::sensor::{Leds, ShellEndConfig};
    let mut c = small_sensor().config.clone();
    let ring = narrow_gel_ring();
    c.leds = Leds::List(ring.clone());
    let end = small_shell_end(&c, Some(25.0));
    c.shell_end = Some(end);
    // Switched on but with no LED glowing: the same bytes as the plain end.
    let on_but_dark = Sensor::from_config("small-end-dark", c.clone()).unwrap();
    let mut plain_c = c.clone();
    plain_c.shell_end = Some(ShellEndConfig {
        led_glow_deg: None,
        ..end
    });
    let plain = Sensor::from_config("small-end-plain", plain_c).unwrap();
    let dark = cpu::render(&on_but_dark, None).unwrap();
    let before = cpu::render(&plain, None).unwrap();
    assert_eq!(dark.frame.rgba, before.frame.rgba);
    // Two LEDs glow, in red and in blue (one dimmer in green).
    let mut glowing = ring;
    glowing[0].end_glow = [1.5, 0.0, 0.0];
    glowing[4].end_glow = [0.0, -0.5, 2.0];
    c.leds = Leds::List(glowing);
    let sensor = Sensor::from_config("small-end-glow", c).unwrap();
    let grid = render::HeightfieldGrid::for_sensor(&sensor);
    let constants = render::uniforms::SensorUniform::new(&sensor, &grid).pipeline_constants();
    assert!(constants.contains(&("END_GLOW", 1.0)));
    gpu_matches_cpu(&sensor);
    let with = cpu::render(&sensor, None).unwrap();
    assert!(!close_enough(&diff(
        &rgb(&with.frame),
        &rgb(&before.frame),
        3
    )));
    // Just outside the end's edge towards LED 0 (azimuth 0, image +x) red rises and blue
    // does not; the tip (the centre) is as it was.
    let pixel_at = |azimuth_deg: f64| {
        let theta = (end.inner_radius_mm * 1.15).atan2(end.z_mm);
        let rho = sensor.lens.project(theta);
        let a = azimuth_deg.to_radians();
        let p = sensor.principal + DVec2::new(rho * a.cos(), rho * a.sin());
        (p.x.round() as u32, p.y.round() as u32)
    };
    let channel = |frame: &render::Frame, (x, y): (u32, u32), k: usize| {
        frame.rgba[4 * (y * frame.width + x) as usize + k] as i32
    };
    let at = pixel_at(0.0);
    assert!(channel(&with.frame, at, 0) >= channel(&before.frame, at, 0) + 10);
    assert!((channel(&with.frame, at, 2) - channel(&before.frame, at, 2)).abs() <= 2);
    let centre = (sensor.principal.x as u32, sensor.principal.y as u32);
    for k in 0..3 {
        assert!((channel(&with.frame, centre, k) - channel(&before.frame, centre, k)).abs() <= 1);
    }
}

/// The camera's softness (`[camera] blur_px`): both renderers blur the same frames the same
/// way (the contact's only where it changed them), and the blur changes them.
#[test]
fn gpu_matches_the_cpu_pipeline_through_a_soft_camera() {
    let mut c = small_sensor().config.clone();
    c.camera.blur_px = 2.0;
    let sensor = Sensor::from_config("small-soft", c).unwrap();
    gpu_matches_cpu(&sensor);
    let soft = cpu::render(&sensor, None).unwrap();
    let sharp = cpu::render(&small_sensor(), None).unwrap();
    assert_eq!(soft.raw().rgba, sharp.frame.rgba);
    assert!(!close_enough(&diff(
        &rgb(&soft.frame),
        &rgb(&sharp.frame),
        3
    )));
}

/// `count` gel LEDs `step_deg` apart, 0.5 mm up the finger, red, green and blue in turn.
fn gel_ring(count: usize, step_deg: f64) -> Vec<geltip::sensor::LedConfig> {
    (0..count)
        .map(|i| geltip::sensor::LedConfig {
            z_mm: 0.5,
            ..geltip::sensor::LedConfig::gel(
                [[1.0, 0.2, 0.1], [0.1, 1.0, 0.2], [0.2, 0.3, 1.0]][i % 3],
                step_deg * i as f64,
            )
        })
        .collect()
}

/// Nine gel LEDs 40 degrees apart with narrow bands that widen fast.
fn narrow_gel_ring() -> Vec<geltip::sensor::LedConfig> {
    gel_ring(9, 40.0)
        .into_iter()
        .map(|l| geltip::sensor::LedConfig {
            width_mm: Some(2.0),
            widening: Some(0.4),
            ..l
        })
        .collect()
}

/// A clear shell ending at the hemisphere's base of the finger of `c`, its LEDs glowing
/// there over `led_glow_deg` when given.
fn small_shell_end(
    c: &geltip::sensor::SensorConfig,
    led_glow_deg: Option<f64>,
) -> geltip::sensor::ShellEndConfig {
    geltip::sensor::ShellEndConfig {
        z_mm: c.finger.cylinder_length_mm,
        inner_radius_mm: 0.6 * c.finger.radius_mm,
        tip_colour: [0.02, 0.05, 0.1],
        tip_transmit: 0.3,
        rim_glow: 0.6,
        rim_width_mm: 1.5,
        led_glow_deg,
    }
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
        let footprint = match Softness::of(&sensor) {
            Some(softness) => cpu::record_contact(
                &sensor,
                r.grid(),
                reference.raw(),
                &reference.frame,
                &softness,
                &c,
            ),
            None => cpu::render_contact(&sensor, r.grid(), reference.raw(), &c),
        }
        .unwrap();
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
            let azimuth = [0.0, 77.0, 200.0][(k + m) % 3];
            let c = Press::at(
                Arc::new(Object::Solid(solid)),
                *place,
                azimuth,
                [1.0, 1.5][m % 2],
            )
            .spun([0.0, 35.0, 110.0][(k + 2 * m) % 3]);
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
