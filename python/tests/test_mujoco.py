"""geltip.mujoco: MuJoCo geoms against geltip's own renders of the same poses, the finger's
MJCF, rollouts recorded to disk, geoms geltip cannot model."""
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import geltip

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo's Python package is not installed (pip install 'geltip[mujoco]')"
)
from geltip.mujoco import Finger, finger_mjcf, record  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
PRISM = REPO / "assets" / "objects" / "irregular-prism.obj"

# The finger's place in the world: turned and moved, so that frames must compose.
FINGER_POS = np.array([0.05, -0.02, 0.3])
FINGER_QUAT = np.array([np.cos(0.4), np.sin(0.4) * 0.6, 0.0, np.sin(0.4) * 0.8])

# Mocap bodies, each holding one geom: parked far away until a test places them.
GEOMS = """
<body name="ball" mocap="true" pos="1 0 0"><geom name="ball" type="sphere" size="0.005"/></body>
<body name="box" mocap="true" pos="1.1 0 0"><geom name="box" type="box" size="0.004 0.003 0.002"/></body>
<body name="capsule" mocap="true" pos="1.2 0 0"><geom name="capsule" type="capsule" size="0.0025 0.004"/></body>
<body name="prism" mocap="true" pos="1.3 0 0"><geom name="prism" type="mesh" mesh="prism"/></body>
<body name="ball2" mocap="true" pos="1.4 0 0"><geom name="ball2" type="sphere" size="0.004"/></body>
"""


def model_xml(extra: str = "", assets: str = "") -> str:
    quat = " ".join(repr(float(v)) for v in FINGER_QUAT / np.linalg.norm(FINGER_QUAT))
    pos = " ".join(repr(float(v)) for v in FINGER_POS)
    return f"""<mujoco>
  <asset><mesh name="prism" file="{PRISM}" scale="0.001 0.001 0.001"/>{assets}</asset>
  <worldbody>
    <body name="hand" pos="{pos}" quat="{quat}">{finger_mjcf("paper")}</body>
    {GEOMS}{extra}
  </worldbody>
</mujoco>"""


@pytest.fixture(scope="module")
def scene(sim):
    model = mujoco.MjModel.from_xml_string(model_xml())
    data = mujoco.MjData(model)
    finger = Finger(model, body="geltip", simulator=sim)
    return model, data, finger


def finger_frame(model, data):
    mujoco.mj_forward(model, data)
    b = model.body("geltip").id
    return data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy()


def place(model, data, body, r_cam, p_cam_mm):
    """Puts mocap body ``body``'s frame at rotation ``r_cam`` and position ``p_cam_mm`` in
    the finger's camera frame."""
    fp, fr = finger_frame(model, data)
    m = model.body(body).mocapid[0]
    data.mocap_pos[m] = fp + fr @ (np.asarray(p_cam_mm) / 1000.0)
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, (fr @ r_cam).reshape(-1))
    data.mocap_quat[m] = q


def park(model, data):
    for k, name in enumerate(["ball", "box", "capsule", "prism", "ball2"]):
        m = model.body(name).mocapid[0]
        data.mocap_pos[m] = [1.0 + 0.1 * k, 0.0, 0.0]
        data.mocap_quat[m] = [1.0, 0.0, 0.0, 0.0]


def rotation(axis, angle):
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float) / np.linalg.norm(axis), angle)
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, q)
    return r.reshape(3, 3)


def matrix(r, origin):
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, origin
    return m.reshape(-1)


def side(height, azimuth_deg):
    """The outward normal of the finger's side at azimuth ``azimuth_deg`` and a point of the
    side ``height`` mm above the camera."""
    a = np.radians(azimuth_deg)
    n = np.array([np.cos(a), np.sin(a), 0.0])
    return n, 7.5 * n + np.array([0.0, 0.0, height])


def render_one(model, data, finger):
    mujoco.mj_forward(model, data)
    return finger.render(data)


