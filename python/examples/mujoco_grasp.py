"""A two-finger gripper with one GelTip finger grasping a ball, a can and a prism (a mesh
from assets/objects/) in MuJoCo, one after the other: the tactile video and its labels.

    pip install "geltip[mujoco]"
    python python/examples/mujoco_grasp.py out/grasp              # the whole rollout
    python python/examples/mujoco_grasp.py out/grasp --steps 400  # the first grasp only

Writes out/grasp/: images/<k>.png, labels.jsonl (each contact's geom, depth, point...),
reference.png, dataset.json and video.gif; --strip FILE also writes a row of frames.
"""
import argparse
import time
from pathlib import Path

import numpy as np

import geltip
from geltip.mujoco import Finger, finger_mjcf, record

try:
    import mujoco
except ImportError:  # pragma: no cover
    raise SystemExit('this example needs MuJoCo: pip install "geltip[mujoco]"')

REPO = Path(__file__).resolve().parents[2]
PRISM = REPO / "assets" / "objects" / "irregular-prism.obj"
# Where the objects stand (x, m) on 30 mm pedestals, and the height (m) of the finger's
# camera at each grasp: the contact lands on the finger's side.
OBJECTS = {"ball": 0.0, "can": 0.07, "prism": 0.14}
GRASP_Z = {"ball": 0.049, "can": 0.064, "prism": 0.052}
# Seconds of each grasp: move over, lower, close, lift, hold, lower, open, raise.
PHASES = [0.15, 0.15, 0.25, 0.15, 0.1, 0.1, 0.15, 0.1]


def model_xml() -> str:
    # The GelTip points down (its +z to world -z) with its image's +x (u) towards the other
    # finger: contacts land on its side, in the right half of the image.
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]], float).reshape(-1))
    geltip_body = finger_mjcf("paper", name="geltip", pos=(0, 0, 0), quat=quat)
    pedestals = "".join(
        f'<geom name="pedestal_{name}" type="cylinder" size="0.008 0.015" pos="{x} 0 0.015"/>'
        for name, x in OBJECTS.items()
    )
    return f"""<mujoco model="geltip grasp">
  <option timestep="0.002"/>
  <asset>
    <mesh name="prism" file="{PRISM}" scale="0.0025 0.0025 0.0025"/>
  </asset>
  <default><geom friction="1 0.01 0.001"/></default>
  <worldbody>
    <light pos="0 0 1"/>
    <geom name="floor" type="plane" size="0.5 0.5 0.01" rgba="0.4 0.45 0.5 1"/>
    <body name="hand" pos="0 0 0.09" gravcomp="1">
      <joint name="x" type="slide" axis="1 0 0" damping="40"/>
      <joint name="z" type="slide" axis="0 0 1" damping="40"/>
      <geom type="box" size="0.01 0.04 0.005" pos="0 0 0.005" mass="0.3" contype="0" conaffinity="0"/>
      <body name="left" pos="0 -0.03 0" gravcomp="1">
        <joint name="left" type="slide" axis="0 1 0" damping="5"/>
        {geltip_body}
      </body>
      <body name="right" pos="0 0.03 0" gravcomp="1">
        <joint name="right" type="slide" axis="0 1 0" damping="5"/>
        <geom name="pad" type="box" size="0.006 0.003 0.014" pos="0 0 -0.014" mass="0.02"/>
      </body>
    </body>
    {pedestals}
    <body name="ball" pos="{OBJECTS['ball']} 0 0.042">
      <freejoint/><geom name="ball" type="sphere" size="0.012" mass="0.06" rgba="0.8 0.3 0.2 1"/>
    </body>
    <body name="can" pos="{OBJECTS['can']} 0 0.05">
      <freejoint/><geom name="can" type="cylinder" size="0.01 0.02" mass="0.03" rgba="0.2 0.5 0.8 1"/>
    </body>
    <body name="prism" pos="{OBJECTS['prism']} 0 0.045">
      <freejoint/><geom name="prism" type="mesh" mesh="prism" mass="0.04" rgba="0.3 0.7 0.3 1"/>
    </body>
  </worldbody>
  <actuator>
    <position name="x" joint="x" kp="3000"/>
    <position name="z" joint="z" kp="3000"/>
    <position name="left" joint="left" kp="400" forcerange="-1 1"/>
    <position name="right" joint="right" kp="400" forcerange="-1 1"/>
  </actuator>
</mujoco>"""


