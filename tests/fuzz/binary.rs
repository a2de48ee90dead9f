//! Mutations of binary inputs: PNG chunk by chunk (header sizes, depths and colour types,
//! dropped, doubled and swapped chunks, torn image data; the checksum fixed most of the time
//! so the decoder gets past it), GLB by its header and its JSON and binary chunks, and blind
//! byte flips, insertions and truncations for any input.

use super::mutate::{json_tree, text, Flavor};
use super::Rng;

/// A blind mutation: a bit flipped, an interesting byte inserted or overwritten, a span
/// deleted or doubled, or the end cut off.
pub fn bytes(rng: &mut Rng, b: &[u8]) -> Vec<u8> {
    let mut out = b.to_vec();
    if out.is_empty() {
        out.push(*rng.pick(&[0u8, b'{', b'[', b'"', 0xff]));
        return out;
    }
    let i = rng.below(out.len());
    const BYTES: [u8; 14] = [
        0, 0xff, 0x7f, 0x80, b'\n', b'\r', b'"', b'\\', b'[', b']', b'{', b'=', b',', b'#',
    ];
    match rng.below(6) {
        0 => out[i] ^= 1 << rng.below(8),
        1 => out[i] = *rng.pick(&BYTES),
        2 => out.insert(i, *rng.pick(&BYTES)),
        3 => {
            let end = (i + 1 + rng.below(64)).min(out.len());
            out.drain(i..end);
        }
        4 => {
            let end = (i + 1 + rng.below(64)).min(out.len());
            let span = out[i..end].to_vec();
            out.splice(i..i, span);
        }
        _ => out.truncate(i),
    }
    out
}

/// A PNG's chunks: (type, data).
fn png_chunks(b: &[u8]) -> Option<Vec<([u8; 4], Vec<u8>)>> {
    if b.len() < 8 || &b[..8] != b"\x89PNG\r\n\x1a\n" {
        return None;
    }
    let mut at = 8;
    let mut out = Vec::new();
    while at + 12 <= b.len() {
        let len = u32::from_be_bytes(b[at..at + 4].try_into().ok()?) as usize;
        let kind: [u8; 4] = b[at + 4..at + 8].try_into().ok()?;
        let data = b.get(at + 8..at + 8 + len)?.to_vec();
        out.push((kind, data));
        at += 12 + len;
    }
    Some(out)
}

/// A PNG from chunks; each chunk's checksum right unless `bad_crc`.
fn png_from(chunks: &[([u8; 4], Vec<u8>)], bad_crc: bool) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    for (kind, data) in chunks {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let mut h = crc32fast::Hasher::new();
        h.update(kind);
        h.update(data);
        let crc = h.finalize() ^ u32::from(bad_crc);
        out.extend_from_slice(&crc.to_be_bytes());
    }
    out
}

/// One mutation of a PNG, chunk-aware when it parses.
pub fn png(rng: &mut Rng, b: &[u8]) -> Vec<u8> {
    let Some(mut chunks) = png_chunks(b).filter(|c| !c.is_empty()) else {
        return bytes(rng, b);
    };
    let ihdr = chunks
        .iter()
        .position(|(k, d)| k == b"IHDR" && d.len() == 13);
    let idat = chunks.iter().position(|(k, _)| k == b"IDAT");
    match rng.below(10) {
        0 | 1 if ihdr.is_some() => {
            let d = &mut chunks[ihdr.unwrap_or(0)].1;
            let side = *rng.pick(&[0u32, 1, 2, 7, 65_535, 65_536, 100_000, 1 << 30, u32::MAX]);
            let at = if rng.chance(0.5) { 0 } else { 4 };
            d[at..at + 4].copy_from_slice(&side.to_be_bytes());
        }
        2 if ihdr.is_some() => {
            let d = &mut chunks[ihdr.unwrap_or(0)].1;
            match rng.below(4) {
                0 => d[8] = *rng.pick(&[0u8, 1, 2, 3, 4, 8, 16, 32, 255]),
                1 => d[9] = *rng.pick(&[0u8, 1, 2, 3, 4, 5, 6, 7, 255]),
                2 => d[12] = *rng.pick(&[0u8, 1, 2, 255]),
                _ => d[10 + rng.below(2)] = *rng.pick(&[0u8, 1, 255]),
            }
        }
        3 if idat.is_some() => {
            let d = &mut chunks[idat.unwrap_or(0)].1;
            let keep = rng.below(d.len().max(1));
            d.truncate(keep);
        }
        4 if idat.is_some() => {
            let d = &mut chunks[idat.unwrap_or(0)].1;
            if !d.is_empty() {
                let i = rng.below(d.len());
                d[i] ^= 1 << rng.below(8);
            }
        }
        5 => {
            chunks.remove(rng.below(chunks.len()));
        }
        6 => {
            let c = chunks[rng.below(chunks.len())].clone();
            let at = rng.below(chunks.len() + 1);
            chunks.insert(at, c);
        }
        7 if chunks.len() > 1 => {
            let (i, j) = (rng.below(chunks.len()), rng.below(chunks.len()));
            chunks.swap(i, j);
        }
        8 => {
            // A chunk whose length field claims far more than the file holds.
            let mut out = png_from(&chunks, false);
            let mut at = 8;
            for _ in 0..rng.below(chunks.len()) {
                let len = u32::from_be_bytes([out[at], out[at + 1], out[at + 2], out[at + 3]]);
                at += 12 + len as usize;
            }
            let claim = *rng.pick(&[u32::MAX, 0x7fff_ffff, 1 << 24]);
            out[at..at + 4].copy_from_slice(&claim.to_be_bytes());
            return out;
        }
        _ => return bytes(rng, b),
    }
    png_from(&chunks, rng.chance(0.1))
}

