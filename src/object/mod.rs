//! Objects pressed into the finger: the seven built-in solids and loaded meshes.
//!
//! Object frame (the renderer relies on it): the object's contact top is at the origin, its
//! body lies in `z <= 0` (it extends along -z) and the finger comes from +z. A signed
//! distance function is negative inside the object, positive outside, in millimetres.
//!
//! - [`solids`]: the paper's seven test solids with exact analytic SDFs (mirrored in
//!   `shaders/shared/object.wgsl` as `solid_sdf(id, p)`) and their meshes.
//! - [`primitive`]: spheres, capsules, cylinders, boxes and ellipsoids of any size, with
//!   exact analytic SDFs (mirrored as `primitive_sdf(kind, size, p)`), named by text such as
//!   `box:x=10,y=6,z=4`.
//! - [`mesh`]: triangle meshes, loading `.obj`/`.gltf`/`.glb`, writing `.obj`, placing a
//!   user mesh in the object frame.
//! - [`sdf_grid`]: SDFs baked from meshes onto voxel grids (index layout documented there).

pub mod mesh;
pub mod primitive;
pub mod sdf_grid;
pub mod solids;
#[cfg(test)]
mod test_rng;

pub use mesh::Mesh;
pub use primitive::Primitive;
pub use sdf_grid::SdfGrid;
pub use solids::{dims, Solid};

use crate::error::{quoted, GeltipError, Result};
use glam::DVec3;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Voxel size (mm) at which [`Object::from_arg`] bakes loaded meshes.
pub const MESH_VOXEL_MM: f64 = 0.25;

/// Exact distances (mm) [`Object::from_arg`] bakes around a loaded mesh: the renderer traces
/// the object grown by the skin's drape radius, down to the press depth, so distances must be
/// exact that far out (see [`Object::exact_reach_mm`]): a gel's thickness, 0.5 mm and its
/// drape, 7.5 mm for the `allsight` preset's 3.5 mm gel.
pub const MESH_PAD_MM: f64 = 8.0;

/// Something to press into the finger.
#[derive(Debug, Clone)]
pub enum Object {
    /// A built-in solid with an analytic SDF.
    Solid(Solid),
    /// A sized primitive with an analytic SDF; `name` is its text ([`Primitive`]'s
    /// `Display`).
    Primitive { name: String, shape: Primitive },
    /// A loaded mesh, placed in the object frame, with its baked SDF.
    Mesh {
        name: String,
        mesh: Mesh,
        grid: SdfGrid,
    },
}

