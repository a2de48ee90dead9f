"""python/examples/azimuth_sensitivity.py: answers turned about their label's centre are
counted again per group; a frame without an answer counts as a miss; bad files and
options are refused on one line."""
import json
import math
import subprocess
import sys

from conftest import REPO

SCRIPT = REPO / "python" / "examples" / "azimuth_sensitivity.py"


def row(group, angle_deg, radius=20.0, centre=(100.0, 100.0), label_deg=0.0):
    pixel = None
    if angle_deg is not None:
        a = math.radians(angle_deg)
        pixel = [centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a)]
    return {"label": {"group": group, "azimuth_deg": label_deg, "centre": list(centre)},
            "pixel": pixel, "found": pixel is not None}


def run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)],
                          capture_output=True, text=True)


def test_a_turn_of_a_pixel_moves_the_count_where_answers_sit_near_the_tolerance(tmp_path):
    # 20 px from the centre, 1 px along the circle is 2.86 degrees.
    rows = [row("tip", a) for a in (14.0, 16.0, -14.5, 5.0, None)]
    rows += [row("far", a, radius=200.0) for a in (14.0, -14.0)]  # 0.29 degrees a pixel
    rows.append({"label": {"group": "tip", "azimuth_deg": None}, "pixel": [0, 0]})  # no azimuth
    path = tmp_path / "per_frame.jsonl"
    path.write_text("\n".join(json.dumps(r) for r in rows) + "\n")
    p = run(path)
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout.strip().splitlines()[-1])
    tip = got["tip"]
    assert tip["frames"] == 5  # the frame without an answer counts, as a miss
    assert tip["at_azimuth_by_shift"]["0.0"] == 3  # 14, -14.5 and 5 degrees
    assert tip["at_azimuth_by_shift"]["1.0"] == 2  # 16.9 leaves, -11.6 and 7.9 stay
    assert tip["at_azimuth_by_shift"]["-1.0"] == 3  # 11.1, 13.1 and 2.1; -17.4 leaves
    assert tip["at_azimuth_by_shift"]["2.0"] == 2  # 19.7, 21.7 out; -8.8, 10.7 in
    assert tip["at_azimuth_by_shift"]["-2.0"] == 3  # 8.3, 10.3, -0.7 in; -20.2 out
    assert abs(tip["median_radius_px"] - 20.0) < 1e-9
    far = got["far"]
    assert all(v == 2 for v in far["at_azimuth_by_shift"].values())  # too far out to move
    assert "| tip | 5 | 20.0 | 3 | 3 | 3 | 3 | 2 | 2 | 2 |" in p.stdout


def test_bad_files_and_options_are_refused_on_one_line(tmp_path):
    p = run(tmp_path / "missing.jsonl")
    assert p.returncode != 0 and p.stderr.strip().startswith("error:") and "missing.jsonl" in p.stderr
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"label": {"azimuth_deg": 3, "centre": [0, 0]}, "pixel": [1, 1]}\nnot json\n')
    p = run(bad)
    assert p.returncode != 0
    assert p.stderr.strip() == f"error: {bad}:2: not a row of geltip evaluate's per_frame.jsonl"
    none = tmp_path / "none.jsonl"
    none.write_text(json.dumps({"label": {"contact": False}, "pixel": None}) + "\n")
    p = run(none)
    assert p.returncode != 0 and "no frame with a labelled azimuth" in p.stderr
    good = tmp_path / "good.jsonl"
    good.write_text(json.dumps(row("g", 1.0)) + "\n")
    p = run(good, "--tolerance", "0")
    assert p.returncode != 0 and p.stderr.strip() == "error: --tolerance must be above 0, got 0.0"
    assert len(p.stderr.strip().splitlines()) == 1
