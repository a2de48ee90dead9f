//! The headless GPU context and readback, on whatever adapter the environment gives
//! (lavapipe in CI). Without an adapter these tests fail with the `NoAdapter` message.

use std::time::{Duration, Instant};

use geltip::gpu::readback::{read_ranges_with, read_texture_region, Readback};
use geltip::gpu::shaders::create_compute_pipeline_from_source;
use geltip::gpu::{create_compute_pipeline, read_buffer, read_texture, GpuContext};
use geltip::GeltipError;
use wgpu::util::DeviceExt;

/// An awkward size: rows of 317 RGBA texels (1268 bytes) need padding to 1280.
const W: u32 = 317;
const H: u32 = 211;

fn ctx() -> &'static GpuContext {
    match GpuContext::shared() {
        Ok(ctx) => ctx,
        Err(e) => panic!("{e}"),
    }
}

const PATTERN_RGBA: &str = r#"
@group(0) @binding(0) var out_tex: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_tex);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let rgb = vec3<u32>(id.x & 255u, id.y & 255u, (id.x ^ id.y) & 255u);
    textureStore(out_tex, vec2<i32>(id.xy), vec4<f32>(vec3<f32>(rgb) / 255.0, 1.0));
}
"#;

const PATTERN_R32F: &str = r#"
@group(0) @binding(0) var out_tex: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_tex);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    textureStore(out_tex, vec2<i32>(id.xy), vec4<f32>(f32(id.x) + 1000.0 * f32(id.y) + 0.5, 0.0, 0.0, 1.0));
}
"#;

const PATTERN_BUFFER: &str = r#"
@group(0) @binding(0) var<storage, read_write> data: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < arrayLength(&data)) {
        data[id.x] = id.x * 2654435761u + 12345u;
    }
}
"#;

fn expected_rgba(x: u32, y: u32) -> [u8; 4] {
    [(x & 255) as u8, (y & 255) as u8, ((x ^ y) & 255) as u8, 255]
}

fn expected_r32f(x: u32, y: u32) -> f32 {
    x as f32 + 1000.0 * y as f32 + 0.5
}

fn storage_texture(ctx: &GpuContext, format: wgpu::TextureFormat) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test target"),
        size: wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// Records a dispatch of `pipeline` over the whole texture into `encoder`.
fn encode_fill(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    texture: &wgpu::Texture,
) {
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("test bind group"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&view),
        }],
    });
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("test fill"),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &bind_group, &[]);
    pass.dispatch_workgroups(W.div_ceil(8), H.div_ceil(8), 1);
}

/// An encoder that runs `source`'s `main` once over `groups` workgroups with `buffer` at
/// binding 0.
fn encode_buffer_pass(
    ctx: &GpuContext,
    name: &str,
    source: &str,
    buffer: &wgpu::Buffer,
    groups: u32,
) -> wgpu::CommandEncoder {
    let pipeline = create_compute_pipeline_from_source(ctx, name, source, "main", None)
        .unwrap_or_else(|e| panic!("{e}"));
    let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    }
    encoder
}

fn fill_texture(ctx: &GpuContext, source: &str, format: wgpu::TextureFormat) -> wgpu::Texture {
    let pipeline = create_compute_pipeline_from_source(ctx, "inline.wgsl", source, "main", None)
        .unwrap_or_else(|e| panic!("{e}"));
    let texture = storage_texture(ctx, format);
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encode_fill(ctx, &mut encoder, &pipeline, &texture);
    ctx.submit_and_wait("test fill", encoder)
        .unwrap_or_else(|e| panic!("{e}"));
    texture
}

