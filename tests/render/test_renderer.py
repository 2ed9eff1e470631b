"""The render passes against closed forms and OpenCV: geometry, depth, ids, linear radiance."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.render.renderer import Passes, View, gl_camera_pose, gl_projection
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl


def _graph(**document):
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(scene_from(**document))


def _window_to_pixel(points_world, K, T_world_from_cam, width, height):
    """Where camgen's OpenGL matrices put world points, as OpenCV pixel coordinates (float64)."""
    P = gl_projection(K, width, height, 0.05, 100.0)
    V = np.linalg.inv(gl_camera_pose(T_world_from_cam))
    clip = np.c_[points_world, np.ones(len(points_world))] @ (P @ V).T
    ndc = clip[:, :2] / clip[:, 3:4]
    # Window coordinates (x right, rows top-down because of the flip) minus the half-pixel centre.
    return np.c_[(ndc[:, 0] + 1) / 2 * width - 0.5, (ndc[:, 1] + 1) / 2 * height - 0.5]


def test_projection_equals_opencv_project_points():
    rng = np.random.default_rng(3)
    for _ in range(20):
        fx, fy = rng.uniform(300, 3000, 2)
        width, height = int(rng.integers(320, 2000)), int(rng.integers(240, 1200))
        K = camera_matrix(fx, fy, (width - 1) / 2 + rng.uniform(-30, 30), (height - 1) / 2 + rng.uniform(-30, 30))
        T = look_at(rng.uniform(-10, 10, 3), rng.uniform(-2, 2, 3))
        points = T[:3, 3] + (T[:3, :3] @ np.c_[rng.uniform(-2, 2, (50, 2)), rng.uniform(1, 40, 50)].T).T
        T_cam_from_world = np.linalg.inv(T)
        expected, _ = cv2.projectPoints(
            points, cv2.Rodrigues(T_cam_from_world[:3, :3])[0], T_cam_from_world[:3, 3], K, np.zeros(5)
        )
        got = _window_to_pixel(points, K, T, width, height)
        np.testing.assert_allclose(got, expected.reshape(-1, 2), atol=1e-6, rtol=0)


def test_supersampled_view_keeps_pixel_areas():
    """Output pixel u covers sub-pixels u·s … u·s + s − 1 of an s× finer view."""
    view = View(camera_matrix(800.0, 810.0, 319.5, 239.5), look_at((0, -5, 1), (0, 0, 1)), 640, 480)
    fine = view.scaled(3)
    point = np.array([[0.3, 0.2, 1.1]])
    coarse_uv = _window_to_pixel(point, view.K_px, view.T_world_from_cam, 640, 480)
    fine_uv = _window_to_pixel(point, fine.K_px, fine.T_world_from_cam, 1920, 1440)
    np.testing.assert_allclose(fine_uv, (coarse_uv + 0.5) * 3 - 0.5, atol=1e-9)


def test_depth_of_a_tilted_plane_at_pixel_centres(renderer):
    # A 40 m plane turned 50° about X and 20° about Z, 6–20 m in front of the camera.
    graph = _graph(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "p",
                    "size_m": [40, 40],
                    "position_m": [0, 12, 0],
                    "rotation_deg": [50, 0, 20],
                }
            ]
        },
        lights=[{"type": "ambient", "illuminance_lux": 100}],
    )
    K = camera_matrix(700.0, 700.0, 330.3, 228.6)
    T = look_at((1.0, -2.0, 3.0), (0.0, 12.0, 0.0))
    out = renderer.draw(graph, View(K, T, 640, 480), ("depth_m", "instance_id"))
    assert out.radiance is None
    hit = out.instance_id == 1
    assert hit.mean() > 0.9
    # Analytic: the plane n·X = c (world) in the camera frame; a pixel's ray X = z·K⁻¹(u, v, 1).
    R = T[:3, :3]
    # Extrinsic X then Z rotation, composed independently of camgen with OpenCV's Rodrigues formula.
    R_plane = (
        cv2.Rodrigues(np.array([0.0, 0.0, math.radians(20)]))[0] @ cv2.Rodrigues(np.array([math.radians(50), 0, 0]))[0]
    )
    normal_world = R_plane @ np.array([0.0, 0.0, 1.0])
    normal_cam = R.T @ normal_world
    offset = normal_world @ (np.array([0.0, 12.0, 0.0]) - T[:3, 3])
    v, u = np.mgrid[0:480, 0:640]
    rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u, dtype=float)], -1)
    expected = offset / (rays @ normal_cam)
    relative = np.abs(out.depth_m[hit] / expected[hit] - 1)
    assert relative.max() <= 1e-4, relative.max()
    assert np.isinf(out.depth_m[~hit]).all()


