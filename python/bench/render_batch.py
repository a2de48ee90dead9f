"""Frames/s of `Simulator.render_batch` from Python against Rust, in one run.

    maturin develop --release -m python/Cargo.toml   # or: pip install ./python
    python python/bench/render_batch.py [--passes 9] [--frames 64]

The contacts are the Rust bench's (`cargo bench --bench render`): the paper's 56 taps
(seven solids x rotations 0, 30, 45, 60 deg and translations 0, 5, 10, 15 mm, 1 mm deep at
azimuth 0) over and over, `--frames` of them per pass, rendered in batches of
`Simulator.batch_frames`. The machine is shared and noisy, so the two are timed pass by pass,
alternating (the order rotates each time): Rust is `examples/render_batch_fps.rs`, the bench's
'batches of 8 contacts' loop in a process kept running beside this one; Python is

- streaming: `render_batch(8 contacts, out=..., depth_out=...)` into arrays reused from
  batch to batch (the Rust loop also drops each batch's frames before the next);
- new arrays: one `render_batch(all frames)` call returning new (N, H, W, 3) uint8 and
  (N, H, W) float32 arrays (fresh memory every pass, which the kernel must fault in).

Each Python pass is divided by the Rust pass next to it; the medians are reported. With
`--cargo-bench`, the bench's own table row is run too, before and after (a cross-check).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import geltip

REPO = Path(__file__).resolve().parents[2]
SOLIDS = ["cone", "sphere", "irregular-prism", "cylinder", "edge", "tube", "slab"]
PLACES = ["rotation=0", "rotation=30", "rotation=45", "rotation=60",
          "translation=0", "translation=5", "translation=10", "translation=15"]


def contacts(n):
    taps = [dict(object=o, at=p, azimuth=0.0, depth=1.0) for o in SOLIDS for p in PLACES]
    return [taps[k % len(taps)] for k in range(n)]


def cargo_bench_row(frames):
    """The 'batches of 8 contacts' row of `cargo bench --bench render` (fps)."""
    cmd = ["cargo", "bench", "--workspace", "--bench", "render", "--", "--repeat", "3",
           "--frames", str(frames)]
    p = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr[-3000:]}")
    for line in p.stdout.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and re.fullmatch(r"batches of \d+ contacts", cells[0]):
            return float(cells[2])
    sys.exit(f"no 'batches of N contacts' row in:\n{p.stdout}")


class RustPasses:
    """examples/render_batch_fps, built in release and kept running."""

    def __init__(self, frames):
        build = ["cargo", "build", "--release", "--workspace", "--example", "render_batch_fps"]
        subprocess.run(build, cwd=REPO, check=True, capture_output=True)
        exe = REPO / "target" / "release" / "examples" / "render_batch_fps"
        self.p = subprocess.Popen([str(exe), "--frames", str(frames)], stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, text=True)
        self.host = self.p.stdout.readline().strip()

    def fps(self):
        self.p.stdin.write("pass\n")
        self.p.stdin.flush()
        line = self.p.stdout.readline()
        if not line:
            sys.exit("the Rust example stopped")
        return float(line)

    def close(self):
        self.p.stdin.write("quit\n")
        self.p.stdin.close()
        self.p.wait()


def streaming_pass(sim, todo, out, depth_out):
    start = time.perf_counter()
    for i in range(0, len(todo), sim.batch_frames):
        chunk = todo[i : i + sim.batch_frames]
        k = len(chunk)
        sim.render_batch(chunk, out=out[:k], depth_out=depth_out[:k])
    return len(todo) / (time.perf_counter() - start)


def new_arrays_pass(sim, todo):
    start = time.perf_counter()
    images, labels, depths = sim.render_batch(todo)
    fps = len(todo) / (time.perf_counter() - start)
    del images, labels, depths
    return fps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--passes", type=int, default=9)
    ap.add_argument("--frames", type=int, default=64)
    ap.add_argument("--cargo-bench", action="store_true",
                    help="also run the bench's own row before and after")
    args = ap.parse_args()
    if geltip.BUILD_PROFILE != "release":
        sys.exit("geltip's native module is a debug build: `maturin develop --release` first")
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    before = cargo_bench_row(args.frames) if args.cargo_bench else None
    rust = RustPasses(args.frames)
    sim = geltip.Simulator("paper")
    todo = contacts(args.frames)
    h, w, _ = sim.sensor.image_shape
    out = np.empty((sim.batch_frames, h, w, 3), np.uint8)
    depth_out = np.empty((sim.batch_frames, h, w), np.float32)
    # Warm-up of both.
    rust.fps()
    streaming_pass(sim, todo, out, depth_out)
    new_arrays_pass(sim, todo)
    print(f"Python: {sim.host}")
    print(f"Rust:   {rust.host}")
    print(f"{args.frames} frames per pass; {args.passes} alternating passes\n")
    print("| pass | Rust fps | Python fps, streaming | ratio | Python fps, new arrays | ratio |")
    print("|---|---|---|---|---|---|")
    runs = {
        "rust": rust.fps,
        "stream": lambda: streaming_pass(sim, todo, out, depth_out),
        "fresh": lambda: new_arrays_pass(sim, todo),
    }
    order = list(runs)
    rows = []
    for k in range(args.passes):
        got = {name: runs[name]() for name in order[k % 3 :] + order[: k % 3]}
        rows.append(got)
        print(f"| {k + 1} | {got['rust']:.1f} | {got['stream']:.1f} | "
              f"{got['stream'] / got['rust']:.3f} | {got['fresh']:.1f} | "
              f"{got['fresh'] / got['rust']:.3f} |", flush=True)
    rust.close()
    med = lambda key: statistics.median(r[key] for r in rows)  # noqa: E731
    ratio = lambda key: statistics.median(r[key] / r["rust"] for r in rows)  # noqa: E731
    print(f"| median | {med('rust'):.1f} | {med('stream'):.1f} | {ratio('stream'):.3f} | "
          f"{med('fresh'):.1f} | {ratio('fresh'):.3f} |")
    if before is not None:
        after = cargo_bench_row(args.frames)
        print(f"\ncargo bench --bench render, 'batches of 8 contacts': {before:.1f} fps before, "
              f"{after:.1f} fps after")
    print(f"\nPython / Rust (median of the passes' ratios): streaming {ratio('stream'):.3f}, "
          f"new arrays {ratio('fresh'):.3f} (target: within 10%, >= 0.9)")


if __name__ == "__main__":
    main()
