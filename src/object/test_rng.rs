//! A small deterministic generator (SplitMix64) for the object unit tests' points.

use glam::DVec3;

pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    pub(crate) fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(self.next(), self.next(), self.next())
    }
}