def test_instance_ids_follow_the_projected_box_edges(renderer):
    boxes = [
        {
            "type": "box",
            "name": "a",
            "size_m": [1.0, 2.0, 1.5],
            "position_m": [-1.0, 8.0, 0.75],
            "rotation_deg": [0, 0, 25],
        },
        {
            "type": "box",
            "name": "b",
            "size_m": [0.6, 0.6, 3.0],
            "position_m": [1.5, 11.0, 1.5],
            "rotation_deg": [10, 0, -40],
        },
    ]
    graph = _graph(environment={"meshes": boxes}, lights=[{"type": "ambient", "illuminance_lux": 100}])
    K = camera_matrix(620.0, 640.0, 315.0, 250.0)
    T = look_at((0.0, 0.0, 2.5), (0.0, 10.0, 0.8))
    out = renderer.draw(graph, View(K, T, 640, 480), ("instance_id",))
    T_cam = np.linalg.inv(T)
    from camgen.config.placement import box_corners, placement
    from camgen.config.scene import BoxMesh

    for instance_id, box in enumerate(boxes, start=1):
        shape = BoxMesh.model_validate(box)
        half = np.array(shape.size_m) / 2
        corners = box_corners(-half, half, placement(shape))
        uv, _ = cv2.projectPoints(corners, cv2.Rodrigues(T_cam[:3, :3])[0], T_cam[:3, 3], K, np.zeros(5))
        hull = cv2.convexHull(uv.reshape(-1, 2).astype(np.float32))
        mask = out.instance_id == instance_id
        # Box b stands in front of a only where the hull says; compare only where no other box is.
        other = (out.instance_id != 0) & ~mask
        ys, xs = np.nonzero(mask != _inside(hull, 640, 480))
        wrong = [(x, y) for x, y in zip(xs, ys, strict=True) if not other[y, x]]
        distances = [abs(cv2.pointPolygonTest(hull, (float(x), float(y)), True)) for x, y in wrong]
        assert mask.sum() > 1000
        assert max(distances, default=0.0) <= 1.0


def _inside(hull, width, height) -> np.ndarray:
    v, u = np.mgrid[0:height, 0:width]
    inside = np.zeros((height, width), bool)
    for y, x in zip(v.ravel(), u.ravel(), strict=True):
        inside[y, x] = cv2.pointPolygonTest(hull, (float(x), float(y)), False) > 0
    return inside


def test_thousands_of_instances_keep_exact_ids(renderer):
    nx, ny = 60, 50  # 3000 boxes on a grid, seen from straight above
    meshes = [
        {
            "type": "box",
            "name": f"b{i}_{j}",
            "size_m": [0.6, 0.6, 0.2],
            "position_m": [i - nx / 2 + 0.5, j - ny / 2 + 0.5, 0.1],
        }
        for j in range(ny)
        for i in range(nx)
    ]
    graph = _graph(environment={"meshes": meshes}, lights=[{"type": "ambient", "illuminance_lux": 100}])
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # looking down, image x = world x, image y = world −y
    T[:3, 3] = (0.0, 0.0, 50.0)
    K = camera_matrix(1000.0, 1000.0, 639.5, 511.5)
    out = renderer.draw(graph, View(K, T, 1280, 1024), ("instance_id",))
    ids = np.unique(out.instance_id)
    assert len(ids) == nx * ny + 1 and ids[0] == 0 and ids[-1] == nx * ny
    for index, mesh in enumerate(meshes[::97]):
        x, y, z = mesh["position_m"]
        u = K[0, 0] * x / (50.0 - z) + K[0, 2]
        v = K[1, 1] * -y / (50.0 - z) + K[1, 2]
        assert out.instance_id[round(v), round(u)] == index * 97 + 1


