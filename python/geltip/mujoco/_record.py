"""`record`: a rollout's tactile frames, as a dataset and a video."""
import json
import os
import shutil
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Union

import numpy as np

from .. import _geltip
from ._finger import Finger, Scene
from ._geoms import TYPE_NAMES, mujoco_module

Control = Callable[[Any, Any], None]


def record(
    model: Any,
    data: Any,
    finger: Finger,
    steps: int,
    out: Union[str, "os.PathLike[str]"],
    every: int = 1,
    control: Optional[Control] = None,
    video: Optional[str] = "video.gif",
    video_scale: float = 0.5,
    fps: Optional[float] = None,
) -> Dict[str, Any]:
    """Steps the simulation ``steps`` times (``control(model, data)`` before each
    `mj_step`, to set ``data.ctrl``), renders every ``every``-th state through ``finger``
    (in batches, at the renderer's batch speed) and writes into ``out``, a new directory,
    the dataset layout ``geltip dataset`` writes: ``dataset.json``, ``reference.png``,
    ``images/<k>.png`` and ``labels.jsonl`` (one line per frame: the frame's scene labels,
    with each contact's ``geom``, plus ``step``, ``time`` and ``geoms``, every felt geom's
    pose in the camera frame, mm). ``geltip.Dataset(out)`` reads it back. ``video``: a GIF
    of the frames (``None`` for none), scaled by ``video_scale``, at ``fps`` (default: the
    simulation's own pace).

    Everything is written under a temporary name and renamed into place at the end: an
    interrupted run leaves no ``out``. The same model, state, control and sensor (without
    noise) give the same bytes. Returns ``{"frames", "contact_frames", "out"}``."""
    mujoco = mujoco_module()
    if not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps: expected a positive number of steps, got {steps!r}")
    if not isinstance(every, int) or every < 1:
        raise ValueError(f"every: expected a positive number of steps, got {every!r}")
    if video is not None and not str(video).lower().endswith(".gif"):
        raise ValueError(f"video: only GIF videos are written (a name ending .gif), got {video!r}")
    if not 0.0 < video_scale <= 1.0:
        raise ValueError(f"video_scale: expected a scale in (0, 1], got {video_scale!r}")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ValueError(f"out: {out} exists and is not an empty directory")
    tmp = out.parent / f".{out.name}.partial-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    (tmp / "images").mkdir(parents=True)
    try:
        frames = _Frames(finger, tmp, video, video_scale)
        for step in range(1, steps + 1):
            if control is not None:
                control(model, data)
            mujoco.mj_step(model, data)
            if step % every == 0:
                frames.add(step, finger.scene(data, poses=True))
        frames.flush()
        pace = fps if fps is not None else 1.0 / (every * float(model.opt.timestep))
        frames.finish(pace)
        _write_json(tmp / "dataset.json", _manifest(model, finger, steps, every, frames, video))
        if out.exists():
            out.rmdir()
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {"frames": frames.count, "contact_frames": frames.touching, "out": str(out)}


class _Frames:
    """Frames collected while stepping, rendered a submission at a time and written."""

    def __init__(self, finger: Finger, root: Path, video: Optional[str], scale: float) -> None:
        self.finger, self.root, self.scale = finger, root, scale
        self.pending: List[Any] = []
        self.count = self.touching = 0
        self.video = video
        self.video_frames: List[Any] = []
        self.labels = open(root / "labels.jsonl", "w")
        _geltip.save_image(root / "reference.png", finger.reference())

    def add(self, step: int, scene: Scene) -> None:
        self.pending.append((step, scene))
        if len(self.pending) >= self.finger.simulator.batch_frames:
            self.flush()

    def flush(self) -> None:
        if not self.pending:
            return
        images, labels = self.finger.render_many([s for _, s in self.pending])
        for (step, scene), image, label in zip(self.pending, images, labels):
            name = f"images/{self.count:06d}.png"
            _geltip.save_image(self.root / name, image)
            line = {
                "index": self.count,
                "image": name,
                "depth": None,
                "mask": None,
                "step": step,
                "time": scene.time,
                **label,
                "geoms": scene.poses,
            }
            self.labels.write(json.dumps(line) + "\n")
            self.touching += bool(label["contacts"])
            self.count += 1
            if self.video is not None:
                self.video_frames.append(_video_frame(image, self.scale))
        self.pending = []

    def finish(self, fps: float) -> None:
        self.labels.close()
        if self.video is not None and self.video_frames:
            first, rest = self.video_frames[0], self.video_frames[1:]
            first.save(
                self.root / self.video,
                save_all=True,
                append_images=rest,
                duration=max(20, round(1000.0 / fps)),
                loop=0,
                optimize=False,
            )


def _video_frame(image: np.ndarray, scale: float) -> Any:
    """One frame of the GIF: scaled, with a palette of its own (Pillow, from the mujoco
    extra)."""
    try:
        from PIL import Image  # type: ignore[import-not-found]
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            'record\'s video needs Pillow: pip install "geltip[mujoco]" (or video=None)'
        ) from e
    frame = Image.fromarray(image)
    if scale != 1.0:
        size = (max(1, round(frame.width * scale)), max(1, round(frame.height * scale)))
        frame = frame.resize(size, Image.Resampling.BOX)
    # Fast octree: 0.5 ms a half-size frame where median cut takes 35 (both deterministic).
    return frame.quantize(colors=256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)


def _manifest(
    model: Any, finger: Finger, steps: int, every: int, frames: _Frames, video: Optional[str]
) -> Dict[str, Any]:
    """``dataset.json``: what was recorded and how (no clock, no paths: a rerun is
    byte-identical)."""
    return {
        "geltip": _geltip.__version__,
        "source": "geltip.mujoco.record",
        "sensor": finger.sensor.name,
        "config": finger.sensor.config,
        "count": frames.count,
        "contact_frames": frames.touching,
        "steps": steps,
        "every": every,
        "timestep": float(model.opt.timestep),
        "finger_body": model.body(finger.body).name,
        "geoms": [
            {
                "geom": g.name,
                "type": TYPE_NAMES.get(int(model.geom_type[g.geom]), "?"),
                "object": g.object,
                "top_mm": list(g.top),
            }
            for g in finger.geoms
        ],
        "video": video,
    }


def _write_json(path: Path, value: Dict[str, Any]) -> None:
    path.write_text(json.dumps(value, indent=2) + "\n")
