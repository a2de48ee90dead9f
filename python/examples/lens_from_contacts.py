"""An equidistant lens's focal length from real contact frames at known push points.

    python python/examples/lens_from_contacts.py                         # the AllSight set
    python python/examples/lens_from_contacts.py --every 4               # a quarter of it

Where a sensor's image circle is a software mask, not the lens's edge, the circle says
nothing of the focal length. Contact frames at known places do: each press's imprint is
found by `geltip.localise` (against its own no-contact frame), and an equidistant lens puts
a point theta off the axis at f * theta from the image centre, so f is the least-squares
ratio of the imprints' image radii to their push points' angles. The AllSight's push points
are in the authors' finger frame (origin on the axis at the elastomer's base, hemisphere
centre at z 14 mm); the camera sits `--camera-below` mm below that origin (0.4: its lens
front 14.4 mm below the hemisphere's centre). Prints one JSON line: f, the rms of the radii
about f * theta, the same for the sensor's own focal length and for a 180-degree lens over
the sensor's image circle, and the frames used (the tip, push point 11, on the axis, left
out of the radii). Then the whole lens from the imprints' places, the tip's included: the
principal point (cx, cy), f and the turn between the finger frame's azimuths and the
image's (either way round), by least squares on (u, v) = c + f theta (cos, sin)(+-phi + turn):
`centre_px`, `centre_focal_px`, `turn_deg`, `mirrored`, `rms_2d_px`. Where the image circle
is a mask, that centre is where the lens's axis meets the image, for `[lens] cx, cy`.
"""
import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

import geltip


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--real", default="../shared/real/allsight", type=Path,
                    help="the folder holding labels.json and its frames")
    ap.add_argument("--sensor", default="allsight", help="the sensor that took them")
    ap.add_argument("--camera-below", type=float, default=0.4,
                    help="mm from the labels' frame origin down to the camera")
    ap.add_argument("--every", type=int, default=1, help="use every n-th contact frame")
    args = ap.parse_args()
    labels = args.real / "labels.json"
    if not labels.is_file():
        sys.exit(f"error: {labels}: no such file (the real AllSight set)")
    sensor = geltip.Sensor(args.sensor)
    cx, cy = sensor.config["lens"]["cx"], sensor.config["lens"]["cy"]
    radii, angles = [], []
    places = []  # (u, v, theta, phi) of every imprint found, the tip's included
    frames = json.loads(labels.read_text())["frames"]
    for f in frames[:: max(args.every, 1)]:
        image = geltip.load_image(args.real / f["image"])
        reference = geltip.load_image(args.real / f["reference_press"])
        found = geltip.localise(sensor, reference, image)
        if not found["detected"]:
            continue
        u, v = found["pixel"]
        x, y, z = f["push_point_finger_frame_mm"]
        theta = math.atan2(math.hypot(x, y), z + args.camera_below)
        places.append((u, v, theta, math.atan2(y, x)))
        if f["num"] == 11:
            continue
        radii.append(math.hypot(u - cx, v - cy))
        angles.append(theta)
    if len(radii) < 2:
        sys.exit("error: fewer than two imprints found")
    focal = sum(r * t for r, t in zip(radii, angles)) / sum(t * t for t in angles)

    def rms(f):
        return math.sqrt(sum((r - f * t) ** 2 for r, t in zip(radii, angles)) / len(radii))

    lens = sensor.config["lens"]
    own = lens["focal_px"]
    # The lens a circle ending at the sensor's field of view would imply were it 180 degrees.
    circle = own * math.radians(lens["fov_deg"] / 2)
    half_turn = circle / (math.pi / 2)
    centre, centre_focal, turn, mirrored, rms_2d = whole_lens(places)
    print(json.dumps({
        "focal_px": round(focal, 2),
        "rms_px": round(rms(focal), 2),
        "sensor_focal_px": own,
        "sensor_rms_px": round(rms(own), 2),
        "focal_180_deg_px": round(half_turn, 2),
        "rms_180_deg_px": round(rms(half_turn), 2),
        "frames": len(radii),
        "centre_px": [round(centre[0], 2), round(centre[1], 2)],
        "centre_focal_px": round(centre_focal, 2),
        "turn_deg": round(turn, 2),
        "mirrored": mirrored,
        "rms_2d_px": round(rms_2d, 2),
        "frames_2d": len(places),
    }))


def whole_lens(places):
    """The principal point, f and the azimuths' turn that put the push points on the
    imprints: for a turn and a side, (cx, cy, f) are linear least squares; the turn is
    searched over a grid each side, then refined."""
    p = np.array(places)
    u, v, theta, phi = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    ones, zeros = np.ones_like(u), np.zeros_like(u)

    def solve(turn, side):
        a = side * phi + turn
        m = np.block([[ones[:, None], zeros[:, None], (theta * np.cos(a))[:, None]],
                      [zeros[:, None], ones[:, None], (theta * np.sin(a))[:, None]]])
        b = np.concatenate([u, v])
        x, *_ = np.linalg.lstsq(m, b, rcond=None)
        return math.sqrt(np.mean((m @ x - b) ** 2) * 2), x

    best = None
    for side in (1.0, -1.0):
        for turn in np.radians(np.arange(0.0, 360.0, 1.0)):
            err, x = solve(turn, side)
            if x[2] > 0 and (best is None or err < best[0]):
                best = (err, turn, side)
    _, turn, side = best
    for step in np.radians([0.1, 0.01]):
        turn = min((turn + k * step for k in range(-10, 11)), key=lambda t: solve(t, side)[0])
    err, (cx, cy, f) = solve(turn, side)
    return (cx, cy), f, math.degrees(turn) % 360.0, side < 0, err


if __name__ == "__main__":
    main()
