//! Structs shared with WGSL (`shaders/shared/common.wgsl`): explicitly padded `#[repr(C)]`
//! Pod types whose sizes are asserted here and whose layout a test checks against naga's.

use super::contact::Footprint;
use super::{ContactPose, HeightfieldGrid, Rect};
use crate::object::Object;
use crate::sensor::{LedKind, Sensor, MAX_LEDS};
use bytemuck::{Pod, Zeroable};

/// WGSL `Sensor`: everything about the sensor that every stage reads.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SensorUniform {
    pub radius: f32,
    pub cylinder_length: f32,
    pub shell_thickness: f32,
    pub junction_s: f32,
    pub lens_model: u32,
    pub focal_px: f32,
    pub max_theta: f32,
    pub max_rho: f32,
    pub k: [f32; 4],
    pub principal: [f32; 2],
    pub image_size: [u32; 2],
    pub texels: u32,
    pub ray_steps: u32,
    pub half_size_mm: f32,
    pub texel_mm: f32,
    pub blend_mm: f32,
    pub bulge: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
    /// LEDs in use (the shaders take it as a pipeline constant).
    pub led_count: u32,
    /// The spread every LED shares, or -1 when they differ (a pipeline constant).
    pub spread: f32,
    pub drape_mm: f32,
    /// Surface mm between the narrow and the wide Gaussian's taps.
    pub narrow_step_mm: f32,
    pub wide_step_mm: f32,
    /// Their taps each side (the shaders take these as pipeline constants).
    pub narrow_taps: u32,
    pub wide_taps: u32,
    /// Sensor noise by channel (8-bit levels; w unused).
    pub noise: [f32; 4],
    /// Ambient light (linear RGB; w unused).
    pub ambient: [f32; 4],
    /// The paint's colour (linear RGB; w unused).
    pub paint_colour: [f32; 4],
    /// Vignetting: x a, y b, z one over the image circle's radius (px); w unused.
    pub vignetting: [f32; 4],
    /// Each LED's position (xyz; w 1 for a gel LED, 0 for a point LED), colour (xyz; w
    /// unused), light (x intensity, y spread, z falloff_mm; w unused) and a gel LED's band
    /// (x width_mm, y widening, z attenuation_mm, w relief). LEDs past `led_count` are zero.
    pub led_position: [[f32; 4]; MAX_LEDS],
    pub led_colour: [[f32; 4]; MAX_LEDS],
    pub led_light: [[f32; 4]; MAX_LEDS],
    pub led_band: [[f32; 4]; MAX_LEDS],
    /// Each LED's glow at a clear shell's open end, per channel (xyz; w unused).
    pub led_end_glow: [[f32; 4]; MAX_LEDS],
    /// The camera's colour matrix by row (xyz; w unused) and one over its gamma by channel
    /// (xyz; w unused).
    pub colour_matrix: [[f32; 4]; 3],
    pub inverse_gamma: [f32; 4],
    /// Whether any LED is a gel LED, whether the camera is not the plain gamma 2.2, and
    /// whether a clear shell ends below the tip (pipeline constants GEL_LEDS,
    /// CAMERA_RESPONSE and SHELL_END; the shaders do not read these).
    pub gel_leds: u32,
    pub camera_response: u32,
    pub has_shell_end: u32,
    pub pad: u32,
    /// The image circle when the sensor file gives one as a mask: centre (xy), radius
    /// squared (z), 1 when there is one (w).
    pub image_circle: [f32; 4],
    /// The shell's open end: height, inner radius, rim glow and rim width (mm); the tip's
    /// own light (xyz) and tip_transmit (w). Zero without one.
    pub shell_end: [f32; 4],
    pub shell_tip: [f32; 4],
    /// How the ambient light shades with the skin's tilt, per channel (xyz; w unused; the
    /// pipeline constant AMBIENT_RELIEF says whether it does).
    pub ambient_relief: [f32; 4],
    /// x: how tightly each LED's glow keeps to its azimuth at the shell's end, one over the
    /// square of its spread (radians; the pipeline constant END_GLOW says whether the LEDs
    /// glow there); yzw unused.
    pub shell_glow: [f32; 4],
    /// The elastomer kernels' normalised weights by tap (x narrow, y wide; zw unused):
    /// [`super::elastomer::blend_weights`].
    pub blend_weights: [[f32; 4]; BLEND_WEIGHTS],
}

