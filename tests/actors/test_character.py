"""glTF 2.0 characters: the specification's node, animation and skin rules, checked against closed
forms on a file written here and against Blender's own evaluation of a character it exported."""

from __future__ import annotations

import base64
import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from camgen.actors.character import character_rig, coco_joint_nodes
from camgen.annotate.keypoints import COCO_KEYPOINTS
from camgen.errors import ConfigError
from camgen.io.gltf import CAMGEN_FROM_GLTF, global_transforms, load_character, pose_character, posed_bounds
from camgen.motion.trajectory import Route

DATA = Path(__file__).parent.parent / "data" / "characters"
WALKER = DATA / "walker.glb"
S45 = math.sin(math.pi / 4)


def _accessor(blob: bytearray, views: list, accessors: list, array: np.ndarray, kind: str, component: int) -> int:
    offset = len(blob)
    data = np.ascontiguousarray(array).tobytes()
    blob += data + b"\0" * (-len(data) % 4)
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data)})
    accessors.append({"bufferView": len(views) - 1, "componentType": component, "count": len(array), "type": kind})
    if kind == "VEC3" and component == 5126:
        accessors[-1]["min"] = np.asarray(array).min(axis=0).tolist()
        accessors[-1]["max"] = np.asarray(array).max(axis=0).tolist()
    return len(accessors) - 1


def _two_joint_bar(path: Path) -> Path:
    """A bar skinned to two joints; the tip joint (1 m up) turns 90° about x over 1 s in each clip.

    The skinned mesh's node is 5 m off (the specification says to ignore it), the tip's inverse bind
    matrix has a translation (written column-major, so a transposed read moves everything), and the
    middle vertex's weights sum to 0.5 (renormalised to one half each)."""
    blob, views, accessors = bytearray(), [], []
    F, U8, U16 = 5126, 5121, 5123
    positions = np.array([[0.2, 0, 0], [0, 2, 0], [0, 1.5, 0]], np.float32)
    pos = _accessor(blob, views, accessors, positions, "VEC3", F)
    joints = _accessor(
        blob, views, accessors, np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]], np.uint8), "VEC4", U8
    )
    weights = _accessor(
        blob, views, accessors, np.array([[1, 0, 0, 0], [1, 0, 0, 0], [0.25, 0.25, 0, 0]], np.float32), "VEC4", F
    )
    indices = _accessor(blob, views, accessors, np.array([0, 1, 2], np.uint16), "SCALAR", U16)
    inverse_bind = np.stack([np.eye(4), np.eye(4)])
    inverse_bind[1, 1, 3] = -1.0  # inverse of the tip's rest transform (1 m up)
    ibm = _accessor(
        blob, views, accessors, inverse_bind.transpose(0, 2, 1).reshape(2, 16).astype(np.float32), "MAT4", F
    )
    quarter = [S45, 0.0, 0.0, S45]  # 90° about x
    t01 = _accessor(blob, views, accessors, np.array([0.0, 1.0], np.float32), "SCALAR", F)
    turn = _accessor(blob, views, accessors, np.array([[0, 0, 0, 1], quarter], np.float32), "VEC4", F)
    negated = _accessor(blob, views, accessors, np.array([[0, 0, 0, 1], [-v for v in quarter]], np.float32), "VEC4", F)
    # CUBICSPLINE output: (in-tangent, value, out-tangent) per keyframe; zero tangents.
    cubic = np.array([[0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 0], quarter, [0, 0, 0, 0]], np.float32)
    cubic_out = _accessor(blob, views, accessors, cubic, "VEC4", F)

    def clip(name, output, interpolation):
        return {
            "name": name,
            "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}],
            "samplers": [{"input": t01, "output": output, "interpolation": interpolation}],
        }

    document = {
        "asset": {"version": "2.0", "generator": "camgen test"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"mesh": 0, "skin": 0, "translation": [5.0, 0.0, 0.0]},
            {"children": [2], "name": "base"},
            {"translation": [0.0, 1.0, 0.0], "name": "tip"},
        ],
        "meshes": [
            {
                "primitives": [
                    {"attributes": {"POSITION": pos, "JOINTS_0": joints, "WEIGHTS_0": weights}, "indices": indices}
                ]
            }
        ],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": ibm}],
        "animations": [
            clip("linear", turn, "LINEAR"),
            clip("step", turn, "STEP"),
            clip("cubic", cubic_out, "CUBICSPLINE"),
            clip("negated", negated, "LINEAR"),
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [
            {"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}
        ],
    }
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def _tip_angle_rad(character, clip_name: str, time_s: float) -> float:
    """The angle by which the bar's tip vertex (2 m up at rest) has turned about the tip joint."""
    ((positions, _),) = pose_character(character, character.clip(clip_name), time_s)
    y, z = positions[1, 1] - 1.0, positions[1, 2]
    return math.atan2(z, y)


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    return load_character(_two_joint_bar(tmp_path_factory.mktemp("gltf") / "bar.gltf"))


def test_skinning_follows_the_specification_in_closed_form(bar):
    ((rest, _),) = pose_character(bar, None, 0.0)
    # The mesh node's 5 m offset is ignored; at rest every joint matrix is the identity.
    np.testing.assert_allclose(rest, [[0.2, 0, 0], [0, 2, 0], [0, 1.5, 0]], atol=1e-6)
    ((posed, normals),) = pose_character(bar, bar.clip("linear"), 1.0)
    # Tip vertex: turned 90° about x around the joint at y = 1 m; the middle vertex, weighted half
    # and half after renormalisation, is the mean of its unturned and turned positions.
    np.testing.assert_allclose(posed[1], [0, 1, 1], atol=1e-6)
    np.testing.assert_allclose(posed[2], [0, 1.25, 0.25], atol=1e-6)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)


