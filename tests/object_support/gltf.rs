//! glTF and GLB files of a mesh, written by hand: for the loading tests and the fuzz seeds.

use geltip::object::Mesh;

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF document for `mesh` (f32 positions, u32 indices): a parent node translated by
/// `parent_t` with a child node that holds the mesh, scaled by `child_scale`. With `glb`,
/// the buffer is the GLB's binary chunk; without, an embedded base64 data URI.
pub fn gltf_json(
    mesh: &Mesh,
    parent_t: [f64; 3],
    child_scale: [f64; 3],
    glb: bool,
) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &mesh.positions {
        for (k, v) in [p.x as f32, p.y as f32, p.z as f32].into_iter().enumerate() {
            bin.extend_from_slice(&v.to_le_bytes());
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    let pos_len = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let uri = if glb {
        String::new()
    } else {
        format!(
            r#","uri":"data:application/octet-stream;base64,{}""#,
            base64(&bin)
        )
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"translation":{pt:?},"children":[1]}},{{"mesh":0,"scale":{cs:?}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],
"buffers":[{{"byteLength":{len}{uri}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len},"target":34962}},
{{"buffer":0,"byteOffset":{pos_len},"byteLength":{idx_len},"target":34963}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{nv},"type":"VEC3","min":{lo:?},"max":{hi:?}}},
{{"bufferView":1,"componentType":5125,"count":{ni},"type":"SCALAR"}}]}}"#,
        pt = parent_t,
        cs = child_scale,
        len = bin.len(),
        idx_len = bin.len() - pos_len,
        nv = mesh.positions.len(),
        ni = 3 * mesh.triangles.len(),
    );
    (json, bin)
}

/// A binary glTF container around `json` and `bin`.
pub fn glb_bytes(json: &str, mut bin: Vec<u8>) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    out
}
