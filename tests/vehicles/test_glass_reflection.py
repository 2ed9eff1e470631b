"""Vehicle glass mirrors its environment (the shader's `transmissive` path, `camgen.render.scene_graph.GLASS_RGB`):
Schlick's Fresnel factor times the sky's radiance where the reflected ray goes up, the lit ground's where it goes
down, as the paint's clear coat does. A bus's side window seen from below (its reflection of the sky) is brighter
than the same window seen from above (its reflection of the ground) by 4 % of the sky's radiance less 4 % of the
ground's (`CLEARCOAT_GROUND_ALBEDO`, 0.15 of the sky's under the ambient light alone); the cabin seen through both
adds the same. OpenGL."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.opengl

AMBIENT_LUX = 10_000.0
SCHLICK_F0 = 0.04
CLEARCOAT_GROUND_ALBEDO = 0.15
"""The shader's ground under the sky (`linear_mesh.frag`)."""


@pytest.fixture(scope="module")
def window_views(renderer):
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from camgen.vehicles.body import nearside_sign
    from tests.render.conftest import camera_matrix, look_at, scene_from

    scene = scene_from(
        # The ambient light stands for a uniform sky of radiance E / π (what the glass mirrors); the sky drawn
        # behind the bus is black, so that what is seen through both its sides adds the same in both views.
        environment={"sky_luminance_cd_m2": 0.0, "shadows": False},
        lights=[{"type": "ambient", "illuminance_lux": AMBIENT_LUX}],
        actors=[{"name": "bus", "class": "bus", "vehicle": {"seed": 5}, "path": {"waypoints_m": [[0, 0]]}}],
    )
    graph = build_scene_graph(scene)
    look, T_vehicle = graph.vehicles[0].look, graph.vehicles[0].T_world_from_vehicle
    # Mid-height of the side glass, halfway between the axles, on the bus's offside (its glazed doors are on the
    # nearside: the left, +y, for a UK-format plate, `camgen.vehicles.body.nearside_sign`).
    side = -nearside_sign(look)
    window = (T_vehicle @ [0.0, side * look.width_m / 2, 0.62 * look.height_m, 1.0])[:3]
    outward = T_vehicle[:3, 1] * side
    views = {}
    for name, rise_m in (("below", -1.6), ("above", 1.6)):  # the reflected ray 15° up or down
        eye = window + 6.0 * outward + np.array([0.0, 0.0, rise_m])
        view = View(camera_matrix(300.0, 300.0, 39.5, 29.5), look_at(eye, window), 80, 60)
        views[name] = renderer.draw(graph, view, ("radiance", "instance_id"))
    return views


def test_a_window_mirrors_the_sky_above_and_the_ground_below(window_views):
    sky_cd_m2 = AMBIENT_LUX / np.pi
    centre = {name: float(passes.radiance[25:35, 35:45].mean()) for name, passes in window_views.items()}
    # Seen 15° off the normal, Schlick's factor is F0 to 1e-5: the window mirrors 4 % of the sky from below and
    # 4 % of the ground (0.15 of the sky's radiance under the ambient light alone) from above.
    expected = SCHLICK_F0 * sky_cd_m2 * (1 - CLEARCOAT_GROUND_ALBEDO)
    assert centre["below"] - centre["above"] == pytest.approx(expected, rel=0.15)
    assert centre["below"] > 2.0 * centre["above"]
