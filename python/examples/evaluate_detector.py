"""A 20-line NumPy contact detector, scored by geltip on the paper's 56 taps.

    python python/examples/evaluate_detector.py [OUT_DIR]

Prints the evaluation's tables and writes its report (summary.json, tables.md, charts)
into OUT_DIR (default eval/peak).
"""
import sys

import numpy as np

import geltip


def detect(image, reference, sensor):
    """The centre of the change from the empty frame, after a 9 x 9 box blur."""
    change = np.abs(image.astype(np.int16) - reference).sum(axis=2).astype(np.float32)
    k = 9  # the box blur, by an integral image
    c = np.pad(change, ((k, 0), (k, 0))).cumsum(0).cumsum(1)
    blur = (c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]) / k**2
    peak = float(blur.max())
    if peak < 8:  # nothing above the noise
        return []
    v, u = np.nonzero(blur > 0.2 * peak)  # the imprint: a fifth of the peak or more
    w = blur[v, u]
    centre = [np.average(u, weights=w) - k / 2 + 0.5, np.average(v, weights=w) - k / 2 + 0.5]
    return [{"pixel": centre, "confidence": min(1.0, peak / 80)}]


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "eval/peak"
    report = geltip.evaluate(detect, suite="paper", sensor="paper", out=out)
    print(report.tables)
    s = report.summary
    print(f"recall {s['recall']:.2f}, median error {s['error_mm']['median']:.2f} mm; wrote {out}")
