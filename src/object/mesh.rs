//! Triangle meshes: the built-in solids' meshes, and user meshes loaded from `.obj`, `.gltf`
//! or `.glb` files, validated and placed in the object frame (top at the origin, body in
//! `z <= 0`).

use crate::error::{GeltipError, Result};
use glam::{DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A triangle mesh in millimetres. Triangles index `positions`; a closed mesh is wound
/// counter-clockwise seen from outside (normals `(b - a) x (c - a)` point out).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Vertices within this distance (mm) of the highest one belong to a mesh's top.
pub const TOP_TOLERANCE_MM: f64 = 1e-6;

impl Mesh {
    /// Loads a mesh from an `.obj` (triangulated; all objects/groups) or a `.gltf`/`.glb`
    /// (all triangle primitives of the default scene, or of every scene when there is no
    /// default, node transforms applied) and validates it.
    ///
    /// Every failure (unreadable file, unknown extension, parse error, no triangles,
    /// non-finite vertex, index out of range) is a one-line [`GeltipError::InvalidMesh`].
    pub fn load(path: impl AsRef<Path>) -> Result<Mesh> {
        let path = path.as_ref();
        let invalid = |reason: String| GeltipError::InvalidMesh {
            path: path.to_path_buf(),
            reason: one_line(&reason),
        };
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if !matches!(ext.as_str(), "obj" | "gltf" | "glb") {
            let shown = if ext.is_empty() {
                "no extension".to_string()
            } else {
                format!("unknown extension '.{ext}'")
            };
            return Err(invalid(format!("{shown}: expected .obj, .gltf or .glb")));
        }
        let bytes = std::fs::read(path).map_err(|e| invalid(format!("cannot read file: {e}")))?;
        let mesh = if ext == "obj" {
            load_obj(&bytes)
        } else {
            load_gltf(&bytes, path.parent())
        }
        .map_err(invalid)?;
        mesh.validate().map_err(invalid)?;
        Ok(mesh)
    }

    /// Checks that the mesh can be used as an object: at least one triangle, every vertex
    /// finite, every index in range. The error names the first problem found.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if self.triangles.is_empty() {
            return Err("no triangles".into());
        }
        if let Some((i, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(format!(
                "vertex {i} is not finite ({}, {}, {})",
                p.x, p.y, p.z
            ));
        }
        let n = self.positions.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "triangle {t} uses vertex index {i} but there are only {n} vertices"
                ));
            }
        }
        Ok(())
    }

    /// The mesh as Wavefront OBJ text: a comment line, `v` lines with six decimals
    /// (a negative zero written as zero), then `f` lines (1-based). Deterministic.
    pub fn to_obj_string(&self) -> String {
        let mut s = String::with_capacity(40 * (self.positions.len() + self.triangles.len()));
        let _ = writeln!(
            s,
            "# geltip mesh: {} vertices, {} triangles, millimetres",
            self.positions.len(),
            self.triangles.len()
        );
        for p in &self.positions {
            let _ = writeln!(s, "v {} {} {}", fixed6(p.x), fixed6(p.y), fixed6(p.z));
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// Writes the mesh as an OBJ file ([`Mesh::to_obj_string`]) atomically: to a temporary
    /// file in the same folder, then renamed over `path`.
    pub fn write_obj(&self, path: impl AsRef<Path>) -> Result<()> {
        write_atomically(path.as_ref(), self.to_obj_string().as_bytes())
    }

    /// The same mesh translated so that its top is at the origin: the top is the centre of
    /// the bounding box of the vertices within [`TOP_TOLERANCE_MM`] of the highest z. The
    /// file's +z then points at the finger, like the built-in solids.
    pub fn placed_for_contact(&self) -> Mesh {
        self.translated(-self.top())
    }

    /// The top point used by [`Mesh::placed_for_contact`] (the origin for an empty mesh).
    pub fn top(&self) -> DVec3 {
        let max_z = self
            .positions
            .iter()
            .map(|p| p.z)
            .fold(f64::NEG_INFINITY, f64::max);
        if !max_z.is_finite() {
            return DVec3::ZERO;
        }
        let (lo, hi) = self
            .positions
            .iter()
            .filter(|p| p.z >= max_z - TOP_TOLERANCE_MM)
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let c = (lo + hi) / 2.0;
        DVec3::new(c.x, c.y, max_z)
    }

    /// The same mesh without unused vertices, the others numbered in the order the
    /// triangles first use them: the order in which an OBJ file is loaded back, so
    /// `Mesh::load` of `m.write_obj` gives `m.compacted()` (up to the file's six decimals).
    pub fn compacted(&self) -> Mesh {
        let mut map = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::with_capacity(self.positions.len());
        let triangles = self
            .triangles
            .iter()
            .map(|t| {
                t.map(|i| {
                    let slot = &mut map[i as usize];
                    if *slot == u32::MAX {
                        *slot = positions.len() as u32;
                        positions.push(self.positions[i as usize]);
                    }
                    *slot
                })
            })
            .collect();
        Mesh {
            positions,
            triangles,
        }
    }

    /// The same mesh moved by `offset`.
    pub fn translated(&self, offset: DVec3) -> Mesh {
        Mesh {
            positions: self.positions.iter().map(|p| *p + offset).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// The axis-aligned bounding box `(min, max)` of the vertices (infinite for no vertices).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            })
    }

    /// The enclosed volume (mm^3) by the divergence theorem: positive for a closed mesh wound
    /// outward, negative for one wound inward.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Reverses every triangle's winding.
    pub fn flip_winding(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// The largest distance from the origin to a vertex.
    pub fn max_radius(&self) -> f64 {
        self.positions
            .iter()
            .map(|p| p.length())
            .fold(0.0, f64::max)
    }

    /// The largest distance from the z axis to a vertex.
    pub fn max_axis_distance(&self) -> f64 {
        self.positions
            .iter()
            .map(|p| p.truncate().length())
            .fold(0.0, f64::max)
    }
}

/// A number with six decimals, never "-0.000000".
fn fixed6(v: f64) -> String {
    let s = format!("{v:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

/// Joins the lines of an error text into one line.
fn one_line(text: &str) -> String {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Writes `bytes` to a temporary file next to `path`, then renames it over `path`.
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| {
            GeltipError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
            )
        })?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = std::fs::write(&tmp, bytes)
        .map_err(|e| GeltipError::io(&tmp, e))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| GeltipError::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Positions and triangles of every object and group of an OBJ file (materials ignored).
fn load_obj(bytes: &[u8]) -> std::result::Result<Mesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    })
    .map_err(|e| format!("cannot parse OBJ: {e}"))?;
    let mut mesh = Mesh::default();
    for model in models {
        let m = model.mesh;
        if !m.positions.len().is_multiple_of(3) || !m.indices.len().is_multiple_of(3) {
            return Err(format!(
                "cannot parse OBJ: object '{}' is malformed",
                model.name
            ));
        }
        let base = mesh.positions.len();
        let n = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0].into(), c[1].into(), c[2].into())),
        );
        for t in m.indices.chunks_exact(3) {
            if let Some(&i) = t.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "object '{}' uses vertex index {} but has only {n} vertices",
                    model.name,
                    i as u64 + 1
                ));
            }
            mesh.triangles
                .push([t[0], t[1], t[2]].map(|i| (i as usize + base) as u32));
        }
    }
    Ok(mesh)
}

