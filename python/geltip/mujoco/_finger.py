"""`Finger`: a body of a MuJoCo model bound to a GelTip sensor."""
from dataclasses import dataclass, field
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from .. import _geltip
from ._geoms import GeomObject, mujoco_module, resolve, sensor_of

Labels = Dict[str, Any]


@dataclass
class Scene:
    """What the finger feels in one state of a simulation (`Finger.scene`): the geltip
    contacts to render, one per geom that can reach the finger, and which geom each is.
    Small and detached from the `MjData`: collect them while stepping, render them
    together (`Finger.render_many`)."""

    #: geltip contact dicts: ``object``, ``pose`` (16 numbers, mm, camera frame) and
    #: ``approach`` (the direction the geom moves in to press: towards the finger's axis).
    contacts: List[Dict[str, Any]]
    #: The geom of each contact: its name and id.
    geoms: List[str]
    geom_ids: List[int]
    #: The simulation's time (s).
    time: float
    #: Every geom the finger can feel, by name: its frame's pose in the camera frame (a
    #: row-major 4x4 matrix, mm), when asked for (``Finger.scene(data, poses=True)``).
    poses: Dict[str, List[float]] = field(default_factory=dict)


class Finger:
    """``Finger(model, body="geltip", sensor="paper", geoms=None, simulator=None)``: the body
    ``body`` of ``model`` (an `MjModel`) seen as a GelTip finger of ``sensor`` (a preset's
    name, a TOML file or a `geltip.Sensor`). The body's frame is geltip's camera frame: origin
    at the camera, +z along the finger's axis towards the tip, +x and +y the image's u and v
    (``finger_mjcf`` writes such a body).

    ``geoms`` (names or ids) are what it can feel; by default every geom not on the body.
    Spheres, capsules, cylinders, boxes and ellipsoids become geltip's sized primitives;
    meshes are baked from the model's vertices once, here. Planes and height fields cannot be
    modelled: they are skipped with one warning naming them. ``simulator`` reuses a
    `geltip.Simulator` of the same sensor (one is made otherwise; ``streams`` for it)."""

    def __init__(
        self,
        model: Any,
        body: Union[str, int] = "geltip",
        sensor: Union[str, "_geltip.Sensor"] = "paper",
        geoms: Optional[Sequence[Union[str, int]]] = None,
        simulator: Optional["_geltip.Simulator"] = None,
        streams: int = 1,
    ) -> None:
        mujoco = mujoco_module()
        self.model = model
        if isinstance(body, str):
            self.body = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body))
            if self.body < 0:
                raise ValueError(f"body: no body named {body!r} in the model")
        elif isinstance(body, (int, np.integer)) and 0 <= int(body) < model.nbody:
            self.body = int(body)
        else:
            raise ValueError(f"body: {body!r} is neither a body's name nor its id")
        self.sensor = sensor_of(sensor if simulator is None else simulator.sensor)
        self.simulator = simulator or _geltip.Simulator(self.sensor, streams=streams)
        finger = self.sensor.config["finger"]
        self._radius = float(finger["radius_mm"])
        self._length = float(finger["cylinder_length_mm"])
        #: The geoms it can feel, as geltip objects.
        self.geoms: List[GeomObject] = resolve(
            model, self.body, None if geoms is None else list(geoms), self.simulator.add_mesh
        )
        self._ids = np.array([g.geom for g in self.geoms], dtype=np.intp)
        self._tops = np.array([g.top for g in self.geoms], dtype=np.float64).reshape(-1, 3)
        self._reach = np.array([g.rbound_mm for g in self.geoms]) + self._radius

    def scene(self, data: Any, poses: bool = False) -> Scene:
        """The contacts ``data`` (an `MjData` after `mj_forward` or `mj_step`) holds: each
        geom whose bounding sphere reaches the finger's capsule, in the camera frame. With
        ``poses``, every geom's pose too (for labels)."""
        body_p = np.asarray(data.xpos[self.body])
        body_r = np.asarray(data.xmat[self.body]).reshape(3, 3)
        # Camera frame, mm: R_f^T (p - p_f) and R_f^T R_g.
        p = (np.asarray(data.geom_xpos[self._ids]) - body_p) @ body_r * 1000.0
        r = np.einsum("ji,kjl->kil", body_r, np.asarray(data.geom_xmat[self._ids]).reshape(-1, 3, 3))
        # Distance to the finger's axis segment: within its radius plus the geom's bound.
        core = np.zeros_like(p)
        core[:, 2] = np.clip(p[:, 2], 0.0, self._length)
        out = p - core
        dist = np.linalg.norm(out, axis=1)
        near = np.nonzero(dist <= self._reach)[0]
        origins = p + np.einsum("kij,kj->ki", r, self._tops)
        contacts, names, ids = [], [], []
        for k in near:
            g = self.geoms[k]
            # Pressing towards the axis: its depth is measured back along the outward
            # normal of the finger's capsule nearest to the geom's centre.
            n = out[k] / dist[k] if dist[k] > 1e-9 else np.array([0.0, 0.0, 1.0])
            contacts.append(
                {"object": g.object, "pose": _matrix(r[k], origins[k]), "approach": -n}
            )
            names.append(g.name)
            ids.append(g.geom)
        scene = Scene(contacts, names, ids, float(data.time))
        if poses:
            scene.poses = {
                g.name: _matrix(r[k], p[k]).tolist() for k, g in enumerate(self.geoms)
            }
        return scene

    def render(self, data: Any) -> Tuple[np.ndarray, Labels]:
        """The tactile image of ``data``'s state, (H, W, 3) uint8, and its labels: those of
        ``geltip render --scene`` (``contacts``, each with its ``geom``, ``depth_mm``,
        ``point``, ``pose``...; ``mask_pixels``, ``mask_bbox``, ``over_pressed``). Geoms
        within reach that do not touch are left out; none touching is the empty finger.
        The depth is what the pose implies: how far the geom lies inside the undeformed
        finger, moving along its approach."""
        images, labels = self.render_many([self.scene(data)])
        return images[0], labels[0]

    def render_many(
        self, items: Iterable[Any], out: Optional[np.ndarray] = None
    ) -> Tuple[np.ndarray, List[Labels]]:
        """Many states at the renderer's batch speed: ``items`` are `Scene`s (from
        `Finger.scene`, collected while stepping) or `MjData`s. Returns (N, H, W, 3) uint8
        images (into ``out`` when given, C-contiguous of that shape) and each one's labels,
        as `render` gives them."""
        scenes = [it if isinstance(it, Scene) else self.scene(it) for it in items]
        images, labels, _ = self.simulator.render_scenes(
            [s.contacts for s in scenes], skip_untouching=True, depth_maps=False, out=out
        )
        return images, [_named(s, l) for s, l in zip(scenes, labels)]

    def reference(self) -> np.ndarray:
        """The empty finger, (H, W, 3) uint8."""
        return self.simulator.reference()

    def __repr__(self) -> str:
        return (
            f"Finger(body={self.body}, sensor='{self.sensor.name}', "
            f"geoms={[g.name for g in self.geoms]})"
        )


def _matrix(r: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """A row-major 4x4 pose: rotation ``r``, translation ``origin``."""
    m = np.zeros(16)
    m[0:3], m[4:7], m[8:11] = r[0], r[1], r[2]
    m[3], m[7], m[11], m[15] = origin[0], origin[1], origin[2], 1.0
    return m


def _named(scene: Scene, labels: Labels) -> Labels:
    """The renderer's labels with each contact's geom named (first) and the contacts left
    out (not touching) forgotten."""
    untouched = set(labels.pop("untouched", []))
    kept = [k for k in range(len(scene.contacts)) if k not in untouched]
    labels["contacts"] = [
        {"geom": scene.geoms[k], "geom_id": scene.geom_ids[k], **c}
        for k, c in zip(kept, labels["contacts"])
    ]
    return labels
