//! Objects pressed into the finger: the seven built-in solids and loaded meshes.
//!
//! Object frame (the renderer relies on it): the object's contact top is at the origin, its
//! body lies in `z <= 0` (it extends along -z) and the finger comes from +z. A signed
//! distance function is negative inside the object, positive outside, in millimetres.
//!
//! - [`solids`]: the paper's seven test solids with exact analytic SDFs (mirrored in
//!   `shaders/shared/object.wgsl` as `solid_sdf(id, p)`) and their meshes.
//! - [`mesh`]: triangle meshes, loading `.obj`/`.gltf`/`.glb`, writing `.obj`, placing a
//!   user mesh in the object frame.
//! - [`sdf_grid`]: SDFs baked from meshes onto voxel grids (index layout documented there).

pub mod mesh;
pub mod sdf_grid;
pub mod solids;

pub use mesh::Mesh;
pub use sdf_grid::SdfGrid;
pub use solids::{dims, Solid};

use crate::error::{GeltipError, Result};
use glam::DVec3;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Voxel size (mm) at which [`Object::from_arg`] bakes loaded meshes.
pub const MESH_VOXEL_MM: f64 = 0.25;

/// Exact distances (mm) [`Object::from_arg`] bakes around a loaded mesh: the renderer traces
/// the object grown by the skin's drape radius, down to the press depth, so distances must be
/// exact that far out (see [`Object::exact_reach_mm`]).
pub const MESH_PAD_MM: f64 = 5.0;

/// Something to press into the finger.
#[derive(Debug, Clone)]
pub enum Object {
    /// A built-in solid with an analytic SDF.
    Solid(Solid),
    /// A loaded mesh, placed in the object frame, with its baked SDF.
    Mesh {
        name: String,
        mesh: Mesh,
        grid: SdfGrid,
    },
}

impl Object {
    /// A built-in solid's name ([`Solid::name`]) or a path to an `.obj`, `.gltf` or `.glb`
    /// file, which is loaded, placed with its +z towards the finger
    /// ([`Mesh::placed_for_contact`]) and baked at [`MESH_VOXEL_MM`].
    pub fn from_arg(arg: &str) -> Result<Object> {
        if let Some(s) = Solid::from_name(arg) {
            return Ok(Object::Solid(s));
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
                    "not a built-in solid ({}) nor a .obj, .gltf or .glb file",
                    names.join(", ")
                ),
            ));
        }
        let mesh = Mesh::load(path)?.placed_for_contact();
        let grid = SdfGrid::bake_padded(&mesh, MESH_VOXEL_MM, MESH_PAD_MM).map_err(|e| {
            GeltipError::InvalidMesh {
                path: path.to_path_buf(),
                reason: match e {
                    GeltipError::InvalidInput { reason, .. } => reason,
                    other => other.to_string(),
                },
            }
        })?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| arg.to_string());
        Ok(Object::Mesh { name, mesh, grid })
    }

    /// The built-in solid's name, or the mesh file's stem.
    pub fn name(&self) -> &str {
        match self {
            Object::Solid(s) => s.name(),
            Object::Mesh { name, .. } => name,
        }
    }

    /// The built-in solid, if this is one.
    pub fn solid(&self) -> Option<Solid> {
        match self {
            Object::Solid(s) => Some(*s),
            Object::Mesh { .. } => None,
        }
    }

    /// Signed distance (mm, negative inside) from `p` in the object frame.
    pub fn sdf(&self, p: DVec3) -> f64 {
        match self {
            Object::Solid(s) => s.sdf(p),
            Object::Mesh { grid, .. } => grid.sample(p),
        }
    }

    /// The largest distance from the origin (the contact top) to any point of the object.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Object::Solid(s) => s.bounding_radius(),
            Object::Mesh { mesh, .. } => mesh.max_radius(),
        }
    }

    /// The largest distance from the z axis to any point of the object.
    pub fn footprint_radius(&self) -> f64 {
        match self {
            Object::Solid(s) => s.footprint_radius(),
            Object::Mesh { mesh, .. } => mesh.max_axis_distance(),
        }
    }

    /// How far (mm) from the object its SDF is exact: unlimited for the analytic solids; for
    /// a baked mesh, the margin between the mesh's bounds and the grid's box (beyond it the
    /// grid gives only a lower bound, which would make a grown object look closer than it is).
    pub fn exact_reach_mm(&self) -> f64 {
        match self {
            Object::Solid(_) => f64::INFINITY,
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
