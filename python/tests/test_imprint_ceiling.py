"""python/examples/imprint_ceiling.py on the real AllSight set (../shared/real, skipped
without it), on every other press: the change predicted from the other presses of a
push point beats no imprint clearly, the presses nearest in azimuth beat all of the push
point's, and the light alone in those windows scores about what the whole circle does."""
import json
import subprocess
import sys

from conftest import REPO, run_example


def test_the_ceiling_of_any_imprint_look():
    run = run_example("imprint_ceiling.py", "--every", "2")
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["frames"] == 180, got
    assert got["push_point_look_db"] > got["no_imprint_db"] + 1.5, got
    assert got["nearest_look_db"] > got["push_point_look_db"] + 1.0, got
    assert 28.0 < got["light_db"] < 34.0, got


def test_a_bad_option_is_refused_on_one_line():
    run = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "imprint_ceiling.py"), "--every", "0"],
        capture_output=True, text=True,
    )
    assert run.returncode != 0
    assert run.stderr.strip() == "error: --every must be at least 1, got 0", run.stderr
