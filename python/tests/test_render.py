"""Simulator against the CLI: the same bytes, labels and depth maps for the same contact;
batches equal single renders; errors as Python exceptions with the CLI's messages."""
import json
import os
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import geltip
from conftest import _find_cli, read_png

# (CLI flags, the same contact as keyword arguments)
CONTACTS = [
    (
        ["--object", "sphere", "--at", "translation=5", "--azimuth", "30", "--depth", "1"],
        dict(object="sphere", at="translation=5", azimuth=30, depth=1),
    ),
    (
        ["--object", "torus", "--at", "rotation=30", "--spin", "15", "--depth", "0.6"],
        dict(object="torus", rotation=30, spin=15.0, depth=0.6),
    ),
    (
        ["--object", "cone", "--at", "s=4", "--azimuth", "200", "--tilt", "20",
         "--tilt-towards", "90", "--depth", "0.8"],
        dict(object="cone", at=("s", 4), azimuth=200, tilt=20, tilt_towards=90, depth=0.8),
    ),
]


def test_reference_matches_cli(sim, cli, tmp_path):
    cli("render", "--sensor", "paper", "--reference", "-o", tmp_path / "ref.png")
    image = sim.reference()
    assert image.shape == (480, 640, 3) and image.dtype == np.uint8
    np.testing.assert_array_equal(image, read_png(tmp_path / "ref.png"))


@pytest.mark.parametrize("flags, kwargs", CONTACTS, ids=["sphere", "torus", "tilted-cone"])
def test_render_matches_cli(sim, cli, tmp_path, flags, kwargs):
    png, labels, npy = tmp_path / "c.png", tmp_path / "c.json", tmp_path / "c.npy"
    printed = cli("render", "--sensor", "paper", *flags, "-o", png, "--labels", labels,
                  "--depth-map", npy)
    image, got_labels, depth = sim.render(**kwargs)
    assert image.shape == (480, 640, 3) and image.dtype == np.uint8
    assert depth.shape == (480, 640) and depth.dtype == np.float32
    want_image = read_png(png)
    assert (image != sim.reference()).any(), "the contact changed nothing"
    np.testing.assert_array_equal(image, want_image)
    # The depth map, bit for bit.
    np.testing.assert_array_equal(depth.view(np.uint32), np.load(npy).view(np.uint32))
    assert depth.max() > 0.1
    assert got_labels == json.loads(labels.read_text()) == printed
    # geltip's own decoder agrees with the pure-Python one.
    np.testing.assert_array_equal(geltip.load_image(png), want_image)


def test_pose_renders_the_same_bytes(sim):
    image, labels, _ = sim.render(object="sphere", at="rotation=45", azimuth=60, depth=1)
    again, labels2, _ = sim.render(object="sphere", pose=labels["pose"])
    np.testing.assert_array_equal(image, again)
    assert labels2["depth_mm"] == pytest.approx(1.0, abs=1e-6)
    # ... and as the CLI's text.
    text = ",".join(repr(v) for v in labels["pose"])
    np.testing.assert_array_equal(sim.render(object="sphere", pose=text)[0], image)


def batch_contacts():
    objects = ["cone", "sphere", "irregular-prism", "cylinder", "edge", "tube", "slab",
               "torus", "disc", "sphere"]
    return [
        dict(object=o, at=f"rotation={10 * k}" if k % 2 else f"translation={k}",
             azimuth=37.0 * k, spin=11.0 * k, depth=0.3 + 0.1 * k)
        for k, o in enumerate(objects)
    ]


def test_batch_equals_single_renders(sim):
    contacts = batch_contacts()
    assert len(contacts) > sim.batch_frames  # crosses a submission boundary
    images, labels, depths = sim.render_batch(contacts)
    assert images.shape == (len(contacts), 480, 640, 3) and images.dtype == np.uint8
    assert depths.shape == (len(contacts), 480, 640) and depths.dtype == np.float32
    assert len(labels) == len(contacts)
    reference = sim.reference()
    for k, c in enumerate(contacts):
        image, label, depth = sim.render(**c)
        assert (image != reference).any(), k
        np.testing.assert_array_equal(images[k], image, err_msg=f"contact {k}")
        np.testing.assert_array_equal(depths[k], depth, err_msg=f"contact {k}")
        assert labels[k] == label, k
    # Distinct frames: each slot holds its own contact.
    assert len({images[k].tobytes() for k in range(len(contacts))}) == len(contacts)