def test_animation_interpolation_modes(bar):
    assert _tip_angle_rad(bar, "linear", 0.5) == pytest.approx(math.pi / 4, abs=1e-6)  # slerp
    assert _tip_angle_rad(bar, "linear", 0.25) == pytest.approx(math.pi / 8, abs=1e-6)
    assert _tip_angle_rad(bar, "linear", 3.0) == pytest.approx(math.pi / 2, abs=1e-6)  # held after the last key
    assert _tip_angle_rad(bar, "step", 0.99) == pytest.approx(0.0, abs=1e-6)
    assert _tip_angle_rad(bar, "step", 1.0) == pytest.approx(math.pi / 2, abs=1e-6)
    # Slerp takes the shorter arc: a negated end quaternion is the same rotation.
    assert _tip_angle_rad(bar, "negated", 0.5) == pytest.approx(math.pi / 4, abs=1e-6)
    # CUBICSPLINE with zero tangents: Hermite weights h = 2u³ − 3u² + 1 on the first value, then normalised.
    u = 0.25
    h = 2 * u**3 - 3 * u**2 + 1
    q = (1 - h) * np.array([S45, 0, 0, S45]) + h * np.array([0, 0, 0, 1.0])
    assert _tip_angle_rad(bar, "cubic", u) == pytest.approx(2 * math.atan2(q[0], q[3]), abs=1e-6)


def test_gltf_axes_become_the_actor_frame():
    # glTF's front (+Z) is the actor's forward (+x), its up (+Y) the actor's up (+z), its +X (the
    # asset's left) the actor's left (+y); a proper rotation.
    R = CAMGEN_FROM_GLTF[:3, :3]
    np.testing.assert_array_equal(R @ [0, 0, 1], [1, 0, 0])
    np.testing.assert_array_equal(R @ [0, 1, 0], [0, 0, 1])
    np.testing.assert_array_equal(R @ [1, 0, 0], [0, 1, 0])
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_blender_export_skins_as_blender_does():
    """walker.glb was exported by Blender 5.0.1 (tests/data/characters/make_walker.py), which saved
    its own evaluation of the skinned mesh at frames of both clips; camgen's pose matches it."""
    from scipy.spatial import cKDTree

    character = load_character(WALKER)
    assert [c.name for c in character.clips] == ["Walk", "Idle"]
    reference = np.load(DATA / "walker_blender_reference.npz")
    fps = float(reference["fps"])
    blender_to_gltf = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)  # Blender z up, −y front
    rest = np.concatenate([p for p, _ in pose_character(character, None, 0.0)])
    distance, match = cKDTree(reference["rest"] @ blender_to_gltf.T).query(rest)
    assert distance.max() < 1e-5  # the exporter split vertices at UV seams; each is one of Blender's
    for key in [k for k in reference.files if k not in ("rest", "fps")]:
        name, frame = key.rsplit("_", 1)
        posed = np.concatenate([p for p, _ in pose_character(character, character.clip(name), int(frame) / fps)])
        expected = (reference[key] @ blender_to_gltf.T)[match]
        assert np.abs(posed - expected).max() < 1e-5, key
        assert np.abs(posed - rest).max() > 0.01, f"{key} should move the mesh"


