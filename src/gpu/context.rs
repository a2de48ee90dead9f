//! The headless GPU context: one wgpu device and queue, error scopes, and timed waits.
//!
//! Backends and adapter come from the environment, as in the wgpu examples:
//! `WGPU_BACKEND` (e.g. `vulkan`), `WGPU_ADAPTER_NAME` (a case-insensitive substring of the
//! adapter's name, e.g. `llvmpipe` for lavapipe), `WGPU_POWER_PREF`, plus the instance flags
//! (`WGPU_VALIDATION`, `WGPU_DEBUG`, ...). `GELTIP_GPU_TIMEOUT_S` sets how long
//! [`GpuContext::wait`] waits for the GPU before giving up.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use super::one_line;
use crate::error::{GeltipError, Result};

/// How long [`GpuContext::wait`] waits for a submission unless `GELTIP_GPU_TIMEOUT_S` says otherwise.
pub const DEFAULT_TIMEOUT_S: f64 = 30.0;

/// The environment variable that overrides [`DEFAULT_TIMEOUT_S`] (seconds, may be fractional).
pub const TIMEOUT_ENV: &str = "GELTIP_GPU_TIMEOUT_S";

/// What to do when no adapter is found.
const INSTALL_HINT: &str = "install a Vulkan driver; for headless software rendering install \
lavapipe (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`) and check that \
/usr/share/vulkan/icd.d/lvp_icd*.json exists";

/// The features [`GpuContext::has_timestamps`] asks for: timestamps written between a command
/// encoder's commands.
const TIMESTAMPS: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// A wgpu device and queue for headless compute, with the adapter they came from.
///
/// Create one per process with [`GpuContext::shared`]; [`GpuContext::new`] makes a fresh one.
#[derive(Debug)]
pub struct GpuContext {
    /// The logical device.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself (name, backend, driver).
    pub adapter_info: wgpu::AdapterInfo,
    /// The adapter the device came from (for format-feature and limit queries).
    pub adapter: wgpu::Adapter,
    timeout: Duration,
}

/// The shared context, or the one-line error its creation gave.
static SHARED: OnceLock<std::result::Result<GpuContext, SharedError>> = OnceLock::new();

/// Devices for render streams 1.. (stream 0 is [`SHARED`]): see [`GpuContext::stream`].
static STREAMS: [OnceLock<std::result::Result<GpuContext, SharedError>>; MAX_STREAMS - 1] =
    [const { OnceLock::new() }; MAX_STREAMS - 1];

/// How many render streams [`GpuContext::stream`] gives.
pub const MAX_STREAMS: usize = 4;

/// A creation error kept for later callers of [`GpuContext::shared`] (`GeltipError` is not `Clone`).
#[derive(Debug)]
enum SharedError {
    NoAdapter(String),
    Gpu(String),
}

impl SharedError {
    fn from_error(e: &GeltipError) -> Self {
        match e {
            GeltipError::NoAdapter(m) => SharedError::NoAdapter(m.clone()),
            GeltipError::Gpu(m) => SharedError::Gpu(m.clone()),
            other => SharedError::Gpu(other.to_string()),
        }
    }

    fn to_error(&self) -> GeltipError {
        match self {
            SharedError::NoAdapter(m) => GeltipError::NoAdapter(m.clone()),
            SharedError::Gpu(m) => GeltipError::Gpu(m.clone()),
        }
    }
}

impl GpuContext {
    /// Creates a fresh instance, adapter, device and queue (headless: no surface).
    ///
    /// Errors with [`GeltipError::NoAdapter`] when no adapter matches (the message says how to
    /// install lavapipe) and with [`GeltipError::Gpu`] when the device cannot be created.
    pub fn new() -> Result<GpuContext> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(select_adapter(&instance, backends))?;
        let adapter_info = adapter.get_info();
        log::info!(
            "gpu adapter: {} ({:?}, {:?}), driver: {} {}",
            adapter_info.name,
            adapter_info.backend,
            adapter_info.device_type,
            adapter_info.driver,
            adapter_info.driver_info
        );

