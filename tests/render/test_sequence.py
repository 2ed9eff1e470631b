"""Rendering a compiled camera: planned passes only, margins, supersampling, static background."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.sequence import CameraRenderer, box_downsample, crop_to_output, render_camera
from tests.conftest import SCENE, write

pytestmark = pytest.mark.opengl

# The test scene with a sun (no shadows, so the static background applies), a parked box and a
# second, faster actor crossing in front of the first.
SUNNY = (
    SCENE.replace(
        "  - {type: ambient, illuminance_lux: 1000}",
        "  - {type: ambient, illuminance_lux: 1000}\n  - {type: sun, illuminance_lux: 20000, azimuth_deg: 250}",
    )
    .replace(
        "      size_m: [20, 20]",
        "      size_m: [20, 20]\n    - {type: box, name: crate, size_m: [1, 1, 1], position_m: [1, 6, 0.5]}\n"
        "  shadows: false",
    )
    .replace(
        "      speed_m_s: 1.4",
        "      speed_m_s: 1.4\n"
        "  - {name: car, class: car, path: {waypoints_m: [[6, 3], [-6, 3]], speed_m_s: 8, motion: linear}}\n"
        # A person standing half inside the crate (ties in depth order) and a car racing off to 500 m
        # (the scene's bounds change every frame): both must not change what the composite shows. The
        # cars keep constant speed (motion: linear): driven from rest they would not cross the view in 1 s.
        "  - {name: inside, class: person, path: {waypoints_m: [[1.1, 5.6]]}}\n"
        "  - {name: racer, class: car, path: {waypoints_m: [[3, 9], [3, 500]], speed_m_s: 60, motion: linear}}",
    )
)


def _job(workspace, text=SUNNY, **settings):
    path = write(workspace, "scenes/s.yaml", text)
    return compile_scene(load_scene(path), PlanSettings(**settings))


def _with_render(camera, **changes):
    return camera.model_copy(update={"render": camera.render.model_copy(update=changes)})


def _without_motion_blur(camera):
    """The camera as planned, but with sharp frames (for tests of the render geometry itself)."""
    return camera.model_copy(update={"stages": tuple(s for s in camera.stages if s.name != "optics.motion_blur")})


def _with_motion_step(camera, step_px):
    """The camera as planned, but with motion blur sampled every `step_px` of image motion instead of the plan's."""
    stages = tuple(
        s.model_copy(update={"params": {**s.params, "sample_step_px": step_px}})
        if s.name == "optics.motion_blur"
        else s
        for s in camera.stages
    )
    return camera.model_copy(update={"stages": stages})


def test_static_background_composite_equals_full_render(workspace, renderer):
    job = _job(workspace)
    # Sub-frames every 4 px of motion instead of the plan's 1 px: the three movers still fall in three groups
    # of their own sample counts (2, 4, 9 at frame 0; 2, 8, 4 at frame 7, against 2, 15, 32 and 3, 29, 15), the
    # largest cycling through all 4 sub-pixel positions of 2× supersampling, at a third of the draws. Only the
    # kept background's draws (`CameraRenderer._draw`) differ between the two renderers, and they are the same.
    camera = _with_motion_step(job.cameras[0], 4.0)
    assert camera.render.static_background
    for supersampling in (1, 2):
        composite = CameraRenderer(renderer, *_graph_and(job, camera, supersampling=supersampling))
        full = CameraRenderer(renderer, *_graph_and(job, camera, supersampling=supersampling, static_background=False))
        try:
            for index in (0, 7):  # at 7 the car is in view
                a, b = composite.frame(index).passes, full.frame(index).passes
                if index == 7:
                    assert (a.instance_id == 2).sum() > 100  # the car is in view
                np.testing.assert_array_equal(a.instance_id, b.instance_id)
                np.testing.assert_allclose(a.radiance, b.radiance, rtol=1e-6, atol=1e-6)
        finally:
            composite.close()


