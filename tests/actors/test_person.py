"""The procedural person: identity, anthropometry, gait without foot sliding, skinning and keypoints."""

from __future__ import annotations

import dataclasses
import math
from typing import get_args

import cv2
import numpy as np
import pytest

from camgen.actors import Crowd, PersonRig, person_rig
from camgen.actors.appearance import CLOTH_RGB, STATURE_CM, draw_appearance
from camgen.actors.gait import Walker, gait_parameters
from camgen.actors.person import SOLE_LIFT_M, build_person
from camgen.actors.skeleton import INDEX, global_transforms, rot_axis, skin, skinning_matrices, weight_matrix
from camgen.config.scene import Actor, ClothColour
from camgen.motion.trajectory import Route


@pytest.fixture(scope="module")
def model():
    return build_person(draw_appearance(11, pinned={"sex": "male", "age_group": "adult", "stature_m": 1.78}))


def test_same_seed_same_person_and_seeds_differ():
    assert draw_appearance(5) == draw_appearance(5)
    looks = {dataclasses.replace(draw_appearance(s), identity_seed=0) for s in range(40)}
    assert len(looks) == 40  # forty different-looking people, not forty seeds
    # Pinning one attribute leaves the others as drawn.
    a, b = draw_appearance(9), draw_appearance(9, pinned={"top_colour": "red"})
    assert b.top_colour == "red" and (a.sex, a.stature_m, a.bottom_colour) == (b.sex, b.stature_m, b.bottom_colour)


def test_clothing_colours_match_the_schema():
    assert set(CLOTH_RGB) == set(get_args(ClothColour))


def test_stature_distribution_follows_nhanes():
    """Adult men's drawn statures: mean and SD within sampling error of NHANES 2015–2018."""
    statures = np.array(
        [draw_appearance(s, pinned={"sex": "male", "age_group": "adult"}).stature_m for s in range(2000)]
    )
    mean_cm, sd_cm = STATURE_CM[("adult", "male")]
    assert abs(statures.mean() * 100 - mean_cm) < 0.6
    assert abs(statures.std() * 100 - sd_cm) < 0.8


def test_model_stands_at_its_stature(model):
    """Soles on the ground; the top of the head at the drawn stature plus hair and shoe sole."""
    assert model.vertices_m[:, 2].min() == pytest.approx(SOLE_LIFT_M, abs=1e-6)
    top = model.vertices_m[:, 2].max()
    assert 1.78 < top < 1.78 + 0.05
    # Anthropometry (Drillis & Contini 1966): hip joint ≈ 0.53 H, shoulder ≈ 0.82 H.
    hip, shoulder = model.joints_m[INDEX["thigh_l"], 2], model.joints_m[INDEX["upperarm_l"], 2]
    assert 0.47 < hip / 1.78 < 0.56
    assert 0.78 < shoulder / 1.78 < 0.85
    assert np.allclose(model.joint_weight.sum(axis=1), 1.0, atol=1e-5)


def test_rest_pose_skins_to_the_rest_mesh(model):
    from camgen.actors.skeleton import Pose

    T = np.eye(4)
    T[:3, 3] = model.joints_m[INDEX["pelvis"]]
    pose = Pose(T, np.tile(np.eye(3), (len(model.joints_m), 1, 1)))
    M = skinning_matrices(model.joints_m, global_transforms(model.joints_m, pose))
    weights = weight_matrix(model.joint_index, model.joint_weight, len(model.joints_m))
    vertices, _normals = skin(model.vertices_m, model.normals, weights, M)
    assert np.abs(vertices - model.vertices_m).max() < 1e-5
    # A rigid turn of the whole body turns every vertex with it.
    T[:3, :3] = rot_axis("z", 0.7)
    M = skinning_matrices(model.joints_m, global_transforms(model.joints_m, Pose(T, pose.local_rotations)))
    turned, _ = skin(model.vertices_m, model.normals, weights, M)
    expected = (model.vertices_m - model.joints_m[INDEX["pelvis"]]) @ rot_axis("z", 0.7).T + T[:3, 3]
    assert np.abs(turned - expected).max() < 1e-4


