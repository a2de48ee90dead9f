//! The per-sample post-process of an image, on the CPU: the rendered tactile change on a base
//! image (the rendered empty finger or a real sensor's empty frame), light and paint jitter,
//! sensor noise, each drawn from `(seed, k)`. The arithmetic is
//! [`crate::render::background::compose`], the one `geltip render --background` uses.
//!
//! The renderer renders noise-free: its own noise is drawn from a counter that depends on the
//! order frames are rendered in, and a per-sample sensor would need a new renderer (1-2 s)
//! per sample.

use super::sampling::{SampleRng, STREAM_BACKGROUND, STREAM_DRIFT, STREAM_LOOK, STREAM_NOISE};
use super::spec::Spec;
use crate::render::background::{compose_drifted, rgb_values};
use crate::render::Frame;
use crate::sensor::Noise;

/// The CPU post-process of a sample's image: the tactile change on a base image, light and
/// paint jitter, sensor noise. `None` when there is nothing to do.
pub(super) struct Look {
    /// The empty finger as rendered (RGB).
    reference: Vec<u8>,
    /// What the change is added to: the backgrounds (one drawn per sample when several),
    /// or the reference.
    bases: Vec<Vec<u8>>,
    noise: Noise,
    light_jitter: f64,
    paint_jitter: f64,
    drift: f64,
    /// Each pixel's azimuth about the principal point (radians), for the drift's sector.
    azimuths: Vec<f32>,
}

/// One sample's drift ([`Spec::drift`]): per channel a gain and an offset (levels), and a
/// sector of one channel mix brightened or dimmed about an azimuth.
struct Drift {
    gains: [f64; 3],
    offsets: [f64; 3],
    centre: f64,
    width: f64,
    amplitude: [f64; 3],
}

impl Drift {
    fn draw(seed: u64, k: u64, strength: f64) -> Drift {
        let mut rng = SampleRng::new(&[seed, k, STREAM_DRIFT]);
        let mut sym = |scale: f64| strength * scale * (2.0 * rng.unit() - 1.0);
        let gains = [1.0 + sym(0.12), 1.0 + sym(0.12), 1.0 + sym(0.12)];
        let offsets = [sym(5.0), sym(5.0), sym(5.0)];
        let bump = sym(0.4);
        let centre = rng.uniform(0.0, std::f64::consts::TAU);
        let width = rng.uniform(0.3, 1.2);
        // Mostly one channel (one colour of LED), a little of the others.
        let main = (rng.unit() * 3.0) as usize % 3;
        let amplitude =
            std::array::from_fn(|c| bump * if c == main { 1.0 } else { 0.3 * rng.unit() });
        Drift {
            gains,
            offsets,
            centre,
            width,
            amplitude,
        }
    }

    /// The sector's weight (0..1) at a pixel's `azimuth`.
    fn bump(&self, azimuth: f64) -> f64 {
        let d = (azimuth - self.centre + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        (-(d / self.width).powi(2)).exp()
    }

    /// Gain and offset of channel `c` at a pixel of sector weight `bump`.
    fn at(&self, c: usize, bump: f64) -> [f64; 2] {
        [
            self.gains[c] * (1.0 + self.amplitude[c] * bump),
            self.offsets[c],
        ]
    }
}

impl Look {
    /// The post-process `spec` asks for, if any, around the rendered empty finger
    /// `reference` and the loaded `backgrounds` (RGB; none for the rendered finger).
    pub(super) fn new(spec: &Spec, reference: &Frame, backgrounds: Vec<Vec<u8>>) -> Option<Look> {
        let needed = !backgrounds.is_empty()
            || spec.noise.any()
            || spec.light_jitter > 0.0
            || spec.paint_jitter > 0.0
            || spec.drift > 0.0;
        let w = reference.width;
        needed.then(|| {
            let reference = reference.to_rgb().into_raw();
            let bases = if backgrounds.is_empty() {
                vec![reference.clone()]
            } else {
                backgrounds
            };
            Look {
                reference,
                noise: spec.noise,
                light_jitter: spec.light_jitter,
                paint_jitter: spec.paint_jitter,
                drift: spec.drift,
                azimuths: if spec.drift > 0.0 {
                    let p = spec.sensor.principal;
                    (0..bases[0].len() / 3)
                        .map(|i| {
                            let (x, y) = ((i as u32 % w) as f64, (i as u32 / w) as f64);
                            (y - p.y).atan2(x - p.x) as f32
                        })
                        .collect()
                } else {
                    Vec::new()
                },
                bases,
            }
        })
    }

