//! Frame memory. Every rendered frame hands its caller two fresh full-image buffers (the
//! colour image and the indentation map, 2.4 MB at 640x480), dropped a frame later. glibc's
//! malloc returns such blocks to the kernel when they are freed (mmap'd blocks at once, the
//! heap's top past 128 kB), so every frame page-faults 600 pages back in: on this project's
//! 2-core VM that cost 1.0-1.4 ms a frame (the render bench's readback column: 2.0-2.4 ms
//! against 0.8-1.0 ms with the memory kept), more than a sixth of a contact frame.

/// Asks the C allocator to keep freed memory for reuse (glibc: `M_TRIM_THRESHOLD` 512 MB,
/// `M_MMAP_THRESHOLD` 32 MB) instead of giving it back to the kernel. A process-wide
/// setting, so the library never makes it on its own: the `geltip` binary and the benches
/// call it first thing; a program embedding geltip may too. Returns whether it applied (it
/// does nothing but on glibc).
pub fn keep_freed_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; called before the frames exist.
        unsafe {
            libc::mallopt(libc::M_TRIM_THRESHOLD, 512 << 20) == 1
                && libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}