@pytest.mark.parametrize("speed_m_s", [0.5, 1.0, 1.4, 2.0, 2.5, 3.0])
def test_no_foot_sliding(model, speed_m_s):
    """A stance foot's contact point (the ball of the foot) moves ≤ 0.05 m/s averaged over each stance,
    at every speed from slow walking to running, on a route with a turn."""
    route = Route(np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 4.0]]), np.zeros(3), speed_m_s, 0.0)
    walker = Walker(model, route)
    dt = 1 / 100
    times = np.arange(0.2, route.duration_s - 0.2, dt)
    balls = {side: [] for side in ("l", "r")}
    for t in times:
        pose = walker.pose(float(t))
        G = global_transforms(model.joints_m, pose)
        for side in balls:
            balls[side].append(G[INDEX[f"ball_{side}"], :3, 3].copy())
    stances = 0
    for positions in balls.values():
        p = np.array(positions)
        grounded = p[:, 2] < model.joints_m[INDEX["ball_l"], 2] + 1e-6
        speed = np.hypot(*np.diff(p[:, :2], axis=0).T) / dt
        # Runs of frames with the ball on the ground are stances.
        edges = np.flatnonzero(np.diff(np.concatenate([[0], grounded.astype(int), [0]])))
        for start, end in zip(edges[::2], edges[1::2], strict=True):
            if end - start < 5:
                continue
            stances += 1
            assert speed[start : end - 1].mean() <= 0.05
    assert stances >= 4
    gait = gait_parameters(speed_m_s, walker.hip_height_m)
    assert gait.running == (speed_m_s > 2.1)