/// Entries of the weight table: taps 0..=MAX_BLEND_TAPS.
pub const BLEND_WEIGHTS: usize = super::elastomer::MAX_BLEND_TAPS as usize + 1;

const _: () =
    assert!(std::mem::size_of::<SensorUniform>() == 352 + 5 * 16 * MAX_LEDS + 16 * BLEND_WEIGHTS);

/// WGSL `Frame`: one contact.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FrameUniform {
    pub texel_rect: [u32; 4],
    pub pixel_rect: [u32; 4],
    pub object_x: [f32; 4],
    pub object_y: [f32; 4],
    pub object_z: [f32; 4],
    pub origin: [f32; 4],
    pub object_kind: u32,
    pub grid_dims: [u32; 3],
    pub grid_origin: [f32; 4],
    pub noise_seed: u32,
    /// The rect of the image the frame's image and indentation buffers hold: its corner and
    /// the pixels from one of its rows to the next ([`image_pitch`] of its width).
    pub image_origin: [u32; 2],
    pub image_pitch: u32,
    /// The texels the contact stage traces: those the object can press.
    pub pressed_rect: [u32; 4],
    /// The texels the elastomer's meridians pass runs over (`Footprint::meridians`).
    pub meridian_rect: [u32; 4],
    /// A sized primitive's sizes (`Primitive::gpu_size`); zero for other objects.
    pub object_size: [f32; 4],
    /// Where a frame's data lies in the buffers bound for its wave (the frames of a
    /// submission recorded side by side, whose stages each run as one dispatch): its lane
    /// (its heightfield, and layer of the maps), the word its image and indentation slice
    /// starts at, the word its counters start at, and the word of the height buffer where a
    /// contact's own penetration field starts (`contact.wgsl`).
    pub lane: u32,
    pub image_at: u32,
    pub counters_at: u32,
    pub field_at: u32,
    /// Frames of the wave whose pixels are selected and cast: the frames the passes over
    /// their lists find their workgroups among (`touched.wgsl` wave_bases).
    pub listed_frames: u32,
    /// The size of the rect the image buffers hold (with `image_origin`).
    pub image_size: [u32; 2],
    /// The word of the counters binding where the frame's touched list starts, its tile
    /// list after it (`shared/touched_list.wgsl`).
    pub list_at: u32,
    /// A dispatch over its frames' work side by side (`Binds::spread`): the first of the
    /// dispatch's workgroups that are this frame's, and the frames the dispatch binds
    /// (`shared/common.wgsl` use_frame_of).
    pub group_base: u32,
    pub group_items: u32,
    pub _pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<FrameUniform>() == 240);

/// `object_kind` of a loaded mesh's baked SDF grid (WGSL `GRID_OBJECT`).
pub const GRID_OBJECT: u32 = 100;
/// `object_kind` of the reference frame: no object, every pixel shaded (WGSL `REFERENCE_FRAME`).
pub const REFERENCE_FRAME: u32 = 101;

/// A rect as a uniform holds it: x, y, w, h (all zero without one).
pub fn rect4(r: Option<Rect>) -> [u32; 4] {
    r.map(|r| [r.x, r.y, r.w, r.h]).unwrap_or([0; 4])
}

