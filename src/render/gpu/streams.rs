//! Renderers on devices of their own, started side by side.

use super::Renderer;
use crate::error::{GeltipError, Result};
use crate::gpu::context::MAX_STREAMS;
use crate::gpu::GpuContext;
use crate::object::Object;
use crate::sensor::Sensor;
use std::sync::Arc;

impl Renderer {
    /// One renderer per render stream 0..`streams` ([`GpuContext::stream`]: each on a
    /// device of its own, so they render at the same time), started side by side, each with
    /// the contact pipelines of `objects` built ([`Renderer::ready_objects`]). `streams`
    /// lies in 1..=[`MAX_STREAMS`].
    pub fn on_streams(
        sensor: &Sensor,
        streams: usize,
        objects: &[Arc<Object>],
    ) -> Result<Vec<Renderer>> {
        if !(1..=MAX_STREAMS).contains(&streams) {
            return Err(GeltipError::input(
                "streams",
                format!("must lie in 1..={MAX_STREAMS}, got {streams}"),
            ));
        }
        std::thread::scope(|scope| {
            let started: Vec<_> = (0..streams)
                .map(|i| {
                    scope.spawn(move || {
                        let mut renderer = Renderer::on(sensor, GpuContext::stream(i)?)?;
                        renderer.ready_objects(objects)?;
                        Ok(renderer)
                    })
                })
                .collect();
            started
                .into_iter()
                .map(|s| {
                    s.join().unwrap_or_else(|_| {
                        Err(GeltipError::Gpu(
                            "a render stream panicked at start-up".into(),
                        ))
                    })
                })
                .collect()
        })
    }
}
