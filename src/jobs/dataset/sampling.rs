//! Sample `k`'s draws: a pure function of `(seed, k, stream, attempt)` by a counter-based hash
//! (SplitMix64), so a sample is the same whether rendered alone, in a batch, in any shard or
//! after a resume.

use crate::error::{GeltipError, Result};
use crate::finger::SurfaceCoord;
use crate::object::Object;
use crate::render::{self, Place, Press};
use crate::sensor::Sensor;
use std::sync::Arc;

/// Draws of a sample's contact before giving up on finding one the camera sees.
pub const MAX_ATTEMPTS: u64 = 1000;

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64 started from a hash of `parts`.
#[derive(Debug, Clone)]
pub struct SampleRng(u64);

/// Streams of a sample's draws: its contact, its look (light and paint gains), its noise.
const STREAM_CONTACT: u64 = 1;
pub(super) const STREAM_LOOK: u64 = 2;
pub(super) const STREAM_NOISE: u64 = 3;
/// Whether a sample is empty and how many contacts it holds.
const STREAM_LAYOUT: u64 = 4;
/// Which of a folder's backgrounds a sample is put on.
pub(super) const STREAM_BACKGROUND: u64 = 5;
/// How a sample's light drifts from its empty frame's.
pub(super) const STREAM_DRIFT: u64 = 6;

impl SampleRng {
    pub fn new(parts: &[u64]) -> SampleRng {
        let mut h = 0x6765_6c74_6970_u64; // "geltip"
        for &p in parts {
            h = mix(h.wrapping_add(GOLDEN) ^ p);
        }
        SampleRng(h)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix(self.0)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The contact of a sample: one place to build it (contact fields may grow).
pub fn make_contact(
    object: Arc<Object>,
    s_mm: f64,
    azimuth_deg: f64,
    spin_deg: f64,
    depth_mm: f64,
) -> Press {
    Press::at(object, Place::ArcLength(s_mm), azimuth_deg, depth_mm).spun(spin_deg)
}

/// Arc length (mm) from the tip of the farthest surface point the lens can see.
pub fn visible_arc_length(sensor: &Sensor) -> f64 {
    render::heightfield_extent(sensor) - render::margin_mm(sensor) - sensor.finger.shell_thickness
}

/// Sample `k`'s contact: drawn from `(seed, k)`, redrawn (attempt 1, 2, ...) until the
/// camera sees the contact point.
pub fn sample_contact(
    sensor: &Sensor,
    objects: &[Arc<Object>],
    depth_range: (f64, f64),
    seed: u64,
    k: u64,
) -> Result<Press> {
    nth_contact(sensor, objects, depth_range, seed, k, 0)
}

/// Sample `k`'s contacts: none with probability `empty_fraction`, else a count uniform in
/// `contacts` (inclusive), each drawn as [`sample_contact`] draws one (the first exactly so,
/// the others from streams of their own).
pub fn sample_contacts(
    sensor: &Sensor,
    objects: &[Arc<Object>],
    depth_range: (f64, f64),
    (empty_fraction, contacts): (f64, (u32, u32)),
    seed: u64,
    k: u64,
) -> Result<Vec<Press>> {
    let mut rng = SampleRng::new(&[seed, k, STREAM_LAYOUT]);
    if rng.unit() < empty_fraction {
        return Ok(Vec::new());
    }
    let span = u64::from(contacts.1.saturating_sub(contacts.0)) + 1;
    let n = u64::from(contacts.0) + rng.next_u64() % span;
    (0..n)
        .map(|j| nth_contact(sensor, objects, depth_range, seed, k, j))
        .collect()
}

/// Contact `j` of sample `k`.
fn nth_contact(
    sensor: &Sensor,
    objects: &[Arc<Object>],
    depth_range: (f64, f64),
    seed: u64,
    k: u64,
    j: u64,
) -> Result<Press> {
    let s_max = visible_arc_length(sensor);
    for attempt in 0..MAX_ATTEMPTS {
        let mut rng = if j == 0 {
            SampleRng::new(&[seed, k, STREAM_CONTACT, attempt])
        } else {
            SampleRng::new(&[seed, k, STREAM_CONTACT, attempt, j])
        };
        let s = rng.uniform(0.0, s_max);
        let azimuth = rng.uniform(0.0, 360.0);
        let depth = rng.uniform(depth_range.0, depth_range.1);
        let spin = rng.uniform(0.0, 360.0);
        let object = &objects[(rng.next_u64() % objects.len() as u64) as usize];
        // The contact point is the surface point at (s, azimuth) whatever the object: no
        // first-touch search here (the renderer does it once, when it prepares the frame).
        let point = sensor.finger.point_at(SurfaceCoord {
            s,
            phi: azimuth.to_radians(),
        });
        if sensor.project(point.point).is_ok() {
            return Ok(make_contact(object.clone(), s, azimuth, spin, depth));
        }
    }
    Err(GeltipError::input(
        format!("sample {k}"),
        format!("no contact the camera sees in {MAX_ATTEMPTS} draws"),
    ))
}

/// Loads the objects named in a spec, once each.
pub fn load_objects(names: &[String]) -> Result<Vec<Arc<Object>>> {
    names
        .iter()
        .map(|n| Object::from_arg(n).map(Arc::new))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Hold;

    #[test]
    fn draws_depend_on_seed_and_index_only() {
        let a: Vec<u64> = (0..4)
            .map(|_| SampleRng::new(&[1, 2, 3]).next_u64())
            .collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            SampleRng::new(&[1, 2, 3]).next_u64(),
            SampleRng::new(&[1, 3, 3]).next_u64()
        );
        assert_ne!(
            SampleRng::new(&[2, 2, 3]).next_u64(),
            SampleRng::new(&[1, 2, 3]).next_u64()
        );
        let mut r = SampleRng::new(&[9]);
        let mean = (0..10_000).map(|_| r.unit()).sum::<f64>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }

    #[test]
    fn sampled_contacts_are_visible_and_in_range() {
        let sensor = Sensor::preset("paper").unwrap();
        let objects = load_objects(&["sphere".into(), "cone".into()]).unwrap();
        for k in 0..200 {
            let c = sample_contact(&sensor, &objects, (0.3, 1.2), 5, k).unwrap();
            let again = sample_contact(&sensor, &objects, (0.3, 1.2), 5, k).unwrap();
            assert_eq!(c.hold, again.hold);
            let Hold::Surface {
                azimuth_deg,
                depth_mm,
                ..
            } = c.hold
            else {
                panic!("sample {k} is not held at a place");
            };
            assert!((0.3..=1.2).contains(&depth_mm));
            assert!((0.0..360.0).contains(&azimuth_deg));
            let pose = c.pose(&sensor).unwrap();
            assert!(sensor.project(pose.point).is_ok());
        }
    }
}
