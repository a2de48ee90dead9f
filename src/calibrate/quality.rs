//! How close a render is to a frame, over the pixels a mask selects: PSNR and SSIM on 8-bit
//! RGB, every channel counted.

/// Peak signal-to-noise ratio (dB) between `a` and `b` (RGB, row by row, `width` wide) over
/// the pixels `mask` selects; infinite for identical images.
pub fn psnr(a: &[u8], b: &[u8], width: u32, mask: impl Fn(u32, u32) -> bool) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (i, (pa, pb)) in a.chunks_exact(3).zip(b.chunks_exact(3)).enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        if !mask(x, y) {
            continue;
        }
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
        }
        n += 3;
    }
    if n == 0 {
        return f64::NAN;
    }
    let mse = sum / n as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    }
}

/// Structural similarity (Wang et al. 2004: 11 x 11 Gaussian window, sigma 1.5, K1 0.01,
/// K2 0.03) of each channel, averaged over the pixels `mask` selects and the channels.
pub fn ssim(a: &[u8], b: &[u8], width: u32, height: u32, mask: impl Fn(u32, u32) -> bool) -> f64 {
    let (w, h) = (width as usize, height as usize);
    let kernel: Vec<f64> = {
        let k: Vec<f64> = (-5i32..=5)
            .map(|i| (-(i * i) as f64 / (2.0 * 1.5 * 1.5)).exp())
            .collect();
        let s: f64 = k.iter().sum();
        k.into_iter().map(|v| v / s).collect()
    };
    let blur = |img: &[f64]| -> Vec<f64> {
        let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
            let mut out = vec![0.0; w * h];
            for y in 0..h {
                for x in 0..w {
                    let mut acc = 0.0;
                    let mut wsum = 0.0;
                    for (k, kv) in kernel.iter().enumerate() {
                        let o = k as i64 - 5;
                        let (sx, sy) = if horizontal {
                            (x as i64 + o, y as i64)
                        } else {
                            (x as i64, y as i64 + o)
                        };
                        if sx < 0 || sy < 0 || sx >= w as i64 || sy >= h as i64 {
                            continue;
                        }
                        acc += kv * src[sy as usize * w + sx as usize];
                        wsum += kv;
                    }
                    out[y * w + x] = acc / wsum;
                }
            }
            out
        };
        pass(&pass(img, true), false)
    };
    let (c1, c2) = ((0.01f64 * 255.0).powi(2), (0.03f64 * 255.0).powi(2));
    let mut total = 0.0;
    let mut n = 0usize;
    for c in 0..3 {
        let x: Vec<f64> = a.chunks_exact(3).map(|p| p[c] as f64).collect();
        let y: Vec<f64> = b.chunks_exact(3).map(|p| p[c] as f64).collect();
        let mx = blur(&x);
        let my = blur(&y);
        let xx = blur(&x.iter().map(|v| v * v).collect::<Vec<_>>());
        let yy = blur(&y.iter().map(|v| v * v).collect::<Vec<_>>());
        let xy = blur(&x.iter().zip(&y).map(|(p, q)| p * q).collect::<Vec<_>>());
        for i in 0..w * h {
            if !mask((i % w) as u32, (i / w) as u32) {
                continue;
            }
            let (vx, vy, cxy) = (
                xx[i] - mx[i] * mx[i],
                yy[i] - my[i] * my[i],
                xy[i] - mx[i] * my[i],
            );
            total += ((2.0 * mx[i] * my[i] + c1) * (2.0 * cxy + c2))
                / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        total / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_score_perfectly_and_a_changed_one_does_not() {
        let a: Vec<u8> = (0..32 * 24 * 3).map(|i| (i * 7 % 251) as u8).collect();
        assert!(psnr(&a, &a, 32, |_, _| true).is_infinite());
        assert!((ssim(&a, &a, 32, 24, |_, _| true) - 1.0).abs() < 1e-12);
        let b: Vec<u8> = a.iter().map(|v| v.saturating_add(4)).collect();
        let p = psnr(&a, &b, 32, |_, _| true);
        assert!(p > 30.0 && p < 37.0, "{p}");
        assert!(ssim(&a, &b, 32, 24, |_, _| true) < 1.0);
        // The mask: only the unchanged half counts.
        let mut c = a.clone();
        for v in &mut c[..32 * 12 * 3] {
            *v = 0;
        }
        assert!(psnr(&a, &c, 32, |_, y| y >= 12).is_infinite());
    }
}
