//! PNG row filtering: each row by whichever of Sub, Up, Average and Paeth suits it best.

/// Paeth's predictor on unsigned bytes only (Luca Versari's form, as the `png` crate uses):
/// branch-free enough to vectorise. `pc` matters only when `c` lies between `a` and `b`,
/// and is then `|pa - pb|`.
#[inline]
pub(super) fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let pa = b.max(c) - b.min(c);
    let pb = a.max(c) - a.min(c);
    let pc = if (a < c) == (c < b) {
        pa.max(pb) - pa.min(pb)
    } else {
        255
    };
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

/// One PNG row filtered (filter type byte first) by whichever of Sub, Up, Average and
/// Paeth has the smallest sum of absolute values as signed bytes (the `png` crate's
/// adaptive heuristic; ties go to the first of the four here, to the last there, which
/// changes no pixel); `prev` is the row above (zeros for the first), 3 bytes a pixel. Each
/// filter is one pass over zipped slices (no bounds checks) into its own buffer of
/// `scratch`, which the compiler vectorises.
// Over 80 lines: the encoder's hot loop, its four vectorised passes kept whole for speed.
pub(super) fn filter_row(row: &[u8], prev: &[u8], scratch: &mut [Vec<u8>; 4], out: &mut Vec<u8>) {
    const BPP: usize = 3;
    const TYPES: [u8; 4] = [1, 2, 3, 4];
    let n = row.len();
    for buffer in scratch.iter_mut() {
        buffer.clear();
        buffer.resize(n, 0);
    }
    let head = BPP.min(n);
    let [sub, up, average, paeth_out] = scratch;
    for (o, (&x, &b)) in up.iter_mut().zip(row.iter().zip(prev)) {
        *o = x.wrapping_sub(b);
    }
    sub[..head].copy_from_slice(&row[..head]);
    for i in 0..head {
        average[i] = row[i].wrapping_sub(prev[i] >> 1);
        paeth_out[i] = row[i].wrapping_sub(prev[i]);
    }
    let (this, left) = (&row[head..], &row[..n - head]);
    let (above, above_left) = (&prev[head..], &prev[..n - head]);
    // Chunks of 32 bytes with fixed bounds, as the `png` crate found vectorises best.
    const CHUNK: usize = 32;
    let mut dst = sub[head..].chunks_exact_mut(CHUNK);
    let (mut x, mut a) = (this.chunks_exact(CHUNK), left.chunks_exact(CHUNK));
    for ((o, x), a) in (&mut dst).zip(&mut x).zip(&mut a) {
        for i in 0..CHUNK {
            o[i] = x[i].wrapping_sub(a[i]);
        }
    }
    for ((o, x), a) in dst
        .into_remainder()
        .iter_mut()
        .zip(x.remainder())
        .zip(a.remainder())
    {
        *o = x.wrapping_sub(*a);
    }
    let mut dst = average[head..].chunks_exact_mut(CHUNK);
    let (mut x, mut a) = (this.chunks_exact(CHUNK), left.chunks_exact(CHUNK));
    let mut b = above.chunks_exact(CHUNK);
    for (((o, x), a), b) in (&mut dst).zip(&mut x).zip(&mut a).zip(&mut b) {
        for i in 0..CHUNK {
            o[i] = x[i].wrapping_sub((a[i] & b[i]) + ((a[i] ^ b[i]) >> 1));
        }
    }
    let tails = x.remainder().iter().zip(a.remainder()).zip(b.remainder());
    for (o, ((x, a), b)) in dst.into_remainder().iter_mut().zip(tails) {
        *o = x.wrapping_sub((a & b) + ((a ^ b) >> 1));
    }
    let mut dst = paeth_out[head..].chunks_exact_mut(CHUNK);
    let (mut x, mut a) = (this.chunks_exact(CHUNK), left.chunks_exact(CHUNK));
    let (mut b, mut c) = (above.chunks_exact(CHUNK), above_left.chunks_exact(CHUNK));
    for ((((o, x), a), b), c) in (&mut dst).zip(&mut x).zip(&mut a).zip(&mut b).zip(&mut c) {
        for i in 0..CHUNK {
            o[i] = x[i].wrapping_sub(paeth(a[i], b[i], c[i]));
        }
    }
    let tails = x
        .remainder()
        .iter()
        .zip(a.remainder())
        .zip(b.remainder())
        .zip(c.remainder());
    for (o, (((x, a), b), c)) in dst.into_remainder().iter_mut().zip(tails) {
        *o = x.wrapping_sub(paeth(*a, *b, *c));
    }
    // Summed in u16 lanes 64 bytes at a time (at most 64 * 128), which vectorises far
    // better than widening every byte to u64.
    let cost = |x: &[u8]| -> u32 {
        x.chunks(64)
            .map(|c| {
                c.iter()
                    .map(|&b| (b as i8).unsigned_abs() as u16)
                    .sum::<u16>() as u32
            })
            .sum()
    };
    let (best, filtered) = scratch
        .iter()
        .enumerate()
        .min_by_key(|(k, x)| (cost(x), *k))
        .expect("four filters");
    out.push(TYPES[best]);
    out.extend_from_slice(filtered);
}
