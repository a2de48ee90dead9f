//! Writing results to disk atomically: PNG, NPY, JSON.
//!
//! Every writer encodes in memory and then calls [`write_atomic`], which writes a temporary
//! file next to the target and renames it over the target: a reader (or a crash) never sees
//! a half-written file.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{GeltipError, Result};

mod lock;
mod png_rows;
pub use lock::{DirLock, LOCK_FILE};
pub use png_rows::PngRowCache;

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, flushed and
/// synced, then renamed over `path`. Parent directories are created. On error the temporary
/// file is removed and `path` is left as it was.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    let path = path.as_ref();
    let file_name = path.file_name().ok_or_else(|| {
        GeltipError::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"),
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&dir).map_err(|e| GeltipError::io(path, e))?;

    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(format!(
        ".{}.{}.tmp",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let tmp = dir.join(tmp_name);

    let written = (|| -> std::io::Result<()> {
        let mut file = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(GeltipError::io(path, e));
    }
    Ok(())
}

/// Writes an 8-bit RGBA image (`width * height * 4` bytes, rows top to bottom) as PNG.
pub fn write_png_rgba8(path: impl AsRef<Path>, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    write_png(
        path.as_ref(),
        width,
        height,
        rgba,
        4,
        image::ExtendedColorType::Rgba8,
    )
}

/// Writes an 8-bit RGB image (`width * height * 3` bytes, rows top to bottom) as PNG.
pub fn write_png_rgb8(path: impl AsRef<Path>, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_png(
        path.as_ref(),
        width,
        height,
        rgb,
        3,
        image::ExtendedColorType::Rgb8,
    )
}

fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    data: &[u8],
    channels: usize,
    color: image::ExtendedColorType,
) -> Result<()> {
    let what = format!("png {}", path.display());
    check_len(&what, width, height, channels, data.len())?;
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        data,
        width,
        height,
        color,
    )
    .map_err(|e| GeltipError::input(&what, e.to_string()))?;
    write_atomic(path, &png)
}

/// Pixel layouts [`png_bytes`] encodes: 8 bits per channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PngColor {
    Gray8,
    Rgb8,
    Rgba8,
}

impl PngColor {
    fn channels(self) -> usize {
        match self {
            PngColor::Gray8 => 1,
            PngColor::Rgb8 => 3,
            PngColor::Rgba8 => 4,
        }
    }
}

/// Encodes an 8-bit image (`width * height` pixels of `color`, rows top to bottom) as PNG
/// bytes in memory, with the given zlib effort and row filter (speed against size).
pub fn png_bytes(
    width: u32,
    height: u32,
    data: &[u8],
    color: PngColor,
    compression: image::codecs::png::CompressionType,
    filter: image::codecs::png::FilterType,
) -> Result<Vec<u8>> {
    check_len("png", width, height, color.channels(), data.len())?;
    let ext = match color {
        PngColor::Gray8 => image::ExtendedColorType::L8,
        PngColor::Rgb8 => image::ExtendedColorType::Rgb8,
        PngColor::Rgba8 => image::ExtendedColorType::Rgba8,
    };
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new_with_quality(&mut png, compression, filter),
        data,
        width,
        height,
        ext,
    )
    .map_err(|e| GeltipError::input("png", e.to_string()))?;
    Ok(png)
}

/// Makes `dst` hold the bytes of `src` atomically: a hard link under a temporary name (no
/// copy when both are on one file system), else a copy through [`write_atomic`].
pub fn link_or_copy_atomic(src: impl AsRef<Path>, dst: impl AsRef<Path>) -> Result<()> {
    let (src, dst) = (src.as_ref(), dst.as_ref());
    let dir = match dst.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&dir).map_err(|e| GeltipError::io(dst, e))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(dst.file_name().unwrap_or_default());
    tmp_name.push(format!(".{}.link.tmp", std::process::id()));
    let tmp = dir.join(tmp_name);
    let _ = fs::remove_file(&tmp);
    if fs::hard_link(src, &tmp).is_ok() {
        return fs::rename(&tmp, dst).map_err(|e| {
            let _ = fs::remove_file(&tmp);
            GeltipError::io(dst, e)
        });
    }
    let bytes = fs::read(src).map_err(|e| GeltipError::io(src, e))?;
    write_atomic(dst, &bytes)
}

