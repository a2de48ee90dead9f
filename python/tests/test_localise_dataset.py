"""localise on rendered contacts (within 0.5 mm of the ground truth), and Dataset over a
small `geltip dataset` set."""
import json

import numpy as np
import pytest

import geltip
from conftest import write_png


@pytest.mark.parametrize(
    "contact",
    [
        dict(object="sphere", at="rotation=30", depth=1.0),
        dict(object="cone", at="translation=5", azimuth=120, depth=1.0),
        dict(object="cylinder", rotation=60, azimuth=250, depth=0.8),
    ],
)
def test_localise_within_half_a_millimetre(sim, sensor, contact):
    reference = sim.reference()
    image, labels, _ = sim.render(**contact)
    found = geltip.localise(sensor, reference, image)
    assert found["detected"], found
    truth = np.array(labels["contact_centre"])
    error = np.linalg.norm(np.array(found["point"]) - truth)
    assert error < 0.5, (error, found, truth)
    # The pixel maps onto the same point.
    point, _, region = sensor.unproject(np.array(found["pixel"]))
    assert geltip.REGION_NAMES[int(region)] == found["region"]
    assert np.linalg.norm(point - np.array(found["point"])) < 1e-6


def test_localise_matches_cli(sim, sensor, cli, tmp_path):
    cli("render", "--sensor", "paper", "--reference", "-o", tmp_path / "ref.png")
    cli("render", "--sensor", "paper", "--object", "edge", "--at", "rotation=45", "--depth",
        "1", "-o", tmp_path / "e.png")
    for method in ("surface", "paper"):
        printed = cli("localise", "--sensor", "paper", "--reference", tmp_path / "ref.png",
                      "--method", method, tmp_path / "e.png")
        got = geltip.localise(sensor, geltip.load_image(tmp_path / "ref.png"),
                              geltip.load_image(tmp_path / "e.png"), method=method)
        assert got == printed, method


def test_the_noise_option_raises_the_bar(sim, sensor):
    """A rendered contact stands out of a noise-free pair; said to come from a sensor far
    noisier than the pair shows, it no longer does."""
    reference = sim.reference()
    image, _, _ = sim.render(object="sphere", at="rotation=40", depth=0.5)
    assert geltip.localise(sensor, reference, image)["detected"] is True
    assert geltip.localise(sensor, reference, image, noise=2.0)["detected"] is True
    found = geltip.localise(sensor, reference, image, noise=200.0)
    assert found["detected"] is False and "no change stands out" in found["note"]


def test_no_contact_is_a_result(sim, sensor):
    reference = sim.reference()
    found = geltip.localise(sensor, reference, reference.copy())
    assert found["detected"] is False and found["point"] is None and found["note"]
    for threshold in (None, 1.0):
        found = geltip.localise(sensor, reference, reference.copy(), method="change",
                                threshold=threshold)
        assert found["detected"] is False and "no change stands out" in found["note"]


def test_localise_bad_arguments(sim, sensor):
    reference = sim.reference()
    with pytest.raises(ValueError, match="^frame: is 640x100 but the reference is 640x480"):
        geltip.localise(sensor, reference, reference[:100])
    with pytest.raises(ValueError, match="^image: expected .* dtype float64"):
        geltip.localise(sensor, reference, reference.astype(np.float64))
    with pytest.raises(ValueError, match="^reference: expected"):
        geltip.localise(sensor, "ref.png", reference)
    with pytest.raises(ValueError, match="^method: unknown 'magic'"):
        geltip.localise(sensor, reference, reference, method="magic")
    with pytest.raises(ValueError, match="^threshold: applies to method 'change'"):
        geltip.localise(sensor, reference, reference, method="surface", threshold=5.0)
    with pytest.raises(ValueError, match="^threshold: must be greater than 0"):
        geltip.localise(sensor, reference, reference, method="change", threshold=0.0)
    with pytest.raises(ValueError, match="^noise: applies to method 'change'"):
        geltip.localise(sensor, reference, reference, method="surface", noise=2.0)
    with pytest.raises(ValueError, match="^noise: must be a finite number"):
        geltip.localise(sensor, reference, reference, noise=float("nan"))
    with pytest.raises(ValueError, match="^area_mm2: applies to method 'change' or 'paper'"):
        geltip.localise(sensor, reference, reference, method="surface", area_mm2=(1.0, 9.0))
    with pytest.raises(ValueError, match="^area_mm2 9,1: needs 0 <= MIN <= MAX"):
        geltip.localise(sensor, reference, reference, area_mm2=(9.0, 1.0))
    # A non-contiguous view is accepted.
    flipped = np.ascontiguousarray(reference[::-1])[::-1]
    assert geltip.localise(sensor, reference, flipped)["detected"] is False


