"""Simulator.render_scenes, add_mesh, sized primitives and approach from Python, and
save_image: the pieces geltip.mujoco is built on, against the CLI and single renders."""
import re

import numpy as np
import pytest

import geltip

# A sphere of radius 5 beside the side, 0.7 mm in along -x, its own axes the camera's.
SIDE_POSE = [1, 0, 0, 7.5 + 5 - 0.7, 0, 1, 0, 0, 0, 0, 1, 10 + 5, 0, 0, 0, 1]


def test_a_primitive_renders_as_the_cli_does(sim, cli, tmp_path):
    image, labels, _ = sim.render(object="box:x=9,y=5,z=3", at="rotation=40", depth=0.8)
    out = cli(
        "render", "--sensor", "paper", "--object", "box:x=9,y=5,z=3", "--at", "rotation=40",
        "--depth", "0.8", "-o", tmp_path / "box.png",
    )
    assert out["object"] == labels["object"] == "box:x=9,y=5,z=3"
    assert np.array_equal(image, geltip.load_image(tmp_path / "box.png"))
    p = cli("render", "--sensor", "paper", "--object", "box:x=9,y=5", "--at", "s=1",
            "--depth", "1", "-o", tmp_path / "x.png", check=False)
    assert p.returncode != 0
    assert p.stderr.strip() == (
        "error: object 'box:x=9,y=5': a box needs x, y, z (its edge lengths, mm); z is missing"
    )


def test_approach_sets_the_depth_of_a_pose(sim, cli, tmp_path):
    _, labels, _ = sim.render(object="sphere:r=5", pose=SIDE_POSE, approach=[-1, 0, 0])
    assert abs(labels["depth_mm"] - 0.7) < 1e-6
    out = cli(
        "render", "--sensor", "paper", "--object", "sphere:r=5",
        "--pose", " ".join(map(str, SIDE_POSE)), "--approach", "-1,0,0",
        "-o", tmp_path / "s.png",
    )
    assert abs(out["depth_mm"] - 0.7) < 1e-6
    for approach, says in [
        ([0, 0], "approach: expected 3 numbers"),
        ([0, 0, 0], "approach: [0, 0, 0] has no direction"),
        ("x", "approach: 'x' is not a number"),
    ]:
        with pytest.raises(geltip.InvalidArgumentError, match="^" + re.escape(says)):
            sim.render(object="sphere:r=5", pose=SIDE_POSE, approach=approach)
    with pytest.raises(geltip.InvalidArgumentError, match="^approach: is for a pose"):
        sim.render(object="sphere", at="s=1", depth=1, approach=[0, 0, 1])


def test_render_scenes_equals_render_scene_and_skips_what_does_not_touch(sim):
    near = {"object": "sphere:r=5", "pose": SIDE_POSE, "approach": [-1, 0, 0]}
    short = dict(near, pose=[*SIDE_POSE[:3], 7.5 + 5 + 0.4, *SIDE_POSE[4:]])
    tap = {"object": "cone", "at": "rotation=20", "azimuth": 200, "depth": 1.0}
    scenes = [[near], [tap, near], [short], [], [short, tap]] * 2  # two submissions
    images, labels, depths = sim.render_scenes(scenes, skip_untouching=True, depth_maps=True)
    assert images.shape == (10, 480, 640, 3) and depths.shape == (10, 480, 640)
    reference = sim.reference()
    for k, (scene, image, label) in enumerate(zip(scenes, images, labels)):
        kept = [c for c in scene if c is not short]
        assert label["untouched"] == [i for i, c in enumerate(scene) if c is short], k
        if kept:
            one, one_labels, one_depth = sim.render_scene(kept)
            assert np.array_equal(image, one), k
            assert np.array_equal(depths[k], one_depth), k
            assert label["contacts"] == one_labels["contacts"], k
        else:
            assert np.array_equal(image, reference) and label["contacts"] == [], k
    # Without skipping, a pose short of touching is an error naming its scene.
    with pytest.raises(geltip.InvalidArgumentError, match=r"^scenes\[2\]: contacts\[0\]\.pose: "
                       r"the object does not touch the finger: it is 0\.400 mm short"):
        sim.render_scenes(scenes)
    with pytest.raises(geltip.InvalidArgumentError, match=r"^scenes\[1\]: contacts\[0\]\.depth"):
        sim.render_scenes([[near], [dict(tap, depth=-1)]], skip_untouching=True)
    with pytest.raises(geltip.InvalidArgumentError, match=r"^scenes: expected a list of lists"):
        sim.render_scenes(3)


def test_add_mesh_equals_the_same_vertices_from_a_file(sim, tmp_path):
    # A tetrahedron-topped prism: vertices exact in float32 and in the OBJ's text.
    v = np.array(
        [[-3, -2, -4], [3, -2, -4], [3, 2, -4], [-3, 2, -4], [-3, -2, 0], [3, -2, 0], [3, 2, 0],
         [-3, 2, 0]], dtype=np.float64,
    ) + [0.5, 0.25, 1.0]
    f = np.array(
        [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
         [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]],
    )
    top = sim.add_mesh("brick", v, f)
    assert np.allclose(top, [0.5, 0.25, 1.0])
    path = tmp_path / "brick.obj"
    path.write_text(
        "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f.tolist())
    )
    a, la, _ = sim.render(object="brick", at="translation=5", azimuth=60, depth=0.9)
    b, lb, _ = sim.render(object=str(path), at="translation=5", azimuth=60, depth=0.9)
    assert np.array_equal(a, b) and la["contact_centre"] == lb["contact_centre"]
    assert la["object"] == "brick"
    for name, vertices, faces, says in [
        ("sphere", v, f, "mesh 'sphere': is a built-in solid's or a primitive's name"),
        ("box:x=1", v, f, "mesh 'box:x=1': is a built-in solid's or a primitive's name"),
        ("x", v[:, :2], f, r"vertices: expected an \(N, 3\) array, got shape \[8, 2\]"),
        ("x", v, -f, "faces: face 0 holds 0, not a vertex index|faces: face 0 holds -2"),
        ("x", v, f + 8, "mesh 'x': triangle 0 uses vertex index 8 but there are only 8"),
        ("x", v * np.nan, f, "mesh 'x': vertex 0 is not finite"),
    ]:
        with pytest.raises(geltip.InvalidArgumentError, match=says):
            sim.add_mesh(name, vertices, faces)


def test_save_image_writes_what_load_image_reads(tmp_path):
    image = (np.arange(7 * 5 * 3) % 251).astype(np.uint8).reshape(7, 5, 3)
    geltip.save_image(tmp_path / "a.png", image)
    assert np.array_equal(geltip.load_image(tmp_path / "a.png"), image)
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"]
    with pytest.raises(geltip.InvalidArgumentError, match=r"^image: expected an \(H, W, 3\)"):
        geltip.save_image(tmp_path / "b.png", image[..., 0])
    with pytest.raises(geltip.GeltipIOError, match="a.png"):
        geltip.save_image(tmp_path / "a.png" / "c.png", image)  # under a file
