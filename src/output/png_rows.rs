//! PNG encoding of images that differ from one reference image in a few rows: a dataset's
//! contact frames against the empty finger (a contact changes the rows of its pixel rect,
//! a tenth to a third of the frame). The reference's rows are filtered and compressed once;
//! a frame re-encodes only the rows that differ from the reference (and each row after one,
//! whose filter reads it) and splices the reference's compressed rows in between.
//!
//! The compressed stream is the one fdeflate writes (what `image`'s PNG encoder uses at its
//! fast level): one deflate block with a fixed Huffman code tuned for filtered image data,
//! literals and runs of zeros. Its bits for a piece of data depend on that data alone, so
//! rows compressed apart concatenate bit for bit into one stream. The code's table and block
//! header are fdeflate 0.3's (MIT or Apache-2.0); a test holds this encoder to fdeflate's
//! bytes.

use crate::error::Result;

/// Code lengths of fdeflate's fixed literal/length code (`fdeflate::tables::HUFFMAN_LENGTHS`).
const HUFFMAN_LENGTHS: [u8; 286] = [
    2, 3, 4, 5, 5, 6, 6, 7, 7, 7, 8, 8, 8, 8, 8, 9, 9, 9, 9, 9, 9, 9, 10, 10, 10, 10, 10, 10, 10,
    10, 10, 11, 11, 11, 11, 11, 11, 11, 11, 11, 11, 11, 11, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 11, 11, 11, 11, 11, 11, 11,
    11, 11, 11, 10, 11, 10, 10, 10, 10, 10, 10, 10, 10, 10, 9, 9, 9, 9, 9, 8, 9, 8, 8, 8, 8, 8, 7,
    7, 7, 6, 6, 6, 5, 4, 3, 12, 12, 12, 9, 9, 11, 10, 11, 11, 10, 11, 11, 11, 11, 11, 11, 12, 11,
    12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 9,
];

/// The zlib header and the block's header (final, dynamic Huffman: the code above and a
/// one-symbol distance code), 53 bytes and 5 bits, as fdeflate writes them.
const HEADER: [u8; 54] = [
    120, 1, 237, 192, 3, 160, 36, 89, 150, 198, 241, 255, 119, 238, 141, 200, 204, 167, 114, 75,
    99, 174, 109, 219, 182, 109, 219, 182, 109, 219, 182, 109, 105, 140, 158, 150, 74, 175, 158,
    50, 51, 34, 238, 249, 118, 183, 106, 122, 166, 135, 59, 107, 213, 15,
];
const HEADER_TAIL_BITS: u32 = 5;

const END_OF_BLOCK: usize = 256;

/// Canonical codes of `HUFFMAN_LENGTHS`, bit-reversed as deflate writes them (RFC 1951,
/// 3.2.2).
const HUFFMAN_CODES: [u16; 286] = {
    let mut codes = [0u16; 286];
    let mut code = 0u32;
    let mut len = 1;
    while len <= 16 {
        let mut i = 0;
        while i < 286 {
            if HUFFMAN_LENGTHS[i] == len {
                codes[i] = (code as u16).reverse_bits() >> (16 - len);
                code += 1;
            }
            i += 1;
        }
        code <<= 1;
        len += 1;
    }
    assert!(code == 2 << 16, "HUFFMAN_LENGTHS is not a complete code");
    codes
};

/// Per match length 3..=258 (index length - 3): its length symbol and extra bits (RFC 1951,
/// 3.2.5).
const LENGTH_SYMBOLS: [(u16, u8); 256] = {
    const BASE: [u16; 29] = [
        3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43, 51, 59, 67, 83, 99, 115,
        131, 163, 195, 227, 258,
    ];
    const EXTRA: [u8; 29] = [
        0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0,
    ];
    let mut table = [(0u16, 0u8); 256];
    let mut length = 3;
    while length <= 258 {
        let mut s = 28;
        while BASE[s] > length {
            s -= 1;
        }
        table[(length - 3) as usize] = (257 + s as u16, EXTRA[s]);
        length += 1;
    }
    table
};

