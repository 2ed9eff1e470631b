"""Named actions of the procedural person: each pose has the property that names it, the pose never
jumps, a fallen body stays above the ground, and the plan refuses a sit or a fall while walking."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.actors import PersonRig
from camgen.actors.actions import fall_duration_s
from camgen.actors.appearance import draw_appearance
from camgen.actors.gait import Walker
from camgen.actors.person import build_person
from camgen.actors.skeleton import INDEX
from camgen.annotate.keypoints import COCO_KEYPOINTS
from camgen.config.scene import Actor, PersonAction
from camgen.errors import ConfigError
from camgen.motion.trajectory import Route

KP = {name: i for i, name in enumerate(COCO_KEYPOINTS)}


@pytest.fixture(scope="module")
def model():
    return build_person(draw_appearance(21, pinned={"sex": "female", "age_group": "adult", "stature_m": 1.66}))


def rig(model, actions, waypoints=((0.0, 0.0),), speed_m_s=1.3) -> PersonRig:
    points = np.array(waypoints, dtype=float)
    route = Route(points, np.zeros(len(points)), speed_m_s)
    walker = Walker(model, route, phase_seed=0.3, actions=tuple(PersonAction(**a) for a in actions))
    return PersonRig(model, walker)


def test_a_wave_raises_the_hand_above_the_head_and_swings_it(model):
    person = rig(model, [{"type": "wave", "start_s": 1.0, "duration_s": 3.0, "side": "left"}])
    person.place(0.5)
    assert person.keypoints_m[KP["left_wrist"], 2] < person.keypoints_m[KP["left_hip"], 2] + 0.1  # hanging
    lateral = []
    for t in np.arange(2.0, 3.0, 0.02):
        person.place(float(t))
        k = person.keypoints_m
        assert k[KP["left_wrist"], 2] > k[KP["nose"], 2]  # above the head
        assert k[KP["right_wrist"], 2] < k[KP["right_hip"], 2] + 0.1  # the other hand stays down
        lateral.append(k[KP["left_wrist"], 1] - k[KP["left_elbow"], 1])
    # The forearm swings side to side at the documented 2.5 Hz (the strongest frequency over 1 s).
    spectrum = np.abs(np.fft.rfft(np.array(lateral) - np.mean(lateral)))
    assert np.fft.rfftfreq(len(lateral), 0.02)[np.argmax(spectrum)] == pytest.approx(2.5, abs=0.5)


def test_a_phone_bends_the_head_and_holds_the_hand_before_the_chest(model):
    person = rig(model, [{"type": "phone", "start_s": 1.0, "duration_s": 5.0}], waypoints=((0, 0), (20, 0)))
    person.place(0.3)
    neutral = person.keypoints_m.copy()
    person.place(3.0)
    k = person.keypoints_m
    forward = np.array([1.0, 0.0])  # the route heads +x
    shoulders = (k[KP["left_shoulder"]] + k[KP["right_shoulder"]]) / 2
    hips = (k[KP["left_hip"]] + k[KP["right_hip"]]) / 2
    # The nose drops relative to the shoulders (head flexed): by 45° about the neck it drops several cm.
    assert (k[KP["nose"], 2] - shoulders[2]) < (neutral[KP["nose"], 2] - (neutral[5, 2] + neutral[6, 2]) / 2) - 0.04
    wrist = k[KP["right_wrist"]]
    assert hips[2] < wrist[2] < shoulders[2]  # at the chest's height
    assert (wrist[:2] - shoulders[:2]) @ forward > 0.15  # in front of the body


def test_sitting_lowers_the_hips_to_the_seat_and_keeps_the_feet(model):
    person = rig(model, [{"type": "sit", "start_s": 1.0, "duration_s": 6.0, "seat_height_m": 0.45}])
    person.place(0.5)
    standing_feet = person.joints_m[[INDEX["ball_l"], INDEX["ball_r"]]].copy()
    person.place(4.0)
    pelvis = person.joints_m[INDEX["pelvis"]]
    assert pelvis[2] == pytest.approx(0.45 + 0.09, abs=0.005)
    np.testing.assert_allclose(person.joints_m[[INDEX["ball_l"], INDEX["ball_r"]]], standing_feet, atol=1e-6)
    # Thighs near horizontal, shins near vertical: a seated posture.
    for side in ("l", "r"):
        thigh = person.joints_m[INDEX[f"calf_{side}"]] - person.joints_m[INDEX[f"thigh_{side}"]]
        assert abs(math.degrees(math.atan2(thigh[2], np.hypot(*thigh[:2])))) < 25
    person.place(7.5)  # stood up again
    assert person.joints_m[INDEX["pelvis"], 2] > 0.85


def test_a_fall_topples_in_under_a_second_and_lies_above_the_ground(model):
    person = rig(model, [{"type": "fall", "start_s": 1.0, "duration_s": 4.0, "direction": "backward"}])
    person.place(0.9)
    standing_pelvis = person.joints_m[INDEX["pelvis"], 2]
    # Falls from standing reach the ground in 0.7–1 s (Hsiao & Robinovitch 1998); the pendulum's time,
    # against its energy integral t = √(L/g) ∫ dθ / √(2 (cos θ₀ − cos θ)) evaluated by scipy's quad.
    from scipy.integrate import quad

    from camgen.actors.actions import FALL_START_TILT_RAD, TRIP_S

    assert 0.7 < fall_duration_s(standing_pelvis) < 1.0
    integral, _ = quad(
        lambda th: 1 / math.sqrt(2 * (math.cos(FALL_START_TILT_RAD) - math.cos(th))), FALL_START_TILT_RAD, math.pi / 2
    )
    free_fall_s = math.sqrt(round(standing_pelvis, 3) / 9.81) * integral
    assert fall_duration_s(standing_pelvis) - TRIP_S == pytest.approx(free_fall_s, abs=1e-3)
    previous = None
    for t in np.arange(0.9, 7.0, 0.02):
        person.place(float(t))
        assert person.vertices_m[:, 2].min() > -0.02, t  # never through the ground
        if previous is not None:  # no jumps: the head of a toppling body hits the ground at about 7 m/s
            assert np.abs(person.joints_m - previous).max() < 0.16, t
        previous = person.joints_m.copy()
    person.place(4.0)
    lying = person.vertices_m
    assert lying[:, 2].max() < 0.6  # lying: nothing higher than a bent knee or an arm
    assert np.ptp(lying[:, 0]) > 1.2 or np.ptp(lying[:, 1]) > 1.2  # stretched out along the ground
    person.place(6.9)  # risen after the action's end
    assert person.joints_m[INDEX["pelvis"], 2] == pytest.approx(standing_pelvis, abs=0.02)


def test_actions_are_checked():
    path = {"waypoints_m": [[0, 0]]}
    with pytest.raises(ValueError, match=r"one action at a time"):
        Actor.model_validate(
            {"name": "p", "class": "person", "path": path, "actions": [
                {"type": "wave", "start_s": 1, "duration_s": 3}, {"type": "phone", "start_s": 2, "duration_s": 1}]}
        )  # fmt: skip
    with pytest.raises(ValueError, match=r"for a procedural person.*a 'car'"):
        Actor.model_validate(
            {"name": "c", "class": "car", "path": path, "actions": [{"type": "wave", "start_s": 0, "duration_s": 1}]}
        )


def test_a_sit_while_walking_is_refused_where_it_is_written(workspace):
    from camgen.config import load_scene
    from camgen.plan import compile_scene
    from tests.conftest import SCENE, write

    text = SCENE.replace(
        "      speed_m_s: 1.4\n",
        "      speed_m_s: 1.4\n    actions: [{type: sit, start_s: 0.5, duration_s: 2}]\n",
    )
    path = write(workspace, "scenes/sit.yaml", text)
    with pytest.raises(ConfigError) as caught:
        compile_scene(load_scene(path, [workspace / "profiles"]))
    message = str(caught.value)
    assert "sit.yaml:17:" in message and "actors[0].actions[0].start_s" in message and "walks at 0.50 s" in message
