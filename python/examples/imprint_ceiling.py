"""How closely any imprint look could match a real sensor's imprints, and what its light allows.

    python python/examples/imprint_ceiling.py                # the AllSight set, about 30 s
    python python/examples/imprint_ceiling.py --out ceiling.md

`geltip imprint` scores a rendered imprint against the real frame inside a 40 px window round
each imprint. This asks what that score could be at best, from the real frames alone:

- Each contact frame's change from its press's t = 0 frame (push points 2 to 10; the tip's 11
  has no azimuth to turn by) is sampled in a patch turned so that its x runs away from the
  image's centre, centred on the imprint (the peak of the smoothed change within 30 degrees
  of the labelled azimuth).
- It is then predicted from other presses only (leave one out): their mean change relative
  to the local level (the reference), moved up to 8 px and scaled to the frame. From every
  other press of its push point: the best a look could do that is the same all round the
  finger but for the local light, the depth and the place. From the 4 presses nearest in
  azimuth: what a look that also knew how the imprint changes round the finger could do.
- The light: the sensor's empty render against each press's t = 0 frame in the same windows.
  A render's error in a window is both, so the last columns add the two errors.

Reads the real set (`--real`, labels.json and its frames) and renders the sensor's empty
finger with the geltip package (`pip install ./python`), whose decoder reads the frames as
`geltip imprint` does. Needs NumPy. Prints a Markdown table (and writes it to --out), then
the whole set's figures as one JSON line.
"""
import argparse
import json
import math
import os
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

import geltip

HALF = 45  # the patch's half side (px): a 40 px window and room to move
WINDOW = 40
SHIFT = 8
NEAREST = 4


def load(path):
    return geltip.load_image(str(path)).astype(np.float64)


def blur(a, sigma):
    k = np.arange(-3 * sigma, 3 * sigma + 1)
    g = np.exp(-(k**2) / (2 * sigma * sigma))
    g /= g.sum()
    a = np.apply_along_axis(lambda r: np.convolve(r, g, "same"), 0, a)
    return np.apply_along_axis(lambda r: np.convolve(r, g, "same"), 1, a)


def bilinear(img, x, y):
    h, w, _ = img.shape
    x0 = np.clip(np.floor(x).astype(int), 0, w - 2)
    y0 = np.clip(np.floor(y).astype(int), 0, h - 2)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    return (img[y0, x0] * (1 - fx) * (1 - fy) + img[y0, x0 + 1] * fx * (1 - fy)
            + img[y0 + 1, x0] * (1 - fx) * fy + img[y0 + 1, x0 + 1] * fx * fy)