def smooth(a: float, b: float, u: float) -> float:
    u = min(max(u, 0.0), 1.0)
    return a + (b - a) * u * u * (3.0 - 2.0 * u)


def control(model, data) -> None:
    """The grasps, one per object, as targets of the position actuators (the hand starts at
    z = 0.09 m; x, z are offsets from there)."""
    period = sum(PHASES)
    k = min(int(data.time // period), len(OBJECTS) - 1)
    name = list(OBJECTS)[k]
    t = data.time - k * period
    ends = np.cumsum(PHASES)
    x_prev = list(OBJECTS.values())[max(k - 1, 0)]
    high, low = 0.0, GRASP_Z[name] - 0.09
    # Fingers: open at +-0.03 m from the centre; closed pushes past the object's width.
    close = {"ball": 0.02, "can": 0.02, "prism": 0.02}[name]
    x = smooth(x_prev, OBJECTS[name], t / ends[0])
    z = high
    z = smooth(high, low, (t - ends[0]) / PHASES[1]) if t > ends[0] else z
    z = smooth(low, low + 0.01, (t - ends[2]) / PHASES[3]) if t > ends[2] else z
    z = smooth(low + 0.01, low, (t - ends[4]) / PHASES[5]) if t > ends[4] else z
    z = smooth(low, high, (t - ends[6]) / PHASES[7]) if t > ends[6] else z
    grip = smooth(0.0, close, (t - ends[1]) / PHASES[2]) if t > ends[1] else 0.0
    grip = smooth(close, 0.0, (t - ends[5]) / PHASES[6]) if t > ends[5] else grip
    data.ctrl[:] = [x, z, grip, -grip]


def strip(out: Path, path: Path) -> None:
    """A row of frames, half size: two of each object's grasp (a third and two thirds of
    the way through the frames that feel it)."""
    ds = geltip.Dataset(out)
    picks = []
    for name in OBJECTS:
        felt = [i for i, line in enumerate(ds.labels) if any(c["geom"] == name for c in line["contacts"])]
        picks += [felt[len(felt) // 3], felt[2 * len(felt) // 3]] if felt else []
    if picks:
        frames = [ds[i]["image"][::2, ::2] for i in picks]
        geltip.save_image(path, np.concatenate(frames, axis=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path, help="a new directory")
    ap.add_argument("--steps", type=int, default=round(3 * sum(PHASES) / 0.002))
    ap.add_argument("--every", type=int, default=10, help="render every k-th step")
    ap.add_argument("--sensor", default="paper")
    ap.add_argument("--strip", type=Path, help="also write a row of frames (PNG)")
    args = ap.parse_args()

    model = mujoco.MjModel.from_xml_string(model_xml())
    data = mujoco.MjData(model)
    finger = Finger(model, body="geltip", sensor=args.sensor, geoms=list(OBJECTS))
    start = time.perf_counter()
    summary = record(model, data, finger, args.steps, args.out, every=args.every, control=control)
    seconds = time.perf_counter() - start
    labels = [line for line in geltip.Dataset(args.out).labels]
    deepest = max((c["depth_mm"] for line in labels for c in line["contacts"]), default=0.0)
    felt = sorted({c["geom"] for line in labels for c in line["contacts"]})
    print(
        f"{summary['frames']} frames ({summary['contact_frames']} with contacts: {', '.join(felt)};"
        f" deepest {deepest:.2f} mm) in {seconds:.1f} s -> {args.out}"
    )
    if args.strip:
        strip(args.out, args.strip)


if __name__ == "__main__":
    main()