def test_the_batch_size_changes_no_frame(sim):
    contacts = batch_contacts()
    want = sim.render_batch(contacts)
    other = geltip.Simulator("paper")
    assert other.batch_frames == sim.batch_frames
    other.batch_frames = 3
    assert other.batch_frames == 3
    got = other.render_batch(contacts)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[2], want[2])
    assert got[1] == want[1]
    for bad in (0, geltip.MAX_BATCH + 1):
        with pytest.raises(ValueError, match="batch: .* frames a submission; 1 to"):
            other.batch_frames = bad


def test_a_batch_takes_tilted_and_posed_contacts_as_render_does(sim):
    # One input type: what render() takes, render_batch() takes, frame for frame.
    tilted = dict(object="cone", at=("s", 4), azimuth=200, tilt=20, tilt_towards=90, depth=0.8)
    image, labels = sim.render(**tilted)[:2]
    posed = dict(object="cone", pose=labels["pose"])
    images, batch_labels, _ = sim.render_batch([tilted, posed])
    np.testing.assert_array_equal(images[0], image)
    np.testing.assert_array_equal(images[1], sim.render(**posed)[0])
    assert batch_labels[0]["tilt_deg"] == labels["tilt_deg"]


def test_streams_share_a_batch_and_render_the_same_frames(sim):
    # Three renderers on devices of their own split the submissions between them, at the
    # same time: the frames, depth maps and labels are those of one renderer, in order.
    contacts = batch_contacts() * 4
    assert len(contacts) > 3 * sim.batch_frames  # a stream gets two submissions
    three = geltip.Simulator("paper", streams=3)
    images, labels, depths = three.render_batch(contacts)
    want, want_labels, want_depths = sim.render_batch(contacts)
    np.testing.assert_array_equal(images, want)
    np.testing.assert_array_equal(depths, want_depths)
    assert labels == want_labels
    n = len(batch_contacts())
    assert len({images[k].tobytes() for k in range(n)}) == n
    single = three.render(**contacts[3])
    np.testing.assert_array_equal(single[0], want[3])
    for bad in (0, 5):
        with pytest.raises(ValueError, match="streams"):
            geltip.Simulator("paper", streams=bad)


def test_batch_into_given_arrays(sim):
    contacts = batch_contacts()[:3]
    out = np.zeros((3, 480, 640, 3), np.uint8)
    depth_out = np.full((3, 480, 640), -1.0, np.float32)
    images, _, depths = sim.render_batch(contacts, out=out, depth_out=depth_out)
    assert images is out and depths is depth_out
    want, _, want_depth = sim.render_batch(contacts)
    np.testing.assert_array_equal(out, want)
    np.testing.assert_array_equal(depth_out, want_depth)
    images, _, none = sim.render_batch(contacts, depth_maps=False)
    assert none is None
    np.testing.assert_array_equal(images, want)
    empty, labels, _ = sim.render_batch([])
    assert empty.shape == (0, 480, 640, 3) and labels == []


def test_scene_matches_cli(sim, cli, tmp_path):
    scene = {"contacts": [
        {"object": "sphere", "at": "rotation=30", "depth": 1},
        {"object": "torus", "at": "translation=8", "azimuth": 180, "depth": 0.6},
    ]}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    printed = cli("render", "--sensor", "paper", "--scene", tmp_path / "scene.json",
                  "-o", tmp_path / "s.png")
    image, labels, depth = sim.render_scene(scene["contacts"])
    np.testing.assert_array_equal(image, read_png(tmp_path / "s.png"))
    assert labels == printed and len(labels["contacts"]) == 2