# Joint lists as the rigs' authors publish them: Mixamo's skeleton (mixamorig: prefix), SMPL's 24 joints
# (Loper et al. 2015), Blender's Rigify metarig (whose shoulder.L is the collarbone).
MIXAMO = ["Hips", "Spine", "Spine1", "Spine2", "Neck", "Head", "HeadTop_End", "LeftEye", "RightEye"] + [
    f"{side}{part}"
    for side in ("Left", "Right")
    for part in ("Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase")
]
SMPL = ["Pelvis", "Spine1", "Spine2", "Spine3", "Neck", "Head", "Jaw"] + [
    f"{side}_{part}"
    for side in "LR"
    for part in ("Hip", "Knee", "Ankle", "Foot", "Collar", "Shoulder", "Elbow", "Wrist", "Hand")
]
RIGIFY = ["spine", "spine.001", "spine.006"] + [
    f"{part}.{side}" for side in "LR" for part in ("shoulder", "upper_arm", "forearm", "hand", "thigh", "shin", "foot")
]
COCO_JOINTS = {  # keypoint → joint for side left (right mirrors it)
    "mixamo": {"eye": "mixamorig:LeftEye", "shoulder": "mixamorig:LeftArm", "elbow": "mixamorig:LeftForeArm",
               "wrist": "mixamorig:LeftHand", "hip": "mixamorig:LeftUpLeg", "knee": "mixamorig:LeftLeg",
               "ankle": "mixamorig:LeftFoot"},
    "smpl": {"shoulder": "L_Shoulder", "elbow": "L_Elbow", "wrist": "L_Wrist", "hip": "L_Hip", "knee": "L_Knee",
             "ankle": "L_Ankle"},
    "rigify": {"shoulder": "upper_arm.L", "elbow": "forearm.L", "wrist": "hand.L", "hip": "thigh.L",
               "knee": "shin.L", "ankle": "foot.L"},
}  # fmt: skip


@pytest.mark.parametrize("rig", ["mixamo", "smpl", "rigify"])
def test_coco_keypoints_come_from_the_joints_each_rig_names(rig):
    names = {"mixamo": [f"mixamorig:{n}" for n in MIXAMO], "smpl": SMPL, "rigify": RIGIFY}[rig]
    found = {
        k: (names[n] if n is not None else None) for k, n in zip(COCO_KEYPOINTS, coco_joint_nodes(names), strict=True)
    }
    for keypoint, joint in found.items():
        side, _, part = keypoint.rpartition("_")
        expected = COCO_JOINTS[rig].get(part)
        if expected is not None and side == "right":
            expected = expected.replace("Left", "Right").replace("L_", "R_").replace(".L", ".R")
        assert joint == expected, keypoint


def test_a_characters_keypoints_are_its_joints_where_blender_put_them():
    """walker.glb's rig (tests/data/characters/make_walker.py) has thighs, shins and one-bone arms: the
    shoulders, hips and knees are the heads of arm_*, thigh_* and shin_* as the script placed them in
    Blender (z up, −y front); the other 11 keypoints are not labelled (NaN)."""
    character = load_character(WALKER)
    nodes = coco_joint_nodes(character.names)
    labelled = {k: n for k, n in zip(COCO_KEYPOINTS, nodes, strict=True) if n is not None}
    heads_blender = {"left_shoulder": (0.22, 0, 1.48), "right_shoulder": (-0.22, 0, 1.48),
                     "left_hip": (0.09, 0, 0.93), "right_hip": (-0.09, 0, 0.93),
                     "left_knee": (0.09, 0, 0.51), "right_knee": (-0.09, 0, 0.51)}  # fmt: skip
    assert set(labelled) == set(heads_blender)
    G = global_transforms(character, None, 0.0)
    blender_to_gltf = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
    for keypoint, node in labelled.items():
        np.testing.assert_allclose(G[node][:3, 3], blender_to_gltf @ heads_blender[keypoint], atol=1e-5)
    # On the route, in the world: the rig's keypoints move with it, NaN rows where it has no joint.
    route = Route(np.array([[3.0, 1.0]]), np.zeros(1), speed_m_s=1.0)
    rig = character_rig(character, route, T_actor_from_mesh=np.eye(4), scale=1.0, clip="Walk",
                        idle_clip="Idle", clip_speed_m_s=1.0)  # fmt: skip
    assert rig.keypoints_m.shape == (17, 3)
    assert np.isnan(rig.keypoints_m).any(axis=1).sum() == 11
    knees = rig.keypoints_m[[COCO_KEYPOINTS.index("left_knee"), COCO_KEYPOINTS.index("right_knee")]]
    assert np.all(np.abs(knees[:, :2] - [3.0, 1.0]).max(axis=1) < 0.3) and np.all(
        (knees[:, 2] > 0.3) & (knees[:, 2] < 0.7)
    )