def test_a_sphere_1mm_in_renders_its_pose_bytes(scene, sim):
    model, data, finger = scene
    park(model, data)
    n, at = side(10.0, 40.0)
    spin = rotation([1, 2, 3], 0.7)  # a sphere's own turn does not matter, its pose does
    centre = at + (5.0 - 1.0) * n
    place(model, data, "ball", spin, centre)
    image, labels = render_one(model, data, finger)
    [c] = labels["contacts"]
    assert c["geom"] == "ball" and c["object"] == "sphere:r=5"
    assert abs(c["depth_mm"] - 1.0) <= 0.02
    # The same pose, worked out here: the top 5 mm above the centre along its own +z.
    want = matrix(spin, centre + spin @ [0, 0, 5.0])
    assert np.allclose(c["pose"], want, atol=1e-9)
    ref, ref_labels, _ = sim.render(object="sphere:r=5", pose=c["pose"], approach=-n)
    assert np.array_equal(image, ref)
    assert abs(ref_labels["depth_mm"] - c["depth_mm"]) < 1e-9
    assert labels["mask_pixels"] == ref_labels["mask_pixels"] > 1000
    # The comparison can fail: 0.2 mm deeper is other bytes.
    deeper = want.copy()
    deeper[[3, 7, 11]] -= 0.2 * n
    other, _, _ = sim.render(object="sphere:r=5", pose=deeper, approach=-n)
    assert not np.array_equal(image, other)


@pytest.mark.parametrize(
    "body,text,r_cam,centre_out",
    [
        # A box turned so that its +z face (4 mm deep: half-size 2) faces the finger.
        ("box", "box:x=8,y=6,z=4", None, 2.0),
        # A capsule lying along the finger's parallel, its side pressing.
        ("capsule", "capsule:r=2.5,l=8", "capsule", 2.5),
    ],
)
def test_a_box_and_a_capsule_render_their_pose_bytes(scene, sim, body, text, r_cam, centre_out):
    model, data, finger = scene
    park(model, data)
    n, at = side(12.0, 200.0)
    if r_cam is None:
        # +z towards the finger (-n), spun 25 degrees about it.
        z = -n
        x = np.cross([0.0, 0.0, 1.0], z)
        x /= np.linalg.norm(x)
        r = np.column_stack([x, np.cross(z, x), z]) @ rotation([0, 0, 1], np.radians(25))
    else:
        # Axis (z) along the parallel, tangent to the side.
        t = np.cross([0.0, 0.0, 1.0], n)
        r = np.column_stack([n, np.cross(t, n), t])
    centre = at + (centre_out - 1.0) * n
    place(model, data, body, r, centre)
    image, labels = render_one(model, data, finger)
    [c] = labels["contacts"]
    assert c["geom"] == body and c["object"] == text
    assert abs(c["depth_mm"] - 1.0) <= 0.02, c["depth_mm"]
    top = {"box": 2.0, "capsule": 2.5 + 4.0}[body]
    assert np.allclose(c["pose"], matrix(r, centre + r @ [0, 0, top]), atol=1e-9)
    ref, ref_labels, _ = sim.render(object=text, pose=c["pose"], approach=-n)
    assert np.array_equal(image, ref)
    assert abs(ref_labels["depth_mm"] - 1.0) <= 0.02


def test_a_mesh_geom_equals_the_same_mesh_loaded_as_obj(scene, sim, tmp_path):
    model, data, finger = scene
    park(model, data)
    n, at = side(14.0, 300.0)
    r = rotation([0.3, -1.0, 0.4], 1.1)
    place(model, data, "prism", r, at + 2.0 * n)
    image, labels = render_one(model, data, finger)
    [c] = labels["contacts"]
    assert c["geom"] == "prism" and c["object"] == "mesh:prism"
    assert c["depth_mm"] > 0.1 and labels["mask_pixels"] > 500
    # The mesh as MuJoCo holds it (re-centred on its inertial frame), in float32 mm, as an
    # OBJ file; its top (the highest vertices' box centre) is the object's origin.
    g = model.geom("prism")
    mesh = model.mesh(g.dataid[0])
    a, nv = mesh.vertadr[0], mesh.vertnum[0]
    fa, nf = mesh.faceadr[0], mesh.facenum[0]
    v = model.mesh_vert[a : a + nv].astype(np.float32) * np.float32(1000)
    f = model.mesh_face[fa : fa + nf]
    path = tmp_path / "prism.obj"
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in v]
    lines += [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in f]
    path.write_text("\n".join(lines) + "\n")
    v = v.astype(np.float64)
    high = v[v[:, 2] >= v[:, 2].max() - 1e-6]
    top = np.array([*(high[:, :2].min(0) + high[:, :2].max(0)) / 2, v[:, 2].max()])
    fp, fr = finger_frame(model, data)
    gr = fr.T @ data.geom_xmat[g.id].reshape(3, 3)
    gp = fr.T @ (data.geom_xpos[g.id] - fp) * 1000
    assert np.allclose(c["pose"], matrix(gr, gp + gr @ top), atol=1e-9)
    [contact] = finger.scene(data).contacts
    ref, ref_labels, _ = sim.render(
        object=str(path), pose=c["pose"], approach=contact["approach"]
    )
    assert np.array_equal(image, ref)
    assert ref_labels["contact_centre"] == c["contact_centre"]