impl Object {
    /// A built-in solid's name ([`Solid::name`]), a primitive's text
    /// ([`primitive::PRIMITIVE_SYNTAX`], e.g. `box:x=10,y=6,z=4`) or a path to an `.obj`,
    /// `.gltf` or `.glb` file, which is loaded, placed with its +z towards the finger
    /// ([`Mesh::placed_for_contact`]) and baked at [`MESH_VOXEL_MM`].
    pub fn from_arg(arg: &str) -> Result<Object> {
        if let Some(s) = Solid::from_name(arg) {
            return Ok(Object::Solid(s));
        }
        if let Some(p) = Primitive::parse(arg)? {
            return Ok(Object::primitive(p));
        }
        let path = Path::new(arg);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let is_mesh_file = matches!(ext.as_deref(), Some("obj" | "gltf" | "glb"));
        if !is_mesh_file && !path.exists() {
            let names: Vec<&str> = Solid::ALL.iter().map(|s| s.name()).collect();
            return Err(GeltipError::input(
                format!("object '{arg}'"),
                format!(
                    "not a built-in solid ({}), a primitive ({}) nor a .obj, .gltf or .glb file",
                    names.join(", "),
                    primitive::PRIMITIVE_SYNTAX
                ),
            ));
        }
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| arg.to_string());
        let (object, _) =
            placed_mesh(name, Mesh::load(path)?).map_err(|reason| GeltipError::InvalidMesh {
                path: path.to_path_buf(),
                reason,
            })?;
        Ok(object)
    }

    /// A sized primitive, named by its text.
    pub fn primitive(shape: Primitive) -> Object {
        Object::Primitive {
            name: shape.to_string(),
            shape,
        }
    }

    /// A mesh given as vertices and triangles (mm; e.g. a physics engine's), checked
    /// ([`Mesh::validate`]), placed and baked exactly as a loaded file is: the same vertices
    /// from an OBJ file give the same object. Returns it and the point of `mesh` that became
    /// its origin (its top, [`Mesh::top`]): the object frame is `mesh`'s frame moved there.
    /// `name` may not be a built-in solid's or a primitive's, which it would hide.
    pub fn from_mesh(name: &str, mesh: Mesh) -> Result<(Object, DVec3)> {
        let bad = |reason: String| GeltipError::input(format!("mesh {}", quoted(name)), reason);
        if name.is_empty() {
            return Err(bad("a mesh needs a name".into()));
        }
        if Solid::from_name(name).is_some() || !matches!(Primitive::parse(name), Ok(None)) {
            return Err(bad(
                "is a built-in solid's or a primitive's name; give the mesh another".into(),
            ));
        }
        placed_mesh(name.to_string(), mesh).map_err(bad)
    }

    /// The built-in solid's name, the primitive's text, or the mesh's name (a file's stem).
    pub fn name(&self) -> &str {
        match self {
            Object::Solid(s) => s.name(),
            Object::Primitive { name, .. } | Object::Mesh { name, .. } => name,
        }
    }

    /// The built-in solid, if this is one.
    pub fn solid(&self) -> Option<Solid> {
        match self {
            Object::Solid(s) => Some(*s),
            Object::Primitive { .. } | Object::Mesh { .. } => None,
        }
    }

    /// Signed distance (mm, negative inside) from `p` in the object frame.
    pub fn sdf(&self, p: DVec3) -> f64 {
        match self {
            Object::Solid(s) => s.sdf(p),
            Object::Primitive { shape, .. } => shape.sdf(p),
            Object::Mesh { grid, .. } => grid.sample(p),
        }
    }

    /// The largest distance from the origin (the contact top) to any point of the object.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Object::Solid(s) => s.bounding_radius(),
            Object::Primitive { shape, .. } => shape.bounding_radius(),
            Object::Mesh { mesh, .. } => mesh.max_radius(),
        }
    }

    /// The largest distance from the z axis to any point of the object.
    pub fn footprint_radius(&self) -> f64 {
        match self {
            Object::Solid(s) => s.footprint_radius(),
            Object::Primitive { shape, .. } => shape.footprint_radius(),
            Object::Mesh { mesh, .. } => mesh.max_axis_distance(),
        }
    }

    /// How far (mm) from the object its SDF is exact: unlimited for the analytic solids; for
    /// a baked mesh, the margin between the mesh's bounds and the grid's box (beyond it the
    /// grid gives only a lower bound, which would make a grown object look closer than it is).
    pub fn exact_reach_mm(&self) -> f64 {
        match self {
            Object::Solid(_) | Object::Primitive { .. } => f64::INFINITY,
            Object::Mesh { mesh, grid, .. } => {
                let (lo, hi) = mesh.bounds();
                (lo - grid.origin).min(grid.max_corner() - hi).min_element()
            }
        }
    }
}

/// Objects by the name they were asked for ([`Object::from_arg`]'s argument): a mesh named
/// by several contacts is loaded and baked once, and they share it (the renderer keeps one
/// GPU grid per object).
#[derive(Debug, Default)]
pub struct ObjectCache {
    loaded: HashMap<String, Arc<Object>>,
}

impl ObjectCache {
    /// The object `arg` names, loaded on first use.
    pub fn get(&mut self, arg: &str) -> Result<Arc<Object>> {
        if let Some(o) = self.loaded.get(arg) {
            return Ok(o.clone());
        }
        let o = Arc::new(Object::from_arg(arg)?);
        self.loaded.insert(arg.to_string(), o.clone());
        Ok(o)
    }

    /// Makes `object` what `name` names from now on (an object made in memory, such as
    /// [`Object::from_mesh`]'s), in place of anything it named before.
    pub fn insert(&mut self, name: &str, object: Object) -> Arc<Object> {
        let o = Arc::new(object);
        self.loaded.insert(name.to_string(), o.clone());
        o
    }
}

/// A mesh placed in the object frame ([`Mesh::placed_for_contact`]) and baked at
/// [`MESH_VOXEL_MM`] with [`MESH_PAD_MM`] around it: the one path of files and meshes made
/// in memory. Returns the object and the point of `mesh` that became its origin; errors are
/// the reason alone, for the caller to say which mesh.
fn placed_mesh(name: String, mesh: Mesh) -> std::result::Result<(Object, DVec3), String> {
    mesh.validate()?;
    let top = mesh.top();
    let mesh = mesh.translated(-top);
    let grid = SdfGrid::bake_padded(&mesh, MESH_VOXEL_MM, MESH_PAD_MM).map_err(|e| match e {
        GeltipError::InvalidInput { reason, .. } => reason,
        other => other.to_string(),
    })?;
    Ok((Object::Mesh { name, mesh, grid }, top))
}

/// Writes `<name>.obj` ([`Solid::mesh`], [`Mesh::write_obj`]) for all seven solids into
/// `dir`, creating it if needed. `assets/objects/` holds exactly this output.
pub fn write_builtin_objects(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| GeltipError::io(dir, e))?;
    for s in Solid::ALL {
        s.mesh().write_obj(dir.join(format!("{}.obj", s.name())))?;
    }
    Ok(())
}