#[test]
fn context_reports_its_adapter() {
    let ctx = ctx();
    let info = &ctx.adapter_info;
    eprintln!(
        "adapter: {} ({:?}, {:?}), driver: {} {}",
        info.name, info.backend, info.device_type, info.driver, info.driver_info
    );
    assert!(!info.name.is_empty());
    // The compute limits are raised beyond the WebGPU defaults where the adapter allows.
    let limits = ctx.device.limits();
    let adapter = ctx.adapter.limits();
    assert_eq!(
        limits.max_storage_buffer_binding_size,
        adapter.max_storage_buffer_binding_size
    );
    assert_eq!(limits.max_buffer_size, adapter.max_buffer_size);
    eprintln!(
        "limits: storage binding {} B, buffer {} B, storage textures/stage {}, invocations/workgroup {}",
        limits.max_storage_buffer_binding_size,
        limits.max_buffer_size,
        limits.max_storage_textures_per_shader_stage,
        limits.max_compute_invocations_per_workgroup
    );
    assert!(std::ptr::eq(ctx, GpuContext::shared().unwrap()));
}

#[test]
fn rgba8_texture_reads_back_every_byte() {
    let ctx = ctx();
    let texture = fill_texture(ctx, PATTERN_RGBA, wgpu::TextureFormat::Rgba8Unorm);
    let bytes = read_texture(ctx, &texture).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(bytes.len(), (W * H * 4) as usize);
    let mut bad = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let i = ((y * W + x) * 4) as usize;
            let want = expected_rgba(x, y);
            if bytes[i..i + 4] != want {
                bad.push(format!("({x}, {y}): {:?} != {want:?}", &bytes[i..i + 4]));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{} wrong texels, first: {:?}",
        bad.len(),
        &bad[..bad.len().min(10)]
    );

    // A region with an odd origin.
    let (ox, oy, rw, rh) = (5, 7, 70, 3);
    let region = read_texture_region(
        ctx,
        &texture,
        wgpu::Origin3d { x: ox, y: oy, z: 0 },
        wgpu::Extent3d {
            width: rw,
            height: rh,
            depth_or_array_layers: 1,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(region.len(), (rw * rh * 4) as usize);
    for y in 0..rh {
        for x in 0..rw {
            let i = ((y * rw + x) * 4) as usize;
            assert_eq!(
                region[i..i + 4],
                expected_rgba(ox + x, oy + y),
                "({x}, {y})"
            );
        }
    }
    let e = read_texture_region(
        ctx,
        &texture,
        wgpu::Origin3d {
            x: W - 1,
            y: 0,
            z: 0,
        },
        wgpu::Extent3d {
            width: 2,
            height: 1,
            depth_or_array_layers: 1,
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("exceeds"), "{e}");
}

#[test]
fn r32float_texture_reads_back_exactly() {
    let ctx = ctx();
    let texture = fill_texture(ctx, PATTERN_R32F, wgpu::TextureFormat::R32Float);
    let bytes = read_texture(ctx, &texture).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(bytes.len(), (W * H * 4) as usize);
    let values: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
    for y in 0..H {
        for x in 0..W {
            let v = values[(y * W + x) as usize];
            assert_eq!(v, expected_r32f(x, y), "({x}, {y})");
        }
    }
}

#[test]
fn reusable_readback_with_the_frame() {
    let ctx = ctx();
    let pipeline =
        create_compute_pipeline_from_source(ctx, "inline.wgsl", PATTERN_RGBA, "main", None)
            .unwrap_or_else(|e| panic!("{e}"));
    let texture = storage_texture(ctx, wgpu::TextureFormat::Rgba8Unorm);
    let readback = Readback::new(ctx, W, H, wgpu::TextureFormat::Rgba8Unorm).unwrap();
    assert_eq!(readback.size(), (W, H));
    let mut out = Vec::new();
    for frame in 0..3 {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encode_fill(ctx, &mut encoder, &pipeline, &texture);
        readback.enqueue_copy(&mut encoder, &texture).unwrap();
        let submission = ctx.submit("frame", encoder).unwrap();
        readback
            .finish_into(ctx, submission, &mut out)
            .unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        assert_eq!(out.len(), readback.packed_len());
        for (i, px) in out.chunks_exact(4).enumerate() {
            let (x, y) = (i as u32 % W, i as u32 / W);
            assert_eq!(px, expected_rgba(x, y), "frame {frame} ({x}, {y})");
        }
    }
    assert_eq!(readback.read(ctx, &texture).unwrap(), out);

    // A texture of another size is refused, not copied wrongly.
    let small = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 4,
            height: 4,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    assert!(readback.read(ctx, &small).is_err());
}

/// Word `i` of the buffer `PATTERN_BUFFER` fills.
fn expected_word(i: u32) -> u32 {
    i.wrapping_mul(2654435761).wrapping_add(12345)
}

/// A storage buffer of `n` words filled on the GPU by `PATTERN_BUFFER`.
fn pattern_buffer(ctx: &GpuContext, n: u32) -> wgpu::Buffer {
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test data"),
        size: u64::from(n) * 4,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let encoder = encode_buffer_pass(ctx, "inline.wgsl", PATTERN_BUFFER, &buffer, n.div_ceil(64));
    ctx.submit_and_wait("buffer fill", encoder).unwrap();
    buffer
}

#[test]
fn storage_buffer_reads_back() {
    let ctx = ctx();
    let n = 1000u32;
    let buffer = pattern_buffer(ctx, n);
    let all: Vec<u32> = read_buffer(ctx, &buffer, 0, n as usize).unwrap();
    assert_eq!(all, (0..n).map(expected_word).collect::<Vec<_>>());
    let part: Vec<u32> = read_buffer(ctx, &buffer, 40, 7).unwrap();
    assert_eq!(part, (10..17).map(expected_word).collect::<Vec<_>>());
    // Values smaller than the 4-byte copy unit.
    let bytes: Vec<u8> = read_buffer(ctx, &buffer, 4, 3).unwrap();
    assert_eq!(bytes, expected_word(1).to_le_bytes()[..3]);
    assert!(read_buffer::<u32>(ctx, &buffer, 0, 0).unwrap().is_empty());
    // Misuse is an error, not a panic or a wgpu validation error.
    assert!(read_buffer::<u32>(ctx, &buffer, 2, 1).is_err());
    assert!(read_buffer::<u32>(ctx, &buffer, 0, n as usize + 1).is_err());
    let no_copy = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &[0u8; 16],
            usage: wgpu::BufferUsages::STORAGE,
        });
    let e = read_buffer::<u32>(ctx, &no_copy, 0, 4).unwrap_err();
    assert!(e.to_string().contains("COPY_SRC"), "{e}");
}

#[test]
fn ranges_read_back_through_a_kept_staging_buffer() {
    let ctx = ctx();
    let n = 1000u32;
    let buffer = pattern_buffer(ctx, n);
    let staging = |size: u64| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("kept staging"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let ranges = [(&buffer, 0, 40), (&buffer, 400, 12), (&buffer, 3996, 4)];
    // Each range is handed over in order, with its index, and unpacked by the caller.
    let read = |kept: Option<&wgpu::Buffer>| {
        read_ranges_with(ctx, kept, &ranges, |k, bytes| {
            (k, bytemuck::pod_collect_to_vec::<u8, u32>(bytes))
        })
        .unwrap()
    };
    let want = vec![
        (0, (0..10).map(expected_word).collect::<Vec<_>>()),
        (1, (100..103).map(expected_word).collect()),
        (2, vec![expected_word(999)]),
    ];
    let kept = staging(1024);
    // Twice through the same staging buffer (it is unmapped after each read), once through
    // one too small for the ranges (a fresh one is used instead), once with none.
    assert_eq!(read(Some(&kept)), want);
    assert_eq!(read(Some(&kept)), want);
    assert_eq!(read(Some(&staging(16))), want);
    assert_eq!(read(None), want);
}

#[test]
fn shader_errors_are_errors_not_panics() {
    let ctx = ctx();
    // Not a registered stage.
    let e = create_compute_pipeline(ctx, "no-such-stage", "main", None).unwrap_err();
    assert!(matches!(e, GeltipError::Shader { .. }), "{e}");

    // A WGSL syntax error: naga reports it with its line.
    let broken = "@compute @workgroup_size(1)\nfn main() {\n    let x = 1 +;\n}\n";
    let e =
        create_compute_pipeline_from_source(ctx, "broken.wgsl", broken, "main", None).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, GeltipError::Shader { .. }), "{msg}");
    assert!(msg.contains("broken.wgsl:3:"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");

    // A missing entry point.
    let e = create_compute_pipeline_from_source(ctx, "rgba.wgsl", PATTERN_RGBA, "nope", None)
        .unwrap_err();
    assert!(e.to_string().contains("nope"), "{e}");

    // Valid WGSL that wgpu rejects: the layout has no binding for the shader's texture.
    let empty_layout = ctx
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("empty"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
    let e = create_compute_pipeline_from_source(
        ctx,
        "rgba.wgsl",
        PATTERN_RGBA,
        "main",
        Some(&empty_layout),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, GeltipError::Gpu(_)), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    eprintln!("layout mismatch: {msg}");
}

#[test]
fn scoped_turns_validation_errors_into_err() {
    let ctx = ctx();
    let e = ctx
        .scoped("odd mapped buffer", || {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("odd"),
                size: 3,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: true,
            })
        })
        .unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with("gpu: odd mapped buffer: "), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    // Outside a scope the same error is logged by the uncaptured-error handler, not a panic.
    let _invalid = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("odd, unscoped"),
        size: 3,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: true,
    });
    // The device is still usable afterwards.
    let ok = ctx.scoped("fine buffer", || {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    });
    assert!(ok.is_ok());
}

