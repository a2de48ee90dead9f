"""python/examples/lens_from_contacts.py on the real AllSight set (../shared/real, skipped
without it): a quarter of its presses pin the equidistant focal length near 118 px with a
few pixels' spread, where the 180-degree lens the image circle would imply (150.88 px)
misses them by far more, and the allsight preset's lens is the pinned one."""
import json
import os
import subprocess
import sys

import pytest

from conftest import REPO

REAL = REPO / ".." / "shared" / "real" / "allsight"


def test_the_contact_frames_pin_the_focal_length():
    if not (REAL / "labels.json").is_file():
        pytest.skip(f"{REAL} is absent (real sensor frames)")
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    run = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "lens_from_contacts.py"),
         "--real", str(REAL), "--every", "4"],
        capture_output=True, text=True, env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["frames"] >= 80
    assert 110 <= got["focal_px"] <= 128 and got["rms_px"] < 6, got
    # The preset holds it, and the circle's 180-degree lens does far worse.
    assert abs(got["sensor_focal_px"] - got["focal_px"]) < 3, got
    assert abs(got["focal_180_deg_px"] - 150.9) < 0.5, got
    assert got["rms_180_deg_px"] > 4 * got["rms_px"], got