/// A little-endian bit stream, as deflate packs it.
struct Bits {
    bytes: Vec<u8>,
    buffer: u64,
    count: u32,
}

impl Bits {
    fn with_capacity(bytes: usize) -> Bits {
        Bits {
            bytes: Vec::with_capacity(bytes),
            buffer: 0,
            count: 0,
        }
    }

    /// Appends the low `n` (<= 64) bits of `bits` (the rest must be zero).
    #[inline]
    fn put(&mut self, bits: u64, n: u32) {
        self.buffer |= bits.checked_shl(self.count).unwrap_or(0);
        self.count += n;
        if self.count >= 64 {
            self.bytes.extend_from_slice(&self.buffer.to_le_bytes());
            self.count -= 64;
            self.buffer = bits.checked_shr(n - self.count).unwrap_or(0);
        }
    }

    #[inline]
    fn literal(&mut self, b: u8) {
        self.put(
            HUFFMAN_CODES[b as usize] as u64,
            HUFFMAN_LENGTHS[b as usize] as u32,
        );
    }

    /// A run of `run` (>= 1) zeros: a literal zero and copies of it at distance 1.
    fn zeros(&mut self, mut run: u32) {
        self.literal(0);
        run -= 1;
        while run >= 258 {
            // Length 258 and the distance code's one (zero) bit.
            self.put(HUFFMAN_CODES[285] as u64, HUFFMAN_LENGTHS[285] as u32 + 1);
            run -= 258;
        }
        if run > 4 {
            let (symbol, extra) = LENGTH_SYMBOLS[run as usize - 3];
            let symbol = symbol as usize;
            self.put(HUFFMAN_CODES[symbol] as u64, HUFFMAN_LENGTHS[symbol] as u32);
            let extra_bits = (run - 3) as u64 & ((1u64 << extra) - 1);
            self.put(extra_bits, extra as u32 + 1);
        } else {
            // Zero's code is all zero bits: short runs are cheaper as literals.
            self.put(0, run * HUFFMAN_LENGTHS[0] as u32);
        }
    }

    /// Compresses `data` as fdeflate's `write_data` does: eight bytes at a time, runs of zeros
    /// as copies, everything else as literals. Runs do not reach past `data`, so what this
    /// appends depends on `data` alone.
    fn compress(&mut self, data: &[u8]) {
        let mut run = 0u32;
        let mut chunks = data.chunks_exact(8);
        for chunk in &mut chunks {
            let word = u64::from_le_bytes(chunk.try_into().expect("8 bytes"));
            if word == 0 {
                run += 8;
                continue;
            } else if run > 0 {
                let run_extra = word.trailing_zeros() / 8;
                self.zeros(run + run_extra);
                run = 0;
                if run_extra > 0 {
                    run = word.leading_zeros() / 8;
                    for &b in &chunk[run_extra as usize..8 - run as usize] {
                        self.literal(b);
                    }
                    continue;
                }
            }
            let run_start = word.leading_zeros() / 8;
            if run_start > 0 {
                for &b in &chunk[..8 - run_start as usize] {
                    self.literal(b);
                }
                run = run_start;
                continue;
            }
            let n: [u32; 8] = std::array::from_fn(|i| HUFFMAN_LENGTHS[chunk[i] as usize] as u32);
            let c: [u64; 8] = std::array::from_fn(|i| HUFFMAN_CODES[chunk[i] as usize] as u64);
            self.put(
                c[0] | c[1] << n[0] | c[2] << (n[0] + n[1]) | c[3] << (n[0] + n[1] + n[2]),
                n[0] + n[1] + n[2] + n[3],
            );
            self.put(
                c[4] | c[5] << n[4] | c[6] << (n[4] + n[5]) | c[7] << (n[4] + n[5] + n[6]),
                n[4] + n[5] + n[6] + n[7],
            );
        }
        if run > 0 {
            self.zeros(run);
        }
        for &b in chunks.remainder() {
            self.literal(b);
        }
    }

