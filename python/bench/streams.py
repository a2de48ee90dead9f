"""Frames/s of `Simulator.render_batch` with 1, 2 and 3 render streams, in one run.

    maturin develop --release -m python/Cargo.toml   # or: pip install ./python
    python python/bench/streams.py [--frames 96] [--rounds 3]

The contacts are the render bench's (the paper's 56 taps over and over); each round renders
`--frames` of them in one `render_batch` call (new arrays each time) on a Simulator with
each stream count, alternating, so the host's phase moves all of them alike.
"""
import argparse
import time

import geltip
from render_batch import contacts


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=96)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    geltip.keep_freed_memory()
    sims = {n: geltip.Simulator("paper", streams=n) for n in (1, 2, 3)}
    print(f"host: {sims[1].host}")
    batch = contacts(args.frames)
    for sim in sims.values():
        sim.render_batch(batch[:3 * sim.batch_frames])  # every stream's pipelines built
    for r in range(args.rounds):
        print(f"round {r + 1}: host loop {geltip.host_speed()['all_cores_ms']:.1f} ms on all cores")
        for n, sim in sims.items():
            start = time.perf_counter()
            sim.render_batch(batch)
            fps = len(batch) / (time.perf_counter() - start)
            print(f"round {r + 1}: {n} stream{'s' if n > 1 else ''}: {fps:.1f} fps")


if __name__ == "__main__":
    main()
