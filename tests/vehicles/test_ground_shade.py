"""The shaded ground under a vehicle seen from behind (`camgen.vehicles.body.ground_shade`, OpenGL): below the
rear bumper the ground under the overhang shows dark, as under a real car, yet it is background in the
instance pass and outside the vehicle's box (`VehicleRig.box_vertices_m`), so the box still bounds the
vehicle's own pixels."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.annotate.boxes import points_box
from camgen.render.renderer import View
from camgen.render.scene_graph import ShadeMaterial, build_scene_graph
from camgen.vehicles.body import GROUND_SHADE_RGB
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

ROAD_RHO = 0.12
WIDTH_PX, HEIGHT_PX = 160, 120
K_PX = camera_matrix(220.0, 220.0, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2)


@pytest.fixture(scope="module")
def behind(renderer):
    """(passes, passes with the shade labelled as the vehicle, T_world_from_cam, the vehicle's rig and instance
    id): a red
    hatchback seen from 8 m behind and 3 m up under an overcast sky (ambient light only)."""
    scene = scene_from(
        environment={
            "sky_luminance_cd_m2": 3000.0,
            "shadows": False,
            "meshes": [
                {"type": "plane", "name": "road", "size_m": [40, 40], "material": {"color_rgb": [ROAD_RHO] * 3}}
            ],
        },
        lights=[{"type": "ambient", "illuminance_lux": 10000.0}],
        actors=[
            {
                "name": "car",
                "class": "car",
                "vehicle": {"seed": 201, "body_type": "hatchback", "colour": "red"},
                "path": {"waypoints_m": [[0, 0]], "heading_deg": 90},
            }
        ],
    )
    graph = build_scene_graph(scene)
    rig = graph.vehicles[0]
    rear = (rig.T_world_from_vehicle @ [-rig.look.length_m / 2, 0.0, 0.5, 1.0])[:3]
    T = look_at(rear + np.array([0.0, -8.0, 2.5]), rear - np.array([0.0, 0.0, 0.1]))
    view = View(K_PX, T, WIDTH_PX, HEIGHT_PX)
    passes = renderer.draw(graph, view, ("radiance", "instance_id"))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(ShadeMaterial, "unlabelled", False)
        labelled = renderer.draw(graph, view, ("radiance", "instance_id"))
    return passes, labelled, T, rig, graph.instance_ids[graph.actor_nodes[0]]


def test_the_ground_under_the_rear_overhang_is_dark_and_background(behind):
    passes, labelled, _, _, car = behind
    shade = (labelled.instance_id == car) & (passes.instance_id != car)
    assert shade.sum() >= 20 and np.all(passes.instance_id[shade] == 0)  # seen below the bumper, background
    assert np.array_equal(passes.radiance, labelled.radiance)
    road = np.median(passes.radiance[-5:, :, 1])  # the open road at the view's bottom edge
    assert road == pytest.approx(ROAD_RHO * 10000.0 / np.pi, rel=0.02)
    expected = np.asarray(GROUND_SHADE_RGB) * 10000.0 / np.pi
    np.testing.assert_allclose(np.median(passes.radiance[shade], axis=0), expected, rtol=0.02)
    assert np.median(passes.radiance[shade][:, 1]) < 0.1 * road


def test_the_box_bounds_the_vehicle_and_leaves_the_shade_out(behind):
    passes, labelled, T, rig, car = behind
    x0, y0, x1, y1 = points_box(rig.box_vertices_m, T, K_PX, np.zeros(5))
    rows, cols = np.nonzero(passes.instance_id == car)
    # The mask's tight box (pixel edges) within a pixel of the projected box.
    np.testing.assert_allclose([cols.min(), rows.min(), cols.max() + 1, rows.max() + 1], [x0, y0, x1, y1], atol=1.0)
    # Every vertex's box would reach down over the shade, below the vehicle's own pixels.
    everything = points_box(rig.vertices_m, T, K_PX, np.zeros(5))
    shade_rows, _ = np.nonzero((labelled.instance_id == car) & (passes.instance_id != car))
    assert everything[3] > y1 + 2 and shade_rows.max() + 1 > y1 + 2
