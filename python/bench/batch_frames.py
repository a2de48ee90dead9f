"""Frames/s of `Simulator.render_batch` and `render_scenes` by `batch_frames`, in one run.

    python python/bench/batch_frames.py [--frames 512] [--repeat 3] [--batch 1,8,64]

The contacts are the render bench's (the paper's 56 taps, 1 mm deep, over and over); each
pass renders `--frames` of them into arrays reused from pass to pass (`out=`, no depth
maps), and as many two-contact scenes (each tap with its twin half a turn away). Each row
is the median of `--repeat` passes, after a warm-up pass; the host's line and its speed
come first (a GPU's figures name the card there).
"""
import argparse
import statistics
import time

import numpy as np

import geltip
from render_batch import contacts  # the render bench's taps, the same as Rust's


def timed(passes, render):
    render()  # warm-up: pipelines, arrays, staging
    fps = []
    for _ in range(passes):
        start = time.perf_counter()
        n = render()
        fps.append(n / (time.perf_counter() - start))
    return statistics.median(fps), min(fps), max(fps)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=512)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--batch", default="1,8,64")
    args = ap.parse_args()
    sim = geltip.Simulator("paper")
    print(f"host: {sim.host}; default batch_frames {sim.batch_frames}")
    print(f"host speed: {geltip.host_speed()}")
    todo = contacts(args.frames)
    twins = [[c, dict(c, azimuth=180.0)] for c in todo]
    out = np.empty((args.frames, *sim.sensor.image_shape), np.uint8)
    print("| what | batch_frames | fps (median) | fps range |")
    print("|---|---|---|---|")
    for batch in (int(b) for b in args.batch.split(",")):
        sim.batch_frames = batch

        def singles():
            sim.render_batch(todo, depth_maps=False, out=out)
            return len(todo)

        def scenes():
            sim.render_scenes(twins, out=out)
            return len(twins)

        for name, render in (("one contact a frame", singles), ("two contacts a frame", scenes)):
            med, lo, hi = timed(args.repeat, render)
            print(f"| {name} | {batch} | {med:.0f} | {lo:.0f}-{hi:.0f} |", flush=True)


if __name__ == "__main__":
    main()
