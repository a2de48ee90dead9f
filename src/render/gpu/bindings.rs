//! The renderer's bindings, in one table: [`BINDINGS`] makes both its one bind group layout
//! and every bind group, and `shaders/shared/common.wgsl` declares the same bindings
//! (`tests/shaders.rs` holds the table to the shader's names and kinds).

use super::resources::{held_bytes, Map, Resources, UNIFORM_STRIDE};
use crate::render::uniforms::FrameUniform;
use crate::render::Rect;

/// What a binding holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    Sensor,
    Frames,
    Penetration,
    ElastomerScratch,
    Height,
    Probes,
    Image,
    Indentation,
    SdfGrid,
    Counters,
    PenetrationMap,
    ElastomerMap,
    HeightMap,
    ProbeMap,
    MapSampler,
    ReferenceImage,
}

/// Every binding of group 0, at its binding number.
pub const BINDINGS: [Binding; 16] = [
    Binding::Sensor,
    Binding::Frames,
    Binding::Penetration,
    Binding::ElastomerScratch,
    Binding::Height,
    Binding::Probes,
    Binding::Image,
    Binding::Indentation,
    Binding::SdfGrid,
    Binding::Counters,
    Binding::PenetrationMap,
    Binding::ElastomerMap,
    Binding::HeightMap,
    Binding::ProbeMap,
    Binding::MapSampler,
    Binding::ReferenceImage,
];

/// How a binding is declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Uniform,
    Storage {
        read_only: bool,
    },
    /// A 2D texture of unfilterable floats.
    Texture,
    /// An array of them.
    TextureArray,
    /// A 2D texture of unsigned integers.
    UintTexture,
    /// A non-filtering sampler.
    Sampler,
}

impl Binding {
    /// The variable the shaders bind it to.
    pub fn wgsl_name(self) -> &'static str {
        match self {
            Binding::Sensor => "sensor",
            Binding::Frames => "frames",
            Binding::Penetration => "penetration",
            Binding::ElastomerScratch => "elastomer_scratch",
            Binding::Height => "height",
            Binding::Probes => "probes",
            Binding::Image => "image",
            Binding::Indentation => "indentation",
            Binding::SdfGrid => "sdf_grid",
            Binding::Counters => "counters",
            Binding::PenetrationMap => "penetration_map",
            Binding::ElastomerMap => "elastomer_map",
            Binding::HeightMap => "height_map",
            Binding::ProbeMap => "probe_map",
            Binding::MapSampler => "map_sampler",
            Binding::ReferenceImage => "reference_image",
        }
    }

    pub fn kind(self) -> Kind {
        match self {
            Binding::Sensor | Binding::Frames => Kind::Uniform,
            Binding::SdfGrid => Kind::Storage { read_only: true },
            Binding::Penetration
            | Binding::ElastomerScratch
            | Binding::Height
            | Binding::Probes
            | Binding::Image
            | Binding::Indentation
            | Binding::Counters => Kind::Storage { read_only: false },
            Binding::PenetrationMap | Binding::ElastomerMap | Binding::HeightMap => {
                Kind::TextureArray
            }
            Binding::ProbeMap => Kind::Texture,
            Binding::ReferenceImage => Kind::UintTexture,
            Binding::MapSampler => Kind::Sampler,
        }
    }

    fn layout_entry(self, binding: u32) -> wgpu::BindGroupLayoutEntry {
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let texture = |sample_type, view_dimension| wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        };
        let floats = wgpu::TextureSampleType::Float { filterable: false };
        let ty = match self.kind() {
            Kind::Uniform => buffer(wgpu::BufferBindingType::Uniform),
            Kind::Storage { read_only } => buffer(wgpu::BufferBindingType::Storage { read_only }),
            Kind::Texture => texture(floats, wgpu::TextureViewDimension::D2),
            Kind::TextureArray => texture(floats, wgpu::TextureViewDimension::D2Array),
            Kind::UintTexture => texture(
                wgpu::TextureSampleType::Uint,
                wgpu::TextureViewDimension::D2,
            ),
            Kind::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
        };
        wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        }
    }

    fn resource<'a>(self, r: &'a Resources, f: &FrameBinding<'a>) -> wgpu::BindingResource<'a> {
        let w = f.wave;
        let slice = |buffer: &'a wgpu::Buffer, offset: u64, bytes: u64| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset,
                size: std::num::NonZeroU64::new(bytes),
            })
        };
        // At least one image row's bytes, for a wave whose frames hold no pixels.
        let image_bytes = w.image_bytes.max(256);
        let heightfield = &r.heightfield;
        let map = |m: Map| wgpu::BindingResource::TextureView(&heightfield.map(m).view);
        match self {
            Binding::Sensor => r.sensor.as_entire_binding(),
            Binding::Frames => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: f.uniform,
                offset: f.uniform_offset,
                size: std::num::NonZeroU64::new(FRAMES_BOUND_BYTES),
            }),
            Binding::Penetration => heightfield.buffer(Map::Penetration).as_entire_binding(),
            Binding::ElastomerScratch => heightfield.buffer(Map::Elastomer).as_entire_binding(),
            Binding::Height => heightfield.buffer(Map::Height).as_entire_binding(),
            Binding::Probes => r.probes.as_entire_binding(),
            Binding::Image => slice(&r.image, w.image_offset, image_bytes),
            Binding::Indentation => slice(&r.indentation, w.image_offset, image_bytes),
            Binding::SdfGrid => f.grid.as_entire_binding(),
            Binding::Counters => slice(
                &r.counters,
                w.first_slot * r.counter_bytes,
                w.slots * r.counter_bytes,
            ),
            Binding::PenetrationMap => map(Map::Penetration),
            Binding::ElastomerMap => map(Map::Elastomer),
            Binding::HeightMap => map(Map::Height),
            Binding::ProbeMap => wgpu::BindingResource::TextureView(&r.probe_map.view),
            Binding::MapSampler => wgpu::BindingResource::Sampler(&r.map_sampler),
            Binding::ReferenceImage => wgpu::BindingResource::TextureView(&r.reference_view),
        }
    }
}

