"""Road markings in the render (`camgen.render.scene_graph`, `camgen.world.markings`): paint shows where its
projection says, with its own instance id after every other; it receives shadows and casts none; its NIR
reflectance reaches the night-mode graph."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from camgen.config.profile import Profile
from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph, instance_table
from camgen.world.markings import PAINT_NIR_REFLECTANCE, PAINT_RGB, marking_paint
from tests.conftest import FIXED_PROFILE
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

GROUND_RHO = 0.1
SIZE_PX = 200
HEIGHT_M = 5.0
F_PX = 500.0
"""5 m straight down at 500 px focal length: 1 cm per pixel on the ground, 2 × 2 m in view."""


def _scene(markings, meshes=(), sun_elevation_deg=None):
    lights = [{"type": "ambient", "illuminance_lux": 1000}]
    if sun_elevation_deg is not None:
        lights.append({"type": "sun", "illuminance_lux": 10000, "azimuth_deg": 0.0, "elevation_deg": sun_elevation_deg})
    ground = {"type": "plane", "name": "ground", "size_m": [20, 20], "material": {"color_rgb": [GROUND_RHO] * 3}}
    return scene_from(
        environment={"meshes": [ground, *meshes], "markings": list(markings)},
        lights=lights,
        actors=[{"name": "walker", "class": "person", "path": {"waypoints_m": [[8, 8]]}}],
    )


def _overhead() -> View:
    T = look_at((0.0, 0.0, HEIGHT_M), (0.0, 0.0, 0.0))
    c = (SIZE_PX - 1) / 2
    return View(camera_matrix(F_PX, F_PX, c, c), T, SIZE_PX, SIZE_PX)


def _pixel_of(view: View, points_m) -> np.ndarray:
    """(N, 2) pixel (u, v) of world points, by the pinhole alone (an independent projection)."""
    p = np.column_stack([np.asarray(points_m, float), np.zeros(len(points_m))])
    T = view.T_world_from_cam
    cam = (p - T[:3, 3]) @ T[:3, :3]
    uvw = cam @ view.K_px.T
    return uvw[:, :2] / uvw[:, 2:]


def _luminance(radiance):
    return radiance @ np.array([0.2126, 0.7152, 0.0722])


def test_paint_shows_inside_its_projection_with_its_own_id(renderer):
    """A 1.6 × 0.5 m bar of new white paint (no wear) on a ground of ρ = 0.1 under ambient light only: every
    pixel 2 px or more inside its projected rectangle renders the paint's reflectance (ρ E / π within the
    ±8 % dirt) and carries the marking's id, the last of the scene's; every pixel 2 px or more outside, the
    ground's. Worn by 30 %, the pixels of paint cover the worn paint's area (0.7 of the bar's) within 3 %."""
    bar = {"type": "line", "along_m": [[-0.8, 0.1], [0.8, 0.1]], "width_m": 0.5, "wear": 0.0}
    view = _overhead()
    corners = _pixel_of(view, [[-0.8, -0.15], [0.8, -0.15], [0.8, 0.35], [-0.8, 0.35]])
    u0, v0 = corners.min(axis=0)
    u1, v1 = corners.max(axis=0)
    us, vs = np.meshgrid(np.arange(SIZE_PX), np.arange(SIZE_PX))
    inner = (us >= u0 + 2) & (us <= u1 - 2) & (vs >= v0 + 2) & (vs <= v1 - 2)
    outer = (us < u0 - 2) | (us > u1 + 2) | (vs < v0 - 2) | (vs > v1 + 2)
    assert inner.sum() > 5000 and outer.sum() > 10000

    scene = _scene([bar])
    ids = {i.name: i.instance_id for i in instance_table(scene)}
    assert ids["line_0"] == max(ids.values()) == 3  # after the walker (1) and the ground (2)
    passes = renderer.draw(build_scene_graph(scene), view, ("radiance", "instance_id"))
    luminance = _luminance(passes.radiance)
    ambient_cd_m2 = 1000 / math.pi
    paint_y = float(np.array([0.2126, 0.7152, 0.0722]) @ PAINT_RGB["white"])
    assert np.all(passes.instance_id[inner] == ids["line_0"])
    assert np.all(passes.instance_id[outer] == ids["ground"])
    assert np.all(np.abs(luminance[inner] / (paint_y * ambient_cd_m2) - 1) < 0.085)
    np.testing.assert_allclose(luminance[outer], GROUND_RHO * ambient_cd_m2, rtol=0.01)

    worn_bar = {**bar, "wear": 0.3}
    worn_scene = _scene([worn_bar])
    worn = renderer.draw(build_scene_graph(worn_scene), view, ("instance_id",))
    pixel_m2 = (HEIGHT_M / F_PX) ** 2
    painted_m2 = np.count_nonzero(worn.instance_id == ids["line_0"]) * pixel_m2
    paint = marking_paint(worn_scene.environment.markings[0], scene_seed=worn_scene.seed, index=0)
    assert paint.painted_area_m2 == pytest.approx(0.7 * 1.6 * 0.5, rel=0.01)
    assert painted_m2 == pytest.approx(paint.painted_area_m2, rel=0.03)
    assert np.all(worn.instance_id[outer] == ids["ground"])


def test_paint_receives_shadows_and_casts_none(renderer):
    """Sun 45° high in +x. A bar of paint floated 1 m over the ground (surface_height_m: 1) would shade the
    ground 1 m towards −x of itself if it cast shadows: that ground stays as lit as the open ground. A 2 m
    pole at x = 0.9 shades the paint on the ground under it: paint in the pole's shadow is lit by the
    ambient light alone (ρ E_ambient / π)."""
    view = _overhead()
    floating = {"type": "line", "along_m": [[-0.2, 0.5], [0.6, 0.5]], "width_m": 0.3, "surface_height_m": 1.0}
    on_ground = {"type": "line", "along_m": [[-0.9, -0.5], [0.8, -0.5]], "width_m": 0.3, "wear": 0.0}
    pole = {"type": "box", "name": "pole", "size_m": [0.1, 0.1, 2.0], "position_m": [0.9, -0.5, 1.0]}
    scene = _scene([floating, on_ground], [pole], sun_elevation_deg=45.0)
    luminance = _luminance(renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance)

    def at(x0, x1, y0, y1):
        (u0, v0), (u1, v1) = np.sort(np.rint(_pixel_of(view, [[x0, y0], [x1, y1]])).astype(int), axis=0)
        return luminance[v0:v1, u0:u1]

    lit_ground = np.median(at(-0.9, -0.5, 0.05, 0.25))
    beside_plate = at(-0.85, -0.45, 0.42, 0.58)  # the floating bar's shadow would fall on x in [-1.2, -0.4]
    np.testing.assert_allclose(beside_plate, lit_ground, rtol=0.01)
    shaded_paint = np.median(at(-0.6, 0.2, -0.53, -0.47))  # the pole's shadow: x from -1.1 to 0.9, |y + 0.5| < 0.05
    sunlit_paint = np.median(at(-0.85, -0.7, -0.6, -0.4))
    paint_y = float(np.array([0.2126, 0.7152, 0.0722]) @ PAINT_RGB["white"])
    assert shaded_paint == pytest.approx(paint_y * 1000 / math.pi, rel=0.085)  # the ambient light alone
    assert sunlit_paint > 3 * shaded_paint


def test_the_night_graph_takes_the_paints_nir_reflectance():
    """The IR pass sees white paint at 0.50 and yellow at 0.45 (± the dirt), grey, over the ground's."""
    from camgen.render.nir import build_nir_graph

    profile = yaml.safe_load(FIXED_PROFILE)
    profile["night_mode"] = {}
    scene = _scene(
        [
            {"type": "line", "along_m": [[0, 0], [1, 0]]},
            {"type": "line", "along_m": [[0, 1], [1, 1]], "colour": "yellow"},
        ]
    )
    graph = build_nir_graph(scene, Profile.model_validate(profile))
    for node, marking, index in zip(graph.environment_nodes[1:], scene.environment.markings, (0, 1), strict=True):
        (primitive,) = node.mesh.primitives
        grey = np.asarray(primitive.color_0)
        expected = marking_paint(marking, scene_seed=scene.seed, index=index).nir_reflectance
        np.testing.assert_allclose(grey[:, 0], expected, rtol=1e-6)
        assert np.allclose(grey[:, 0], grey[:, 1]) and np.allclose(grey[:, 0], grey[:, 2])
        assert abs(float(grey[:, 0].mean()) - PAINT_NIR_REFLECTANCE[marking.colour]) < 0.03
        assert tuple(primitive.material.baseColorFactor[:3]) == (1.0, 1.0, 1.0)


def test_paint_casts_no_shadow_under_a_spot_light(renderer):
    """A spot lamp 3 m up at x = 2 (a spot's shadow map is pyrender's pass, not the sun's cascades). A bar of
    paint floated 1 m over the ground (x −0.2…0.6, y 0.35…0.65) would shade the ground at x −1.3…−0.1,
    y 0.5…1.0 if it cast shadows: that ground is as lit as in the same scene without the bar. A box plate of
    the same size at y −0.5 does shade the ground at y −1.0…−0.5 (shadows are on)."""
    view = _overhead()
    floating = {"type": "line", "along_m": [[-0.2, 0.5], [0.6, 0.5]], "width_m": 0.3, "surface_height_m": 1.0}
    plate = {"type": "box", "name": "plate", "size_m": [0.8, 0.3, 0.02], "position_m": [0.2, -0.5, 1.0]}
    spot = {"type": "spot", "position_m": [2.0, 0.0, 3.0], "target_m": [-0.5, 0.0, 0.0], "intensity_cd": 5000}

    def luminance(markings):
        ground = {"type": "plane", "name": "ground", "size_m": [20, 20], "material": {"color_rgb": [GROUND_RHO] * 3}}
        scene = scene_from(
            environment={"meshes": [ground, plate], "markings": markings},
            lights=[{"type": "ambient", "illuminance_lux": 100}, spot],
        )
        return _luminance(renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance)

    with_bar, without = luminance([floating]), luminance([])

    def at(image, x0, x1, y0, y1):
        (u0, v0), (u1, v1) = np.sort(np.rint(_pixel_of(view, [[x0, y0], [x1, y1]])).astype(int), axis=0)
        return image[v0:v1, u0:u1]

    np.testing.assert_allclose(at(with_bar, -0.9, -0.4, 0.6, 0.9), at(without, -0.9, -0.4, 0.6, 0.9), rtol=1e-4)
    assert np.median(at(without, -0.9, -0.4, -0.9, -0.6)) < 0.5 * np.median(at(without, -0.9, -0.4, 0.6, 0.9))
