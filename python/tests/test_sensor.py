"""Sensor.project / unproject on arrays against the CLI's JSON for the same points."""
import numpy as np
import pytest

import geltip
from conftest import REPO

REGION_OF = {"none": 0, "hemisphere": 1, "cylinder": 2}

# Pixels across the paper sensor's image: the centre, the tip's neighbourhood, the
# hemisphere and the cylinder, a corner beyond the 170 degree field of view, and two pixels
# outside the image.
PIXELS = np.array(
    [
        [320.0, 240.0],
        [400.0, 240.0],
        [320.0, 100.0],
        [150.5, 300.25],
        [600.0, 240.0],
        [320.0, 479.0],
        [10.0, 10.0],
        [-3.0, 100.0],
        [320.0, 480.0],
        [500.0, 410.0],
    ]
)


def test_unproject_matches_cli(sensor, cli):
    points, normals, region = sensor.unproject(PIXELS)
    assert points.shape == (len(PIXELS), 3) and normals.shape == (len(PIXELS), 3)
    assert region.shape == (len(PIXELS),) and region.dtype == np.int8
    seen = set()
    for k, (u, v) in enumerate(PIXELS):
        want = cli("unproject", "--sensor", "paper", u, v)
        seen.add(want["region"])
        assert region[k] == REGION_OF[want["region"]], (k, want)
        assert geltip.region_names(region)[k] == want["region"]
        if want["region"] == "none":
            assert np.isnan(points[k]).all() and np.isnan(normals[k]).all()
        else:
            # The same f64 arithmetic: equal to the last bit (JSON prints shortest
            # round-trip decimals).
            assert points[k].tolist() == want["point"], k
            assert normals[k].tolist() == want["normal"], k
    # The sample covers every case.
    assert seen == {"none", "hemisphere", "cylinder"}


def test_project_matches_cli(sensor, cli):
    visible, _, region = sensor.unproject(PIXELS)
    visible = visible[region != 0]
    # Plus points the camera cannot see: outside the finger, at the camera, beyond the
    # field of view (behind the camera, inside the tube).
    hidden = np.array([[20.0, 0.0, 20.0], [0.0, 0.0, 0.0], [0.0, 1.0, -5.0]])
    points = np.vstack([visible, hidden])
    pixels, reasons = sensor.project(points, reasons=True)
    assert pixels.shape == (len(points), 2)
    for k, p in enumerate(points):
        want = cli("project", "--sensor", "paper", *p)
        if want["pixel"] is None:
            assert np.isnan(pixels[k]).all(), k
            assert reasons[k] == want["reason"], k
        else:
            assert pixels[k].tolist() == want["pixel"], k
            assert reasons[k] is None
    assert sum(r is not None for r in reasons) == len(hidden)


def test_round_trip(sensor):
    u, v = np.meshgrid(np.linspace(0, 639, 33), np.linspace(0, 479, 25))
    pixels = np.stack([u.ravel(), v.ravel()], axis=1)
    points, normals, region = sensor.unproject(pixels)
    ok = region != 0
    assert 0.3 < ok.mean() < 1.0
    back = sensor.project(points[ok])
    assert np.abs(back - pixels[ok]).max() < 1e-6
    assert np.allclose(np.linalg.norm(normals[ok], axis=1), 1.0)
    # NaN only where not visible.
    assert not np.isnan(points[ok]).any() and np.isnan(points[~ok]).all()


def test_single_point_and_lists(sensor):
    pixel = sensor.project([3.5, 0, 26.6])
    assert pixel.shape == (2,)
    point, normal, region = sensor.unproject(pixel)
    assert point.shape == (3,) and normal.shape == (3,) and region.shape == ()
    # Integer input is converted.
    assert sensor.unproject(np.array([[320, 240]]))[2].tolist() == [geltip.REGION_HEMISPHERE]


def test_from_toml_file_and_text(tmp_path):
    path = REPO / "assets" / "sensors" / "tube13.toml"
    from_file = geltip.Sensor.from_toml(path)
    from_text = geltip.Sensor.from_toml(path.read_text(), name="mine")
    preset = geltip.Sensor("tube13")
    px = np.array([[320.0, 200.0], [100.0, 240.0]])
    for s in (from_file, from_text):
        for a, b in zip(s.unproject(px), preset.unproject(px)):
            np.testing.assert_array_equal(a, b)
    assert from_text.name == "mine" and from_file.config == preset.config
    # Sensor(path) as --sensor does.
    assert geltip.Sensor(str(path)).config == preset.config


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: geltip.Sensor("nonesuch"), "unknown sensor 'nonesuch'"),
        (
            lambda: geltip.Sensor.from_toml(
                (REPO / "assets/sensors/paper.toml").read_text().replace("focal_px = 180.0", "focal_px = -1.0")
            ),
            "lens.focal_px",
        ),
        (lambda: geltip.Sensor.from_toml("[finger]\nradius_mm = 7.5\n"), "sensor config"),
        (lambda: geltip.Sensor("paper").project(np.zeros((4, 2))), "points"),
        (lambda: geltip.Sensor("paper").unproject(np.zeros((4, 3))), "pixels"),
        (lambda: geltip.Sensor("paper").unproject("middle"), "pixels"),
    ],
)
def test_bad_sensor_arguments(make, field):
    with pytest.raises(ValueError, match=field) as e:
        make()
    assert isinstance(e.value, geltip.GeltipError)
    assert "\n" not in str(e.value)


def test_sensor_errors_match_cli(cli):
    p = cli("unproject", "--sensor", "nonesuch", 1, 2, check=False)
    assert p.returncode != 0
    with pytest.raises(ValueError) as e:
        geltip.Sensor("nonesuch")
    assert p.stderr.strip() == f"error: {e.value}"
