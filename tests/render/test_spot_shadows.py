"""A street lamp's shadow (a spot light's perspective shadow map, filtered like the sun's): lit ground does
not shadow itself, a straight edge stays straight, and a shadow stays at its caster's foot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

LAMP_HEIGHT_M = 6.0


def _graph(meshes: list[dict], target_m, shadows: bool = True):
    """Ground and `meshes` under one 6000 lm lamp 6 m up (the default 70° cone: a 151° shadow map, 2.3 cm
    texels at 6 m) aimed at `target_m`."""
    from camgen.render.scene_graph import build_scene_graph

    lamp = {"type": "lamp", "position_m": [0.0, 0.0, LAMP_HEIGHT_M], "target_m": target_m, "flux_lm": 6000}
    ground = {"type": "plane", "name": "ground", "size_m": [200.0, 200.0]}
    return build_scene_graph(scene_from(environment={"shadows": shadows, "meshes": [ground, *meshes]}, lights=[lamp]))


def _looking_down(centre_m, height_m: float, image_x_deg: float, f_px: float, width_px: int, height_px: int) -> View:
    """Straight down from `height_m` over `centre_m` (x, y), the image's x axis along `image_x_deg` (from +X)."""
    a = math.radians(image_x_deg)
    x, z = np.array([math.cos(a), math.sin(a), 0.0]), np.array([0.0, 0.0, -1.0])
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = [centre_m[0], centre_m[1], height_m]
    return View(camera_matrix(f_px, f_px, (width_px - 1) / 2, (height_px - 1) / 2), T, width_px, height_px)


@pytest.mark.parametrize("target_m", [[-1.0, 2.5, 0.0], [2.5, 1.5, 0.0], [-4.6, -3.9, 0.0]])
def test_open_lamp_lit_ground_does_not_shadow_itself(renderer, target_m):
    """Flat ground under a lamp tilted 24°, 26° and 45° from the vertical, seen from 2.5 m over the pool out
    to where the light grazes it: every pixel the lamp lights (over 1/1000 of the brightest, which keeps
    n·l above the bias's floor of 0.1) gets the light it gets with shadows off (measured: all exactly). The
    ground's depth in a tilted lamp's map slopes, and the filtered lookup compares texels two away; pyrender's
    one lookup with its constant bias left 0 % of the light on most of the ground here at the first
    direction (its lookup sits half a texel off the grid, so the acne came and went with the lamp's
    azimuth)."""
    view = View(
        camera_matrix(80.0, 80.0, 79.5, 59.5),
        look_at((-1.0, -1.0, 2.5), (2 * target_m[0], 2 * target_m[1], 0.0)),
        160,
        120,
    )
    green = {s: renderer.draw(_graph([], target_m, s), view, ("radiance",)).radiance[..., 1] for s in (True, False)}
    lit = green[False] > 1e-3 * green[False].max()
    assert lit.mean() > 0.5
    ratio = green[True][lit] / green[False][lit]
    assert ratio.min() >= 0.99, f"darkest lit ground pixel at {ratio.min():.4f} of its light"


def test_a_straight_lamp_shadow_edge_stays_straight(renderer):
    """A long wall (20 cm thick, 1 m high, at 30° to the map's axes) 1.39 m from the foot of a lamp tilted
    12°: the shadow of its top's far edge is a straight line on the ground, 6/5 of the edge's distance from
    the lamp's foot: 1.783 m. Seen from 3 m straight down at 5 mm a pixel (texels 2.3 cm, 4.6 pixels), the
    filtered lookup's edge changes its row smoothly from column to column (RMS second difference 0.095 px
    measured) and lies on the geometric line (0.22 px, 1.1 mm); pyrender's one lookup followed the texels'
    staircase (0.580 px) half a texel off (3.1 cm)."""
    along = np.array([math.cos(math.radians(30.0)), math.sin(math.radians(30.0))])
    away = np.array([-along[1], along[0]])  # from the lamp's foot across the wall
    centre = np.array([0.0, 1.6])
    far_face_m = abs(centre @ away) + 0.1
    edge_m = far_face_m * LAMP_HEIGHT_M / (LAMP_HEIGHT_M - 1.0)
    wall = {
        "type": "box",
        "name": "wall",
        "size_m": [10.0, 0.2, 1.0],
        "position_m": [centre[0], centre[1], 0.5],
        "rotation_deg": [0, 0, 30],
    }
    view = _looking_down(edge_m * away, 3.0, 30.0, 600.0, 320, 120)  # the edge on the middle row (59.5)
    radiance = renderer.draw(_graph([wall], [1.2, 0.4, 0.0]), view, ("radiance",)).radiance
    luminance = radiance @ np.array([0.2126, 0.7152, 0.0722])
    level = (np.percentile(luminance, 95) + np.percentile(luminance, 5)) / 2
    rows = []  # lit ground above (farther from the lamp), the wall's shadow below
    for column in range(luminance.shape[1]):
        values = luminance[:, column]
        (crossing,) = np.flatnonzero((values[:-1] >= level) & (values[1:] < level))
        rows.append(crossing + (values[crossing] - level) / (values[crossing] - values[crossing + 1]))
    rows = np.array(rows)
    roughness_px = np.sqrt(np.mean(np.diff(rows, 2) ** 2))
    print(f"spot shadow edge: roughness {roughness_px:.3f} px, mean row {rows.mean():.2f} (geometric 59.5)")
    assert roughness_px < 0.2
    assert rows.mean() == pytest.approx(59.5, abs=1.0)  # 5 mm