def test_walk_plays_by_distance_and_keeps_the_actor_on_its_route():
    character = load_character(WALKER)
    route = Route(np.array([[0.0, 0.0], [10.0, 0.0]]), np.zeros(2), speed_m_s=2.0)
    rig = character_rig(character, route, T_actor_from_mesh=np.eye(4), scale=1.0, clip="Walk",
                        idle_clip="Idle", clip_speed_m_s=1.0)  # fmt: skip
    duration = character.clip("Walk").duration_s
    assert rig.cycle_m == pytest.approx(duration)  # 1 m/s × the loop's duration
    # Played by distance: at 2 m/s the loop runs twice as fast as authored.
    clip, t, _ = rig.clip_time(0.25)
    assert clip.name == "Walk" and t == pytest.approx((0.5 / rig.cycle_m % 1.0) * duration)
    rig.place(1.0)
    low, high = posed_bounds(character, [None, character.clip("Walk")])
    centre = rig.vertices_m.mean(axis=0)
    assert centre[0] == pytest.approx(2.0, abs=0.3) and abs(centre[1]) < 0.3
    assert rig.vertices_m[:, 2].min() >= low[2] - 1e-4 and rig.vertices_m[:, 2].max() <= high[2] + 1e-4
    rig.place(6.0)  # arrived and standing: the idle clip plays in time
    assert rig.clip_time(6.0)[0].name == "Idle"


def test_walking_in_place_needs_a_speed():
    character = load_character(WALKER)
    route = Route(np.array([[0.0, 0.0], [10.0, 0.0]]), np.zeros(2), speed_m_s=1.0)
    with pytest.raises(ConfigError, match="walks in place"):
        character_rig(character, route, T_actor_from_mesh=np.eye(4), scale=1.0, clip=None, idle_clip=None,
                      clip_speed_m_s=None)  # fmt: skip
    with pytest.raises(ConfigError, match=r"'Run'.*'Walk', 'Idle'"):
        character.clip("Run")


def test_not_gltf_is_a_clear_error(tmp_path):
    bad = tmp_path / "x.glb"
    bad.write_bytes(b"not a gltf file at all")
    with pytest.raises(ConfigError, match=r"x\.glb: is not a readable glTF 2\.0 file"):
        load_character(bad)


CHARACTER_SCENE = """\
duration_s: 1.2
fps: 5
seed: 3
environment:
  sky_luminance_cd_m2: 2000
  meshes:
    - {type: plane, name: ground, size_m: [20, 20], material: {color_rgb: [0.3, 0.3, 0.3]}}
lights:
  - {type: sun, illuminance_lux: 40000, azimuth_deg: 200, elevation_deg: 50}
  - {type: ambient, illuminance_lux: 8000}
actors:
  - name: walker
    class: person
    shape:
      {type: file, name: walker_mesh, path: walker.glb, animation: {clip: Walk, idle_clip: Idle, clip_speed_m_s: 1.2}}
    path: {waypoints_m: [[-0.9, 0], [1.5, 0]], speed_m_s: 1.2}
cameras:
  - name: cam
    profile: fixed
    mount: {position_m: [0, -8, 1.2], yaw_deg: 90, pitch_deg: -3}
outputs: {video: false, frames: png, annotations: [coco]}
"""


