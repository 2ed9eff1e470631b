"""Reflections in a wet road (`camgen.render.wet`): the mirror's geometry, the water's reflectance, which
pixels are wet, and a rendered wet frame against the closed form."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.renderer import View
from camgen.render.wet import (
    WET_SURFACE_TOLERANCE_M,
    block_means,
    block_view,
    coarse_view,
    flat_nodes,
    mirrored_view,
    view_geometry,
    wet_pixels,
)
from camgen.world.rain import WATER_REFRACTIVE_INDEX, water_fresnel
from tests.conftest import SCENE, write
from tests.render.conftest import camera_matrix, look_at, scene_from


def _project(view: View, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (N, 2) and camera z (N,) of world points through `view`."""
    T_cam = np.linalg.inv(view.T_world_from_cam)
    p = points_m @ T_cam[:3, :3].T + T_cam[:3, 3]
    uv = p @ view.K_px.T
    return uv[:, :2] / uv[:, 2:], p[:, 2]


def test_water_reflectance_matches_fresnels_sine_and_tangent_laws():
    # An independent form of Fresnel's equations: r_s = −sin(θi − θt)/sin(θi + θt), r_p = tan(θi − θt)/tan(θi + θt).
    n = WATER_REFRACTIVE_INDEX
    theta_i = np.radians(np.linspace(1.0, 89.5, 200))
    theta_t = np.arcsin(np.sin(theta_i) / n)
    r_s = -np.sin(theta_i - theta_t) / np.sin(theta_i + theta_t)
    r_p = np.tan(theta_i - theta_t) / np.tan(theta_i + theta_t)
    np.testing.assert_allclose(water_fresnel(np.cos(theta_i)), (r_s**2 + r_p**2) / 2, rtol=1e-9)
    assert water_fresnel(1.0) == pytest.approx(((n - 1) / (n + 1)) ** 2, rel=1e-12)  # 0.0204 straight down
    assert water_fresnel(0.0) == pytest.approx(1.0)
    brewster = np.arctan(n)  # p-polarised light is not reflected: F = r_s²/2 there
    theta_t = np.arcsin(np.sin(brewster) / n)
    assert water_fresnel(np.cos(brewster)) == pytest.approx(
        np.sin(brewster - theta_t) ** 2 / np.sin(brewster + theta_t) ** 2 / 2
    )


def test_the_mirrored_view_sees_at_each_pixel_what_the_ground_there_reflects():
    view = View(camera_matrix(800.0, 820.0, 319.5, 239.5), look_at((0.0, -5.0, 6.0), (0.5, 10.0, 0.0)), 640, 480)
    height_m = 0.2
    mirror = mirrored_view(view, height_m)
    assert np.linalg.det(mirror.T_world_from_cam[:3, :3]) == pytest.approx(-1.0)
    rng = np.random.default_rng(3)
    points_m = np.column_stack([rng.uniform(-4, 4, 50), rng.uniform(5, 20, 50), rng.uniform(0.5, 4.0, 50)])
    camera_m = view.T_world_from_cam[:3, 3]
    # The bounce point on the ground: where the line from the camera to the point's mirror image crosses z = h.
    images_m = points_m * [1, 1, -1] + [0, 0, 2 * height_m]
    t = (camera_m[2] - height_m) / (camera_m[2] - images_m[:, 2])
    bounces_m = camera_m + t[:, None] * (images_m - camera_m)
    seen_px, _ = _project(mirror, points_m)
    bounce_px, _ = _project(view, bounces_m)
    np.testing.assert_allclose(seen_px, bounce_px, atol=1e-9)
    # and its distance to the point is the reflected path's length (what fog must see)
    _, depth_m = _project(mirror, points_m)
    ray_len = np.linalg.norm(
        np.column_stack([(seen_px - view.K_px[:2, 2]) / np.diag(view.K_px)[:2], np.ones(50)]), axis=1
    )
    path_m = np.linalg.norm(bounces_m - camera_m, axis=1) + np.linalg.norm(points_m - bounces_m, axis=1)
    np.testing.assert_allclose(depth_m * ray_len, path_m, rtol=1e-9)


def test_a_coarse_view_samples_the_middle_of_each_block_of_pixels():
    view = View(camera_matrix(900.0, 900.0, 333.0, 201.0), look_at((0, 0, 3), (0, 10, 0)), 640, 360)
    points_m = np.array([[0.3, 8.0, 0.0], [-2.0, 12.0, 1.0], [1.5, 6.0, 0.5]])
    full_px, _ = _project(view, points_m)
    for step_x, step_y in ((1, 1), (2, 5), (3, 8)):
        coarse = coarse_view(view, step_x, step_y)
        coarse_px, _ = _project(coarse, points_m)
        np.testing.assert_allclose(
            coarse_px * [step_x, step_y] + [(step_x - 1) / 2, (step_y - 1) / 2], full_px, atol=1e-9
        )
        assert coarse.width_px * step_x >= 640 and coarse.height_px * step_y >= 360
        assert (coarse.width_px - 1) * step_x < 640 and (coarse.height_px - 1) * step_y < 360


