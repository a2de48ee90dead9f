//! Headless wgpu: context, shader loading and validation, readback.