def test_geoms_that_do_not_reach_give_the_empty_frame(scene, sim):
    model, data, finger = scene
    park(model, data)
    image, labels = render_one(model, data, finger)
    assert labels["contacts"] == [] and labels["mask_pixels"] == 0
    assert np.array_equal(image, sim.reference())
    # A box whose bounding sphere reaches the finger, its face 0.5 mm short of touching:
    # left out.
    n, at = side(8.0, 90.0)
    z = -n
    x = np.cross([0.0, 0.0, 1.0], z)
    place(model, data, "box", np.column_stack([x, np.cross(z, x), z]), at + 2.5 * n)
    mujoco.mj_forward(model, data)
    assert len(finger.scene(data).contacts) == 1
    image, labels = render_one(model, data, finger)
    assert labels["contacts"] == [] and np.array_equal(image, sim.reference())


def test_two_geoms_give_two_labelled_contacts(scene, sim):
    model, data, finger = scene
    park(model, data)
    n1, at1 = side(6.0, 0.0)
    n2, at2 = side(16.0, 180.0)
    place(model, data, "ball", np.eye(3), at1 + 4.2 * n1)
    place(model, data, "ball2", np.eye(3), at2 + 3.4 * n2)
    image, labels = render_one(model, data, finger)
    got = {c["geom"]: c for c in labels["contacts"]}
    assert set(got) == {"ball", "ball2"}
    assert abs(got["ball"]["depth_mm"] - 0.8) < 0.02
    assert abs(got["ball2"]["depth_mm"] - 0.6) < 0.02
    assert all(c["mask_pixels"] > 100 for c in got.values())
    both, both_labels, _ = sim.render_scene(finger.scene(data).contacts)
    assert np.array_equal(image, both)
    assert [c["depth_mm"] for c in both_labels["contacts"]] == [
        c["depth_mm"] for c in labels["contacts"]
    ]


def test_render_many_renders_the_single_frames(scene):
    model, data, finger = scene
    park(model, data)
    n, at = side(9.0, 130.0)
    scenes, singles = [], []
    for k in range(10):  # two submissions
        place(model, data, "ball", np.eye(3), at + (5.05 - 0.1 * k) * n)
        mujoco.mj_forward(model, data)
        scenes.append(finger.scene(data))
        singles.append(finger.render(data))
    images, labels = finger.render_many(scenes)
    assert images.shape == (10, 480, 640, 3)
    for (image, label), many, many_labels in zip(singles, images, labels):
        assert np.array_equal(image, many)
        assert label == many_labels
    assert labels[0]["contacts"] == [] and len(labels[-1]["contacts"]) == 1


def test_the_mjcf_finger_has_the_sensors_size():
    for name in ["paper", "tube21"]:
        sensor = geltip.Sensor(name)
        model = mujoco.MjModel.from_xml_string(
            f"<mujoco><worldbody>{finger_mjcf(sensor, name='f')}</worldbody></mujoco>"
        )
        r = sensor.config["finger"]["radius_mm"] / 1000
        d = sensor.config["finger"]["cylinder_length_mm"] / 1000
        tube, tip = model.geom("f_tube"), model.geom("f_tip")
        assert tube.type[0] == mujoco.mjtGeom.mjGEOM_CYLINDER
        assert np.allclose(tube.size[:2], [r, d / 2]) and np.allclose(tube.pos, [0, 0, d / 2])
        assert tip.type[0] == mujoco.mjtGeom.mjGEOM_SPHERE
        assert np.isclose(tip.size[0], r) and np.allclose(tip.pos, [0, 0, d])
        assert np.allclose(model.site("f_camera").pos, 0)


def test_geoms_geltip_cannot_model_are_skipped_with_a_warning(sim):
    xml = model_xml(
        extra='<geom name="floor" type="plane" size="1 1 0.1" pos="0 0 -1"/>'
        '<geom name="terrain" type="hfield" hfield="hf" pos="0 0 -2"/>'
        '<geom name="slab" type="box" size="6 6 0.1" pos="0 0 -3"/>',
        assets='<hfield name="hf" nrow="4" ncol="4" size="1 1 0.1 0.1"/>',
    )
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    says = (r"skipping geoms geltip cannot model: 'floor' \(plane\), 'terrain' \(height "
            r"field\), 'slab' \(box box:x=12000,y=12000,z=200: sizes from 0.001 to 10000 mm\)")
    with pytest.warns(UserWarning, match=says):
        finger = Finger(model, body="geltip", simulator=sim)
    assert "floor" not in [g.name for g in finger.geoms]
    park(model, data)
    n, at = side(10.0, 0.0)
    place(model, data, "ball", np.eye(3), at + 4.5 * n)
    _, labels = render_one(model, data, finger)
    assert [c["geom"] for c in labels["contacts"]] == ["ball"]