def test_a_lamp_shadow_starts_at_its_casters_foot(renderer):
    """A board 1 cm thick and 1.5 m high, broadside to a lamp 6 m up and 6 m away (the light 45° from the
    vertical, texels 2.8 cm there): the ground behind it is in its shadow from its back face on. Seen
    edge-on from 10 m up at 2.5 mm a pixel, the first ground pixel behind it keeps 0.62 of its light (the
    filter's kernel reaches the lit ground in front) and under half of it is left from 1.4 cm behind it on, as with
    no depth bias at all; a 3 cm constant bias would leave over three quarters of it lit out to 2 cm, and
    pyrender's one lookup shadowed it fully from the first pixel."""
    back_m = 6.005
    board = {"type": "box", "name": "board", "size_m": [0.01, 2.0, 1.5], "position_m": [6.0, 0.0, 0.75]}
    view = _looking_down((back_m, 0.0), 10.0, 0.0, 4000.0, 160, 120)
    green = {
        s: renderer.draw(_graph([board], [1.5, 0.0, 0.0], s), view, ("radiance",)).radiance[60, :, 1]
        for s in (True, False)
    }
    x_m = back_m + (np.arange(160) - 79.5) * 10.0 / 4000.0  # the ground's x under each column of row 60
    behind = x_m > back_m
    ratio = green[True][behind] / green[False][behind]
    half_lit_m = x_m[behind][np.flatnonzero(ratio < 0.5)[0]] - back_m
    print(f"behind the board: {np.round(ratio[:8], 2)}; half the light gone {100 * half_lit_m:.2f} cm behind")
    assert ratio[0] < 0.8
    assert half_lit_m < 0.02
    assert ratio[40:].max() < 0.01  # 10 cm on: in the full shadow


def test_a_renderer_draws_fewer_spot_lights_after_more():
    """A renderer that drew a scene with two spot lights and a sun then draws one with a single spot light and the
    sun as a fresh renderer does: the program's second spot shadow map kept the unit the first scene gave it, which
    the second gives the sun's cascade array, and OpenGL refused the draw ("invalid operation") before the unused
    entries were pointed at the first map's unit."""
    from camgen.render.renderer import Renderer
    from camgen.render.scene_graph import build_scene_graph

    ground = {"type": "plane", "name": "ground", "size_m": [40.0, 40.0]}
    box = {"type": "box", "name": "box", "size_m": [1.0, 1.0, 1.0], "position_m": [0.0, 2.0, 0.5]}
    sun = {"type": "sun", "illuminance_lux": 20000, "azimuth_deg": 200, "elevation_deg": 30}
    spot = {"type": "spot", "intensity_cd": 20000, "position_m": [2.0, 2.0, 6.0], "target_m": [0.0, 2.0, 0.0]}
    other = {"type": "spot", "intensity_cd": 20000, "position_m": [-2.0, 4.0, 0.6], "target_m": [-2.0, 12.0, 0.2]}

    def graph(lights):
        return build_scene_graph(scene_from(environment={"meshes": [ground, box]}, lights=lights))

    view = View(camera_matrix(80.0, 80.0, 79.5, 59.5), look_at((0.0, -6.0, 4.0), (0.0, 2.0, 0.0)), 160, 120)
    with Renderer() as fresh:
        expected = fresh.draw(graph([sun, spot]), view, ("radiance",)).radiance
    with Renderer() as used:
        used.draw(graph([sun, spot, other]), view, ("radiance",))
        again = used.draw(graph([sun, spot]), view, ("radiance",)).radiance
    assert np.array_equal(again, expected)