        let required_limits = compute_limits(&adapter.limits());
        // Optional: timestamps between commands, for the stage profiler only (rendering never
        // needs them; adapters without them profile stage by stage instead).
        let required_features = adapter.features() & TIMESTAMPS;
        let desc = wgpu::DeviceDescriptor {
            label: Some("geltip"),
            required_features,
            required_limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        // `request_device` documents panics for impossible requests; keep them errors.
        let (device, queue) = catch_unwind(AssertUnwindSafe(|| {
            pollster::block_on(adapter.request_device(&desc))
        }))
        .map_err(|p| {
            GeltipError::Gpu(format!(
                "request_device on {} panicked: {}",
                adapter_info.name,
                one_line(&panic_text(p.as_ref()))
            ))
        })?
        .map_err(|e| {
            GeltipError::Gpu(format!(
                "cannot create a device on {}: {}",
                adapter_info.name,
                one_line(&e.to_string())
            ))
        })?;

        device.on_uncaptured_error(Arc::new(|e: wgpu::Error| {
            log::error!("gpu: uncaptured error: {}", one_line(&e.to_string()));
        }));
        device.set_device_lost_callback(|reason, message| match reason {
            wgpu::DeviceLostReason::Destroyed => log::debug!("gpu: device destroyed"),
            _ => log::error!("gpu: device lost ({reason:?}): {}", one_line(&message)),
        });

        Ok(GpuContext {
            device,
            queue,
            adapter_info,
            adapter,
            timeout: timeout_from_env(),
        })
    }

    /// The process-wide context, created on first use.
    ///
    /// If creation failed, every later call returns the same error (without retrying).
    pub fn shared() -> Result<&'static GpuContext> {
        match SHARED.get_or_init(|| GpuContext::new().map_err(|e| SharedError::from_error(&e))) {
            Ok(ctx) => Ok(ctx),
            Err(e) => Err(e.to_error()),
        }
    }

    /// The device of render stream `i` (< [`MAX_STREAMS`]): stream 0 is
    /// [`GpuContext::shared`], each other a device of its own, created on first use and kept
    /// for the process. Work on different devices runs at the same time: on lavapipe each
    /// device has its own queue thread and its own pool of workers, so one stream's
    /// dispatches fill the cores another's leave idle (small dispatches, the gaps between
    /// dispatches and submissions).
    pub fn stream(i: usize) -> Result<&'static GpuContext> {
        let slot = match i {
            0 => return GpuContext::shared(),
            i if i < MAX_STREAMS => &STREAMS[i - 1],
            _ => {
                return Err(GeltipError::input(
                    "render streams",
                    format!("at most {MAX_STREAMS}, asked for stream {i}"),
                ))
            }
        };
        match slot.get_or_init(|| GpuContext::new().map_err(|e| SharedError::from_error(&e))) {
            Ok(ctx) => Ok(ctx),
            Err(e) => Err(e.to_error()),
        }
    }

    /// Whether the device writes timestamps between an encoder's commands (requested when
    /// the adapter offers them; lavapipe does).
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(TIMESTAMPS)
    }

    /// How long [`GpuContext::wait`] waits for a submission.
    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// Runs `f` (device calls) inside validation, out-of-memory and internal error scopes.
    ///
    /// A captured error becomes `GeltipError::Gpu("<what>: <error on one line>")`. Error scopes
    /// are per thread, so the wgpu calls must happen inside `f` on this thread.
    pub fn scoped<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        // Pop in reverse order of pushing; the futures are ready at once on native backends.
        let errors = [
            pollster::block_on(validation.pop()),
            pollster::block_on(internal.pop()),
            pollster::block_on(oom.pop()),
        ];
        match errors.into_iter().flatten().next() {
            None => Ok(value),
            Some(e) => Err(GeltipError::Gpu(format!("{what}: {}", error_text(&e)))),
        }
    }

    /// Finishes `encoder`, submits it (both in an error scope) and returns the submission.
    pub fn submit(
        &self,
        what: &str,
        encoder: wgpu::CommandEncoder,
    ) -> Result<wgpu::SubmissionIndex> {
        self.scoped(what, || self.queue.submit(Some(encoder.finish())))
    }

    /// Submits command buffers recorded elsewhere (in order, in one submission), turning a
    /// validation error into a `Gpu` error that names `what`.
    pub fn submit_buffers(
        &self,
        what: &str,
        buffers: Vec<wgpu::CommandBuffer>,
    ) -> Result<wgpu::SubmissionIndex> {
        self.scoped(what, || self.queue.submit(buffers))
    }

    /// [`GpuContext::submit`], then [`GpuContext::wait`].
    pub fn submit_and_wait(&self, what: &str, encoder: wgpu::CommandEncoder) -> Result<()> {
        let submission = self.submit(what, encoder)?;
        self.wait(submission, what)
    }

    /// Blocks until `submission` has finished on the GPU (and map callbacks have run), at most
    /// [`GpuContext::timeout`].
    ///
    /// Errors with `GeltipError::Gpu("<what> did not finish within N s")` on timeout, and with a
    /// `Gpu` error when the device is lost. Every wait on the GPU in geltip goes through here.
    pub fn wait(&self, submission: wgpu::SubmissionIndex, what: &str) -> Result<()> {
        self.wait_for(submission, what, self.timeout)
    }

    /// [`GpuContext::wait`] with an explicit timeout.
    pub fn wait_for(
        &self,
        submission: wgpu::SubmissionIndex,
        what: &str,
        timeout: Duration,
    ) -> Result<()> {
        let poll = catch_unwind(AssertUnwindSafe(|| {
            self.device.poll(wgpu::PollType::Wait {
                submission_index: Some(submission),
                timeout: Some(timeout),
            })
        }));
        match poll {
            Ok(Ok(_status)) => Ok(()),
            Ok(Err(wgpu::PollError::Timeout)) => Err(GeltipError::Gpu(format!(
                "{what} did not finish within {} (set {TIMEOUT_ENV} to wait longer)",
                format_secs(timeout)
            ))),
            Ok(Err(e)) => Err(GeltipError::Gpu(format!(
                "{what}: waiting failed: {}",
                one_line(&e.to_string())
            ))),
            // wgpu panics in `poll` when the device is lost.
            Err(p) => Err(GeltipError::Gpu(format!(
                "{what}: device lost while waiting: {}",
                one_line(&panic_text(p.as_ref()))
            ))),
        }
    }

    /// Runs map callbacks and cleanup without blocking.
    pub fn poll_now(&self) -> Result<()> {
        catch_unwind(AssertUnwindSafe(|| self.device.poll(wgpu::PollType::Poll)))
            .map_err(|p| {
                GeltipError::Gpu(format!(
                    "poll: device lost: {}",
                    one_line(&panic_text(p.as_ref()))
                ))
            })?
            .map(|_| ())
            .map_err(|e| GeltipError::Gpu(format!("poll: {}", one_line(&e.to_string()))))
    }
}