def test_bad_bindings_are_named(scene, sim):
    model, _, _ = scene
    with pytest.raises(ValueError, match="body: no body named 'thumb'"):
        Finger(model, body="thumb", simulator=sim)
    with pytest.raises(ValueError, match="geoms: no geom named 'pear'"):
        Finger(model, body="geltip", geoms=["ball", "pear"], simulator=sim)
    finger = Finger(model, body="geltip", geoms=["ball"], simulator=sim)
    assert [g.name for g in finger.geoms] == ["ball"]


def rollout_model():
    """A ball on a slide joint, driven into the finger's side and back by a position
    actuator."""
    xml = f"""<mujoco><option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    {finger_mjcf("paper")}
    <body name="slider" pos="0.016 0 0.012">
      <joint name="x" type="slide" axis="1 0 0" damping="2"/>
      <geom name="ball" type="sphere" size="0.005" mass="0.01"/>
    </body>
  </worldbody>
  <actuator><position joint="x" kp="50"/></actuator>
</mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def press_and_release(model, data):
    data.ctrl[0] = -0.006 if data.time < 0.1 else 0.0


def test_a_rollout_recorded_twice_is_byte_identical(sim, tmp_path):
    outs = []
    for k in range(2):
        model = rollout_model()
        data = mujoco.MjData(model)
        finger = Finger(model, body="geltip", simulator=sim)
        out = tmp_path / f"run{k}"
        summary = record(model, data, finger, 120, out, every=10, control=press_and_release)
        assert summary["frames"] == 12 and summary["contact_frames"] >= 2
        outs.append(out)
    files = sorted(p.relative_to(outs[0]) for p in outs[0].rglob("*") if p.is_file())
    assert {"dataset.json", "labels.jsonl", "reference.png", "video.gif"} <= {
        str(f) for f in files
    }
    assert len([f for f in files if str(f).startswith("images/")]) == 12
    for f in files:
        assert (outs[0] / f).read_bytes() == (outs[1] / f).read_bytes(), f
    lines = [json.loads(line) for line in (outs[0] / "labels.jsonl").read_text().splitlines()]
    assert [line["step"] for line in lines] == list(range(10, 121, 10))
    assert all(abs(line["time"] - 0.002 * line["step"]) < 1e-12 for line in lines)
    assert all(set(line["geoms"]) == {"ball"} and len(line["geoms"]["ball"]) == 16 for line in lines)
    deepest = max((c for line in lines for c in line["contacts"]), key=lambda c: c["depth_mm"])
    assert deepest["geom"] == "ball" and deepest["depth_mm"] > 0.3
    # The dataset reader takes it as it takes `geltip dataset`'s sets.
    ds = geltip.Dataset(outs[0])
    assert len(ds) == 12 and ds[3]["image"].shape == (480, 640, 3)
    assert ds.manifest["source"] == "geltip.mujoco.record"
    # Nothing is left beside the output (the temporary directory was renamed).
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run0", "run1"]


def test_record_refuses_a_used_directory_and_leaves_nothing_on_failure(sim, tmp_path):
    model = rollout_model()
    data = mujoco.MjData(model)
    finger = Finger(model, body="geltip", simulator=sim)
    used = tmp_path / "used"
    used.mkdir()
    (used / "x").write_text("x")
    with pytest.raises(ValueError, match="exists and is not an empty directory"):
        record(model, data, finger, 10, used)

    def fails(model, data):
        if data.time > 0.01:
            raise RuntimeError("controller failed")

    with pytest.raises(RuntimeError, match="controller failed"):
        record(model, data, finger, 50, tmp_path / "new", control=fails)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["used"]
    with pytest.raises(ValueError, match="every: expected a positive"):
        record(model, data, finger, 10, tmp_path / "new", every=0)
    with pytest.raises(ValueError, match="video: only GIF"):
        record(model, data, finger, 10, tmp_path / "new", video="v.mp4")


def test_the_adapters_own_cost_is_small(scene):
    """Not a speed target (python/bench/mujoco_grasp.py measures that): a sanity check
    that building a scene is numpy work, not per-geom Python loops over the model."""
    model, data, finger = scene
    park(model, data)
    mujoco.mj_forward(model, data)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = finger.scene(data, poses=True)
    assert s.contacts == [] and set(s.poses) == {"ball", "box", "capsule", "prism", "ball2"}
