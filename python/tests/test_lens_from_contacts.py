"""python/examples/lens_from_contacts.py on the real AllSight set (../shared/real, skipped
without it): a quarter of its presses pin the equidistant focal length near 118 px with a
few pixels' spread, where the 180-degree lens the image circle would imply (150.88 px)
misses them by far more, and the allsight preset's lens is the pinned one. The whole lens
fitted to the imprints' places puts the principal point within a few pixels of the mask's
centre (where the preset has it), far from where the light alone would put it."""
import json
import math

from conftest import run_example


def test_the_contact_frames_pin_the_focal_length():
    run = run_example("lens_from_contacts.py", "--every", "4")
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["frames"] >= 80
    assert 110 <= got["focal_px"] <= 128 and got["rms_px"] < 6, got
    # The preset holds it, and the circle's 180-degree lens does far worse.
    assert abs(got["sensor_focal_px"] - got["focal_px"]) < 3, got
    assert abs(got["focal_180_deg_px"] - 150.9) < 0.5, got
    assert got["rms_180_deg_px"] > 4 * got["rms_px"], got
    # The imprints' places pin the centre: near the preset's (240, 240), the focal length
    # as the radii give it, a few pixels' scatter; not the light's (234, 248).
    cx, cy = got["centre_px"]
    assert math.hypot(cx - 240.0, cy - 240.0) < 4 and got["rms_2d_px"] < 8, got
    assert math.hypot(cx - 234.0, cy - 248.0) > 8, got
    assert abs(got["centre_focal_px"] - got["focal_px"]) < 3, got
    assert got["frames_2d"] >= got["frames"], got