/// Picks the adapter: the one `WGPU_ADAPTER_NAME` names, else wgpu's default choice.
///
/// (`wgpu::util::initialize_adapter_from_env` panics when the name matches nothing; this
/// returns an error instead.)
async fn select_adapter(
    instance: &wgpu::Instance,
    backends: wgpu::Backends,
) -> Result<wgpu::Adapter> {
    let wanted = std::env::var("WGPU_ADAPTER_NAME")
        .ok()
        .filter(|w| !w.trim().is_empty());
    if let Some(wanted) = wanted {
        let adapters = instance.enumerate_adapters(backends).await;
        let names: Vec<String> = adapters
            .iter()
            .map(|a| {
                let info = a.get_info();
                format!("{} ({:?})", info.name, info.backend)
            })
            .collect();
        let needle = wanted.trim().to_lowercase();
        return adapters
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&needle))
            .ok_or_else(|| {
                let found = if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                };
                GeltipError::NoAdapter(format!(
                    "no GPU adapter matches WGPU_ADAPTER_NAME={wanted:?} (backends {backends:?}; found: {found}); {INSTALL_HINT}"
                ))
            });
    }
    let options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::from_env()
            .unwrap_or(wgpu::PowerPreference::HighPerformance),
        ..Default::default()
    };
    instance.request_adapter(&options).await.map_err(|e| {
        GeltipError::NoAdapter(format!(
            "no GPU adapter found (backends {backends:?}: {}); {INSTALL_HINT}",
            one_line(&e.to_string())
        ))
    })
}

