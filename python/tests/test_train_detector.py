"""python/examples/train_detector.py --quick: the sim-to-real check end to end (render,
compose on real no-contact frames, train, score the real set and held-out geltip frames),
and its predictions file scored by `geltip evaluate --predictions` gives the same report as
the run itself. Skipped without PyTorch or the real frames (../shared/real)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO, _find_cli

REAL = REPO / ".." / "shared" / "real" / "allsight"


def _example():
    """python/examples/train_detector.py as a module."""
    sys.path.insert(0, str(REPO / "python" / "examples"))
    try:
        import train_detector
    finally:
        sys.path.pop(0)
    return train_detector


def test_the_quick_run_scores_the_real_set_and_its_predictions_agree(tmp_path):
    pytest.importorskip("torch", reason="PyTorch is not installed (pip install torch)")
    pytest.importorskip("PIL", reason="Pillow is not installed")
    if not (REAL / "labels.json").is_file():
        pytest.skip(f"{REAL} is absent (real sensor frames)")
    out = tmp_path / "run"
    cli = _find_cli()
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    run = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "train_detector.py"), "--quick",
         "--real", str(REAL), "--out", str(out), "--geltip", str(cli), "--workers", "2"],
        capture_output=True, text=True, env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    training = json.loads((out / "training.json").read_text())
    assert training["samples"] > 400
    # Two networks (the default ensemble), each from its own seed, two epochs each.
    members = training["members"]
    assert [m["seed"] for m in members] == [1, 1 + 7919]
    assert all(len(m["epochs"]) == 2 for m in members)
    bce = lambda m: [e["presence_bce"] for e in m["epochs"]]  # noqa: E731
    assert bce(members[0]) != bce(members[1])
    lines = (out / "predictions.jsonl").read_text().splitlines()
    assert [json.loads(l)["sample"] for l in lines] == list(range(600))
    # The held-out geltip frames (60 in a quick run, a quarter empty) scored besides.
    check = training["synthetic_check"]
    assert check["visible"] + check["empty_frames"] == 60 and check["empty_frames"] > 0
    summary = json.loads((out / "eval-synthetic" / "summary.json").read_text())
    assert summary["samples"] == 60 and summary["detector"] == "synthetic-cnn"
    # The file, scored by the CLI, gives the run's own report.
    again = tmp_path / "again"
    p = subprocess.run(
        [str(cli), "evaluate", "--real", str(REAL / "labels.json"), "--sensor", "allsight",
         "--predictions", str(out / "predictions.jsonl"), "--out", str(again)],
        capture_output=True, text=True,
    )
    assert p.returncode == 0, p.stderr
    rows = lambda d: json.loads((d / "summary.json").read_text())["rows"]  # noqa: E731
    assert rows(again) == rows(out / "eval")
    # A missing real set is one line naming it.
    bad = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "train_detector.py"),
         "--real", str(tmp_path / "nowhere"), "--out", str(out)],
        capture_output=True, text=True, env=env,
    )
    assert bad.returncode != 0 and "nowhere/labels.json: not found" in bad.stderr
    bad = subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / "train_detector.py"),
         "--members", "0", "--out", str(out)],
        capture_output=True, text=True, env=env,
    )
    assert bad.returncode != 0 and "--members must be 1 or more, got 0" in bad.stderr


def test_the_footprint_tint_stays_on_the_footprint_within_its_bound(tmp_path):
    pytest.importorskip("torch", reason="PyTorch is not installed (pip install torch)")
    Image = pytest.importorskip("PIL.Image", reason="Pillow is not installed")
    import numpy as np
    train_detector = _example()
    ys, xs = np.mgrid[0:64, 0:64]
    disc = ((xs - 20) ** 2 + (ys - 30) ** 2 < 8**2).astype(np.uint8) * 255
    Image.fromarray(disc).save(tmp_path / "mask.png")
    shifts = []
    for k in range(20):
        t = train_detector.footprint_tint(tmp_path / "mask.png", 2.0, 12.0, np.random.default_rng(k))
        assert t.shape == (64, 64, 3)
        # Nothing beyond the softened edge (2 px Gaussian: gone 8 px out), the full shift
        # at the centre, never past the bound.
        far = (xs - 20) ** 2 + (ys - 30) ** 2 > 16**2
        assert np.abs(t[far]).max() < 1e-3
        assert np.abs(t).max() <= 12.0 + 1e-4
        shifts.append(t[30, 20])
    shifts = np.array(shifts)
    assert (shifts > 1).any() and (shifts < -1).any()  # either sign, per channel
    # A shallow press shifts in proportion to its depth (0.25 mm: a quarter).
    full = train_detector.footprint_tint(tmp_path / "mask.png", 2.0, 12.0, np.random.default_rng(3))
    shallow = train_detector.footprint_tint(tmp_path / "mask.png", 0.25, 12.0, np.random.default_rng(3))
    assert np.allclose(shallow, full / 4, atol=1e-4)


def test_the_ensemble_answers_with_its_members_mean():
    torch = pytest.importorskip("torch", reason="PyTorch is not installed (pip install torch)")
    pytest.importorskip("PIL", reason="Pillow is not installed")
    td = _example()
    nets = []
    for seed in (3, 4):
        torch.manual_seed(seed)
        nets.append(td.ContactNet().eval())
    g = torch.Generator().manual_seed(0)
    frame, reference = torch.rand(2, 3, 120, 120, generator=g), torch.rand(2, 3, 120, 120, generator=g)
    with torch.no_grad():
        prob, pixel = td.Ensemble(nets).eval()(frame, reference)
        each = [n(frame, reference) for n in nets]
    probs = [torch.sigmoid(logit) for logit, _, _ in each]
    pixels = [td.soft_argmax(heat, shape) for _, heat, shape in each]
    assert torch.allclose(prob, (probs[0] + probs[1]) / 2)
    assert torch.allclose(pixel, (pixels[0] + pixels[1]) / 2)
    # Untrained members from different seeds disagree, so the mean is neither one's answer.
    assert not torch.allclose(pixel, pixels[0], atol=1e-3)
    # One member is that member.
    with torch.no_grad():
        alone, where = td.Ensemble(nets[:1]).eval()(frame, reference)
    assert torch.allclose(alone, probs[0]) and torch.allclose(where, pixels[0])