/// The layout's entries, from [`BINDINGS`].
pub(super) fn layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    (0..)
        .zip(BINDINGS)
        .map(|(binding, b)| b.layout_entry(binding))
        .collect()
}

/// Frame uniforms a bind group holds (WGSL `FRAMES_BOUND`): a dispatch's frames (or pieces
/// of frames), each workgroup finding its own (`shaders/shared/common.wgsl` use_frame_of).
pub const FRAMES_BOUND: u64 = 256;

/// Bytes of the frame uniforms as bound: [`FRAMES_BOUND`] of them, [`UNIFORM_STRIDE`] apart
/// (64 KiB, WebGPU's least limit on a uniform binding).
pub(super) const FRAMES_BOUND_BYTES: u64 = FRAMES_BOUND * UNIFORM_STRIDE;

const _: () = assert!(std::mem::size_of::<FrameUniform>() as u64 <= UNIFORM_STRIDE);

/// Where a wave's frames lie in the frame buffers: `slots` slots of the counters from
/// `first_slot`, and `image_bytes` of the image and indentation buffers from
/// `image_offset` (the frames' held rects, packed in order: [`packed_offsets`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct WaveRange {
    pub first_slot: u64,
    pub slots: u64,
    pub image_offset: u64,
    pub image_bytes: u64,
}

/// What differs between the bind groups: the frame uniforms (from `uniform_offset` of
/// `uniform`), the wave whose frames they are, and the SDF grid a contact pass traces (a
/// loaded mesh's, else an empty one). Every group binds the whole heightfield, every
/// lane's.
pub(super) struct FrameBinding<'a> {
    pub uniform: &'a wgpu::Buffer,
    pub uniform_offset: u64,
    pub wave: WaveRange,
    pub grid: &'a wgpu::Buffer,
}

/// Where each frame's held rect (`None`: nothing) starts in the image and indentation
/// buffers, packed in order so that a submission's frames are read back in one copy each;
/// and the bytes they take. (Each rect's bytes are whole 256-byte rows: every offset is
/// aligned for a binding.)
pub(super) fn packed_offsets(rects: &[Option<Rect>]) -> (Vec<u64>, u64) {
    let mut at = 0;
    let offsets = rects
        .iter()
        .map(|r| {
            let offset = at;
            at += r.map_or(0, held_bytes);
            offset
        })
        .collect();
    (offsets, at)
}

impl Resources {
    /// A bind group over every binding of [`BINDINGS`].
    pub(super) fn bind_group(&self, device: &wgpu::Device, f: FrameBinding) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = (0..)
            .zip(BINDINGS)
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.resource(self, &f),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("geltip frame"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}