    /// Which base sample `k` is put on: drawn from `(seed, k)` when there are several.
    pub(super) fn base_of(&self, seed: u64, k: u64) -> usize {
        match self.bases.len() {
            0 | 1 => 0,
            n => (SampleRng::new(&[seed, k, STREAM_BACKGROUND]).next_u64() % n as u64) as usize,
        }
    }

    /// Sample `k`'s image (RGB) from its rendered frame, on base `base` ([`Look::base_of`]).
    pub(super) fn apply(&self, seed: u64, k: u64, base: usize, frame: &Frame) -> Vec<u8> {
        let mut rng = SampleRng::new(&[seed, k, STREAM_LOOK]);
        let gains: [f64; 3] =
            std::array::from_fn(|_| 1.0 + self.light_jitter * (2.0 * rng.unit() - 1.0));
        let contrast = 1.0 + self.paint_jitter * (2.0 * rng.unit() - 1.0);
        let noise = SampleRng::new(&[seed, k, STREAM_NOISE]);
        let drift = (self.drift > 0.0).then(|| Drift::draw(seed, k, self.drift));
        // The sector's weight once a pixel, not once a value.
        let bumps: Vec<f64> = drift.as_ref().map_or_else(Vec::new, |d| {
            self.azimuths.iter().map(|&a| d.bump(a as f64)).collect()
        });
        let field = drift
            .as_ref()
            .map(|d| move |i: usize| d.at(i % 3, bumps[i / 3]));
        let field = field.as_ref().map(|f| f as &dyn Fn(usize) -> [f64; 2]);
        self.compose(base, rgb_values(frame), gains, contrast, noise, field)
    }

    /// The empty frame of the samples on base `base`: the base with the set's noise (drawn
    /// from its own stream, as no sample's), without jitter.
    pub(super) fn reference(&self, seed: u64, base: usize) -> Vec<u8> {
        let noise = SampleRng::new(&[seed, u64::MAX, STREAM_NOISE]);
        self.compose(
            base,
            self.reference.iter().copied(),
            [1.0; 3],
            1.0,
            noise,
            None,
        )
    }

    /// The base plus `contrast` times the change of `rendered` (RGB values) from the empty
    /// finger, times each channel's gain, plus noise.
    fn compose(
        &self,
        base: usize,
        rendered: impl Iterator<Item = u8>,
        gains: [f64; 3],
        contrast: f64,
        mut noise: SampleRng,
        drift: Option<&dyn Fn(usize) -> [f64; 2]>,
    ) -> Vec<u8> {
        // Approximately Gaussian: the sum of four 16-bit uniforms, scaled to unit variance.
        let scale = self.noise.rgb().map(|s| s * 3.0_f64.sqrt() / 65536.0);
        let draw = |c: usize| {
            let r = noise.next_u64();
            let sum = (r & 0xffff) + ((r >> 16) & 0xffff) + ((r >> 32) & 0xffff) + (r >> 48);
            (sum as f64 - 2.0 * 65535.0) * scale[c]
        };
        compose_drifted(
            &self.bases[base],
            rendered,
            &self.reference,
            contrast,
            gains,
            self.noise.any().then_some(draw),
            drift,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::Sensor;

    #[test]
    fn backgrounds_are_drawn_evenly_and_from_the_seed_and_index_alone() {
        let sensor = Sensor::preset("paper").unwrap();
        let spec = Spec::new("paper", sensor, 10, 3);
        let frame = Frame {
            width: 1,
            height: 1,
            rgba: vec![0; 4],
            indentation: vec![0.0],
        };
        let look = Look::new(&spec, &frame, vec![vec![0; 3]; 3]).unwrap();
        let mut counts = [0usize; 3];
        for k in 0..3000 {
            counts[look.base_of(3, k)] += 1;
        }
        assert!(
            counts.iter().all(|&c| (900..=1100).contains(&c)),
            "{counts:?}"
        );
        assert_eq!(look.base_of(3, 17), look.base_of(3, 17));
        assert!((0..50).any(|k| look.base_of(3, k) != look.base_of(4, k)));
        let one = Look::new(&spec, &frame, vec![vec![0; 3]]).unwrap();
        assert!((0..50).all(|k| one.base_of(3, k) == 0));
    }
}
