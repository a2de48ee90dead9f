//! The camera's softness (`[camera] blur_px`): every frame as the camera records it is
//! blurred by a Gaussian of that many pixels, over the pixels its lens sees only (the black
//! beyond the lens or a software mask is neither blurred into the picture nor changed), on
//! the 8-bit values, where a small camera's processing softens them. Applied on the host to
//! the frames both renderers make, the same code for both, so they stay byte for byte alike.
//! A contact frame is blurred again only where its contact changed it (its pixel rect grown
//! by the kernel's reach); elsewhere it is the blurred reference.

use super::{Frame, Rect};
use crate::sensor::Sensor;
use glam::DVec2;
use rayon::prelude::*;
use std::sync::Arc;

/// A sensor's camera softness: its kernel and the pixels its lens sees.
#[derive(Debug, Clone)]
pub struct Softness {
    width: u32,
    height: u32,
    /// Gaussian weights at offsets 0..=reach.
    weights: Vec<f32>,
    /// 1 where the lens sees the skin, else 0 (row-major).
    seen: Arc<[f32]>,
}

impl Softness {
    /// The softness of `sensor`'s camera, or `None` when it has none (`blur_px` 0).
    pub fn of(sensor: &Sensor) -> Option<Softness> {
        if !sensor.config.camera.blurs() {
            return None;
        }
        Softness::with_seen(sensor, Softness::seen_by(sensor))
    }

    /// The pixels `sensor`'s lens sees: 1 where it does, else 0 (row-major). It depends on
    /// the lens and the image alone, so a caller trying many blurs finds it once.
    pub fn seen_by(sensor: &Sensor) -> Arc<[f32]> {
        let width = sensor.width;
        (0..width * sensor.height)
            .into_par_iter()
            .map(|i| {
                let pixel = DVec2::new((i % width) as f64, (i / width) as f64);
                f32::from(u8::from(sensor.ray_direction(pixel).is_some()))
            })
            .collect::<Vec<f32>>()
            .into()
    }