impl SensorUniform {
    pub fn new(sensor: &Sensor, grid: &HeightfieldGrid) -> Self {
        let c = &sensor.config;
        let light = sensor.lighting();
        let mut leds = [[[0.0f32; 4]; MAX_LEDS]; 5];
        for (i, l) in light.leds.iter().enumerate() {
            let gel = match l.kind {
                LedKind::Point => None,
                LedKind::Gel(band) => Some(band),
            };
            leds[0][i] = vec4(l.position, if gel.is_some() { 1.0 } else { 0.0 });
            leds[1][i] = vec4(l.colour, 0.0);
            leds[4][i] = vec4(l.end_glow, 0.0);
            leds[2][i] = [
                l.intensity as f32,
                l.spread as f32,
                l.falloff_mm as f32,
                0.0,
            ];
            if let Some(b) = gel {
                leds[3][i] = [
                    b.width_mm as f32,
                    b.widening as f32,
                    b.attenuation_mm as f32,
                    b.relief as f32,
                ];
            }
        }
        let camera = &light.camera;
        let row = |r: [f64; 3]| [r[0] as f32, r[1] as f32, r[2] as f32, 0.0];
        let noise = c.render.noise.rgb();
        let f = &sensor.finger;
        let kernel = super::elastomer::Kernel::for_config(c, grid);
        let mut blend_weights = [[0.0f32; 4]; BLEND_WEIGHTS];
        for (slot, w) in blend_weights
            .iter_mut()
            .zip(super::elastomer::blend_weights(&c.elastomer, kernel))
        {
            *slot = [w.x as f32, w.y as f32, 0.0, 0.0];
        }
        SensorUniform {
            radius: f.radius as f32,
            cylinder_length: f.cylinder_length as f32,
            shell_thickness: f.shell_thickness as f32,
            junction_s: f.junction_s() as f32,
            lens_model: match sensor.lens.model {
                crate::LensModel::Pinhole => 0,
                crate::LensModel::Equidistant => 1,
                crate::LensModel::Equisolid => 2,
                crate::LensModel::KannalaBrandt => 3,
            },
            focal_px: sensor.lens.focal_px as f32,
            max_theta: sensor.lens.max_theta as f32,
            max_rho: sensor.lens.max_rho() as f32,
            k: sensor.lens.k.map(|k| k as f32),
            principal: [sensor.principal.x as f32, sensor.principal.y as f32],
            image_size: [sensor.width, sensor.height],
            texels: grid.texels,
            ray_steps: c.render.ray_steps,
            half_size_mm: grid.half_size_mm as f32,
            texel_mm: grid.texel_mm() as f32,
            blend_mm: c.elastomer.blend_mm as f32,
            bulge: c.elastomer.bulge as f32,
            diffuse: c.paint.diffuse as f32,
            specular: c.paint.specular as f32,
            shininess: c.paint.shininess as f32,
            led_count: light.leds.len() as u32,
            spread: light.shared_spread().map_or(-1.0, |s| s as f32),
            drape_mm: c.elastomer.drape_mm as f32,
            narrow_step_mm: kernel.narrow.step_mm as f32,
            wide_step_mm: kernel.wide.step_mm as f32,
            narrow_taps: kernel.narrow.count as u32,
            wide_taps: kernel.wide.count as u32,
            noise: [noise[0] as f32, noise[1] as f32, noise[2] as f32, 0.0],
            ambient: vec4(light.ambient, 0.0),
            paint_colour: vec4(light.paint_colour, 0.0),
            vignetting: [
                light.vignetting[0] as f32,
                light.vignetting[1] as f32,
                (1.0 / sensor.image_circle().1) as f32,
                0.0,
            ],
            led_position: leds[0],
            led_colour: leds[1],
            led_light: leds[2],
            led_band: leds[3],
            led_end_glow: leds[4],
            colour_matrix: camera.colour_matrix.map(row),
            inverse_gamma: row(camera.gamma.map(|g| 1.0 / g)),
            gel_leds: light.has_gel_leds() as u32,
            camera_response: !camera.has_default_response() as u32,
            has_shell_end: light.shell_end.is_some() as u32,
            pad: 0,
            image_circle: c.image.circle.map_or([0.0; 4], |[cx, cy, r]| {
                [cx as f32, cy as f32, (r as f32) * (r as f32), 1.0]
            }),
            shell_end: light.shell_end.map_or([0.0; 4], |e| {
                [
                    e.z_mm as f32,
                    e.inner_radius_mm as f32,
                    e.rim_glow as f32,
                    e.rim_width_mm as f32,
                ]
            }),
            shell_tip: light.shell_end.map_or([0.0; 4], |e| {
                let [r, g, b] = e.tip_colour.map(|c| c as f32);
                [r, g, b, e.tip_transmit as f32]
            }),
            ambient_relief: vec4(light.ambient_relief, 0.0),
            shell_glow: [
                light
                    .shell_end
                    .and_then(|e| e.led_glow_deg)
                    .map_or(0.0, |d| super::leds::end_glow_concentration(d) as f32),
                0.0,
                0.0,
                0.0,
            ],
            blend_weights,
        }
    }

