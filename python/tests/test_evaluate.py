"""geltip.evaluate: a Python detector scored like `geltip evaluate` scores a file or a
program (the same summary), built-in localisers by name, exceptions and bad answers."""
import json
from pathlib import Path
import sys

import numpy as np
import pytest

import geltip


@pytest.fixture(scope="module")
def mixed_set(cli, tmp_path_factory):
    """12 frames: some empty, one or two contacts in the others."""
    out = tmp_path_factory.mktemp("evaluate") / "set"
    cli("dataset", "--sensor", "paper", "--count", 12, "--seed", 2, "--empty-fraction", 0.2,
        "--contacts-per-sample", "1..2", "--out", out)
    return out


def labels(set_dir):
    """index -> the visible contacts' centres."""
    out = {}
    for line in (set_dir / "labels.jsonl").read_text().splitlines():
        v = json.loads(line)
        out[v["index"]] = [c["contact_centre"] for c in v["contacts"] if c["pixel"] is not None]
    return out


def oracle_by_image(set_dir):
    """A Python detector that knows each image's labels (by its bytes)."""
    truth = {}
    for k, centres in labels(set_dir).items():
        image = geltip.load_image(set_dir / "images" / f"{k:06d}.png")
        truth[image.tobytes()] = centres

    def oracle(image, reference, sensor):
        assert image.shape == reference.shape == sensor.image_shape
        return [{"point": np.array(c), "confidence": 0.9} for c in truth[image.tobytes()]]

    return oracle


def without_run_fields(summary):
    return {k: v for k, v in summary.items() if k not in ("seconds", "detector")}


def test_python_file_and_program_give_the_same_summary(mixed_set, cli, tmp_path):
    report = geltip.evaluate(oracle_by_image(mixed_set), dataset=mixed_set, out=tmp_path / "py")
    s = report.summary
    assert s["recall"] == 1.0 and s["false_positives"] == 0, s
    assert s["error_mm"]["max"] <= 0.05
    assert s["empty_frames"] > 0
    assert s["detector"] == "oracle"
    assert "summary.json" in report.files and (tmp_path / "py" / "tables.md").is_file()
    assert len(report.per_sample) == s["samples"] == 12
    assert report.tables.startswith("# Detector evaluation")

    predictions = tmp_path / "oracle.jsonl"
    predictions.write_text("".join(
        json.dumps({"sample": k, "detections": [{"point": c, "confidence": 0.9} for c in cs]}) + "\n"
        for k, cs in labels(mixed_set).items()))
    p = cli("evaluate", "--dataset", mixed_set, "--predictions", predictions, "--out",
            tmp_path / "file", check=False)
    assert p.returncode == 0, p.stderr
    program = tmp_path / "detect.py"
    program.write_text(
        "import json, sys\n"
        f"answers = {{json.loads(l)['sample']: l for l in open({str(predictions)!r})}}\n"
        "for line in sys.stdin:\n"
        "    print(answers[json.loads(line)['sample']], end='', flush=True)\n")
    p = cli("evaluate", "--dataset", mixed_set, "--detector", f"{sys.executable} {program}",
            "--out", tmp_path / "program", check=False)
    assert p.returncode == 0, p.stderr
    by_file = json.loads((tmp_path / "file" / "summary.json").read_text())
    by_program = json.loads((tmp_path / "program" / "summary.json").read_text())
    assert without_run_fields(s) == without_run_fields(by_file) == without_run_fields(by_program)


def test_a_built_in_localiser_by_name_matches_the_command(mixed_set, cli, tmp_path):
    report = geltip.evaluate("surface", dataset=mixed_set, name="mine")
    assert report.summary["detector"] == "mine"
    p = cli("evaluate", "--dataset", mixed_set, "--method", "surface", "--out", tmp_path, check=False)
    assert p.returncode == 0, p.stderr
    command = json.loads((tmp_path / "summary.json").read_text())
    assert without_run_fields(report.summary) == without_run_fields(command)
    assert "mine" in repr(report)


def test_a_suite_renders_while_the_detector_runs():
    seen = []

    def blind(image, reference, sensor):
        seen.append(sensor.name)
        return []

    report = geltip.evaluate(blind, suite="paper", sensor="paper", gate_mm=None)
    assert report.summary["samples"] == len(seen) == 56
    assert report.summary["recall"] == 0.0 and report.summary["gate_mm"] is None


def test_an_exception_in_the_detector_is_raised_again(mixed_set):
    class Broken(Exception):
        pass

    def broken(image, reference, sensor):
        raise Broken("my detector failed")

    with pytest.raises(Broken, match="my detector failed"):
        geltip.evaluate(broken, dataset=mixed_set)