@pytest.mark.parametrize("speed_m_s", [3.0, 4.5])
def test_a_runner_bounces_and_flies_ballistically(model, speed_m_s):
    """Running, the pelvis rises and falls by 5.5–10 cm per step (Lee & Farley 1998; Gullstrand et al. 2009),
    lowest while a foot is planted, and falls freely (≈ −g) while both feet are off the ground; the stance
    knee flexes to 35–55° (about 45°: Novacheck 1998), not into a crouch."""
    route = Route(np.array([[0.0, 0.0], [60.0, 0.0]]), np.zeros(2), speed_m_s, 0.0)
    walker = Walker(model, route)
    dt = 1 / 400
    times = np.arange(2.0, 4.0, dt)
    heights, airborne, stance_knees = [], [], []
    ground = model.joints_m[INDEX["ball_l"], 2] + 1e-6
    for t in times:
        pose = walker.pose(float(t))
        G = global_transforms(model.joints_m, pose)
        heights.append(pose.T_world_from_pelvis[2, 3])
        airborne.append(all(G[INDEX[f"ball_{side}"], 2, 3] > ground for side in "lr"))
        for side in "lr":
            if G[INDEX[f"ball_{side}"], 2, 3] <= ground:
                hip, knee, ankle = (G[INDEX[f"{joint}_{side}"], :3, 3] for joint in ("thigh", "calf", "foot"))
                thigh, shin = hip - knee, ankle - knee
                cosine = thigh @ shin / np.linalg.norm(thigh) / np.linalg.norm(shin)
                stance_knees.append(180 - math.degrees(math.acos(cosine)))
    heights, airborne = np.array(heights), np.array(airborne)
    assert 0.055 < heights.max() - heights.min() < 0.10
    assert airborne.any() and not airborne.all()
    # a parabola through each flight (the pelvis height is tabulated 96 times a stride, linear between)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], airborne.astype(int), [0]])))
    flights = [(a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= 8]
    assert len(flights) >= 4
    for a, b in flights:
        assert 2 * np.polyfit(times[a:b], heights[a:b], 2)[0] == pytest.approx(-9.81, abs=1.5)
    assert heights[airborne].mean() > heights[~airborne].mean()
    assert 35 < max(stance_knees) < 55


def test_stride_follows_speed_and_body_size():
    """Alexander's relative stride grows with speed and is ~1.41 m at 1.37 m/s for h = 0.9 m (Perry)."""
    assert gait_parameters(1.37, 0.9).stride_m == pytest.approx(1.41, rel=0.03)
    assert gait_parameters(3.0, 0.9).stride_m == pytest.approx(2.3, rel=0.05)
    assert gait_parameters(1.4, 0.8).stride_m < gait_parameters(1.4, 0.95).stride_m


def test_keypoints_match_cv2_project_points(model):
    """COCO keypoints of a posed person projected by camgen equal cv2.projectPoints with the same K
    and distortion (≤ 0.5 px)."""
    from camgen.annotate.keypoints import keypoint_visibility

    route = Route(np.array([[0.0, 0.0], [6.0, 0.0]]), np.zeros(2), 1.4, 0.0)
    rig = PersonRig(model, Walker(model, route))
    rig.place(1.3)
    K = np.array([[900.0, 0, 640], [0, 900.0, 360], [0, 0, 1]])
    distortion = np.array([-0.3, 0.1, 0.001, -0.0005, -0.02])
    R_world_from_cam = np.array([[0.0, 0, 1], [-1, 0, 0], [0, -1, 0]]) @ rot_axis("x", -0.2)
    T = np.eye(4)
    T[:3, :3] = rot_axis("z", math.pi / 2) @ R_world_from_cam
    T[:3, 3] = (2.0, -6.0, 1.6)
    ids = np.full((720, 1280), 1, dtype=np.uint32)
    keypoints = keypoint_visibility(rig.keypoints_m, T, K, distortion, ids, 1, 1280, 720)
    T_cam = np.linalg.inv(T)
    rvec, _ = cv2.Rodrigues(T_cam[:3, :3])
    expected, _ = cv2.projectPoints(rig.keypoints_m, rvec, T_cam[:3, 3], K, distortion)
    inside = keypoints[:, 2] > 0
    assert inside.sum() == 17
    assert np.abs(keypoints[:, :2] - 0.5 - expected[:, 0]).max() < 0.5


def test_person_rig_from_scene_actor_is_reproducible():
    actor = Actor.model_validate({"name": "a", "class": "person", "path": {"waypoints_m": [[0, 0], [5, 0]]}})
    route = Route(np.array([[0.0, 0.0], [5.0, 0.0]]), np.zeros(2), 1.4, 0.0)
    a = person_rig(actor, route, scene_seed=1, actor_index=0)
    b = person_rig(actor, route, scene_seed=1, actor_index=0)
    c = person_rig(actor, route, scene_seed=1, actor_index=1)
    a.place(0.8)
    b.place(0.8)
    assert np.array_equal(a.vertices_m, b.vertices_m)
    assert a.model.appearance != c.model.appearance


def test_a_crowd_skins_each_person_as_alone(model):
    """Skinning many people in one product gives each the vertices it gets skinned alone."""
    other = build_person(draw_appearance(12))
    routes = [Route(np.array([[0.0, 0.0], [6.0, 0.0]]), np.zeros(2), v, 0.0) for v in (1.1, 2.8)]
    alone = [PersonRig(m, Walker(m, r)) for m, r in zip((model, other), routes, strict=True)]
    crowd = Crowd([PersonRig(m, Walker(m, r)) for m, r in zip((model, other), routes, strict=True)])
    crowd.place(1.7)
    for rig, single in zip(crowd.rigs, alone, strict=True):
        single.place(1.7)
        np.testing.assert_allclose(rig.vertices_m, single.vertices_m, atol=1e-5)
        np.testing.assert_allclose(rig.keypoints_m, single.keypoints_m, atol=1e-9)
