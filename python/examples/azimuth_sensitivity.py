"""How much of a real set's azimuth score a detector's sub-pixel bias decides.

    geltip evaluate --real ../shared/real/allsight/labels.json --sensor allsight --method change --out ev
    python python/examples/azimuth_sensitivity.py ev/per_frame.jsonl

Reads the per-frame report of `geltip evaluate --real` (or `geltip.evaluate(real=...)`),
turns every answer about its label's centre by a few pixels (along the circle through it,
the same way for every frame) and counts again, per group, the frames within the
tolerance of their labelled azimuth. Where labels are off by about the tolerance, as the
AllSight's push point 10 near the tip, the count then swings with a pixel's turn: a
detector's score there is its bias, not its skill. Random scatter of the answers is shown
beside (the mean over draws). Prints a table and, last, one JSON line of the figures.
"""
import argparse
import json
import math
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

SHIFTS = (-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0)
SCATTER = (1.0, 2.0, 3.0)


def rows_of(path):
    """(group, label, pixel or None) for every frame labelled with an azimuth about a
    centre; a frame without an answer keeps None (a miss at any turn)."""
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except OSError as e:
        sys.exit(f"error: {path}: {e.strerror}")
    rows = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            r = json.loads(line)
            label = r["label"]
        except (json.JSONDecodeError, KeyError, TypeError):
            sys.exit(f"error: {path}:{n}: not a row of geltip evaluate's per_frame.jsonl")
        if label.get("azimuth_deg") is None or label.get("centre") is None:
            continue
        pixel = None if r.get("pixel") is None else np.asarray(r["pixel"], float)
        rows.append((label.get("group", "all"), label, pixel))
    if not rows:
        sys.exit(f"error: {path}: no frame with a labelled azimuth about a centre")
    return rows


def within(pixel, label, tolerance):
    c = label["centre"]
    a = math.degrees(math.atan2(pixel[1] - c[1], pixel[0] - c[0]))
    return abs((a - label["azimuth_deg"] + 180) % 360 - 180) <= tolerance


def turned(pixel, label, shift):
    """`pixel` moved `shift` px along the circle about the label's centre (towards larger
    azimuths, image y down)."""
    v = pixel - np.asarray(label["centre"], float)
    r = np.hypot(*v)
    if r == 0:
        return pixel
    return pixel + shift * np.array([-v[1], v[0]]) / r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("per_frame", help="per_frame.jsonl of geltip evaluate --real")
    ap.add_argument("--tolerance", type=float, default=15.0, help="degrees (evaluate's default)")
    ap.add_argument("--draws", type=int, default=200, help="random draws for the scatter columns")
    args = ap.parse_args()
    if not args.tolerance > 0:
        sys.exit(f"error: --tolerance must be above 0, got {args.tolerance}")
    if args.draws < 1:
        sys.exit(f"error: --draws must be at least 1, got {args.draws}")
    groups = defaultdict(list)
    for group, label, pixel in rows_of(args.per_frame):
        groups[group].append((label, pixel))
    rng = np.random.default_rng(0)
    out = {}
    head = " | ".join(f"{s:+g} px" for s in SHIFTS)
    scat = " | ".join(f"±{s:g} px" for s in SCATTER)
    print(f"| group | frames | median radius px | {head} | {scat} |")
    print("|---" * (3 + len(SHIFTS) + len(SCATTER)) + "|")
    for group in sorted(groups):
        rows = groups[group]
        found = [(lab, p) for lab, p in rows if p is not None]
        counts = [sum(within(turned(p, lab, s), lab, args.tolerance) for lab, p in found)
                  for s in SHIFTS]
        scatter = [
            float(np.mean([
                sum(within(p + rng.normal(0.0, sd, 2), lab, args.tolerance) for lab, p in found)
                for _ in range(args.draws)
            ]))
            for sd in SCATTER
        ]
        radius = float(np.median([np.hypot(*(p - np.asarray(lab["centre"], float)))
                                  for lab, p in found])) if found else float("nan")
        out[group] = {"frames": len(rows), "median_radius_px": radius,
                      "at_azimuth_by_shift": dict(zip(map(str, SHIFTS), counts)),
                      "at_azimuth_by_scatter": dict(zip(map(str, SCATTER), scatter))}
        print(f"| {group} | {len(rows)} | {radius:.1f} | "
              + " | ".join(str(c) for c in counts) + " | "
              + " | ".join(f"{s:.1f}" for s in scatter) + " |")
    print(json.dumps(out))


if __name__ == "__main__":
    main()
