"""geltip: a simulator of the GelTip optical tactile sensor, from Python.

NumPy in and out: images are (H, W, 3) uint8 arrays, indentation (depth) maps (H, W)
float32 in mm, points (N, 3) float64 in mm, pixels (N, 2) float64 (OpenCV convention).

    import geltip
    sensor = geltip.Sensor("paper")
    sim = geltip.Simulator(sensor)
    reference = sim.reference()
    image, labels, depth = sim.render(object="sphere", at="rotation=30", depth=1.0)
    found = geltip.localise(sensor, reference, image)
    mine = geltip.calibrate("empty.png")   # a Sensor fitted to a real GelTip's frame

``geltip.mujoco`` (the ``mujoco`` extra) renders what a finger in a MuJoCo scene feels.

Errors are ``geltip.GeltipError`` subclasses carrying the command line's one-line message:
``InvalidArgumentError`` (a ``ValueError``), ``GpuError`` (a ``RuntimeError``) and
``GeltipIOError`` (an ``OSError``).
"""
from typing import Tuple

import numpy as np

from ._errors import GeltipError, GeltipIOError, GpuError, InvalidArgumentError
from ._geltip import (
    BUILD_PROFILE,
    MAX_BATCH,
    PRIMITIVE_SIZE_MM,
    REGION_CYLINDER,
    REGION_HEMISPHERE,
    REGION_NONE,
    Sensor,
    Simulator,
    __version__,
    calibrate,
    host_speed,
    keep_freed_memory,
    load_image,
    localise,
    save_image,
)
from .dataset import Dataset
from .evaluate import EvaluationReport, evaluate

#: Names of `Sensor.unproject`'s region codes, by code: 0 none, 1 hemisphere, 2 cylinder
#: (the CLI's "region" strings).
REGION_NAMES: Tuple[str, str, str] = ("none", "hemisphere", "cylinder")


def region_names(regions: "np.typing.ArrayLike") -> np.ndarray:
    """`Sensor.unproject`'s region codes as the CLI's strings ("none", "hemisphere",
    "cylinder"), same shape."""
    return np.asarray(REGION_NAMES, dtype=object)[np.asarray(regions, dtype=np.intp)]


__all__ = [
    "BUILD_PROFILE",
    "Dataset",
    "EvaluationReport",
    "GeltipError",
    "GeltipIOError",
    "GpuError",
    "InvalidArgumentError",
    "MAX_BATCH",
    "PRIMITIVE_SIZE_MM",
    "REGION_CYLINDER",
    "REGION_HEMISPHERE",
    "REGION_NAMES",
    "REGION_NONE",
    "Sensor",
    "Simulator",
    "__version__",
    "calibrate",
    "evaluate",
    "host_speed",
    "keep_freed_memory",
    "load_image",
    "localise",
    "region_names",
    "save_image",
]
