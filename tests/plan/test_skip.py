"""The plan skips what a scene does not need, and says why."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.optics.intrinsics import blur_circle_diameter_mm
from camgen.plan import Job, PlanSettings, compile, compile_scene
from camgen.plan.compile import LIMB_SPEED_FACTOR
from camgen.plan.visibility import box_corners, visible_depth_range_m
from tests.conftest import FIXED_PROFILE, SCENE, write


def plan(workspace, scene_text, profile_edit=None, settings=None, name="s.yaml", base=FIXED_PROFILE):
    """Plan `scene_text` with the profile `base` plus `profile_edit` appended (never cumulative)."""
    write(workspace, "profiles/fixed.yaml", base + (profile_edit or ""))
    job = compile_scene(load_scene(write(workspace, f"scenes/{name}", scene_text)), settings)
    return job.cameras[0]


def decision(camera, stage):
    (d,) = [d for d in camera.decisions if d.stage == stage]
    return d


def stage_names(camera):
    return [s.name for s in camera.stages]


def test_no_annotations_plans_no_instance_pass(workspace):
    camera = plan(workspace, SCENE + "outputs: {annotations: []}\n")
    assert "instance_id" not in camera.render.passes
    assert not decision(camera, "pass.instance_id").included
    assert "annotate" not in stage_names(camera)
    with_annotations = plan(workspace, SCENE, name="t.yaml")
    assert "instance_id" in with_annotations.render.passes
    assert "annotate" in stage_names(with_annotations)


def test_zero_distortion_plans_no_remap_and_no_margin(workspace):
    # No blur stage but diffraction: a fast lens (f/1.0 on 3 µm: σ = 0.084 px, whose discrete kernel reaches
    # ⌈4σ⌉ + 1 = 2 px, the whole margin) and a short manual exposure (no motion blur).
    camera = plan(
        workspace,
        SCENE,
        profile_edit="exposure: {mode: manual, exposure_time_s: 0.0005}\n",
        base=FIXED_PROFILE.replace("f_number: 2.0", "f_number: 1.0"),
    )
    assert "optics.remap" not in stage_names(camera)
    assert decision(camera, "optics.distortion").reason == "all coefficients are zero"
    assert not {"optics.motion_blur", "optics.depth_of_field"} & set(stage_names(camera))
    assert "optics.diffraction" in stage_names(camera)
    assert camera.render.margin_px == (2, 2, 2, 2)
    assert (camera.render.width_px, camera.render.height_px) == (644, 484)
    assert camera.states[0].distortion == (0.0,) * 8


def test_a_depth_output_alone_still_goes_through_the_lens(workspace):
    """Only a depth output asked for (no frames, no annotations): the depth map is placed by the
    distortion as the frames and masks would be, not left a pinhole image."""
    camera = plan(
        workspace,
        SCENE + "outputs: {video: false, annotations: [], depth: exr}\n",
        profile_edit="  distortion: {k1: -0.3}\n",
    )
    assert decision(camera, "optics.distortion").included
    assert "optics.remap" in stage_names(camera)


def test_distortion_plans_remap_and_a_margin_that_covers_the_source(workspace):
    # A short exposure keeps motion blur out, so the margin is the lens's (plus < 1 px of diffraction).
    camera = plan(
        workspace,
        SCENE,
        profile_edit="  distortion: {k1: -0.3}\nexposure: {mode: manual, exposure_time_s: 0.0005}\n",
    )
    assert "optics.motion_blur" not in stage_names(camera)
    assert "optics.remap" in stage_names(camera)
    left, _, right, _ = camera.render.margin_px
    # Barrel: the output corner samples the pinhole image beyond the frame. Closed form for k1 only:
    # the corner at distorted radius rd comes from r with r + k1 r³ = rd.
    K = np.array(camera.states[0].K_px)
    rd = math.hypot(320 / K[0, 0], 240 / K[1, 1])
    r = rd
    for _ in range(100):
        r = rd / (1 - 0.3 * r * r)
    overshoot_x = (r / rd - 1) * 320
    assert left >= overshoot_x and left <= overshoot_x + 4
    assert camera.render.width_px == 640 + left + right
    assert camera.states[0].distortion[0] == -0.3


def test_shallow_depth_of_field_plans_a_depth_pass_and_deep_one_does_not(workspace):
    deep = plan(workspace, SCENE)
    d = decision(deep, "optics.depth_of_field")
    assert not d.included and d.effect < 0.5
    assert "depth_m" not in deep.render.passes
    assert not decision(deep, "pass.depth_m").included

    # The same camera focused at 0.5 m: the ground 8–30 m away is out of focus.
    shallow = plan(
        workspace, SCENE.replace("pitch_deg: -20", "pitch_deg: -20\n    focus_distance_m: 0.5"), name="near.yaml"
    )
    d = decision(shallow, "optics.depth_of_field")
    assert d.included and d.effect > 0.5
    assert "depth_m" in shallow.render.passes
    assert "optics.depth_of_field" in stage_names(shallow)


def test_blur_circle_closed_form():
    # f = 50 mm, N = 2, focus 2 m, object 4 m: c = (f/N)·|d − s|/d · f/(s − f).
    expected = 25.0 * (2.0 / 4.0) * 50.0 / 1950.0
    assert blur_circle_diameter_mm(4.0, 50.0, 2.0, 2.0) == pytest.approx(expected)
    assert blur_circle_diameter_mm(2.0, 50.0, 2.0, 2.0) == 0.0


def test_visible_depth_range_of_a_wall_and_of_the_ground():
    K = np.array([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]])
    T = np.eye(4)  # camera at the origin looking along +z (camera frame = world frame here)
    wall = box_corners(np.array([-50, -50, 0.0]), np.array([50, 50, 0.0]), np.eye(4) @ _translate(0, 0, 7.0))
    near, far = visible_depth_range_m([wall], T, K, 640, 480)
    assert near == pytest.approx(7.0) and far == pytest.approx(7.0)
    # A floor 2 m below (y down): seen from the image's bottom edge (v = 479.5) to the horizon.
    floor = box_corners(np.array([-100, 2.0, 0.0]), np.array([100, 2.0, 100.0]), np.eye(4))
    near, far = visible_depth_range_m([floor], T, K, 640, 480)
    assert near == pytest.approx(2.0 * 500.0 / (479.5 - 239.5))
    assert far == pytest.approx(100.0)
    # Behind the camera: nothing.
    assert visible_depth_range_m([box_corners(np.full(3, -5.0), np.full(3, -4.0), np.eye(4))], T, K, 640, 480) is None


def _translate(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def test_forcing_all_stages_plans_every_stage_and_says_so(workspace):
    skipped = plan(workspace, SCENE)
    forced = plan(workspace, SCENE, settings=PlanSettings(force_all_stages=True), name="f.yaml")
    assert len(forced.stages) > len(skipped.stages)
    for name in ("optics.remap", "optics.vignetting", "optics.depth_of_field", "optics.diffraction"):
        assert name in stage_names(forced)
    assert decision(forced, "optics.vignetting").reason.startswith("forced on")
    assert "depth_m" in forced.render.passes


def test_motion_blur_follows_actor_speed_and_exposure(workspace):
    manual_1ms = "exposure: {mode: manual, exposure_time_s: 0.001, exposure_time_max_s: 0.01}\n"
    slow = plan(workspace, SCENE, profile_edit=manual_1ms)
    assert not decision(slow, "optics.motion_blur").included
    fast = plan(workspace, SCENE.replace("speed_m_s: 1.4", "speed_m_s: 30"), name="fast.yaml", profile_edit=manual_1ms)
    d = decision(fast, "optics.motion_blur")
    # 30 m/s for 1 ms at ≈ 10 m depth with f = 1333 px moves the body ≈ 4 px, a walker's fastest limb
    # LIMB_SPEED_FACTOR times that.
    assert d.included and 2.0 * LIMB_SPEED_FACTOR < d.effect < 8.0 * LIMB_SPEED_FACTOR


def test_raw_only_output_plans_no_isp(workspace):
    camera = plan(workspace, SCENE + "outputs: {video: false, raw_dng: true, annotations: []}\n")
    names = stage_names(camera)
    assert "io.raw_dng" in names and "sensor.adc" in names
    assert not any(n.startswith("isp.") for n in names)


def test_annotations_only_plans_no_radiance(workspace):
    camera = plan(workspace, SCENE + "outputs: {video: false, annotations: [coco]}\n")
    assert camera.render.passes == ("instance_id",)
    assert not any(n.startswith(("sensor.", "isp.")) for n in stage_names(camera))


@pytest.mark.parametrize("kind", ["mot", "yolo", "reid"])
def test_annotations_written_with_their_frames_plan_the_camera(workspace, kind):
    camera = plan(workspace, SCENE + f"outputs: {{video: false, annotations: [{kind}]}}\n", name=f"{kind}.yaml")
    assert "radiance" in camera.render.passes and "isp.tone" in stage_names(camera)


def test_job_round_trips_through_json_and_its_id_is_its_content(workspace):
    loaded = load_scene(write(workspace, "scenes/s.yaml", SCENE))
    job = compile_scene(loaded)
    again = Job.from_json(job.to_json())
    assert again == job
    assert again.content_hash() == job.job_id
    assert compile_scene(loaded).job_id == job.job_id
    other = compile(
        loaded.scene.model_copy(update={"seed": 2}),
        loaded.profile_models,
        scene_name=loaded.name,
        profile_names=loaded.profile_names,
    )
    assert other.job_id != job.job_id
    assert len(job.cameras[0].states) == loaded.scene.frame_count == 10


def test_compile_checks_cameras_against_profiles(workspace):
    loaded = load_scene(write(workspace, "scenes/s.yaml", SCENE))
    fast = loaded.scene.model_copy(update={"fps": 100.0})
    with pytest.raises(ConfigError, match="fps must be ≤ 30 Hz"):
        compile(fast, loaded.profile_models)
    with pytest.raises(ConfigError, match="no profile given for camera"):
        compile(loaded.scene, {})


def _near_depth_m(camera) -> float:
    reason = decision(camera, "optics.depth_of_field").reason
    return float(re.search(r"over depths ([0-9.]+)–", reason).group(1))


def test_depth_range_covers_what_a_barrel_lens_sees_beyond_the_pinhole_frame(workspace):
    pinhole = plan(workspace, SCENE)
    barrel = plan(workspace, SCENE, profile_edit="  distortion: {k1: -0.3}\n", name="b.yaml")
    # The camera looks down at the ground: the wider view of the barrel lens reaches nearer ground.
    assert _near_depth_m(barrel) < _near_depth_m(pinhole)


def test_false_colour_suppression_is_planned_for_a_colour_sensor_that_asks_for_it():
    from camgen.config.loader import load_profile
    from camgen.plan.compile import isp_steps
    from tests.conftest import REPO

    bullet = load_profile(REPO / "profiles/bullet_4mp_2p8mm.yaml").profile
    assert "isp.false_colour" in isp_steps(bullet.isp, bullet.sensor)  # the example sets 5 px
    off = bullet.isp.model_copy(update={"false_colour_median_px": 0})
    assert "isp.false_colour" not in isp_steps(off, bullet.sensor)
    mono = bullet.sensor.model_copy(update={"cfa": "mono"})
    assert "isp.false_colour" not in isp_steps(bullet.isp, mono)  # no colour to suppress
