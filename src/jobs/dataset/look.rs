//! The per-sample post-process of an image, on the CPU: the rendered tactile change on a base
//! image (the rendered empty finger or a real sensor's empty frame), light and paint jitter,
//! sensor noise, each drawn from `(seed, k)`. The arithmetic is
//! [`crate::render::background::compose`], the one `geltip render --background` uses.
//!
//! The renderer renders noise-free: its own noise is drawn from a counter that depends on the
//! order frames are rendered in, and a per-sample sensor would need a new renderer (1-2 s)
//! per sample.

use super::sampling::{SampleRng, STREAM_LOOK, STREAM_NOISE};
use super::spec::Spec;
use crate::render::background::{compose, rgb_values};
use crate::render::Frame;
use crate::sensor::Noise;

/// The CPU post-process of a sample's image: the tactile change on a base image, light and
/// paint jitter, sensor noise. `None` when there is nothing to do.
pub(super) struct Look {
    /// The empty finger as rendered (RGB).
    reference: Vec<u8>,
    /// What the change is added to: the background, or the reference.
    base: Vec<u8>,
    noise: Noise,
    light_jitter: f64,
    paint_jitter: f64,
}

impl Look {
    /// The post-process `spec` asks for, if any, around the rendered empty finger
    /// `reference` and the loaded `background` (RGB).
    pub(super) fn new(spec: &Spec, reference: &Frame, background: Option<Vec<u8>>) -> Option<Look> {
        let needed = background.is_some()
            || spec.noise.any()
            || spec.light_jitter > 0.0
            || spec.paint_jitter > 0.0;
        needed.then(|| {
            let reference = reference.to_rgb().into_raw();
            Look {
                base: background.unwrap_or_else(|| reference.clone()),
                reference,
                noise: spec.noise,
                light_jitter: spec.light_jitter,
                paint_jitter: spec.paint_jitter,
            }
        })
    }

    /// Sample `k`'s image (RGB) from its rendered frame.
    pub(super) fn apply(&self, seed: u64, k: u64, frame: &Frame) -> Vec<u8> {
        let mut rng = SampleRng::new(&[seed, k, STREAM_LOOK]);
        let gains: [f64; 3] =
            std::array::from_fn(|_| 1.0 + self.light_jitter * (2.0 * rng.unit() - 1.0));
        let contrast = 1.0 + self.paint_jitter * (2.0 * rng.unit() - 1.0);
        let noise = SampleRng::new(&[seed, k, STREAM_NOISE]);
        self.compose(rgb_values(frame), gains, contrast, noise)
    }

    /// The set's empty frame: the base with the set's noise (drawn from its own stream, as
    /// no sample's), without jitter.
    pub(super) fn reference(&self, seed: u64) -> Vec<u8> {
        let noise = SampleRng::new(&[seed, u64::MAX, STREAM_NOISE]);
        self.compose(self.reference.iter().copied(), [1.0; 3], 1.0, noise)
    }

    /// The base plus `contrast` times the change of `rendered` (RGB values) from the empty
    /// finger, times each channel's gain, plus noise.
    fn compose(
        &self,
        rendered: impl Iterator<Item = u8>,
        gains: [f64; 3],
        contrast: f64,
        mut noise: SampleRng,
    ) -> Vec<u8> {
        // Approximately Gaussian: the sum of four 16-bit uniforms, scaled to unit variance.
        let scale = self.noise.rgb().map(|s| s * 3.0_f64.sqrt() / 65536.0);
        let draw = |c: usize| {
            let r = noise.next_u64();
            let sum = (r & 0xffff) + ((r >> 16) & 0xffff) + ((r >> 32) & 0xffff) + (r >> 48);
            (sum as f64 - 2.0 * 65535.0) * scale[c]
        };
        compose(
            &self.base,
            rendered,
            &self.reference,
            contrast,
            gains,
            self.noise.any().then_some(draw),
        )
    }
}
