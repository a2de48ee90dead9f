"""MuJoCo geoms as geltip objects: primitives by their sizes, meshes by their vertices."""
import warnings
from dataclasses import dataclass
from typing import Any, List, Optional, Tuple, Union

import numpy as np

from .. import _geltip

# mjtGeom's values (MuJoCo's enum, fixed by its file format).
PLANE, HFIELD, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH, SDF = range(9)
TYPE_NAMES = {
    PLANE: "plane",
    HFIELD: "height field",
    SPHERE: "sphere",
    CAPSULE: "capsule",
    ELLIPSOID: "ellipsoid",
    CYLINDER: "cylinder",
    BOX: "box",
    MESH: "mesh",
    SDF: "sdf",
}


def mujoco_module() -> Any:
    """MuJoCo's Python package, imported on first use."""
    try:
        import mujoco  # type: ignore[import-not-found]
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "geltip.mujoco needs MuJoCo's Python package: "
            'pip install "geltip[mujoco]" (or pip install mujoco)'
        ) from e
    return mujoco


def sensor_of(sensor: Union[str, "_geltip.Sensor", Any]) -> "_geltip.Sensor":
    """A `geltip.Sensor`, or a preset's name or a TOML file's path as one."""
    if isinstance(sensor, _geltip.Sensor):
        return sensor
    return _geltip.Sensor(sensor)


@dataclass(frozen=True)
class GeomObject:
    """A geom the finger can feel: the geltip object it is, and where that object's origin
    (its top, towards +z) lies in the geom's frame."""

    geom: int
    name: str
    #: geltip's object name: a primitive's text ("box:x=10,y=6,z=4") or a mesh's name.
    object: str
    #: The object's origin in the geom frame, mm.
    top: Tuple[float, float, float]
    #: MuJoCo's bounding-sphere radius about the geom frame's origin, mm.
    rbound_mm: float


def geom_name(model: Any, g: int) -> str:
    """The geom's name, or ``geom<id>`` for an unnamed one."""
    return model.geom(g).name or f"geom{g}"


def _size(mm: float) -> Tuple[str, float]:
    """A size in mm as the primitive's text writes it (12 significant digits) and the number
    that text is, so that the placement uses what geltip will parse."""
    text = format(mm, ".12g")
    return text, float(text)


def primitive(kind: int, size_m: np.ndarray) -> Tuple[str, Tuple[float, float, float]]:
    """A MuJoCo primitive (half-sizes in metres) as geltip's text and its top's place on the
    geom's z axis (mm): geltip's primitives have their top at the origin and their centre
    that far below it, where MuJoCo's geom frame is centred."""
    half = [float(v) * 1000.0 for v in size_m]
    if kind == SPHERE:
        r, rv = _size(half[0])
        return f"sphere:r={r}", (0.0, 0.0, rv)
    if kind in (CAPSULE, CYLINDER):
        (r, rv), (length, lv) = _size(half[0]), _size(2.0 * half[1])
        top = lv / 2.0 + (rv if kind == CAPSULE else 0.0)
        name = "capsule" if kind == CAPSULE else "cylinder"
        return f"{name}:r={r},l={length}", (0.0, 0.0, top)
    x, y, z = (_size(2.0 * h) for h in half)
    name = "box" if kind == BOX else "ellipsoid"
    return f"{name}:x={x[0]},y={y[0]},z={z[0]}", (0.0, 0.0, z[1] / 2.0)


def mesh_arrays(model: Any, mesh: int) -> Tuple[np.ndarray, np.ndarray]:
    """A mesh's vertices (float32 mm, the precision an OBJ file loads at: the same vertices
    written to a file load as these) and faces, in its geom's frame (MuJoCo re-centres
    meshes on their inertial frame)."""
    a, n = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    f, m = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
    vertices = np.asarray(model.mesh_vert[a : a + n], dtype=np.float32) * np.float32(1000.0)
    return vertices, np.asarray(model.mesh_face[f : f + m], dtype=np.int64)


def mesh_object_name(model: Any, mesh: int) -> str:
    """The geltip name of a MuJoCo mesh: ``mesh:<name>`` (never a built-in's or a
    primitive's name)."""
    return f"mesh:{model.mesh(mesh).name or mesh}"


def resolve(
    model: Any,
    body: int,
    geoms: Optional[List[Union[int, str]]],
    add_mesh: Any,
) -> List[GeomObject]:
    """The geoms the finger can feel, as objects: ``geoms`` (names or ids), or every geom
    not on the finger's body. Geoms geltip cannot model are skipped with one warning naming
    them; meshes are baked through ``add_mesh(name, vertices, faces) -> top`` once each."""
    mujoco = mujoco_module()
    if geoms is None:
        ids = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) != body]
    else:
        ids = []
        for g in geoms:
            if isinstance(g, str):
                i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g)
                if i < 0:
                    raise ValueError(f"geoms: no geom named {g!r} in the model")
                ids.append(int(i))
            elif isinstance(g, (int, np.integer)) and 0 <= int(g) < model.ngeom:
                ids.append(int(g))
            else:
                raise ValueError(f"geoms: {g!r} is neither a geom's name nor its id")
    objects, skipped, tops = [], [], {}
    for g in ids:
        kind = int(model.geom_type[g])
        name = geom_name(model, g)
        if kind in (SPHERE, CAPSULE, CYLINDER, BOX, ELLIPSOID):
            text, top = primitive(kind, model.geom_size[g])
            low, high = _geltip.PRIMITIVE_SIZE_MM
            sizes = [float(v.split("=")[1]) for v in text.split(":")[1].split(",")]
            if not all(low <= v <= high for v in sizes):
                why = f"sizes from {low:g} to {high:g} mm"
                skipped.append(f"'{name}' ({TYPE_NAMES[kind]} {text}: {why})")
                continue
        elif kind == MESH:
            mesh = int(model.geom_dataid[g])
            text = mesh_object_name(model, mesh)
            if text not in tops:
                vertices, faces = mesh_arrays(model, mesh)
                tops[text] = tuple(float(v) for v in add_mesh(text, vertices, faces))
            top = tops[text]
        else:
            skipped.append(f"'{name}' ({TYPE_NAMES.get(kind, f'type {kind}')})")
            continue
        rbound = float(model.geom_rbound[g]) * 1000.0
        objects.append(GeomObject(g, name, text, top, rbound))
    if skipped:
        warnings.warn(
            "geltip.mujoco: skipping geoms geltip cannot model: " + ", ".join(skipped),
            stacklevel=3,
        )
    return objects
