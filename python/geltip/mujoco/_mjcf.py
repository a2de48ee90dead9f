"""The finger's collision body as MJCF."""
from typing import Optional, Sequence, Union

from .. import _geltip
from ._geoms import sensor_of


def finger_mjcf(
    sensor: Union[str, "_geltip.Sensor"] = "paper",
    name: str = "geltip",
    pos: Sequence[float] = (0.0, 0.0, 0.0),
    quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
    rgba: Sequence[float] = (0.85, 0.85, 0.8, 1.0),
    solref: Optional[Sequence[float]] = None,
    solimp: Optional[Sequence[float]] = None,
) -> str:
    """A ``<body>`` to put inside a gripper's body: the finger's collision shape (a
    cylinder of the sensor's radius from the camera up to the hemisphere's centre, and the
    hemisphere as a sphere there) and a site at the camera. The body's frame is geltip's
    camera frame: ``Finger(model, body=name)`` binds it.

    ``pos`` (metres) and ``quat`` (w x y z) place it in its parent. ``solref`` and
    ``solimp``, when given, go on its geoms: how far the physics lets an object into the
    finger is the depth the sensor images, so they set how soft the gel feels (MuJoCo's
    defaults let a 20 g object about 1 mm in under a newton, less for heavier ones). Geoms
    are named ``<name>_tube`` and ``<name>_tip``, the site ``<name>_camera``."""
    sensor = sensor_of(sensor)
    finger = sensor.config["finger"]
    r = float(finger["radius_mm"]) / 1000.0
    d = float(finger["cylinder_length_mm"]) / 1000.0

    def nums(values: Sequence[float]) -> str:
        return " ".join(repr(float(v)) for v in values)

    attrs = f'rgba="{nums(rgba)}"'
    if solref is not None:
        attrs += f' solref="{nums(solref)}"'
    if solimp is not None:
        attrs += f' solimp="{nums(solimp)}"'
    return (
        f'<body name="{name}" pos="{nums(pos)}" quat="{nums(quat)}">'
        f'<geom name="{name}_tube" type="cylinder" pos="0 0 {d / 2!r}" '
        f'size="{r!r} {d / 2!r}" {attrs}/>'
        f'<geom name="{name}_tip" type="sphere" pos="0 0 {d!r}" size="{r!r}" {attrs}/>'
        f'<site name="{name}_camera" pos="0 0 0" size="{r / 5!r}"/>'
        "</body>"
    )