/// A text file that grows by whole lines (a manifest): each line goes to the file in one
/// write, after whatever it describes is complete. A failed append (a full disk) is cut back
/// off the file; a crash can leave at most the last line torn, which readers must ignore
/// (see the dataset job's resume).
pub struct LineLog {
    path: PathBuf,
    file: fs::File,
    /// The file's length after the last whole line.
    len: u64,
}

impl LineLog {
    /// Opens `path` for appending, creating it.
    pub fn open(path: impl AsRef<Path>) -> Result<LineLog> {
        let path = path.as_ref().to_path_buf();
        let file = fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(|e| GeltipError::io(&path, e))?;
        let len = file
            .metadata()
            .map_err(|e| GeltipError::io(&path, e))?
            .len();
        Ok(LineLog { path, file, len })
    }

    /// Appends `line` (which must not contain a newline) and a newline, in one write. On
    /// error the file is cut back to its last whole line: a write the disk had room for
    /// only part of leaves no torn line behind.
    pub fn append(&mut self, line: &str) -> Result<()> {
        let mut buf = Vec::with_capacity(line.len() + 1);
        buf.extend_from_slice(line.as_bytes());
        buf.push(b'\n');
        if let Err(e) = self.file.write_all(&buf) {
            let _ = self.file.set_len(self.len);
            return Err(GeltipError::io(&self.path, e));
        }
        self.len += buf.len() as u64;
        Ok(())
    }
}

fn check_len(what: &str, width: u32, height: u32, channels: usize, len: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(GeltipError::input(
            what,
            format!("empty image {width}x{height}"),
        ));
    }
    let expected = (width as usize)
        .checked_mul(height as usize)
        .and_then(|n| n.checked_mul(channels));
    if expected != Some(len) {
        return Err(GeltipError::input(
            what,
            format!(
                "{width}x{height} with {channels} values a pixel needs {} values, got {len}",
                expected.map_or_else(|| "too many".to_string(), |n| n.to_string())
            ),
        ));
    }
    Ok(())
}

/// The bytes of a NumPy `.npy` (format version 1.0) file holding `data` as a little-endian
/// `float32` array of shape `(height, width)` in C order.
pub fn npy_f32_bytes(width: u32, height: u32, data: &[f32]) -> Result<Vec<u8>> {
    check_len("npy", width, height, 1, data.len())?;
    let dict =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({height}, {width}), }}");
    // magic (6) + version (2) + header length (2) + dict + padding + '\n' ≡ 0 (mod 64)
    let unpadded = 10 + dict.len() + 1;
    let header_len = unpadded.next_multiple_of(64) - 10;
    let mut out = Vec::with_capacity(10 + header_len + data.len() * 4);
    out.extend_from_slice(b"\x93NUMPY");
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(header_len as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(10 + header_len - 1, b' ');
    out.push(b'\n');
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// Writes `data` (`height` rows of `width` values) as a NumPy `.npy` file: `numpy.load` gives
/// a `float32` array of shape `(height, width)`.
pub fn write_npy_f32(path: impl AsRef<Path>, width: u32, height: u32, data: &[f32]) -> Result<()> {
    let path = path.as_ref();
    let bytes = npy_f32_bytes(width, height, data).map_err(|e| match e {
        GeltipError::InvalidInput { reason, .. } => {
            GeltipError::input(format!("npy {}", path.display()), reason)
        }
        other => other,
    })?;
    write_atomic(path, &bytes)
}

/// Writes `value` as pretty-printed JSON with a trailing newline.
pub fn write_json(path: impl AsRef<Path>, value: &serde_json::Value) -> Result<()> {
    let path = path.as_ref();
    let mut text = serde_json::to_string_pretty(value)
        .map_err(|e| GeltipError::input(format!("json {}", path.display()), e.to_string()))?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_data_is_64_byte_aligned() {
        for (w, h) in [(1, 1), (317, 211), (100_000, 100)] {
            let n = (w * h) as usize;
            let bytes = npy_f32_bytes(w, h, &vec![0.5; n]).unwrap();
            assert_eq!((bytes.len() - n * 4) % 64, 0);
            let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            assert_eq!(bytes[10 + header_len - 1], b'\n');
        }
    }

    #[test]
    fn wrong_lengths_are_rejected() {
        assert!(npy_f32_bytes(2, 2, &[0.0; 3]).is_err());
        assert!(check_len("x", 2, 2, 4, 15).is_err());
        assert!(check_len("x", 0, 2, 4, 0).is_err());
        assert!(check_len("x", 2, 2, 4, 16).is_ok());
    }
}