def _lit_plane(**lights):
    return _graph(
        environment={
            "sky_luminance_cd_m2": lights.pop("sky", 0.0),
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [20, 20],
                    "material": {"color_rgb": [0.5, 0.25, 0.8], "emission_cd_m2": lights.pop("emission", 0.0)},
                },
                {"type": "box", "name": "post", "size_m": [0.4, 0.4, 2.0], "position_m": [0.5, 0.5, 1.0]},
            ],
        },
        lights=lights["lights"],
    )


def _overhead_view(width=320, height=240) -> View:
    return View(camera_matrix(300.0, 300.0, 159.5, 119.5), look_at((0.0, -6.0, 5.0), (0.0, 0.0, 0.0)), width, height)


def test_radiance_is_linear_and_unclamped(renderer):
    sun = {"type": "sun", "azimuth_deg": 200, "elevation_deg": 40}
    point = {"type": "point", "position_m": [2, -2, 3], "intensity_cd": 3000}
    draws = []
    for scale in (1.0, 2.0):
        lights = [
            {**sun, "illuminance_lux": 30000 * scale},
            {**point, "intensity_cd": 3000 * scale},
            {"type": "ambient", "illuminance_lux": 5000 * scale},
        ]
        draws.append(renderer.draw(_lit_plane(lights=lights), _overhead_view(), ("radiance",)).radiance)
    single, double = draws
    lit = single > 1e-3
    assert single.max() > 1000.0  # cd/m², far above 8-bit white
    np.testing.assert_allclose(double[lit], 2.0 * single[lit], rtol=1e-3)


def test_a_repeated_draw_sends_no_unchanged_uniform_and_a_changed_one_takes_effect(renderer, monkeypatch):
    # camgen.render.renderer._RememberingProgram skips setting a uniform to the value it holds (pyrender
    # sets every uniform of every primitive in every draw); a light changed between draws must still show.
    from OpenGL import GL

    lights = [
        {"type": "sun", "illuminance_lux": 40000, "elevation_deg": 50},
        {"type": "point", "position_m": [2, -2, 3], "intensity_cd": 2000},
    ]
    graph = _lit_plane(lights=lights, sky=100.0)
    view = _overhead_view()
    first = renderer.draw(graph, view, ("radiance",)).radiance
    sent = []
    counting = GL.glUniform1f

    def count(location, value):
        sent.append(location)
        counting(location, value)

    monkeypatch.setattr(GL, "glUniform1f", count)
    again = renderer.draw(graph, view, ("radiance",)).radiance
    np.testing.assert_array_equal(again, first)
    assert sent == []  # every float uniform (intensities, cone scales, texture LOD bias) already held
    (sun,) = graph.scene.directional_light_nodes
    sun.light.intensity *= 2.0
    brighter = renderer.draw(graph, view, ("radiance",)).radiance
    assert len(sent) >= 1
    sun.light.intensity /= 2.0
    np.testing.assert_array_equal(renderer.draw(graph, view, ("radiance",)).radiance, first)
    lit_by_sun = brighter - first
    assert lit_by_sun.max() > 1.0 and lit_by_sun.min() >= 0.0


def test_ambient_emission_and_sky_in_cd_per_m2(renderer):
    """Closed forms: a Lambertian surface under a uniform sky of E lux has L = ρ·E/π; emission adds."""
    graph = _lit_plane(lights=[{"type": "ambient", "illuminance_lux": 1000.0}], sky=4321.0, emission=7.0)
    out = renderer.draw(graph, _overhead_view(), ("radiance", "instance_id"))
    ground = out.instance_id == 1
    expected = np.array([0.5, 0.25, 0.8]) * 1000.0 / math.pi + 7.0
    np.testing.assert_allclose(out.radiance[ground], np.broadcast_to(expected, out.radiance[ground].shape), rtol=1e-5)
    np.testing.assert_array_equal(out.radiance[out.instance_id == 0], 4321.0)


