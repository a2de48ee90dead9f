"""Tactile frames/s with MuJoCo stepping in the same process, and the adapter's own cost.

    maturin develop --release -m python/Cargo.toml   # or: pip install "./python[mujoco]"
    python python/bench/mujoco_grasp.py [--frames 400] [--repeat 3] [--every 5] [--streams 1]

Two grasps, each a GelTip finger and a pad squeezing objects with a grip that swells and
eases (so contacts slide, deepen and lift off): one ball (one contact), and two balls one
above the other (two contacts on the finger's side). MuJoCo steps `--every` steps (2 ms
each) per tactile frame. Two paths:

- batched: `Finger.scene(data)` after each frame's steps, `Finger.render_many` on every
  `Simulator.batch_frames` scenes into a reused array (what `geltip.mujoco.record` does);
- single: `Finger.render(data)` every frame.

Columns: frames/s over the whole loop (stepping, scenes, rendering, labels), and per frame
the renderer's share (`Simulator.render_scenes`, the PyO3 call included), the adapter's own
(`Finger.scene`, and naming the labels' geoms) and MuJoCo's (`mj_step`). The median of
`--repeat` runs; the host's speed (`geltip.host_speed()`) is printed before and after.
"""
import argparse
import statistics
import time

import numpy as np

import geltip
from geltip.mujoco import Finger, finger_mjcf

try:
    import mujoco
except ImportError:  # pragma: no cover
    raise SystemExit('this benchmark needs MuJoCo: pip install "geltip[mujoco]"')

BALLS = {
    "one contact": [("ball", 0.010, 0.006)],
    "two contacts": [("low", 0.009, 0.005), ("high", 0.019, 0.004)],
}


def model(balls):
    """The finger (camera at the origin, pointing up) and a pad either side of the balls,
    each ball on a slide towards the finger at camera-frame height z (m), radius r."""
    bodies = "".join(
        f'<body name="{n}" pos="{0.0075 + r + 0.0005} 0 {z}"><joint name="{n}" type="slide" '
        f'axis="1 0 0" damping="1"/><geom name="{n}" size="{r}" mass="0.02"/></body>'
        for n, z, r in balls
    )
    return mujoco.MjModel.from_xml_string(
        f"""<mujoco><option timestep="0.002" gravity="0 0 0"/><worldbody>
        {finger_mjcf("paper")}{bodies}</worldbody><actuator>
        {"".join(f'<motor joint="{n}"/>' for n, _, _ in balls)}</actuator></mujoco>"""
    )


def grip(data):
    """Each ball pushed towards the finger by a force that swells from 0 to 1.2 N and back
    every 0.4 s."""
    data.ctrl[:] = -0.6 * (1.0 - np.cos(2 * np.pi * data.time / 0.4))


class Timed:
    """`Simulator.render_scenes` with its time counted."""

    def __init__(self, sim):
        self.sim, self.seconds = sim, 0.0

    def __getattr__(self, name):
        return getattr(self.sim, name)

    def render_scenes(self, *args, **kwargs):
        start = time.perf_counter()
        try:
            return self.sim.render_scenes(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - start


def run(sim, balls, frames, every, batched):
    m = model(balls)
    d = mujoco.MjData(m)
    finger = Finger(m, body="geltip", simulator=sim)
    timed = Timed(sim)
    finger.simulator = timed
    out = np.empty((sim.batch_frames, *sim.sensor.image_shape), np.uint8)
    t_step = t_scene = t_render_many = 0.0
    pending, contacts = [], 0
    start = time.perf_counter()
    for _ in range(frames):
        a = time.perf_counter()
        for _ in range(every):
            grip(d)
            mujoco.mj_step(m, d)
        b = time.perf_counter()
        if batched:
            pending.append(finger.scene(d))
            c = time.perf_counter()
            if len(pending) == sim.batch_frames:
                _, labels = finger.render_many(pending, out=out)
                contacts += sum(len(l["contacts"]) for l in labels)
                pending = []
            t_scene += c - b
            t_render_many += time.perf_counter() - c
        else:
            _, labels = finger.render(d)
            contacts += len(labels["contacts"])
            t_render_many += time.perf_counter() - b
        t_step += b - a
    if pending:
        c = time.perf_counter()
        finger.render_many(pending, out=out[: len(pending)])
        t_render_many += time.perf_counter() - c
    total = time.perf_counter() - start
    render = timed.seconds
    # Single frames build their scene inside `render`: the adapter's time is what is not
    # the renderer's.
    adapter = t_scene + (t_render_many - render)
    return {
        "fps": frames / total,
        "render_ms": 1e3 * render / frames,
        "adapter_ms": 1e3 * adapter / frames,
        "mujoco_ms": 1e3 * t_step / frames,
        "contacts": contacts / frames,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=400)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--every", type=int, default=5, help="MuJoCo steps per tactile frame")
    ap.add_argument("--streams", type=int, default=1)
    args = ap.parse_args()
    if geltip.BUILD_PROFILE != "release":
        raise SystemExit("a debug build of geltip is imported: maturin develop --release")
    geltip.keep_freed_memory()
    sim = geltip.Simulator("paper", objects=["sphere:r=6", "sphere:r=5", "sphere:r=4"],
                           streams=args.streams)
    print(f"host: {sim.host}; streams: {args.streams}")
    print(f"host speed before: {geltip.host_speed()}")
    rows = []
    for grasp, balls in BALLS.items():
        for path, batched in (("batched", True), ("single", False)):
            run(sim, balls, 2 * sim.batch_frames, args.every, batched)  # warm-up
            runs = [run(sim, balls, args.frames, args.every, batched) for _ in range(args.repeat)]
            med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
            rows.append((grasp, path, med, [r["fps"] for r in runs]))
    print(f"host speed after: {geltip.host_speed()}")
    print(f"\n{args.frames} frames a run, {args.every} MuJoCo steps a frame, median of {args.repeat}\n")
    print("| grasp | path | frames/s with MuJoCo | runs | render ms/frame | adapter ms/frame "
          "| MuJoCo ms/frame | contacts/frame |")
    print("|---|---|---|---|---|---|---|---|")
    for grasp, path, m, fps in rows:
        print(f"| {grasp} | {path} | {m['fps']:.1f} | {', '.join(f'{f:.0f}' for f in fps)} "
              f"| {m['render_ms']:.2f} | {m['adapter_ms']:.3f} | {m['mujoco_ms']:.3f} "
              f"| {m['contacts']:.2f} |")


if __name__ == "__main__":
    main()