def _graph_and(job, camera, **render_changes):
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(job.scene), _with_render(camera, **render_changes)


def test_shadows_rule_out_the_static_background(workspace):
    job = _job(workspace, SUNNY.replace("  shadows: false", "  shadows: true"))
    decision = next(d for d in job.cameras[0].decisions if d.stage == "render.static_background")
    assert not decision.included and "shadows" in decision.reason


def test_only_planned_passes_are_rendered(workspace, renderer):
    annotations_only = SUNNY + "outputs: {video: false, annotations: [coco]}\n"  # mot writes images too
    job = _job(workspace, annotations_only)
    frame = next(render_camera(renderer, job, job.cameras[0]))
    assert job.cameras[0].render.passes == ("instance_id",)
    assert frame.passes.radiance is None and frame.passes.depth_m is None
    assert crop_to_output(frame.passes.instance_id, job.cameras[0].render).shape == (480, 640)

    video_only = SUNNY + "outputs: {video: true, annotations: []}\n"
    job = _job(workspace, video_only)
    frame = next(render_camera(renderer, job, job.cameras[0]))
    assert frame.passes.instance_id is None and frame.passes.depth_m is None
    assert crop_to_output(frame.passes.radiance, job.cameras[0].render).shape == (480, 640, 3)
    assert frame.passes.radiance.dtype == np.float32


def test_margin_render_crops_back_to_the_output(workspace, renderer):
    job = _job(workspace, supersampling=1)
    camera = _with_render(_without_motion_blur(job.cameras[0]), margin_px=(0, 0, 0, 0), width_px=640, height_px=480)
    plain = next(render_camera(renderer, job, camera, frames=[3])).passes
    wide = _with_render(camera, margin_px=(7, 5, 3, 9), width_px=650, height_px=494)
    framed = next(render_camera(renderer, job, wide, frames=[3])).passes
    assert framed.radiance.shape == (494, 650, 3)
    cropped_ids = crop_to_output(framed.instance_id, wide.render)
    # The same rays hit the same surfaces; only rounding at silhouette edges may differ.
    assert (cropped_ids == plain.instance_id).mean() > 0.9995
    same = cropped_ids == plain.instance_id
    close = np.isclose(crop_to_output(framed.radiance, wide.render)[same], plain.radiance[same], rtol=1e-4)
    # A few pixels where two surfaces intersect, or where a person's or a procedural car's small
    # triangles bend the interpolated normal steeply (and the cars' glossy glass turns it into a
    # highlight), round differently (210 values of 921 597 measured, 1.2e-4 relative).
    assert close.mean() > 0.9995


def test_box_downsample_is_the_block_mean():
    image = np.random.default_rng(0).random((12, 18, 3), dtype=np.float32) * 1000
    expected = image.reshape(4, 3, 6, 3, 3).mean(axis=(1, 3))
    np.testing.assert_allclose(box_downsample(image, 3), expected, rtol=1e-6)