/// The limits to request: WebGPU defaults (clamped to what the adapter has), with the limits
/// that matter for compute raised to everything the adapter offers.
pub fn compute_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    let mut limits = wgpu::Limits::defaults().or_worse_values_from(adapter);
    limits.max_texture_dimension_1d = adapter.max_texture_dimension_1d;
    limits.max_texture_dimension_2d = adapter.max_texture_dimension_2d;
    limits.max_texture_dimension_3d = adapter.max_texture_dimension_3d;
    limits.max_texture_array_layers = adapter.max_texture_array_layers;
    limits.max_bind_groups = adapter.max_bind_groups;
    limits.max_bindings_per_bind_group = adapter.max_bindings_per_bind_group;
    limits.max_storage_buffers_per_shader_stage = adapter.max_storage_buffers_per_shader_stage;
    limits.max_storage_textures_per_shader_stage = adapter.max_storage_textures_per_shader_stage;
    limits.max_sampled_textures_per_shader_stage = adapter.max_sampled_textures_per_shader_stage;
    limits.max_uniform_buffers_per_shader_stage = adapter.max_uniform_buffers_per_shader_stage;
    limits.max_buffers_and_acceleration_structures_per_shader_stage =
        adapter.max_buffers_and_acceleration_structures_per_shader_stage;
    limits.max_uniform_buffer_binding_size = adapter.max_uniform_buffer_binding_size;
    limits.max_storage_buffer_binding_size = adapter.max_storage_buffer_binding_size;
    limits.max_buffer_size = adapter.max_buffer_size;
    limits.max_compute_workgroup_storage_size = adapter.max_compute_workgroup_storage_size;
    limits.max_compute_invocations_per_workgroup = adapter.max_compute_invocations_per_workgroup;
    limits.max_compute_workgroup_size_x = adapter.max_compute_workgroup_size_x;
    limits.max_compute_workgroup_size_y = adapter.max_compute_workgroup_size_y;
    limits.max_compute_workgroup_size_z = adapter.max_compute_workgroup_size_z;
    limits.max_compute_workgroups_per_dimension = adapter.max_compute_workgroups_per_dimension;
    limits
}

/// The timeout from `GELTIP_GPU_TIMEOUT_S`, or [`DEFAULT_TIMEOUT_S`].
fn timeout_from_env() -> Duration {
    let default = Duration::from_secs_f64(DEFAULT_TIMEOUT_S);
    match std::env::var(TIMEOUT_ENV) {
        Err(_) => default,
        Ok(text) => match text.trim().parse::<f64>() {
            Ok(s) if s.is_finite() && s > 0.0 && s < 1.0e9 => Duration::from_secs_f64(s),
            _ => {
                log::warn!(
                    "{TIMEOUT_ENV}={text:?} is not a positive number of seconds; using {DEFAULT_TIMEOUT_S} s"
                );
                default
            }
        },
    }
}

/// `30 s`, `0.25 s`.
fn format_secs(d: Duration) -> String {
    if d.subsec_nanos() == 0 {
        format!("{} s", d.as_secs())
    } else {
        format!("{} s", d.as_secs_f64())
    }
}

/// A wgpu error on one line, with its source chain when the description does not already say it.
fn error_text(e: &wgpu::Error) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let s_text = s.to_string();
        if !text.contains(&s_text) {
            text.push_str(": ");
            text.push_str(&s_text);
        }
        source = s.source();
    }
    one_line(&text)
}

/// The message of a caught panic.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn secs_are_formatted_plainly() {
        assert_eq!(format_secs(Duration::from_secs(30)), "30 s");
        assert_eq!(format_secs(Duration::from_millis(250)), "0.25 s");
    }

    #[test]
    fn compute_limits_never_exceed_the_adapter() {
        let adapter = wgpu::Limits::downlevel_defaults();
        let limits = compute_limits(&adapter);
        assert!(limits.check_limits(&adapter));
        let big = wgpu::Limits {
            max_storage_buffer_binding_size: 1 << 31,
            max_buffer_size: 1 << 32,
            ..wgpu::Limits::defaults()
        };
        let limits = compute_limits(&big);
        assert!(limits.check_limits(&big));
        assert_eq!(limits.max_buffer_size, 1 << 32);
    }
}