@pytest.fixture(scope="module")
def character_render(tmp_path_factory):
    """The Blender-made walker crossing a 640×480 view, rendered by the CLI: (coco, camera dir)."""
    import shutil

    from camgen.cli.main import main
    from tests.conftest import FIXED_PROFILE, write

    root = tmp_path_factory.mktemp("character")
    write(root, "profiles/fixed.yaml", FIXED_PROFILE)
    write(root, "scene.yaml", CHARACTER_SCENE)
    shutil.copy(WALKER, root / "walker.glb")
    assert (
        main(["render", str(root / "scene.yaml"), "-o", str(root / "out"), "--profiles", str(root / "profiles")]) == 0
    )
    (camera,) = (root / "out").glob("*/cam")
    return json.loads((camera / "coco.json").read_text(encoding="utf-8")), camera


@pytest.mark.opengl
def test_a_character_renders_textured_moving_and_boxed(character_render):
    import cv2
    from pycocotools import mask as mask_utils

    coco, camera = character_render
    annotations = sorted(coco["annotations"], key=lambda a: a["image_id"])
    assert len(annotations) == len(coco["images"]) == 6
    centres = [a["bbox"][0] + a["bbox"][2] / 2 for a in annotations]
    assert all(b > a + 10 for a, b in itertools.pairwise(centres)), centres  # walks left to right
    for a in annotations:
        # Unoccluded and whole in view: the box of the posed mesh is the tight box of its mask.
        assert a["visibility"] == pytest.approx(1.0, abs=0.01)
        assert np.abs(np.subtract(a["amodal_bbox"], a["bbox"])).max() <= 1.0
        # The keypoints its rig has joints for (shoulders, hips, knees), inside the figure's box; the rest 0.
        keypoints = np.reshape(a["keypoints"], (17, 3))
        assert 4 <= a["num_keypoints"] <= 6 and np.count_nonzero(keypoints[:, 2]) == a["num_keypoints"]
        x, y, w, h = a["bbox"]
        shown = keypoints[keypoints[:, 2] > 0]
        assert np.all((shown[:, 0] >= x - 2) & (shown[:, 0] <= x + w + 2) & (shown[:, 1] >= y) & (shown[:, 1] <= y + h))
        assert np.all(keypoints[keypoints[:, 2] == 0, :2] == 0)
        assert sum(point is None for point in a["keypoints_world_m"]) == 11
    # The cloth texture's red and blue stripes both show inside the figure's mask.
    a = annotations[3]
    image = cv2.imread(str(camera / coco["images"][a["image_id"] - 1]["file_name"]))[..., ::-1].astype(int)
    inside = image[mask_utils.decode(a["segmentation"]).astype(bool)]
    red = np.mean((inside[:, 0] > inside[:, 2] + 30) & (inside[:, 0] > inside[:, 1] + 20))
    blue = np.mean(inside[:, 2] > inside[:, 0] + 30)
    assert red > 0.1 and blue > 0.1, (red, blue)


@pytest.mark.parametrize(
    "animation, key, message",
    [
        ("{clip: Run, clip_speed_m_s: 1.2}", "actors[0].shape.animation.clip", "names 'Run'"),
        ("{clip: Walk}", "actors[0].shape.animation.clip_speed_m_s", "walks in place"),
    ],
)
def test_bad_character_animation_is_a_located_error(tmp_path, animation, key, message):
    import shutil

    from camgen.config import load_scene
    from tests.conftest import FIXED_PROFILE, write

    write(tmp_path, "profiles/fixed.yaml", FIXED_PROFILE)
    text = CHARACTER_SCENE.replace("{clip: Walk, idle_clip: Idle, clip_speed_m_s: 1.2}", animation)
    path = write(tmp_path, "scene.yaml", text)
    shutil.copy(WALKER, tmp_path / "walker.glb")
    with pytest.raises(ConfigError) as caught:
        load_scene(path, [tmp_path / "profiles"])
    text = str(caught.value)
    assert "scene.yaml:15:" in text and key in text and message in text, text


def test_animation_on_an_environment_mesh_is_refused(tmp_path):
    from camgen.config import load_scene
    from tests.conftest import FIXED_PROFILE, write

    write(tmp_path, "profiles/fixed.yaml", FIXED_PROFILE)
    text = CHARACTER_SCENE.replace(
        "    - {type: plane, name: ground",
        "    - {type: file, name: statue, path: walker.glb, animation: {clip: Walk}}\n    - {type: plane, name: ground",
    )
    path = write(tmp_path, "scene.yaml", text)
    with pytest.raises(ConfigError, match=r"environment\.meshes\[0\]\.animation.*fixed mesh of the environment"):
        load_scene(path, [tmp_path / "profiles"])