const GLB_JSON: u32 = 0x4E4F_534A;
const GLB_BIN: u32 = 0x004E_4942;

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// A GLB's chunks: (type, data).
fn glb_chunks(b: &[u8]) -> Option<Vec<(u32, Vec<u8>)>> {
    if b.get(..4)? != b"glTF" {
        return None;
    }
    let mut at = 12;
    let mut out = Vec::new();
    while at + 8 <= b.len() {
        let len = u32_at(b, at)? as usize;
        let kind = u32_at(b, at + 4)?;
        out.push((kind, b.get(at + 8..at + 8 + len)?.to_vec()));
        at += 8 + len;
    }
    Some(out)
}

/// A GLB from chunks, lengths and padding right.
fn glb_from(chunks: &[(u32, Vec<u8>)]) -> Vec<u8> {
    let mut body = Vec::new();
    for (kind, data) in chunks {
        let mut data = data.clone();
        let pad = if *kind == GLB_JSON { b' ' } else { 0 };
        while data.len() % 4 != 0 {
            data.push(pad);
        }
        body.extend_from_slice(&(data.len() as u32).to_le_bytes());
        body.extend_from_slice(&kind.to_le_bytes());
        body.extend_from_slice(&data);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + body.len()) as u32).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// One mutation of a GLB: its JSON chunk mutated as JSON (lengths then fixed), its binary
/// chunk torn or flipped, or a header or length field set to something else.
pub fn glb(rng: &mut Rng, b: &[u8]) -> Vec<u8> {
    let Some(mut chunks) = glb_chunks(b).filter(|c| !c.is_empty()) else {
        return bytes(rng, b);
    };
    match rng.below(8) {
        0..=3 => {
            if let Some((_, json)) = chunks.iter_mut().find(|(k, _)| *k == GLB_JSON) {
                let trimmed: Vec<u8> = json.trim_ascii_end().to_vec();
                *json = json_tree(rng, &trimmed)
                    .unwrap_or_else(|| text(rng, &trimmed, &[], Flavor::Json));
            }
        }
        4 => {
            if let Some((_, bin)) = chunks.iter_mut().find(|(k, _)| *k == GLB_BIN) {
                if rng.chance(0.5) {
                    let keep = rng.below(bin.len().max(1));
                    bin.truncate(keep);
                } else if !bin.is_empty() {
                    let i = rng.below(bin.len());
                    bin[i] ^= 1 << rng.below(8);
                }
            }
        }
        5 => {
            let mut out = glb_from(&chunks);
            let field = *rng.pick(&[4usize, 8, 12, 16]);
            let v = *rng.pick(&[0u32, 1, 3, u32::MAX, 0x7fff_ffff, GLB_BIN, GLB_JSON]);
            if out.len() >= field + 4 {
                out[field..field + 4].copy_from_slice(&v.to_le_bytes());
            }
            return out;
        }
        6 => {
            let i = rng.below(chunks.len());
            if rng.chance(0.5) {
                chunks.remove(i);
            } else {
                let c = chunks[i].clone();
                chunks.push(c);
            }
        }
        _ => return bytes(rng, b),
    }
    glb_from(&chunks)
}
