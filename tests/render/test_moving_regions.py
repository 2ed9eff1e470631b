"""Motion blur drawn only where something moves (`CameraRenderer.moving_rects_px`): the composited frame
equals every sub-frame drawn whole within float rounding, on a scene whose fast car casts a long shadow
under a low sun and a spot light, over textured (mipmapped) ground under a CIE sky."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render import sequence
from camgen.render.renderer import SKY_STEP_PX
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer, aligned_rect_px, jittered_samples, render_view, shifted
from tests.conftest import FIXED_PROFILE, write

pytestmark = pytest.mark.opengl

SMALL_PROFILE = (
    FIXED_PROFILE.replace("640", "160").replace("480", "120").replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
    + "exposure: {mode: manual, exposure_time_s: 0.02}\n"
)
SCENE = """\
duration_s: 2
fps: 10
environment:
  sky: clear
  meshes:
    - {type: plane, name: ground, size_m: [60, 60],
       material: {color_rgb: [0.3, 0.3, 0.3], texture: {type: asphalt, seed: 1}}}
    - {type: box, name: wall, size_m: [24, 0.5, 3], position_m: [0, 16, 1.5],
       material: {color_rgb: [0.5, 0.45, 0.4], texture: {type: brick, seed: 2}}}
lights:
  - {type: sun, illuminance_lux: 50000, azimuth_deg: 235, elevation_deg: 12}
  - {type: ambient, illuminance_lux: 3000}
  - {type: spot, intensity_cd: 40000, position_m: [2, 9, 7], target_m: [2, 9, 0], cone_half_angle_deg: 35}
actors:
  - name: mover
    class: car
    shape: {type: box, name: body, size_m: [1.6, 0.8, 1.4], position_m: [0, 0, 0.7],
            material: {color_rgb: [0.8, 0.1, 0.1]}}
    path: {waypoints_m: [[-15, 9], [15, 9]], speed_m_s: 15, motion: linear}
  - name: parked
    class: car
    shape: {type: box, name: body, size_m: [1.6, 0.8, 1.4], position_m: [0, 0, 0.7],
            material: {color_rgb: [0.1, 0.3, 0.8]}}
    path: {waypoints_m: [[-6, 12]], heading_deg: 30}
outputs: {annotations: []}
cameras:
  - {name: cam, profile: fixed, mount: {position_m: [0, -4, 4], yaw_deg: 90, pitch_deg: -15}}
