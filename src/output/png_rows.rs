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
use deflate::{adler32, adler32_combine, start_stream, Bits, Piece};
use filter::filter_row;

mod deflate;
mod filter;
#[cfg(test)]
mod tests;

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
