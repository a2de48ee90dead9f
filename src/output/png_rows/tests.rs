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