    /// Appends a piece compressed on its own.
    fn splice(&mut self, piece: &Piece) {
        let (full, last) = piece.words.split_at(piece.words.len().saturating_sub(1));
        for &w in full {
            self.put(w, 64);
        }
        if let Some(&w) = last.first() {
            self.put(w, piece.bits - 64 * full.len() as u32);
        }
    }

    /// The stream so far as a piece (its bits in words).
    fn into_piece(self) -> Piece {
        let bits = 8 * self.bytes.len() as u32 + self.count;
        let mut words: Vec<u64> = self
            .bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        if self.count > 0 {
            words.push(self.buffer);
        }
        Piece { words, bits }
    }

    /// Ends the block and pads to a byte.
    fn finish(mut self) -> Vec<u8> {
        self.put(
            HUFFMAN_CODES[END_OF_BLOCK] as u64,
            HUFFMAN_LENGTHS[END_OF_BLOCK] as u32,
        );
        let bytes = self.count.div_ceil(8) as usize;
        self.bytes
            .extend_from_slice(&self.buffer.to_le_bytes()[..bytes]);
        self.bytes
    }
}

/// A row's compressed bits, starting at bit 0 of its first word.
#[derive(Debug, Clone)]
struct Piece {
    words: Vec<u64>,
    bits: u32,
}

fn start_stream(bits: &mut Bits) {
    bits.bytes.extend_from_slice(&HEADER[..HEADER.len() - 1]);
    bits.put(HEADER[HEADER.len() - 1] as u64, HEADER_TAIL_BITS);
}

fn adler32(data: &[u8]) -> u32 {
    let mut a = simd_adler32::Adler32::new();
    a.write(data);
    a.finish()
}

/// The Adler-32 of `a`'s data followed by `b`'s `b_len` bytes (zlib's `adler32_combine`).
fn adler32_combine(a: u32, b: u32, b_len: u64) -> u32 {
    const BASE: u64 = 65_521;
    let rem = b_len % BASE;
    let (a1, a2) = (a as u64 & 0xffff, a as u64 >> 16);
    let (b1, b2) = (b as u64 & 0xffff, b as u64 >> 16);
    let sum1 = (a1 + b1 + BASE - 1) % BASE;
    let sum2 = (rem * a1 + a2 + b2 + BASE - rem) % BASE;
    (sum1 | sum2 << 16) as u32
}