    /// [`Softness::of`] with the lens's pixels already found ([`Softness::seen_by`] of a
    /// sensor with the same lens and image).
    pub fn with_seen(sensor: &Sensor, seen: Arc<[f32]>) -> Option<Softness> {
        let sigma = sensor.config.camera.blur_px;
        if sigma <= 0.0 {
            return None;
        }
        let reach = (3.0 * sigma).ceil() as usize;
        let weights = (0..=reach)
            .map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp() as f32)
            .collect();
        Some(Softness {
            width: sensor.width,
            height: sensor.height,
            weights,
            seen,
        })
    }

    /// How many pixels a change reaches once blurred.
    pub fn reach(&self) -> u32 {
        (self.weights.len() - 1) as u32
    }

    /// `raw` (RGBA, as rendered) blurred whole.
    pub fn soften(&self, raw: &[u8]) -> Vec<u8> {
        let mut out = raw.to_vec();
        let whole = Rect {
            x: 0,
            y: 0,
            w: self.width,
            h: self.height,
        };
        self.soften_over(raw, &mut out, whole);
        out
    }

    /// `frame` blurred whole, its indentation kept.
    pub fn soften_frame(&self, frame: &Frame) -> Frame {
        Frame {
            rgba: self.soften(&frame.rgba),
            ..frame.clone()
        }
    }

    /// Writes into `out` the blur of `raw` over `changed` grown by the kernel's reach, the
    /// pixels a change inside `changed` can reach; `out` holds the blurred reference
    /// elsewhere.
    pub fn soften_changed(&self, raw: &[u8], out: &mut [u8], changed: Rect) {
        let r = self.reach();
        let x0 = changed.x.saturating_sub(r);
        let y0 = changed.y.saturating_sub(r);
        let x1 = (changed.x + changed.w + r).min(self.width);
        let y1 = (changed.y + changed.h + r).min(self.height);
        let grown = Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        };
        self.soften_over(raw, out, grown);
    }

    /// The normalised blur of `raw`'s seen pixels, written into `out` over `area`: a
    /// separable Gaussian of value x seen and of seen alone, their ratio (the blur of the
    /// pixels the lens sees, each weighted as the kernel says). Unseen pixels are left.
    fn soften_over(&self, raw: &[u8], out: &mut [u8], area: Rect) {
        let (w, h) = (self.width as usize, self.height as usize);
        let reach = self.weights.len() - 1;
        // The pixels the area's blur reads: the area grown by the reach, clipped.
        let (ax0, ay0) = (area.x as usize, area.y as usize);
        let (ax1, ay1) = (ax0 + area.w as usize, ay0 + area.h as usize);
        let (sx0, sy0) = (ax0.saturating_sub(reach), ay0.saturating_sub(reach));
        let (sx1, sy1) = ((ax1 + reach).min(w), (ay1 + reach).min(h));
        let cols = ax1 - ax0;
        // Horizontal pass, per source row: (R, G, B) x seen and seen, summed over the taps.
        let mut across = vec![[0.0f32; 4]; (sy1 - sy0) * cols];
        across
            .par_chunks_mut(cols.max(1))
            .enumerate()
            .for_each(|(row, sums)| {
                let y = sy0 + row;
                let line: Vec<[f32; 4]> = (sx0..sx1)
                    .map(|x| {
                        let i = y * w + x;
                        let m = self.seen[i];
                        let p = &raw[i * 4..i * 4 + 3];
                        [p[0] as f32 * m, p[1] as f32 * m, p[2] as f32 * m, m]
                    })
                    .collect();
                for (col, sum) in sums.iter_mut().enumerate() {
                    let x = ax0 + col;
                    let (lo, hi) = (x.saturating_sub(reach).max(sx0), (x + reach).min(sx1 - 1));
                    let mut acc = [0.0f32; 4];
                    for xx in lo..=hi {
                        let k = self.weights[xx.abs_diff(x)];
                        let v = line[xx - sx0];
                        for c in 0..4 {
                            acc[c] += k * v[c];
                        }
                    }
                    *sum = acc;
                }
            });
        // Vertical pass over the area's rows, written straight into `out`.
        let row_bytes = w * 4;
        out.par_chunks_mut(row_bytes)
            .enumerate()
            .skip(ay0)
            .take(ay1 - ay0)
            .for_each(|(y, line)| {
                let (lo, hi) = (y.saturating_sub(reach).max(sy0), (y + reach).min(sy1 - 1));
                for col in 0..cols {
                    let x = ax0 + col;
                    if self.seen[y * w + x] == 0.0 {
                        continue;
                    }
                    let mut acc = [0.0f32; 4];
                    for yy in lo..=hi {
                        let k = self.weights[yy.abs_diff(y)];
                        let v = across[(yy - sy0) * cols + col];
                        for c in 0..4 {
                            acc[c] += k * v[c];
                        }
                    }
                    for c in 0..3 {
                        line[x * 4 + c] = (acc[c] / acc[3]).round().clamp(0.0, 255.0) as u8;
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sensor(blur: f64) -> Sensor {
        let mut c = Sensor::preset("allsight").unwrap().config;
        c.camera.blur_px = blur;
        Sensor::from_config("soft", c).unwrap()
    }

    fn flat(s: &Softness, value: u8) -> Vec<u8> {
        (0..s.width * s.height)
            .flat_map(|i| {
                let v = if s.seen[i as usize] > 0.0 { value } else { 0 };
                [v, v, v, 255]
            })
            .collect()
    }

    #[test]
    fn no_blur_means_no_softness() {
        assert!(Softness::of(&sensor(0.0)).is_none());
    }

    #[test]
    fn an_even_picture_stays_even_up_to_the_lens_edge_and_black_stays_black() {
        let s = Softness::of(&sensor(3.0)).unwrap();
        let raw = flat(&s, 100);
        assert_eq!(s.soften(&raw), raw);
    }

    #[test]
    fn a_bright_pixel_spreads_as_the_gaussian_and_keeps_its_light() {
        let s = Softness::of(&sensor(2.0)).unwrap();
        let mut raw = flat(&s, 0);
        let centre = (240 * s.width + 240) as usize;
        raw[centre * 4] = 255;
        let out = s.soften(&raw);
        let at = |dx: i64, dy: i64| out[((240 + dy) * s.width as i64 + 240 + dx) as usize * 4];
        // exp(-0.5) of the middle one pixel off, exp(-1) of it on the diagonal.
        let (mid, side, corner) = (at(0, 0) as f64, at(1, 0) as f64, at(1, 1) as f64);
        assert!(
            (side / mid - (-0.125f64).exp()).abs() < 0.05,
            "{mid} {side}"
        );
        assert!(
            (corner / mid - (-0.25f64).exp()).abs() < 0.05,
            "{mid} {corner}"
        );
        assert_eq!(at(0, 7), 0);
        let total: f64 = out.chunks(4).map(|p| p[0] as f64).sum();
        assert!((total - 255.0).abs() < 30.0, "{total}");
    }

    #[test]
    fn softening_only_where_a_contact_changed_equals_softening_the_whole() {
        let s = Softness::of(&sensor(3.0)).unwrap();
        let reference: Vec<u8> = (0..s.width * s.height)
            .flat_map(|i| [(i % 251) as u8, (i % 13) as u8 * 9, (i / 480) as u8, 255])
            .collect();
        let soft_reference = s.soften(&reference);
        let mut contact = reference.clone();
        let changed = Rect {
            x: 100,
            y: 150,
            w: 30,
            h: 20,
        };
        for y in changed.y..changed.y + changed.h {
            for x in changed.x..changed.x + changed.w {
                contact[((y * s.width + x) * 4) as usize + 1] = 250;
            }
        }
        let mut out = soft_reference.clone();
        s.soften_changed(&contact, &mut out, changed);
        assert_eq!(out, s.soften(&contact));
        assert_ne!(out, soft_reference);
    }
}