def test_gil_released_while_rendering(sim):
    """While a batch renders on another thread, this thread keeps running Python: the
    longest pause it sees is a small part of the batch's time (with the GIL held for the
    whole render it would be nearly all of it)."""
    contacts = batch_contacts() * 4
    done = threading.Event()
    thread = threading.Thread(target=lambda: (sim.render_batch(contacts), done.set()))
    longest, ticks = 0.0, 0
    start = last = time.perf_counter()
    thread.start()
    while thread.is_alive():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
        ticks += 1
    thread.join()
    elapsed = time.perf_counter() - start
    assert done.is_set()
    assert elapsed > 0.1, elapsed
    assert longest < 0.5 * elapsed, (longest, elapsed, ticks)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(object="sphere", at="rotation=30", depth=-1), "^depth: a press depth cannot be negative"),
        (dict(object="sphere", at="rotation=30", depth=float("nan")), "^depth: must be a finite number"),
        (dict(object="sphere", at="rotation=30", depth="deep"), "^depth: expected a number"),
        (dict(object="sphere", at="rotation=30"), "^depth: required"),
        (dict(at="rotation=30", depth=1), "^object: required"),
        (dict(object="banana", at="rotation=30", depth=1), "object 'banana'"),
        (dict(object="sphere", at="rotation=abc", depth=1), "^at: the value of 'rotation=abc' is not a number"),
        (dict(object="sphere", at="elevation=3", depth=1), "^at: expected rotation=<deg>, translation=<mm> or s=<mm>, got 'elevation=3'"),
        (dict(object="sphere", at=("elevation", 3), depth=1), "^at: unknown place 'elevation'"),
        (dict(object="sphere", depth=1), "^at: required"),
        (dict(object="sphere", at="rotation=30", rotation=30, depth=1), "^rotation: give one place"),
        (dict(object="sphere", translation=float("inf"), depth=1), "^at: translation must be a finite number, got inf"),
        (dict(object="sphere", at="rotation=30", azimuth=[1], depth=1), "^azimuth: expected a number"),
        (dict(object="sphere", at="rotation=30", tilt=95, depth=1), r"^tilt: must lie in \(-90, 90\) degrees"),
        (dict(object="sphere", pose=[1, 2, 3]), "^pose: expected 16 numbers"),
        (dict(object="sphere", pose="1,0,0,0", depth=1), "^depth: cannot be combined with pose"),
        (dict(object="/nonexistent/part.obj", at="rotation=30", depth=1), "part.obj"),
    ],
)
def test_bad_render_arguments(sim, kwargs, field):
    with pytest.raises(ValueError, match=field) as e:
        sim.render(**kwargs)
    assert isinstance(e.value, geltip.GeltipError)
    assert "\n" not in str(e.value)


def test_render_errors_match_cli(sim, cli, tmp_path):
    for flags, kwargs in [
        (["--at", "rotation=30", "--depth", "-1"], dict(at="rotation=30", depth=-1)),
        (["--at", "rotation=abc", "--depth", "1"], dict(at="rotation=abc", depth=1)),
        (["--at", "rotation=30", "--depth", "1", "--tilt", "95"],
         dict(at="rotation=30", depth=1, tilt=95)),
    ]:
        p = cli("render", "--sensor", "paper", "--object", "sphere", *flags, "-o",
                tmp_path / "x.png", check=False)
        assert p.returncode == 1
        with pytest.raises(ValueError) as e:
            sim.render(object="sphere", **kwargs)
        # The library names the contact's field; the command line names its flag.
        assert p.stderr.strip() == f"error: --{e.value}"


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", depth=1), dict(object="sphere", at="rotation=2")]), r"^contacts\[1\]\.depth: required"),
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", depth=-2)]), r"^contacts\[0\]\.depth: a press depth cannot be negative"),
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", dpth=1)]), r"^contacts\[0\]\.dpth: unknown key"),
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", depth=1, tilt=95)]), r"^contacts\[0\]\.tilt: must lie in"),
        (lambda sim: sim.render_batch(["sphere"]), r"^contacts\[0\]: expected a dict"),
        (lambda sim: sim.render_batch(3), "^contacts: expected a list"),
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", depth=1)], out=np.zeros((2, 480, 640, 3), np.uint8)), "^out: expected shape"),
        (lambda sim: sim.render_batch([dict(object="sphere", at="rotation=1", depth=1)], out=np.zeros((1, 480, 640, 3), np.float32)), "^out: expected a u8 array"),
        (lambda sim: sim.render_scene([]), "^scene: no contacts to render"),
    ],
)
def test_bad_batch_arguments(sim, call, field):
    with pytest.raises(ValueError, match=field):
        call(sim)