def test_supersampling_antialiases_radiance_but_not_ids(workspace, renderer):
    # People drawn as cylinders and cars as boxes: one grey material everywhere (a procedural person has
    # coloured clothes, a procedural car paint, glass and lamps).
    cylinder = "shape: {type: cylinder, name: body, radius_m: 0.25, height_m: 1.75, position_m: [0, 0, 0.875]}, "
    box = "shape: {type: box, name: body, size_m: [4.5, 1.8, 1.5], position_m: [0, 0, 0.75]}, "
    text = (
        SUNNY.replace("  - {type: sun, illuminance_lux: 20000, azimuth_deg: 250}\n", "")
        .replace("  shadows: false", "  shadows: false\n  ground_to_horizon: false")
        .replace("class: car, ", "class: car, " + box)
        .replace("{name: inside, class: person, ", "{name: inside, class: person, " + cylinder)
        .replace("    class: person\n", "    class: person\n    " + cylinder.removesuffix(", ") + "\n")
    )
    job = _job(workspace, text, supersampling=1)
    camera = _without_motion_blur(job.cameras[0])
    sharp = next(render_camera(renderer, job, camera, frames=[0])).passes
    smooth = next(render_camera(renderer, job, _with_render(camera, supersampling=4), frames=[0])).passes
    np.testing.assert_array_equal(smooth.instance_id, sharp.instance_id)
    # Ambient light on one grey material: every surface has the same radiance L, so 1× shows 0 (the sky,
    # with no far ground under the horizon: ground_to_horizon is off) and L only, and 4× shows the 17
    # coverage fractions k/16 of L at edges.
    radiance = sharp.radiance[..., 1].max()
    np.testing.assert_array_equal(np.unique(sharp.radiance), [0.0, radiance])
    fractions = smooth.radiance[..., 1] / radiance * 16
    np.testing.assert_allclose(fractions, np.round(fractions), atol=1e-4)
    assert len(np.unique(np.round(fractions))) == 17


def test_a_render_larger_than_the_gpu_allows_is_refused_with_the_fix(workspace):
    from types import SimpleNamespace

    from camgen.errors import ConfigError
    from camgen.render.scene_graph import build_scene_graph

    job = _job(workspace, supersampling=4)
    small_gpu = SimpleNamespace(max_size_px=2000)
    with pytest.raises(ConfigError, match=r"at supersampling 4 needs \d+ pixels per side.*use supersampling 2 or less"):
        CameraRenderer(small_gpu, build_scene_graph(job.scene), job.cameras[0])


def test_view_at_turns_the_camera_with_the_head_rates():
    """A sub-frame view `dt` after the frame time is the head's pose at pan + ṗ·dt, tilt + ṫ·dt, with
    the focal lengths scaled by exp(ż·dt) (from R_world_from_cam, independently)."""
    from camgen.job import CameraState, RenderSpec
    from camgen.motion.pose import R_world_from_cam, T_world_from_cam
    from camgen.render.sequence import view_at

    mount = dict(yaw_deg=30.0, pitch_deg=-5.0, roll_deg=2.0)
    K = ((1000.0, 0.0, 640.0), (0.0, 1000.0, 360.0), (0.0, 0.0, 1.0))
    T = T_world_from_cam((1.0, 2.0, 6.0), R_world_from_cam(**mount, pan_deg=40.0, tilt_deg=-12.0))
    state = CameraState(
        frame=0,
        time_s=0.0,
        pan_deg=40.0,
        tilt_deg=-12.0,
        zoom_x=2.0,
        focal_length_mm=9.0,
        f_number=2.0,
        focus_distance_m=10.0,
        exposure_time_s=0.02,
        gain_db=0.0,
        K_px=K,
        distortion=(0.0,) * 8,
        T_world_from_cam=tuple(map(tuple, T.tolist())),
        pan_deg_s=60.0,
        tilt_deg_s=-20.0,
        log_zoom_per_s=0.5,
    )
    spec = RenderSpec(
        width_px=1300,
        height_px=740,
        margin_px=(10, 10, 10, 10),
        passes=("radiance",),
        supersampling=1,
        static_background=False,
    )
    view = view_at(state, spec, 0.01)
    expected = R_world_from_cam(**mount, pan_deg=40.6, tilt_deg=-12.2)
    np.testing.assert_allclose(view.T_world_from_cam[:3, :3], expected, atol=1e-12)
    np.testing.assert_allclose(view.T_world_from_cam[:3, 3], (1.0, 2.0, 6.0))
    assert view.K_px[0, 0] == pytest.approx(1000.0 * np.exp(0.005))
    assert view.K_px[0, 2] == pytest.approx(650.0)  # principal point (plus the left margin) unchanged
    np.testing.assert_array_equal(view_at(state, spec, 0.0).T_world_from_cam, T)