@pytest.fixture(scope="module")
def dataset_dir(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("set")
    cli("dataset", "--sensor", "paper", "--count", "5", "--seed", "3", "--out", out,
        "--depth-maps", "--masks", "--objects", "sphere,cone")
    return out


def test_dataset_reads_a_geltip_set(dataset_dir):
    ds = geltip.Dataset(dataset_dir)
    assert len(ds) == 5
    lines = [json.loads(l) for l in (dataset_dir / "labels.jsonl").read_text().splitlines()]
    for i in range(len(ds)):
        sample = ds[i]
        assert sample["index"] == i and sample["labels"] == lines[i]
        assert sample["image"].shape == (480, 640, 3) and sample["image"].dtype == np.uint8
        assert sample["depth"].shape == (480, 640) and sample["depth"].dtype == np.float32
        assert sample["mask"].dtype == bool
        # The mask is the label's pixel count, and the depth map's pressed pixels.
        assert int(sample["mask"].sum()) == lines[i]["mask_pixels"]
        np.testing.assert_array_equal(sample["mask"], sample["depth"] > 0.01)
    assert ds[-1]["index"] == 4 and [s["index"] for s in ds[1:3]] == [1, 2]
    with pytest.raises(IndexError):
        ds[5]
    assert sum(1 for _ in ds) == 5
    assert ds.manifest["options"]["count"] == 5


def test_dataset_matches_a_render(dataset_dir, sim):
    """A sample's image is what the simulator renders for its label's contact (no noise,
    no jitter in this set)."""
    label = geltip.Dataset(dataset_dir)[0]["labels"]
    image, _, _ = sim.render(object=label["object"], s=label["s_mm"],
                             azimuth=label["azimuth_deg"], spin=label["spin_deg"],
                             depth=label["depth_mm"])
    np.testing.assert_array_equal(image, geltip.Dataset(dataset_dir)[0]["image"])


def test_a_set_on_a_folder_of_backgrounds_gives_each_sample_its_reference(cli, tmp_path):
    folder = tmp_path / "backgrounds"
    folder.mkdir()
    for k in range(2):
        write_png(folder / f"bg{k}.png", np.full((480, 640, 3), 60 + 90 * k, np.uint8))
    out = tmp_path / "set"
    cli("dataset", "--sensor", "paper", "--count", "6", "--seed", "5", "--out", out,
        "--background", folder)
    for sample in geltip.Dataset(out):
        name = sample["labels"]["background"]
        want = 60 + 90 * int(name[2])
        assert sample["reference"].shape == (480, 640, 3)
        assert (sample["reference"] == want).all()


def test_dataset_without_labels(tmp_path):
    with pytest.raises(FileNotFoundError, match="labels.jsonl"):
        geltip.Dataset(tmp_path)


def test_dataset_reads_labels_by_the_librarys_rule(dataset_dir, tmp_path):
    """As every reader of labels.jsonl: an unfinished last line (a run killed while writing
    it) is left out; a bad line elsewhere, or a sample named twice, is an error naming it."""
    import shutil

    text = (dataset_dir / "labels.jsonl").read_text()
    lines = text.splitlines()
    for name, body, says in (
        ("torn", text + '{"index": 5, "ima', None),
        ("bad", lines[0] + "\n{oops\n" + "\n".join(lines[1:]) + "\n", "line 2: not valid JSON"),
        ("twice", text + lines[0] + "\n", "line 6: index: sample 0 again"),
    ):
        root = tmp_path / name
        shutil.copytree(dataset_dir, root)
        (root / "labels.jsonl").write_text(body)
        if says is None:
            assert len(geltip.Dataset(root)) == 5
        else:
            with pytest.raises(geltip.InvalidArgumentError, match=says):
                geltip.Dataset(root)


def test_dataset_is_a_torch_dataset_when_torch_imports(dataset_dir):
    from geltip import dataset

    if dataset.TORCH:
        import torch.utils.data

        assert isinstance(geltip.Dataset(dataset_dir), torch.utils.data.Dataset)
    else:
        from collections.abc import Sequence

        assert isinstance(geltip.Dataset(dataset_dir), Sequence)


def test_dataset_subclasses_torch_dataset(dataset_dir, monkeypatch):
    """With PyTorch importable, Dataset is a torch.utils.data.Dataset (checked here with a
    stand-in torch module when PyTorch is not installed)."""
    import importlib
    import sys
    import types

    import geltip.dataset

    if not geltip.dataset.TORCH:
        class FakeTorchDataset:
            pass

        torch = types.ModuleType("torch")
        utils = types.ModuleType("torch.utils")
        data = types.ModuleType("torch.utils.data")
        data.Dataset = FakeTorchDataset
        torch.utils, utils.data = utils, data
        for name, module in [("torch", torch), ("torch.utils", utils), ("torch.utils.data", data)]:
            monkeypatch.setitem(sys.modules, name, module)
    try:
        reloaded = importlib.reload(geltip.dataset)
        import torch.utils.data

        ds = reloaded.Dataset(dataset_dir)
        assert reloaded.TORCH and isinstance(ds, torch.utils.data.Dataset)
        assert len(ds) == 5 and ds[2]["index"] == 2
    finally:
        monkeypatch.undo()
        importlib.reload(geltip.dataset)