#[test]
fn wait_returns_within_its_timeout() {
    let ctx = ctx();
    let encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let submission = ctx.submit("empty", encoder).unwrap();
    let start = Instant::now();
    ctx.wait(submission, "empty submission").unwrap();
    assert!(start.elapsed() < ctx.timeout());
}

const SLOW: &str = r#"
@group(0) @binding(0) var<storage, read_write> data: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var acc = id.x;
    for (var i = 0u; i < 20000u; i++) {
        acc = acc * 1664525u + 1013904223u;
    }
    data[id.x] = acc;
}
"#;

#[test]
fn wait_times_out_on_long_work() {
    // A device of its own: polls of one device from other test threads would hold this
    // thread's short wait up.
    let own = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let ctx = &own;
    let n = 64 * 1024u32;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("slow data"),
        size: u64::from(n) * 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let encoder = encode_buffer_pass(ctx, "slow.wgsl", SLOW, &buffer, n / 64);
    let submission = ctx.submit("slow", encoder).unwrap();
    let start = Instant::now();
    let result = ctx.wait_for(submission.clone(), "slow work", Duration::from_millis(1));
    let timed_out_after = start.elapsed();
    // Let the work finish before leaving (the device is shared with the other tests).
    ctx.wait(submission, "slow work").unwrap();
    let total = start.elapsed();
    eprintln!("slow work: waited {timed_out_after:?} of {total:?}: {result:?}");
    if total < Duration::from_millis(20) {
        // A GPU this fast finishes before the short timeout; nothing to check.
        return;
    }
    let e = result.unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("slow work did not finish within 0.001 s"),
        "{msg}"
    );
    assert!(timed_out_after < total, "{timed_out_after:?} vs {total:?}");
}

/// Run in a child process (environment variables are process-wide).
#[test]
#[ignore = "run by adapter_name_that_matches_nothing_is_an_error"]
fn child_adapter_name_mismatch() {
    assert_eq!(
        std::env::var("WGPU_ADAPTER_NAME").as_deref(),
        Ok("no-such-adapter-geltip")
    );
    let e = GpuContext::new().unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, GeltipError::NoAdapter(_)), "{msg}");
    assert!(msg.contains("no-such-adapter-geltip"), "{msg}");
    assert!(msg.contains("apt-get install mesa-vulkan-drivers"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    // Later calls of `shared` give the same error.
    let first = GpuContext::shared().unwrap_err().to_string();
    assert_eq!(first, GpuContext::shared().unwrap_err().to_string());
    assert_eq!(first, msg);
}

#[test]
fn adapter_name_that_matches_nothing_is_an_error() {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "child_adapter_name_mismatch",
            "--ignored",
            "--nocapture",
        ])
        .env("WGPU_ADAPTER_NAME", "no-such-adapter-geltip")
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    assert!(text.contains("1 passed"), "{text}");
}
