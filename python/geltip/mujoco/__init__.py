"""`geltip.mujoco`: tactile frames from a MuJoCo scene.

A GelTip finger is a body of a MuJoCo model whose frame is geltip's camera frame (origin at
the camera, +z along the finger towards its tip, +x and +y the image's u and v). Every step,
each geom that can reach it becomes a geltip object held in the pose the physics put it in,
and one frame is rendered with all of them; labels name each contact's geom.

    import mujoco, geltip
    from geltip.mujoco import Finger, finger_mjcf, record

    xml = f'''<mujoco><worldbody>
      <body name="hand">{finger_mjcf("paper")}</body>
      <body name="ball" pos="0.012 0 0.015"><freejoint/><geom size="0.005"/></body>
    </worldbody></mujoco>'''
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    finger = Finger(model, body="geltip", sensor="paper")
    mujoco.mj_forward(model, data)
    image, labels = finger.render(data)      # (H, W, 3) uint8, {"contacts": [...], ...}

MuJoCo's metres come in, geltip's millimetres go out. Needs MuJoCo's own package:
``pip install "geltip[mujoco]"`` (MuJoCo and Pillow, for the video). Details:
docs/mujoco.md.
"""
from ._finger import Finger, Scene
from ._mjcf import finger_mjcf
from ._record import record

__all__ = ["Finger", "Scene", "finger_mjcf", "record"]