@pytest.mark.parametrize("answer, says", [
    ([{"pixel": [float("nan"), 3.0]}], "detector, sample 0: detections[0]: pixel: expected"),
    ([{"pixel": [900.0, 3.0]}], "detector, sample 0: detections[0]: pixel: (900, 3) is outside"),
    ([{"confidence": 1.0}], "detector, sample 0: detections[0]: needs"),
    ([3], "detector, sample 0: detections[0]: expected an object"),
    ([{"pixel": "ab"}], "detector, sample 0: detections[0]: pixel: expected a sequence of numbers"),
    ([{"point": [1.0, 2.0]}], "detector, sample 0: detections[0]: point: expected [x, y, z] in mm"),
    (({"pixel": (3.0, 4.0), "confidence": "high"},),
     "detector, sample 0: detections[0]: confidence: expected a number, got 'high'"),
    ([{"pixel": np.array([3.0, 4.0]), "confidence": float("inf")}],
     "detector, sample 0: detections[0]: confidence: expected a finite number, got inf"),
])
def test_bad_detections_name_the_sample(mixed_set, answer, says):
    with pytest.raises(geltip.InvalidArgumentError) as e:
        geltip.evaluate(lambda image, reference, sensor: answer, dataset=mixed_set)
    assert str(e.value).startswith(says), str(e.value)


def test_bad_arguments(mixed_set):
    with pytest.raises(TypeError, match="a detector returns a list"):
        geltip.evaluate(lambda i, r, s: "x", dataset=mixed_set)
    with pytest.raises(geltip.InvalidArgumentError, match="detector: unknown 'nope'"):
        geltip.evaluate("nope", dataset=mixed_set)
    with pytest.raises(geltip.InvalidArgumentError, match="detector: expected a function"):
        geltip.evaluate(3, dataset=mixed_set)
    with pytest.raises(geltip.InvalidArgumentError, match="either a dataset or a suite"):
        geltip.evaluate("surface")
    with pytest.raises(geltip.InvalidArgumentError, match="name a sensor"):
        geltip.evaluate("surface", suite="paper")
    # A set holds its own sensor: another one given with it is refused, not ignored.
    with pytest.raises(geltip.InvalidArgumentError,
                       match="^sensor: a dataset holds its own sensor"):
        geltip.evaluate("surface", dataset=mixed_set, sensor="paper")
    with pytest.raises(geltip.InvalidArgumentError, match="gate_mm: must be a positive"):
        geltip.evaluate("surface", dataset=mixed_set, gate_mm=-1)


REAL = Path(__file__).resolve().parents[2] / ".." / "shared" / "real" / "allsight"


def test_real_frames_and_the_change_threshold(tmp_path):
    """Real labelled frames (../shared/real, skipped where absent): a drift-only pair is no
    contact for the change method, a contact at threshold 0.5, none again when the noise is
    said to be far larger; a threshold or noise for another method is refused."""
    with pytest.raises(ValueError, match="threshold"):
        geltip.evaluate("surface", suite="paper", sensor="paper", threshold=5)
    with pytest.raises(ValueError, match="^noise"):
        geltip.evaluate("paper", suite="paper", sensor="paper", noise=3)
    with pytest.raises(ValueError, match="^noise: applies to the method 'change'"):
        geltip.evaluate(lambda *_: [], suite="paper", sensor="paper", noise=3)
    if not REAL.is_dir():
        pytest.skip(f"{REAL} is absent (real sensor frames)")
    line = {"image": str(REAL / "s1_image2_0.03_0.jpg"),
            "reference": str(REAL / "s1_ref_frame.jpg"), "contact": False, "group": "drift"}
    (tmp_path / "set.jsonl").write_text(json.dumps(line) + "\n")
    for threshold, noise, false_contacts in ((None, None, 0), (0.5, None, 1), (0.5, 200, 0)):
        report = geltip.evaluate("change", real=tmp_path / "set.jsonl", sensor="allsight",
                                 threshold=threshold, noise=noise, out=tmp_path / "out")
        assert report.summary["rows"][-1]["false_contacts"] == false_contacts, report.tables
        assert "summary.json" in report.files


def test_the_paper_method_with_an_area_on_the_finger(tmp_path):
    """The paper's area window is in its own sensor's pixels: on a real AllSight contact
    (../shared/real, skipped where absent) it passes no region; a window on the finger in
    mm^2 finds the contact."""
    with pytest.raises(ValueError, match="^area_mm2: applies to method 'change' or 'paper'"):
        geltip.evaluate("surface", suite="paper", sensor="paper", area_mm2=(1, 9))
    if not REAL.is_dir():
        pytest.skip(f"{REAL} is absent (real sensor frames)")
    line = {"image": str(REAL / "s1_image4_0.45_5.12.jpg"),
            "reference": str(REAL / "s1_image4_0.45_0.jpg"), "contact": True, "group": "press"}
    (tmp_path / "set.jsonl").write_text(json.dumps(line) + "\n")
    for area, found in ((None, 0), ((2.0, 100.0), 1)):
        report = geltip.evaluate("paper", real=tmp_path / "set.jsonl", sensor="allsight",
                                 area_mm2=area)
        assert report.summary["rows"][-1]["found"] == found, report.tables
