//! The deflate compressor: fdeflate's fixed Huffman code for filtered image data (literals
//! and runs of zeros) in one block, whose bits for a piece of data depend on that data alone
//! so that rows compressed apart concatenate; and Adler-32, combinable over concatenations.

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
pub(super) struct Bits {
    bytes: Vec<u8>,
    buffer: u64,
    count: u32,
}

impl Bits {
    pub(super) fn with_capacity(bytes: usize) -> Bits {
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
    pub(super) fn compress(&mut self, data: &[u8]) {
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
    pub(super) fn splice(&mut self, piece: &Piece) {
        let (full, last) = piece.words.split_at(piece.words.len().saturating_sub(1));
        for &w in full {
            self.put(w, 64);
        }
        if let Some(&w) = last.first() {
            self.put(w, piece.bits - 64 * full.len() as u32);
        }
    }

    /// The stream so far as a piece (its bits in words).
    pub(super) fn into_piece(self) -> Piece {
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
    pub(super) fn finish(mut self) -> Vec<u8> {
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
pub(super) struct Piece {
    pub(super) words: Vec<u64>,
    bits: u32,
}

/// Writes the zlib header and the deflate block's header.
pub(super) fn start_stream(bits: &mut Bits) {
    bits.bytes.extend_from_slice(&HEADER[..HEADER.len() - 1]);
    bits.put(HEADER[HEADER.len() - 1] as u64, HEADER_TAIL_BITS);
}

/// The Adler-32 checksum of `data`.
pub(super) fn adler32(data: &[u8]) -> u32 {
    let mut a = simd_adler32::Adler32::new();
    a.write(data);
    a.finish()
}

/// The Adler-32 of `a`'s data followed by `b`'s `b_len` bytes (zlib's `adler32_combine`).
pub(super) fn adler32_combine(a: u32, b: u32, b_len: u64) -> u32 {
    const BASE: u64 = 65_521;
    let rem = b_len % BASE;
    let (a1, a2) = (a as u64 & 0xffff, a as u64 >> 16);
    let (b1, b2) = (b as u64 & 0xffff, b as u64 >> 16);
    let sum1 = (a1 + b1 + BASE - 1) % BASE;
    let sum2 = (rem * a1 + a2 + b2 + BASE - rem) % BASE;
    (sum1 | sum2 << 16) as u32
}