def run_python(code, **env):
    full = dict(os.environ, **env)
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, env=full, timeout=300)


def test_no_adapter_is_an_exception(tmp_path):
    code = """
        import geltip
        try:
            geltip.Simulator("paper")
        except geltip.GpuError as e:
            assert isinstance(e, RuntimeError)
            print(e)
        else:
            raise SystemExit("no error")
    """
    p = run_python(code, WGPU_ADAPTER_NAME="no-such-adapter-geltip")
    assert p.returncode == 0, p.stderr
    assert "no GPU adapter matches" in p.stdout
    r = subprocess.run([str(_find_cli()), "render", "--sensor", "paper", "--reference", "-o",
                        str(tmp_path / "r.png")], capture_output=True, text=True,
                       env=dict(os.environ, WGPU_ADAPTER_NAME="no-such-adapter-geltip"))
    assert r.returncode == 1
    assert r.stderr.strip() == f"error: {p.stdout.strip()}"


def test_gpu_timeout_is_an_exception():
    code = """
        import geltip
        try:
            sim = geltip.Simulator("paper")
            sim.render_batch([dict(object="sphere", at="rotation=30", depth=1)] * 8)
        except geltip.GpuError as e:
            print(e)
        else:
            raise SystemExit("no timeout")
    """
    p = run_python(code, GELTIP_GPU_TIMEOUT_S="0.000001")
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("gpu: ") and "\n" not in p.stdout.strip(), p.stdout


def test_mesh_object_matches_cli(sensor, cli, tmp_path):
    """A mesh file, preloaded by Simulator(objects=[...]) (baked once), renders the CLI's
    bytes; asking for it again uses the preloaded object."""
    cli("objects", "--out", tmp_path)
    mesh = str(tmp_path / "cone.obj")
    cli("render", "--sensor", "paper", "--object", mesh, "--at", "rotation=30", "--depth", "1",
        "-o", tmp_path / "m.png", "--labels", tmp_path / "m.json")
    sim = geltip.Simulator(sensor, objects=[mesh])
    image, labels, _ = sim.render(object=mesh, at="rotation=30", depth=1)
    np.testing.assert_array_equal(image, read_png(tmp_path / "m.png"))
    assert labels == json.loads((tmp_path / "m.json").read_text())
    assert labels["object"] == "cone"
    images, _, _ = sim.render_batch([dict(object=mesh, at="rotation=30", depth=1)])
    np.testing.assert_array_equal(images[0], image)
    with pytest.raises(ValueError, match=r"^objects\[0\]: expected a str or a path"):
        geltip.Simulator(sensor, objects=[3])


def test_host_speed_times_the_loop():
    """Two positive, finite times, the all-cores one no shorter than a tenth of the
    one-core one (the loop runs on each core at least once)."""
    speed = geltip.host_speed()
    assert set(speed) == {"one_core_ms", "all_cores_ms"}
    for v in speed.values():
        assert isinstance(v, float) and 0.0 < v < 60_000.0
    assert speed["all_cores_ms"] > 0.1 * speed["one_core_ms"]


def test_keep_freed_memory_applies_on_glibc():
    """The allocator setting applies on glibc Linux (False elsewhere), in a fresh process
    (it is process-wide), and rendering works after it."""
    import platform
    code = """
        import geltip
        kept = geltip.keep_freed_memory()
        geltip.Simulator("paper").render(object="sphere", at="rotation=30", depth=1.0)
        print(kept)
    """
    p = run_python(code)
    assert p.returncode == 0, p.stderr
    glibc = platform.system() == "Linux" and platform.libc_ver()[0] == "glibc"
    assert p.stdout.strip() == str(glibc), p.stdout