def test_shared_draw_equals_separate_draws(renderer):
    lights = [{"type": "sun", "illuminance_lux": 50000}, {"type": "ambient", "illuminance_lux": 5000}]
    graph = _lit_plane(lights=lights, sky=3000.0)
    view = _overhead_view()
    shared = renderer.draw(graph, view, ("radiance", "depth_m", "instance_id"))
    alone = Passes(
        radiance=renderer.draw(graph, view, ("radiance",)).radiance,
        depth_m=renderer.draw(graph, view, ("depth_m",)).depth_m,
        instance_id=renderer.draw(graph, view, ("instance_id",)).instance_id,
    )
    np.testing.assert_array_equal(shared.radiance, alone.radiance)
    np.testing.assert_array_equal(shared.depth_m, alone.depth_m)
    np.testing.assert_array_equal(shared.instance_id, alone.instance_id)


def test_unknown_pass_is_refused(renderer):
    graph = _lit_plane(lights=[{"type": "ambient", "illuminance_lux": 10}])
    with pytest.raises(ValueError, match="passes must be"):
        renderer.draw(graph, _overhead_view(), ("normals",))


def test_closing_one_renderer_leaves_another_working(renderer):
    from camgen.render.renderer import Renderer

    graph = _lit_plane(lights=[{"type": "ambient", "illuminance_lux": 10}])
    with Renderer() as other:
        other.draw(graph, _overhead_view(), ("instance_id",))
    assert (renderer.draw(graph, _overhead_view(), ("instance_id",)).instance_id == 1).any()


def test_more_than_four_point_lights_all_shine(renderer):
    """Superposition: six lamps together give the sum of each lamp alone (pyrender alone keeps 4)."""
    lamps = [{"type": "point", "position_m": [x, y, 3.0], "intensity_cd": 500} for x in (-3, 0, 3) for y in (-2, 2)]
    view = _overhead_view()
    together = renderer.draw(_lit_plane(lights=lamps), view, ("radiance",)).radiance
    alone = sum(renderer.draw(_lit_plane(lights=[lamp]), view, ("radiance",)).radiance for lamp in lamps)
    np.testing.assert_allclose(together, alone, rtol=1e-4, atol=1e-3)


def test_sun_on_a_matte_plane_is_lambertian_and_casts_the_right_shadow(renderer):
    """L = ρ·E·sin(elevation)/π on open ground (plus a small specular part at roughness 1); a 2 m pole
    lit from azimuth 0° (+X) at 45° casts a 2 m shadow towards −X."""
    graph = _graph(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [20, 20],
                    "material": {"color_rgb": [0.5, 0.5, 0.5], "roughness": 1.0},
                },
                {"type": "box", "name": "pole", "size_m": [0.2, 0.2, 2.0], "position_m": [0, 0, 1.0]},
            ]
        },
        lights=[{"type": "sun", "illuminance_lux": 10000, "azimuth_deg": 0, "elevation_deg": 45}],
    )
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # straight down: image x = world x, image y = world −y
    T[:3, 3] = (0.0, 0.0, 10.0)
    K = camera_matrix(100.0, 100.0, 319.5, 239.5)
    out = renderer.draw(graph, View(K, T, 640, 480), ("radiance", "instance_id"))
    luminance = out.radiance[..., 1]

    def at(x_m, y_m):
        return luminance[round(239.5 - 10 * y_m), round(319.5 + 10 * x_m)]

    lambertian = 0.5 * 10000 * math.sin(math.radians(45)) / math.pi
    assert lambertian <= at(3.0, 3.0) <= 1.05 * lambertian  # open ground: diffuse + a little specular
    assert at(1.0, 0.0) == pytest.approx(at(3.0, 3.0), rel=0.02)  # sun side of the pole: lit
    for x_m in (-0.5, -1.0, -1.5):  # the shadow, from the pole's foot to 2 m towards −X
        assert at(x_m, 0.0) < 0.05 * lambertian
    assert at(-2.6, 0.0) == pytest.approx(at(3.0, 3.0), rel=0.02)  # beyond the shadow's tip