/// Paeth's predictor on unsigned bytes only (Luca Versari's form, as the `png` crate uses):
/// branch-free enough to vectorise. `pc` matters only when `c` lies between `a` and `b`,
/// and is then `|pa - pb|`.
#[inline]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
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
fn filter_row(row: &[u8], prev: &[u8], scratch: &mut [Vec<u8>; 4], out: &mut Vec<u8>) {
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

/// An RGB PNG encoder for images close to one reference image (RGBA rows in, RGB8 out, the
/// alpha dropped), compressed as fdeflate does: see the module's comment.
#[derive(Debug, Clone)]
pub struct PngRowCache {
    width: u32,
    height: u32,
    /// The reference's RGBA rows, to find the rows that differ.
    reference_rgba: Vec<u8>,
    /// The reference's RGB rows, which a differing row's successor is filtered against.
    reference_rgb: Vec<u8>,
    /// Each reference row filtered against the reference row above, compressed.
    pieces: Vec<Piece>,
    /// Adler-32 of each such filtered row.
    adlers: Vec<u32>,
}

impl PngRowCache {
    /// Filters and compresses the rows of `reference_rgba` (`width * height * 4` bytes).
    pub fn new(width: u32, height: u32, reference_rgba: &[u8]) -> Result<PngRowCache> {
        super::check_len("png reference", width, height, 4, reference_rgba.len())?;
        let reference_rgb = rgb_of(reference_rgba);
        let row = 3 * width as usize;
        let zeros = vec![0u8; row];
        let mut filtered = Vec::with_capacity(row + 1);
        let mut scratch = Default::default();
        let mut pieces = Vec::with_capacity(height as usize);
        let mut adlers = Vec::with_capacity(height as usize);
        for y in 0..height as usize {
            let prev = if y == 0 {
                &zeros[..]
            } else {
                &reference_rgb[(y - 1) * row..y * row]
            };
            filtered.clear();
            filter_row(
                &reference_rgb[y * row..(y + 1) * row],
                prev,
                &mut scratch,
                &mut filtered,
            );
            let mut bits = Bits::with_capacity(row);
            bits.compress(&filtered);
            pieces.push(bits.into_piece());
            adlers.push(adler32(&filtered));
        }
        Ok(PngRowCache {
            width,
            height,
            reference_rgba: reference_rgba.to_vec(),
            reference_rgb,
            pieces,
            adlers,
        })
    }

    /// The PNG of `rgba` (the reference's size): rows equal to the reference's, whose row
    /// above is too, are the reference's compressed bits; the rest are filtered and
    /// compressed now.
    pub fn encode(&self, rgba: &[u8]) -> Result<Vec<u8>> {
        super::check_len("png", self.width, self.height, 4, rgba.len())?;
        let (rgba_row, row) = (4 * self.width as usize, 3 * self.width as usize);
        let filtered_len = row as u64 + 1;
        let zeros = vec![0u8; row];
        let mut bits = Bits::with_capacity(self.pieces.iter().map(|p| p.words.len() * 8).sum());
        start_stream(&mut bits);
        let mut adler = 1u32;
        let (mut rgb, mut prev_rgb) = (Vec::with_capacity(row), Vec::with_capacity(row));
        let mut filtered = Vec::with_capacity(row + 1);
        let mut scratch = Default::default();
        let mut prev_changed = false;
        for y in 0..self.height as usize {
            let this = &rgba[y * rgba_row..(y + 1) * rgba_row];
            let changed = this != &self.reference_rgba[y * rgba_row..(y + 1) * rgba_row];
            if changed {
                rgb.clear();
                rgb.extend(this.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]));
            }
            if changed || prev_changed {
                let row_rgb = if changed {
                    &rgb[..]
                } else {
                    &self.reference_rgb[y * row..(y + 1) * row]
                };
                let prev = match (y, prev_changed) {
                    (0, _) => &zeros[..],
                    (_, true) => &prev_rgb[..],
                    (_, false) => &self.reference_rgb[(y - 1) * row..y * row],
                };
                filtered.clear();
                filter_row(row_rgb, prev, &mut scratch, &mut filtered);
                bits.compress(&filtered);
                adler = adler32_combine(adler, adler32(&filtered), filtered_len);
            } else {
                bits.splice(&self.pieces[y]);
                adler = adler32_combine(adler, self.adlers[y], filtered_len);
            }
            if changed {
                std::mem::swap(&mut rgb, &mut prev_rgb);
            }
            prev_changed = changed;
        }
        let mut zlib = bits.finish();
        zlib.extend_from_slice(&adler.to_be_bytes());
        Ok(png_file(self.width, self.height, &zlib))
    }
}