/// Positions and triangles of every triangle primitive in a glTF/GLB, node transforms applied.
fn load_gltf(bytes: &[u8], base: Option<&Path>) -> std::result::Result<Mesh, String> {
    // The gltf crate subtracts the header's size from the length a GLB declares unchecked.
    let declared = bytes
        .get(8..12)
        .map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]));
    if bytes.starts_with(b"glTF") && declared.is_some_and(|l| l < 12) {
        return Err(
            "cannot parse glTF: the GLB header declares a length shorter than itself".into(),
        );
    }
    let unchecked = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| format!("cannot parse glTF: {e}"))?;
    let root = unchecked.document.into_json();
    check_attribute_indices(&root)?;
    let doc = &gltf::Document::from_json(root).map_err(|e| format!("cannot parse glTF: {e}"))?;
    let base = base.filter(|b| !b.as_os_str().is_empty());
    let buffers = gltf::import_buffers(doc, Some(base.unwrap_or(Path::new("."))), unchecked.blob)
        .map_err(|e| format!("cannot read glTF buffers: {e}"))?;
    let mut mesh = Mesh::default();
    let mut stack: Vec<(gltf::Node, DMat4)> = Vec::new();
    let roots: Vec<gltf::Node> = match doc.default_scene() {
        Some(scene) => scene.nodes().collect(),
        None if doc.scenes().len() > 0 => doc.scenes().flat_map(|s| s.nodes()).collect(),
        None => {
            // No scenes at all: take every mesh as it is.
            for m in doc.meshes() {
                add_gltf_mesh(&mut mesh, &m, DMat4::IDENTITY, &buffers)?;
            }
            return Ok(mesh);
        }
    };
    stack.extend(roots.into_iter().map(|n| (n, DMat4::IDENTITY)));
    // The nodes form trees (the spec's rule): a node reached twice is a cycle or a shared
    // child, whose meshes would be added again and again.
    let mut visited = vec![false; doc.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(format!(
                "glTF node {} is reached twice: the node hierarchy must be a tree",
                node.index()
            ));
        }
        let local = node.transform().matrix().map(|c| c.map(f64::from));
        let world = parent * DMat4::from_cols_array_2d(&local);
        if let Some(m) = node.mesh() {
            add_gltf_mesh(&mut mesh, &m, world, &buffers)?;
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    Ok(mesh)
}