    /// Values of the shaders' pipeline-overridable constants (`shared/common.wgsl`): the
    /// fields that shape control flow, and the shading's exponents, fixed per sensor so the
    /// driver can fold the lens switch, unroll the loops and multiply whole powers out.
    pub fn pipeline_constants(&self) -> [(&'static str, f64); 15] {
        // Nested exactly as the shader steps them: the wide step twice the narrow one in f32.
        let nested = self.wide_step_mm == 2.0 * self.narrow_step_mm;
        [
            ("LENS_MODEL", self.lens_model as f64),
            ("RAY_STEPS", self.ray_steps as f64),
            ("NARROW_TAPS", self.narrow_taps as f64),
            ("WIDE_TAPS", self.wide_taps as f64),
            ("WIDE_TAPS_NESTED", if nested { 1.0 } else { 0.0 }),
            ("LED_COUNT", self.led_count as f64),
            ("LED_SPREAD", self.spread as f64),
            ("PAINT_SHININESS", self.shininess as f64),
            (
                "VIGNETTING",
                if self.vignetting[..2] == [0.0, 0.0] {
                    0.0
                } else {
                    1.0
                },
            ),
            ("GEL_LEDS", self.gel_leds as f64),
            ("CAMERA_RESPONSE", self.camera_response as f64),
            ("SHELL_END", self.has_shell_end as f64),
            ("SHELL_EDGE_MM", crate::sensor::shell_end::SHELL_EDGE_MM),
            ("END_GLOW", if self.shell_glow[0] > 0.0 { 1.0 } else { 0.0 }),
            (
                "AMBIENT_RELIEF",
                if self.ambient_relief[..3] == [0.0; 3] {
                    0.0
                } else {
                    1.0
                },
            ),
        ]
    }
}

/// `object_kind` of an object: a built-in solid's id, a primitive's kind, or
/// [`GRID_OBJECT`] for a mesh.
pub fn object_kind(object: &Object) -> u32 {
    match object {
        Object::Solid(s) => s.id(),
        Object::Primitive { shape, .. } => shape.kind(),
        Object::Mesh { .. } => GRID_OBJECT,
    }
}

/// A vector as a uniform's vec4: xyz and `w`.
fn vec4(v: glam::DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

/// Pixels from one row of a frame's image buffers to the next, for a rect `width` pixels
/// wide: a whole number of 256-byte rows, as copies between buffers and textures need.
pub fn image_pitch(width: u32) -> u32 {
    width.next_multiple_of(64)
}

impl FrameUniform {
    /// The reference frame: no contact, every pixel.
    pub fn reference(sensor: &Sensor, noise_seed: u32) -> Self {
        FrameUniform {
            pixel_rect: [0, 0, sensor.width, sensor.height],
            object_kind: REFERENCE_FRAME,
            noise_seed,
            image_pitch: image_pitch(sensor.width),
            image_size: [sensor.width, sensor.height],
            ..Zeroable::zeroed()
        }
    }

    /// The same frame with its image buffers holding `rect` of the image (nothing without).
    pub fn holding(mut self, rect: Option<Rect>) -> Self {
        let r = rect.unwrap_or(Rect {
            x: 0,
            y: 0,
            w: 0,
            h: 0,
        });
        self.image_origin = [r.x, r.y];
        self.image_size = [r.w, r.h];
        self.image_pitch = image_pitch(r.w);
        self
    }

    /// A contact pressing `pressed_rect` and moving `texel_rect`, re-rendering `pixel_rect`.
    pub fn contact(
        pose: &ContactPose,
        object: &Object,
        max_trace_depth: f64,
        footprint: Option<Footprint>,
        noise_seed: u32,
    ) -> Self {
        // Rows of object_from_world = columns of world_from_object.
        let m = pose.world_from_object;
        let row = |v: glam::DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        let kind = object_kind(object);
        let (dims, grid_origin) = match object {
            Object::Solid(_) | Object::Primitive { .. } => ([0; 3], [0.0; 4]),
            Object::Mesh { grid, .. } => (
                grid.dims,
                [
                    grid.origin.x as f32,
                    grid.origin.y as f32,
                    grid.origin.z as f32,
                    grid.voxel_mm as f32,
                ],
            ),
        };
        FrameUniform {
            texel_rect: rect4(footprint.map(|f| f.texels)),
            pixel_rect: rect4(footprint.and_then(|f| f.pixels)),
            object_x: row(m.x_axis),
            object_y: row(m.y_axis),
            object_z: row(m.z_axis),
            origin: [
                pose.origin.x as f32,
                pose.origin.y as f32,
                pose.origin.z as f32,
                max_trace_depth as f32,
            ],
            object_kind: kind,
            grid_dims: dims,
            grid_origin,
            noise_seed,
            image_origin: [0; 2],
            image_pitch: 0,
            pressed_rect: rect4(footprint.map(|f| f.pressed)),
            meridian_rect: rect4(footprint.map(|f| f.meridians)),
            object_size: match object {
                Object::Primitive { shape, .. } => shape.gpu_size(),
                _ => [0.0; 4],
            },
            ..Zeroable::zeroed()
        }
    }
}