def test_double_sided_surfaces_keep_depth_and_ids_from_behind(renderer):
    graph = _graph(
        environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [20, 20]}]},
        lights=[{"type": "ambient", "illuminance_lux": 100}],
    )
    ground = graph.environment_nodes[0]
    for primitive in ground.mesh.primitives:
        primitive.material.doubleSided = True
    view = View(camera_matrix(300.0, 300.0, 159.5, 119.5), look_at((0.0, -6.0, -5.0), (0.0, 0.0, 0.0)), 320, 240)
    lit = renderer.draw(graph, view, ("radiance", "instance_id")).instance_id
    geometric = renderer.draw(graph, view, ("depth_m", "instance_id")).instance_id
    assert (lit == 1).sum() > 1000
    np.testing.assert_array_equal(geometric, lit)


def test_a_renderer_dropped_without_close_leaves_others_working(renderer):
    import gc

    from camgen.render.renderer import Renderer

    graph = _lit_plane(lights=[{"type": "ambient", "illuminance_lux": 10}])
    Renderer().draw(graph, _overhead_view(), ("instance_id",))
    gc.collect()
    assert (
        renderer.draw(
            _lit_plane(lights=[{"type": "ambient", "illuminance_lux": 10}]), _overhead_view(), ("instance_id",)
        ).instance_id
        == 1
    ).any()


def test_a_wall_rising_past_a_spot_lights_plane_has_no_nan(renderer):
    """A street lamp (a spot pointing down) half a metre from a wall that rises above it: the wall's
    pixels level with the lamp lie on its plane (w = 0 in its shadow map's projection). Dividing by w
    there made 0 · inf = NaN in 531 of the 641 × 481 pixels (and in 3 pixels of scenes/night_street.yaml
    at 4 MP, which stopped the sensor); the shader now skips what lies outside the beam."""
    graph = _graph(
        environment={"meshes": [{"type": "box", "name": "wall", "size_m": [0.2, 30, 12], "position_m": [10, 0, 6]}]},
        lights=[
            {"type": "spot", "position_m": [9.5, 0, 5], "target_m": [9.5, 0, 0], "intensity_cd": 2000,
             "cone_half_angle_deg": 60},
            {"type": "ambient", "illuminance_lux": 0.1},
        ],
    )  # fmt: skip
    view = View(camera_matrix(100, 100, 320, 240), look_at((0, 0, 5), (1, 0, 5)), 641, 481)
    radiance = renderer.draw(graph, view, ("radiance",)).radiance
    assert np.isfinite(radiance).all()
    assert radiance[:240, 320].max() < radiance[250:, 320].max()  # the wall is lit below the lamp only


def test_an_opengl_without_texture_gathers_is_refused_with_what_to_do():
    from camgen.errors import ConfigError
    from camgen.render.renderer import check_gl_features

    check_gl_features((4, 5), set(), "llvmpipe")  # Mesa's llvmpipe
    check_gl_features((3, 3), {"GL_ARB_texture_gather"}, "an old driver with the extension")
    with pytest.raises(ConfigError, match=r"OpenGL 3\.3 \(softpipe\) lacks texture gathers.*llvmpipe"):
        check_gl_features((3, 3), {"GL_ARB_instanced_arrays"}, "softpipe")


def test_this_machines_opengl_has_what_the_shaders_use(renderer):
    from OpenGL import GL

    renderer._make_current()
    assert (int(GL.glGetIntegerv(GL.GL_MAJOR_VERSION)), int(GL.glGetIntegerv(GL.GL_MINOR_VERSION))) >= (4, 0)