def test_each_sample_of_the_mirror_is_the_mean_of_the_block_of_pixels_around_it():
    view = View(camera_matrix(700.0, 710.0, 320.5, 180.0), look_at((0, 0, 3), (0, 10, 0)), 641, 361)
    rng = np.random.default_rng(5)
    for step_x, step_y in ((1, 1), (2, 5), (3, 7)):
        grown, coarse = block_view(view, step_x, step_y), coarse_view(view, step_x, step_y)
        assert (grown.width_px, grown.height_px) == (coarse.width_px * step_x, coarse.height_px * step_y)
        np.testing.assert_array_equal(grown.K_px, view.K_px)  # the frame's own pixels, more at two edges
        np.testing.assert_array_equal(grown.T_world_from_cam, view.T_world_from_cam)
        image = rng.random((grown.height_px, grown.width_px, 3)).astype(np.float32)
        blocks = image.reshape(coarse.height_px, step_y, coarse.width_px, step_x, 3)
        np.testing.assert_allclose(block_means(image, step_x, step_y), blocks.mean(axis=(1, 3)), rtol=1e-5)
        # the pixel a point lands on lies in the block of the sample nearest to where it lands in the coarse view
        points_m = np.column_stack([rng.uniform(-3, 3, 200), rng.uniform(4, 20, 200), rng.uniform(0, 2, 200)])
        frame_px, _ = _project(view, points_m)
        coarse_px, _ = _project(coarse, points_m)
        inside = np.all((frame_px > -0.5) & (frame_px < [640.5, 360.5]), axis=1)
        pixel = np.round(frame_px[inside]).astype(int)
        np.testing.assert_array_equal(pixel // [step_x, step_y], np.round(coarse_px[inside]).astype(int))


def test_wet_pixels_are_the_grounds_and_not_what_stands_on_it():
    height_m = 0.01
    view = View(camera_matrix(500.0, 500.0, 159.5, 40.0), look_at((0, 0, 4.0), (0, 10, 0.0)), 320, 240)
    geometry = view_geometry(view)
    rise = geometry.rise_per_m.astype(np.float64)
    with np.errstate(divide="ignore"):
        depth_m = np.where(rise < 0, (height_m - 4.0) / rise, np.inf).astype(np.float32)  # the ground plane
    wet = wet_pixels(view, depth_m, height_m, far_ground_m=None, rise_per_m=geometry.rise_per_m)
    np.testing.assert_array_equal(wet, np.isfinite(depth_m))
    # a box standing on the ground from 5 cm up hides some of it: those pixels are not wet
    standing = depth_m.copy()
    standing[150:200, 100:200] *= 0.9  # points nearer along the same rays: above the ground
    lifted_m = 4.0 + standing[150:200, 100:200] * rise[150:200, 100:200] - height_m
    assert lifted_m.min() > WET_SURFACE_TOLERANCE_M
    assert not wet_pixels(view, standing, height_m, None)[150:200, 100:200].any()
    # beyond the ground's mesh, the ground continued to the horizon is wet too; the sky never is
    open_depth = np.where(np.arange(240)[:, None] > 60, np.inf, depth_m)
    far = wet_pixels(view, open_depth, height_m, far_ground_m=0.0)
    np.testing.assert_array_equal(far, rise < 0)
    assert not wet_pixels(view, open_depth, height_m, far_ground_m=None)[61:].any()


WET_SCENE = SCENE.replace(
    "      size_m: [20, 20]", "      size_m: [40, 40]\n  wet: true\n  sky_luminance_cd_m2: 800"
).replace(
    "actors:\n  - name: walker\n    class: person\n    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n"
    "      speed_m_s: 1.4\n",
    "actors: []\n",
)


def _wet_camera(workspace, text):
    path = write(workspace, "scenes/wet.yaml", text)
    job = compile_scene(load_scene(path), PlanSettings(supersampling=1))
    return job, job.cameras[0]


def test_the_plan_draws_depth_for_a_wet_ground_and_says_why(workspace):
    _, camera = _wet_camera(workspace, WET_SCENE)
    assert "depth_m" in camera.render.passes
    decision = next(d for d in camera.decisions if d.stage == "render.wet_reflections")
    assert decision.included and "Fresnel" in decision.reason
    _, dry = _wet_camera(workspace, WET_SCENE.replace("  wet: true\n", ""))
    assert "depth_m" not in dry.render.passes
    assert not any(d.stage == "render.wet_reflections" for d in dry.decisions)


def test_the_wet_ground_is_the_largest_level_plane_facing_up():
    from camgen.world.rain import wet_ground_height_m

    def environment(*meshes, wet=True):
        lights = [{"type": "ambient", "illuminance_lux": 1000}]
        return scene_from(environment={"meshes": list(meshes), "wet": wet}, lights=lights).environment

    road = {"type": "plane", "name": "road", "size_m": [8, 100], "position_m": [0, 0, 0.01]}
    square = {"type": "plane", "name": "square", "size_m": [20, 20], "position_m": [0, 0, 0.02]}
    assert wet_ground_height_m(environment(road, square)) == pytest.approx(0.01)  # 800 m² over 400
    assert wet_ground_height_m(environment(road, square, wet=False)) is None
    facing_down = {**road, "rotation_deg": [180, 0, 0]}
    tilted = {**road, "rotation_deg": [0, 5, 30]}
    assert wet_ground_height_m(environment(facing_down, square)) == pytest.approx(0.02)
    assert wet_ground_height_m(environment(tilted, {**square, "rotation_deg": [360, 0, 45]})) == pytest.approx(0.02)
    slab = {"type": "box", "name": "slab", "size_m": [40, 40, 0.2], "position_m": [0, 0, -0.1]}
    assert wet_ground_height_m(environment(slab, tilted)) is None


def test_a_wet_scene_without_a_level_plane_draws_nothing_for_reflections_and_says_why(workspace):
    # The ground a box: nothing for the film to lie on, so no mirror and no depth pass drawn for one.
    text = WET_SCENE.replace(
        "    - type: plane\n      name: ground\n      size_m: [40, 40]\n",
        "    - {type: box, name: ground, size_m: [40, 40, 0.2], position_m: [0, 0, -0.1]}\n",
    )
    assert "plane" not in text
    _, camera = _wet_camera(workspace, text)
    assert "depth_m" not in camera.render.passes
    decision = next(d for d in camera.decisions if d.stage == "render.wet_reflections")
    assert not decision.included and "no level plane" in decision.reason


@pytest.mark.opengl
def test_a_wet_ground_under_a_uniform_sky_mirrors_it_by_waters_reflectance(workspace, renderer):
    # Nothing stands on the ground, so the mirror holds the sky alone (800 cd/m² everywhere): at each wet pixel
    # the frame must be (1 − F)·L + F·800 for the frame L drawn without the mirror, F the water's reflectance at
    # that pixel's angle; the sky's pixels are untouched.
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer, render_view

    job, camera = _wet_camera(workspace, WET_SCENE.replace("pitch_deg: -20", "pitch_deg: -8"))
    graph = build_scene_graph(job.scene)
    wet_frame = CameraRenderer(renderer, graph, camera).frame(0).passes
    plain = CameraRenderer(renderer, graph, camera)
    plain._wet_ground_m = None
    base = plain.frame(0).passes
    depth_m = base.depth_m
    view = render_view(camera.states[0], camera.render)
    geometry = view_geometry(view)
    wet = wet_pixels(view, depth_m, 0.0, graph.far_ground.height_m if graph.far_ground else None, geometry.rise_per_m)
    assert 0.3 < wet.mean() < 0.95 and (~wet).any()  # ground and sky both in view
    F = water_fresnel(geometry.cos_incidence.astype(np.float64))[wet][:, None]
    expected = (1 - F) * base.radiance[wet] + F * 800.0
    np.testing.assert_allclose(wet_frame.radiance[wet], expected, rtol=2e-4)
    np.testing.assert_array_equal(wet_frame.radiance[~wet], base.radiance[~wet])
    assert F.max() > 0.2  # grazing rays near the horizon: a bright sheen, not a rounding error


@pytest.mark.opengl
def test_a_static_cameras_mirror_over_its_kept_still_part_equals_the_whole_mirror(workspace, renderer):
    # A held camera over a still background draws the mirror's still part once and the walker over it each frame
    # (as its frame's own draw does): the wet frames are those of the mirror drawn whole, bit for bit.
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer

    text = SCENE.replace("      size_m: [20, 20]", "      size_m: [40, 40]\n  wet: true\n  sky_luminance_cd_m2: 800")
    job, camera = _wet_camera(workspace, text.replace("pitch_deg: -20", "pitch_deg: -8"))
    assert camera.render.static_background and job.scene.actors
    whole = camera.model_copy(update={"render": camera.render.model_copy(update={"static_background": False})})
    graph = build_scene_graph(job.scene)
    kept_frames = CameraRenderer(renderer, graph, camera)
    whole_frames = CameraRenderer(renderer, graph, whole)
    for index in (0, 3, 6):
        np.testing.assert_array_equal(
            kept_frames.frame(index).passes.radiance, whole_frames.frame(index).passes.radiance
        )
    assert "cam:wet mirror" in kept_frames._kept_views and "cam:wet mirror" not in whole_frames._kept_views
    kept_frames.close()


@pytest.mark.opengl
def test_a_box_on_the_wet_ground_is_mirrored_under_itself_with_its_front_faces(workspace, renderer):
    # The mirror is drawn with the winding reversed: were the box drawn with its back faces, the mirror would
    # show its far side, and its depth along the reflected ray would be the far side's.
    from camgen.render.scene_graph import build_scene_graph

    scene = scene_from(
        environment={
            "meshes": [
                {"type": "plane", "name": "ground", "size_m": [40, 40]},
                {"type": "box", "name": "crate", "size_m": [2, 2, 2], "position_m": [0, 10, 1]},
            ],
            "wet": True,
        },
        lights=[{"type": "ambient", "illuminance_lux": 1000}],
    )
    graph = build_scene_graph(scene)
    view = View(camera_matrix(400.0, 400.0, 159.5, 119.5), look_at((0, 0, 3.0), (0, 10, 0.5)), 320, 240)
    mirror = mirrored_view(view, 0.0)
    flat = flat_nodes(graph, 0.0)
    assert len(flat) == 1  # the ground, not the crate
    nodes = [n for n in graph.environment_nodes if id(n) not in flat]
    drawn = renderer.draw(graph, mirror, ("depth_m", "instance_id"), nodes=nodes)
    crate = next(i for node, i in graph.instance_ids.items() if node.name == "environment:crate")
    # The crate's near face (y = 9) at x = 0, z = 0.5: seen in the mirror at the pixel of its bounce point.
    near_face_m = np.array([[0.0, 9.0, 0.5]])
    px, depth_m = _project(mirror, near_face_m)
    u, v = np.round(px[0]).astype(int)
    assert drawn.instance_id[v, u] == crate
    assert drawn.depth_m[v, u] == pytest.approx(depth_m[0], rel=1e-3)
    # The same pixel in the camera's own view shows the ground in front of the crate (the bounce point).
    seen = renderer.draw(graph, view, ("depth_m", "instance_id"))
    assert seen.instance_id[v, u] != crate and seen.instance_id[v, u] != 0


SMALL_BRIGHT_CUBE_SCENE = """\
duration_s: 1
fps: 10
seed: 1
environment:
  meshes:
    - {type: plane, name: ground, size_m: [60, 60], material: {color_rgb: [0.05, 0.05, 0.05]}}
    - {type: box, name: cube, size_m: [0.06, 0.06, 0.06], position_m: [0, 12, HEIGHT], material: {color_rgb: [1, 1, 1]}}
  wet: true
  sky_luminance_cd_m2: 50
lights:
  - {type: ambient, illuminance_lux: 5000}
actors: []
cameras:
  - name: cam
    profile: fixed
    mount: {position_m: [0, -5, 3], yaw_deg: 90, pitch_deg: -10}
"""


@pytest.mark.opengl
def test_a_small_bright_things_reflection_is_its_whole_light_wherever_it_falls_between_samples(
    workspace, renderer, monkeypatch
):
    # A 6 cm white cube 17 m away covers a few pixels; the mirror's samples lie 2 × 7 pixels apart there. Its
    # reflection (the frame with the cube less the frame without) must hold the light of the reflection spread
    # at every pixel, the cube a little higher or lower: point samples caught it whole (1.4-1.8 times too
    # bright, by where it fell between them) or would have missed it.
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer

    def wet_frame(text: str) -> np.ndarray:
        job, camera = _wet_camera(workspace, text)
        return CameraRenderer(renderer, build_scene_graph(job.scene), camera).frame(0).passes.radiance.astype(float)

    without = SMALL_BRIGHT_CUBE_SCENE.replace(
        "    - {type: box, name: cube, size_m: [0.06, 0.06, 0.06], position_m: [0, 12, HEIGHT], "
        "material: {color_rgb: [1, 1, 1]}}\n",
        "",
    )
    assert "cube" not in without
    for height in ("1.0", "1.02", "1.04"):
        text = SMALL_BRIGHT_CUBE_SCENE.replace("HEIGHT", height)
        sampled = wet_frame(text) - wet_frame(without)
        with monkeypatch.context() as patch:
            patch.setattr("camgen.render.wet.mirror_step_px", lambda sigma_px: 1)
            every_pixel = wet_frame(text) - wet_frame(without)
        under = (slice(250, None), slice(None))  # the cube's image ends above; its reflection lies below
        assert every_pixel[under].sum() > 0.05 * every_pixel.sum()  # a reflection to compare
        assert sampled[under].sum() == pytest.approx(every_pixel[under].sum(), rel=0.03)
        assert sampled[under].max() == pytest.approx(every_pixel[under].max(), rel=0.03)