"""
FRAME = 10  # t = 1 s: the mover at x = 0, its shadow stretched away from the low sun


@pytest.fixture(scope="module")
def case(renderer, tmp_path_factory):
    """The job, its camera, and the frame drawn both ways (composited, every sub-frame whole)."""
    root = tmp_path_factory.mktemp("moving_regions")
    write(root, "profiles/fixed.yaml", SMALL_PROFILE)
    job = compile_scene(load_scene(write(root, "scenes/s.yaml", SCENE)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    assert any(stage.name == "optics.motion_blur" for stage in camera.stages)
    graph = build_scene_graph(job.scene)
    composited = CameraRenderer(renderer, graph, camera)
    whole = CameraRenderer(renderer, graph, camera, moving_regions=False)
    state = camera.states[FRAME]
    return {
        "job": job,
        "camera": camera,
        "graph": graph,
        "composited": composited,
        "state": state,
        "fast": composited.frame(FRAME).passes.radiance,
        "reference": whole.frame(FRAME).passes.radiance,
    }


def _rects(case):
    composited, state = case["composited"], case["state"]
    view = render_view(state, case["camera"].render)
    samples = jittered_samples(composited.motion_samples(state), case["camera"].render.supersampling)
    return composited.moving_rects_px(state, view, [t for t, _, _ in samples], composited.shadow_fit(view)), view


def test_the_composited_frame_equals_every_sub_frame_drawn_whole(case):
    rects, view = _rects(case)
    samples = case["composited"].motion_samples(case["state"])
    assert samples > 4  # more sub-frames than sub-pixel positions, drawn in the rectangles only
    assert rects, "the mover is in view, so there is a moving region"
    area = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rects)
    assert area < 0.5 * view.width_px * view.height_px  # most of the frame is not redrawn
    fast, reference = case["fast"], case["reference"]
    assert np.all(np.isfinite(reference))
    assert np.abs(fast - reference).max() <= 1e-5 * reference.max()


def test_the_mover_blurs_and_its_shadow_lies_outside_its_own_box(case):
    """The scene exercises what the rectangles must hold: the mover is smeared, and its shadow reaches
    pixels that its own swept box does not cover (`_shadow_lights` left out, the composite breaks)."""
    reference = case["reference"]
    sharp_camera = case["camera"].model_copy(
        update={"stages": tuple(s for s in case["camera"].stages if s.name != "optics.motion_blur")}
    )
    sharp = CameraRenderer(case["composited"].renderer, case["graph"], sharp_camera).frame(FRAME).passes.radiance
    assert np.abs(sharp - reference).max() > 0.05 * reference.max()


def test_a_rectangle_that_misses_the_shadow_breaks_the_equality(case, monkeypatch):
    monkeypatch.setattr(sequence, "_shadow_lights", lambda scene: [])
    no_shadow = CameraRenderer(case["composited"].renderer, case["graph"], case["camera"]).frame(FRAME)
    reference = case["reference"]
    assert np.abs(no_shadow.passes.radiance - reference).max() > 1e-3 * reference.max()


def test_a_cropped_draw_is_the_same_part_of_the_whole_draw(case, renderer):
    """Sky (on its grid), far ground, textures with mipmaps and sun and spot shadows come out alike in a
    view cropped to an aligned rectangle; the rectangle's alignment is what keeps the sky grid's nodes."""
    composited, state = case["composited"], case["state"]
    view = shifted(render_view(state, case["camera"].render), 0.25, -0.25)
    fit = composited.shadow_fit(view)
    clip = composited.clip_range_m(view)
    case["graph"].place_actors(state.time_s)
    whole = renderer.draw(case["graph"], view, ("radiance",), clip_range_m=clip, shadow_fit=fit).radiance
    rect = aligned_rect_px((13, 5, 101, 70), view.width_px, view.height_px)
    x0, y0, x1, y1 = rect
    assert x0 % SKY_STEP_PX == 0 and (x1 - 1) % SKY_STEP_PX == 0 and x1 >= 101 and y0 <= 5
    part = renderer.draw(case["graph"], view, ("radiance",), clip_range_m=clip, shadow_fit=fit, crop_px=rect)
    expected = whole[y0:y1, x0:x1]
    assert np.abs(part.radiance - expected).max() <= 1e-5 * whole.max()
    # The window holds sky and ground both.
    assert expected[..., 2].max() > 1.2 * expected[..., 2].min()


def test_a_panning_head_falls_back_to_whole_sub_frames(case):
    composited, state = case["composited"], case["state"]
    view = render_view(state, case["camera"].render)
    panning = state.model_copy(update={"pan_deg_s": 20.0})
    assert composited.moving_rects_px(panning, view, [-0.25, 0.25], composited.shadow_fit(view)) is None
    assert composited.moving_rects_px(state, view, [-0.25, 0.25], composited.shadow_fit(view)) is not None


def test_a_sun_under_the_horizon_falls_back(case):
    """(A spot light below a moving top is bounded by the box of every surface: tests/render/test_spot_cone_regions.)"""
    composited, state, graph = case["composited"], case["state"], case["graph"]
    view = render_view(state, case["camera"].render)
    scene = graph.scene
    (sun,) = scene.directional_light_nodes
    sun_pose = scene.get_pose(sun).copy()
    try:
        under = sun_pose.copy()
        under[:3, :3] = np.diag([1.0, -1.0, -1.0]) @ sun_pose[:3, :3]  # −Z (the light's travel) points up
        scene.set_pose(sun, under)
        assert composited.moving_rects_px(state, view, [-0.25, 0.25], composited.shadow_fit(view)) is None
    finally:
        scene.set_pose(sun, sun_pose)


def test_no_moving_actor_in_the_exposure_leaves_no_region(case):
    composited, state = case["composited"], case["state"]
    view = render_view(state, case["camera"].render)
    assert composited.moving_rects_px(state, view, [0.0, 0.0], composited.shadow_fit(view)) == []


@pytest.mark.parametrize("light", ["sun", "spot", "low spot"])
def test_the_shadow_slices_hold_the_whole_shadow_volume(light):
    """Points p + λd of a box's shadow volume (p in the box, down to the ground), or L + κ(p − L) for a
    spot light at L, sampled at random, each lie in one of the slices' convex hulls (scipy's Delaunay). A low
    spot light (below the box's top: rays over it go up and never reach the ground) has its volume bounded by
    a box holding every surface: the points of the volume inside that box."""
    from scipy.spatial import Delaunay

    from camgen.render.scene_graph import _look_along
    from camgen.render.sequence import _shadow_slices

    class Node:
        def __init__(self, kind):
            from pyrender.light import DirectionalLight, SpotLight

            self.light = DirectionalLight() if kind == "sun" else SpotLight()

    class Scene:
        def __init__(self, pose):
            self.pose = pose

        def get_pose(self, node):
            return self.pose

    d = np.array([0.9, 0.3, -0.12])  # a low sun: a shadow 8 times as long as the box is high
    L = np.array([1.0, -2.0, 2.5]) if light != "low spot" else np.array([1.0, -4.0, 0.6])  # a headlamp's height
    low, high = np.array([-1.0, -0.5, 0.2]), np.array([1.0, 0.5, 1.6])
    if light == "sun":
        pose = _look_along(d)
    else:  # straight down from over the box, or a headlamp aimed at it
        pose = _look_along(np.array([0.0, 0.0, -1.0]) if light == "spot" else (low + high) / 2 - L, L)
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])
    surfaces = (np.array([-20.0, -20.0, 0.0]), np.array([20.0, 30.0, 10.0]))  # every surface: a street and houses
    if light == "low spot":  # without the surfaces' box its rays over the lamp run on for ever
        assert _shadow_slices(Scene(pose), Node("spot"), corners, 0.0) is None
    slices = _shadow_slices(Scene(pose), Node(light.split()[-1]), corners, 0.0, surfaces)
    assert len(slices) > 2  # a long shadow is cut into pieces
    rng = np.random.default_rng(0)
    p = low + rng.random((4000, 3)) * (high - low)
    if light == "sun":
        reach = p[:, 2] / -(d[2] / np.linalg.norm(d))
        points = p + (rng.random(len(p)) * reach)[:, None] * (d / np.linalg.norm(d))
    elif light == "spot":
        reach = L[2] / (L[2] - p[:, 2])
        points = L + (1.0 + rng.random(len(p)) * (reach - 1.0))[:, None] * (p - L)
    else:  # out to 15 times as far along each ray, then those inside the surfaces' box (the ground its floor)
        points = L + (1.0 + rng.random(len(p)) * 14.0)[:, None] * (p - L)
        points = points[np.all((points >= surfaces[0]) & (points <= surfaces[1]), axis=1)]
        assert len(points) > 1000 and points[:, 2].max() > 5.0  # rays over the lamp reach the houses' height
    inside = np.zeros(len(points), bool)
    for hull in slices:
        inside |= Delaunay(hull).find_simplex(points, tol=1e-9) >= 0
    assert inside.all()


def test_a_kept_static_background_composites_alike(renderer, tmp_path):
    """Without shadows the plan keeps the environment's draw (`static_background`): the whole sub-frames
    go through it, the rectangles draw everything; the two agree."""
    write(tmp_path, "profiles/fixed.yaml", SMALL_PROFILE)
    scene = SCENE.replace("  sky: clear\n", "  sky: clear\n  shadows: false\n", 1)
    job = compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", scene)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    assert camera.render.static_background
    graph = build_scene_graph(job.scene)
    fast = CameraRenderer(renderer, graph, camera).frame(FRAME).passes.radiance
    reference = CameraRenderer(renderer, graph, camera, moving_regions=False).frame(FRAME).passes.radiance
    assert np.abs(fast - reference).max() <= 1e-5 * reference.max()
