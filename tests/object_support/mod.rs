//! Helpers shared by the object tests (tests/objects*.rs): seeded points around a solid,
//! temporary folders, repository paths, a compute pass read back as f32 (the WGSL twins).
#![allow(dead_code)]

pub mod gltf;

use geltip::gpu::shaders::create_compute_pipeline_from_source;
use geltip::gpu::{read_buffer, GpuContext};
use geltip::object::Solid;
use glam::DVec3;
use std::path::{Path, PathBuf};
use wgpu::util::DeviceExt;

/// The voxel size (mm) the object tests bake at.
pub const VOXEL: f64 = 0.25;

/// A small deterministic generator (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(self.next(), self.next(), self.next())
    }
}

/// A fresh, empty temporary folder for one test.
pub fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-objects-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The box around a solid (and 1.5 mm more) in which test points are drawn.
pub fn test_box(s: Solid) -> (DVec3, DVec3) {
    let f = s.footprint_radius() + 1.5;
    let depth = s.bounding_radius() + 1.5;
    (DVec3::new(-f, -f, -depth), DVec3::new(f, f, 1.5))
}

/// Runs `main` of the WGSL `source` over `input` (read-only storage at binding 0), one
/// invocation per value of the output (an `array<f32>` at binding 1, 64 to a workgroup),
/// and reads back the `n` values it wrote. `name` labels the shader (`{name}-test.wgsl`) and
/// the GPU objects (`{name} test ...`).
pub fn compute_f32(ctx: &GpuContext, name: &str, source: &str, input: &[u8], n: usize) -> Vec<f32> {
    let label = format!("{name} test");
    let pipeline = create_compute_pipeline_from_source(
        ctx,
        &format!("{name}-test.wgsl"),
        source,
        "main",
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let input = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label} points")),
            contents: input,
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(&format!("{label} sdf")),
        size: 4 * n as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&label),
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
            label: Some(&label),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((n as u32).div_ceil(64), 1, 1);
    }
    ctx.submit_and_wait(&label, encoder)
        .unwrap_or_else(|e| panic!("{e}"));
    read_buffer(ctx, &output, 0, n).unwrap_or_else(|e| panic!("{e}"))
}
