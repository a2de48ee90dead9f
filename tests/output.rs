//! The atomic writers: NPY header layout, PNG round trips, failed writes leave nothing behind.

use std::fs;
use std::path::{Path, PathBuf};

use geltip::output::{write_atomic, write_json, write_npy_f32, write_png_rgb8, write_png_rgba8};

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-output-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn npy_header_is_numpy_v1_and_data_is_aligned() {
    let dir = scratch("npy");
    let (w, h) = (317u32, 211u32);
    let data: Vec<f32> = (0..w * h).map(|i| i as f32 * 0.25 - 100.0).collect();
    let path = dir.join("depth.npy");
    write_npy_f32(&path, w, h, &data).unwrap();
    let bytes = fs::read(&path).unwrap();

    assert_eq!(&bytes[..6], b"\x93NUMPY", "magic");
    assert_eq!(&bytes[6..8], &[1, 0], "version 1.0");
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let data_start = 10 + header_len;
    assert_eq!(data_start % 64, 0, "data starts at a multiple of 64");
    let header = std::str::from_utf8(&bytes[10..data_start]).unwrap();
    assert!(header.ends_with('\n'), "{header:?}");
    assert!(header.is_ascii());
    assert_eq!(
        header.trim_end(),
        "{'descr': '<f4', 'fortran_order': False, 'shape': (211, 317), }"
    );
    assert_eq!(bytes.len(), data_start + data.len() * 4, "total length");
    let back: Vec<f32> = bytes[data_start..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(back, data);
    assert_eq!(entries(&dir), ["depth.npy"]);

    let e = write_npy_f32(dir.join("short.npy"), w, h, &data[1..]).unwrap_err();
    assert!(e.to_string().contains("short.npy"), "{e}");
    assert_eq!(entries(&dir), ["depth.npy"]);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn png_round_trips_through_image() {
    let dir = scratch("png");
    let (w, h) = (37u32, 23u32);
    let rgba: Vec<u8> = (0..w * h * 4).map(|i| (i * 7 % 256) as u8).collect();
    let path = dir.join("sub/dir/tactile.png");
    write_png_rgba8(&path, w, h, &rgba).unwrap();
    let img = image::open(&path).unwrap().into_rgba8();
    assert_eq!(img.dimensions(), (w, h));
    assert_eq!(img.as_raw(), &rgba);

    let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 13 % 256) as u8).collect();
    let path = dir.join("rgb.png");
    write_png_rgb8(&path, w, h, &rgb).unwrap();
    let img = image::open(&path).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    assert_eq!(img.into_rgb8().as_raw(), &rgb);

    let e = write_png_rgba8(dir.join("bad.png"), w, h, &rgb).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("bad.png") && !msg.contains('\n'), "{msg}");
    assert!(!dir.join("bad.png").exists());
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn json_is_pretty_with_trailing_newline_and_overwrites() {
    let dir = scratch("json");
    let path = dir.join("meta.json");
    write_json(&path, &serde_json::json!({"a": 1})).unwrap();
    write_json(&path, &serde_json::json!({"b": [1, 2]})).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    assert!(
        text.ends_with("}\n") && text.contains("\n  \"b\""),
        "{text:?}"
    );
    let back: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(back, serde_json::json!({"b": [1, 2]}));
    assert_eq!(entries(&dir), ["meta.json"]);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn failed_write_leaves_nothing_and_names_the_path() {
    let dir = scratch("fail");
    // The parent of the target is a file: neither the directory nor the file can be made.
    let blocker = dir.join("blocker");
    fs::write(&blocker, b"not a directory").unwrap();
    let target = blocker.join("out.png");
    let e = write_atomic(&target, b"data").unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains(&*target.to_string_lossy()), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    assert_eq!(entries(&dir), ["blocker"]);
    assert_eq!(fs::read(&blocker).unwrap(), b"not a directory");

    // The target is a directory: the rename fails, the temporary file is removed.
    let target = dir.join("taken");
    fs::create_dir(&target).unwrap();
    fs::write(target.join("keep"), b"x").unwrap();
    let e = write_atomic(&target, b"data").unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("taken") && !msg.contains('\n'), "{msg}");
    assert_eq!(entries(&dir), ["blocker", "taken"]);
    assert_eq!(entries(&target), ["keep"]);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn atomic_write_replaces_contents_whole() {
    let dir = scratch("replace");
    let path = dir.join("f.bin");
    write_atomic(&path, &[1u8; 1000]).unwrap();
    write_atomic(&path, &[2u8; 10]).unwrap();
    assert_eq!(fs::read(&path).unwrap(), [2u8; 10]);
    assert_eq!(entries(&dir), ["f.bin"]);
    fs::remove_dir_all(&dir).unwrap();
}