def psnr(sq, n):
    return 10 * math.log10(255.0**2 / (sq / n)) if sq > 0 else float("inf")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--real", default="../shared/real/allsight", type=Path,
                    help="the real set's folder (labels.json and its frames)")
    ap.add_argument("--sensor", default="allsight", help="the sensor whose empty render is scored")
    ap.add_argument("--out", type=Path, help="also write the table here")
    ap.add_argument("--every", type=int, default=1,
                    help="use the frames of every N-th press only (a quicker, rougher check)")
    args = ap.parse_args()
    if args.every < 1:
        sys.exit(f"error: --every must be at least 1, got {args.every}")
    labels = args.real / "labels.json"
    if not labels.is_file():
        sys.exit(f"error: {labels}: not found (the real set; see --real)")
    frames = [f for f in json.loads(labels.read_text())["frames"] if f["num"] != 11]
    presses = set(list(dict.fromkeys(f["reference_press"] for f in frames))[:: args.every])
    frames = [f for f in frames if f["reference_press"] in presses]
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    empty = geltip.Simulator(geltip.Sensor(args.sensor)).reference().astype(np.float64)

    h, w, _ = empty.shape
    centre = np.array([w / 2, h / 2])
    yy, xx = np.mgrid[0:h, 0:w]
    radius = np.hypot(xx - centre[0], yy - centre[1])
    angle = np.arctan2(yy - centre[1], xx - centre[0])
    u, v = np.meshgrid(np.arange(-HALF, HALF + 1), np.arange(-HALF, HALF + 1))
    disc = u**2 + v**2 <= WINDOW**2
    circle = min(h, w) / 2 - 4  # inside the frames' masked image circle

    rows = []
    light = defaultdict(lambda: [0.0, 0])
    for k, f in enumerate(frames):
        image = load(args.real / f["image"])
        ref = load(args.real / f["reference_press"])
        change = image - ref
        peak = blur(np.abs(change).sum(2), 4)
        off = np.angle(np.exp(1j * (angle - math.radians(f["image_azimuth_deg"]))))
        peak[(np.abs(off) > math.radians(30)) | (radius > circle - 10)] = -1
        cy, cx = np.unravel_index(np.argmax(peak), peak.shape)
        out = np.array([cx, cy]) - centre
        out /= np.linalg.norm(out)
        across = np.array([-out[1], out[0]])
        px = cx + u * out[0] + v * across[0]
        py = cy + u * out[1] + v * across[1]
        group = f"{f['image'][:2]} push {f['num']}"
        rows.append({"group": group, "azimuth": f["image_azimuth_deg"],
                     "change": bilinear(change, px, py),
                     "level": np.maximum(bilinear(ref, px, py), 8.0)})
        window = ((xx - cx) ** 2 + (yy - cy) ** 2 <= WINDOW**2) & (radius <= circle)
        light[group][0] += ((empty - ref)[window] ** 2).sum()
        light[group][1] += 3 * int(window.sum())
        print(f"\rimprints {k + 1}/{len(frames)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)

    def best_fit(rel, change, level):
        """The smallest squared error of rel (moved, times the level, scaled) on the disc."""
        c = change[disc]
        best = np.inf
        for dx in range(-SHIFT, SHIFT + 1, 2):
            for dy in range(-SHIFT, SHIFT + 1, 2):
                p = (np.roll(np.roll(rel, dy, 0), dx, 1) * level)[disc]
                s = (p * c).sum() / max((p * p).sum(), 1e-9)
                best = min(best, ((c - s * p) ** 2).sum())
        return best

    groups = defaultdict(list)
    for i, r in enumerate(rows):
        groups[r["group"]].append(i)
    relative = [r["change"] / r["level"] for r in rows]
    sums = defaultdict(lambda: np.zeros(4))
    for group, members in groups.items():
        for n, i in enumerate(members):
            others = [j for j in members if j != i]
            turn = [abs(math.remainder(rows[j]["azimuth"] - rows[i]["azimuth"], 360)) for j in others]
            near = [others[k] for k in np.argsort(turn)[:NEAREST]]
            c, level = rows[i]["change"], rows[i]["level"]
            errors = [(c[disc] ** 2).sum(),
                      best_fit(np.mean([relative[j] for j in others], 0), c, level),
                      best_fit(np.mean([relative[j] for j in near], 0), c, level),
                      3 * disc.sum()]
            for key in (group, "all"):
                sums[key] += errors
            print(f"\r{group}: {n + 1}/{len(members)}   ", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    light["all"] = [sum(v[0] for v in light.values()), sum(v[1] for v in light.values())]

    lines = [
        f"Inside {WINDOW} px of each real imprint (`{labels}`, push points 2 to 10), PSNR in dB.",
        "Change predicted from other presses only: of the push point, or the "
        f"{NEAREST} nearest in azimuth.",
        "",
        "| group | frames | no imprint | push point's look | nearest in azimuth | light: empty "
        "render vs press reference | render at best: push point's | render at best: nearest |",
        "|---|---|---|---|---|---|---|---|",
    ]
    order = sorted(groups, key=lambda g: (g[:2], int(g.split()[-1]))) + ["all"]
    for key in order:
        s = sums[key]
        n = s[3]
        imprint = [psnr(s[0], n), psnr(s[1], n), psnr(s[2], n)]
        bg = psnr(*light[key])
        both = [-10 * math.log10(10 ** (-bg / 10) + 10 ** (-x / 10)) for x in imprint[1:]]
        count = len(groups[key]) if key != "all" else len(rows)
        lines.append(f"| {key} | {count} | " + " | ".join(f"{x:.1f}" for x in imprint + [bg] + both)
                     + " |")
    # The loop ends on "all": the whole set's figures.
    summary = {"frames": count, "no_imprint_db": imprint[0], "push_point_look_db": imprint[1],
               "nearest_look_db": imprint[2], "light_db": bg, "render_best_push_point_db": both[0],
               "render_best_nearest_db": both[1]}
    table = "\n".join(lines)
    print(table)
    if args.out:
        args.out.write_text(table + "\n")
    print(json.dumps({k: round(v, 2) for k, v in summary.items()}))


if __name__ == "__main__":
    main()