/// RGB bytes of RGBA pixels.
fn rgb_of(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// A PNG file: signature, IHDR (8-bit RGB, not interlaced), one IDAT of `zlib`, IEND.
fn png_file(width: u32, height: u32, zlib: &[u8]) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(data);
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        out.extend_from_slice(&crc.finalize().to_be_bytes());
    }
    let mut out = Vec::with_capacity(zlib.len() + 64);
    out.extend_from_slice(&[137, 80, 78, 71, 13, 10, 26, 10]);
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", zlib);
    chunk(&mut out, b"IEND", &[]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Compresses `data` into a zlib stream, bit for bit as `fdeflate::compress_to_vec` does.
    fn fdeflate_zlib(data: &[u8]) -> Vec<u8> {
        let mut bits = Bits::with_capacity(data.len() / 3 + 64);
        start_stream(&mut bits);
        bits.compress(data);
        let mut out = bits.finish();
        out.extend_from_slice(&adler32(data).to_be_bytes());
        out
    }

    /// Deterministic bytes with runs of zeros of every length (the case the run code
    /// handles) between stretches of small and large values.
    fn test_bytes(n: usize, seed: u64) -> Vec<u8> {
        let mut s = seed;
        let mut next = move || {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (s >> 33) as u32
        };
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let kind = next() % 4;
            let len = (next() % 600) as usize;
            for _ in 0..len {
                out.push(match kind {
                    0 => 0,
                    1 => (next() % 5) as u8,
                    2 => (next() % 256) as u8,
                    _ => 255 - (next() % 3) as u8,
                });
            }
        }
        out.truncate(n);
        out
    }

    #[test]
    fn the_compressor_writes_fdeflates_bytes() {
        for (n, seed) in [
            (0, 1),
            (1, 2),
            (7, 3),
            (8, 4),
            (1000, 5),
            (70_000, 6),
            (300_000, 7),
        ] {
            let data = test_bytes(n, seed);
            assert_eq!(
                fdeflate_zlib(&data),
                fdeflate::compress_to_vec(&data),
                "{n} bytes"
            );
        }
        let zeros = vec![0u8; 5000];
        assert_eq!(fdeflate_zlib(&zeros), fdeflate::compress_to_vec(&zeros));
    }

    #[test]
    fn adler32_combines_as_over_the_concatenation() {
        let data = test_bytes(200_000, 9);
        for cut in [0, 1, 65_520, 65_521, 100_000, 200_000] {
            let (a, b) = data.split_at(cut);
            assert_eq!(
                adler32_combine(adler32(a), adler32(b), b.len() as u64),
                adler32(&data),
                "cut at {cut}"
            );
        }
    }

    /// A reference image and a frame that differs from it in a band of rows.
    fn reference_and_frame(w: u32, h: u32, band: std::ops::Range<u32>) -> (Vec<u8>, Vec<u8>) {
        let mut reference = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h {
            for x in 0..w {
                let v = ((x * 3 + y * 5) % 200) as u8;
                reference.extend_from_slice(&[v, v / 2, 255 - v, 255]);
            }
        }
        let mut frame = reference.clone();
        for y in band {
            for x in w / 4..w / 2 {
                let i = ((y * w + x) * 4) as usize;
                frame[i] = frame[i].wrapping_add(40 + (x % 7) as u8);
                frame[i + 2] = frame[i + 2].wrapping_sub(17);
            }
        }
        (reference, frame)
    }

    fn decode_rgb(png: &[u8]) -> Vec<u8> {
        image::load_from_memory_with_format(png, image::ImageFormat::Png)
            .expect("a valid PNG")
            .to_rgb8()
            .into_raw()
    }

    #[test]
    fn encoded_frames_decode_to_their_pixels() {
        let (w, h) = (37, 29);
        for band in [0..0, 0..1, 5..9, 28..29, 0..29] {
            let (reference, frame) = reference_and_frame(w, h, band.clone());
            let cache = PngRowCache::new(w, h, &reference).expect("cache");
            let png = cache.encode(&frame).expect("encode");
            assert_eq!(decode_rgb(&png), rgb_of(&frame), "rows {band:?}");
            // The same stream as compressing every row now.
            let fresh = PngRowCache::new(w, h, &frame).expect("cache");
            assert_eq!(png, fresh.encode(&frame).expect("encode"), "rows {band:?}");
        }
    }

    #[test]
    fn a_changed_pixel_changes_the_decoded_image() {
        let (w, h) = (16, 12);
        let (reference, mut frame) = reference_and_frame(w, h, 3..5);
        let cache = PngRowCache::new(w, h, &reference).expect("cache");
        let before = decode_rgb(&cache.encode(&frame).expect("encode"));
        frame[(7 * w as usize + 2) * 4 + 1] ^= 0x10;
        let after = decode_rgb(&cache.encode(&frame).expect("encode"));
        assert_ne!(before, after);
        assert_eq!(after, rgb_of(&frame));
    }

    #[test]
    fn a_frame_of_another_size_is_refused() {
        let (reference, _) = reference_and_frame(8, 8, 0..0);
        let cache = PngRowCache::new(8, 8, &reference).expect("cache");
        let err = cache.encode(&reference[..100]).expect_err("wrong size");
        assert!(err.to_string().contains("png"), "{err}");
    }
}