/// Refuses a primitive attribute naming an accessor that does not exist: the gltf crate's
/// validation indexes the accessors by it unchecked.
fn check_attribute_indices(root: &gltf::json::Root) -> std::result::Result<(), String> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(index) = prim.attributes.values().find(|i| i.value() >= n) {
                return Err(format!(
                    "cannot parse glTF: mesh {m} primitive {p} names accessor {} of {n}",
                    index.value()
                ));
            }
        }
    }
    Ok(())
}

/// Refuses an accessor that the gltf crate's reader would panic on or misread: of a type
/// other than `types` and `dims`, sparse, empty, or reaching past its buffer view or its
/// view past its buffer.
fn check_accessor(
    label: &str,
    role: &str,
    a: &gltf::Accessor,
    types: &[DataType],
    dims: Dimensions,
    buffers: &[gltf::buffer::Data],
) -> std::result::Result<(), String> {
    if !types.contains(&a.data_type()) || a.dimensions() != dims {
        return Err(format!(
            "{label}'s {role} are {:?} of {:?}, expected {dims:?} of {types:?}",
            a.dimensions(),
            a.data_type()
        ));
    }
    if a.sparse().is_some() {
        return Err(format!(
            "{label}'s {role} are sparse, which is not supported"
        ));
    }
    let view = a
        .view()
        .ok_or_else(|| format!("{label}'s {role} have no buffer view"))?;
    if a.count() == 0 {
        return Err(format!("{label} has no {role}"));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    let end = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(a.offset()))
        .and_then(|x| x.checked_add(size));
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |b| b.0.len());
    let view_end = view.offset().checked_add(view.length());
    if stride < size
        || end.is_none_or(|e| e > view.length())
        || view_end.is_none_or(|e| e > buffer_len)
    {
        return Err(format!(
            "{label}'s {role} ({} of {size} bytes, {stride} apart, from byte {}) do not fit their buffer view ({} bytes from byte {} of a {buffer_len}-byte buffer)",
            a.count(),
            a.offset(),
            view.length(),
            view.offset()
        ));
    }
    Ok(())
}

/// Appends the triangle primitives of one glTF mesh, transformed by `world`.
fn add_gltf_mesh(
    mesh: &mut Mesh,
    m: &gltf::Mesh,
    world: DMat4,
    buffers: &[gltf::buffer::Data],
) -> std::result::Result<(), String> {
    let flip = world.determinant() < 0.0;
    for prim in m.primitives() {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            continue;
        }
        let label = format!("mesh {} primitive {}", m.index(), prim.index());
        let positions = prim
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| format!("{label} has no readable positions"))?;
        check_accessor(
            &label,
            "positions",
            &positions,
            &[DataType::F32],
            Dimensions::Vec3,
            buffers,
        )?;
        if let Some(indices) = prim.indices() {
            let types = [DataType::U8, DataType::U16, DataType::U32];
            check_accessor(
                &label,
                "indices",
                &indices,
                &types,
                Dimensions::Scalar,
                buffers,
            )?;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<DVec3> = reader
            .read_positions()
            .ok_or_else(|| format!("{label} has no readable positions"))?
            .map(|p| world.transform_point3(DVec3::new(p[0].into(), p[1].into(), p[2].into())))
            .collect();
        let n = positions.len();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{label} has {} indices, not a multiple of 3",
                indices.len()
            ));
        }
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(format!(
                "{label} uses vertex index {i} but has only {n} vertices"
            ));
        }
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(positions);
        for t in indices.chunks_exact(3) {
            let tri = [t[0] + base, t[1] + base, t[2] + base];
            mesh.triangles
                .push(if flip { [tri[0], tri[2], tri[1]] } else { tri });
        }
    }
    Ok(())
}
