"""A bus's own features (`camgen.vehicles.body`, `camgen.vehicles.sign`): steel disc wheels instead of a car's
five-spoke alloys, and an LED destination display over the windscreen.

- Wheels: seen along its axle, a bus's wheel is a closed disc of steel (the rim's colour over at least 90 %
  of the rim's circle, a car's hub, ring and five spokes over 0.52) with `HAND_HOLES` dark holes and
  `STUD_COUNT` nuts on ISO 4107's 335 mm circle.
- The display: its lit dots read back as the matrix of the bus's route and destination (dot by dot), lie
  on the front end above the windscreen's glass within the display's size, and in a scene without
  light (0.001 lux) it is the only thing the bus shows, amber at the display's night luminance (OpenGL).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.vehicles.body import (
    HAND_HOLES,
    PROFILES,
    RIM_RGB,
    RIM_SHARE,
    SIGN_PANEL_MARGIN_M,
    SIGN_TOP_SHARE,
    STUD_CIRCLE_M,
    STUD_COUNT,
    TYRE_RGB,
    build_vehicle,
    steel_disc_wheel_meshes,
    wheel_meshes,
)
from camgen.vehicles.look import draw_look
from camgen.vehicles.sign import (
    MATRIX_COLUMNS,
    MATRIX_ROWS,
    SIGN_SIZE_M,
    destination_text,
    display_luminance_cd_m2,
    matrix,
)

GRID_PX = 400


def _covered(meshes, radius_m: float) -> float:
    """Share of the disc of `radius_m` about the axle that `meshes` (wheel frame, axle along y) cover seen along
    the axle."""
    scale = GRID_PX / (2.2 * radius_m)
    image = np.zeros((GRID_PX, GRID_PX), np.uint8)
    for mesh in meshes:
        for triangle in np.asarray(mesh.vertices)[np.asarray(mesh.faces)][:, :, [0, 2]]:
            cv2.fillConvexPoly(image, np.round((triangle * scale + GRID_PX / 2) * 16).astype(np.int32), 1, shift=4)
    y, x = np.mgrid[:GRID_PX, :GRID_PX] - (GRID_PX - 1) / 2
    inside = np.hypot(x, y) < radius_m * scale
    return float(image[inside].mean())


def test_a_bus_rolls_on_steel_discs_and_a_car_on_spokes():
    look = draw_look(1, "bus")
    rim_m = RIM_SHARE["bus"] * look.wheel_radius_m
    disc, holes = steel_disc_wheel_meshes(look.wheel_radius_m, 0.29, RIM_SHARE["bus"])
    assert _covered(disc, 0.98 * rim_m) > 0.9
    _, spokes = wheel_meshes(look.wheel_radius_m, 0.29, RIM_SHARE["bus"])
    assert _covered(spokes, 0.98 * rim_m) < 0.6  # hub, ring and five spokes: 0.52
    assert len(holes) == HAND_HOLES and len(disc) == 2 + STUD_COUNT
    nuts = np.array([np.asarray(piece.vertices)[:, [0, 2]].mean(axis=0) for piece in disc[2:]])
    assert np.hypot(*nuts.T) == pytest.approx(STUD_CIRCLE_M / 2, abs=1e-3)
    # The built bus carries them: its rims' vertices of one wheel hold the disc and nuts, its dark gear the holes.
    gear = next(part for part in build_vehicle(look).parts if part.name == "running_gear")
    wheel = gear.wheel == 0
    rim = wheel & np.all(np.isclose(gear.colours, RIM_RGB), axis=1)
    dark = wheel & np.all(np.isclose(gear.colours, TYRE_RGB), axis=1)
    assert rim.sum() == sum(3 * len(piece.faces) for piece in disc)  # flat-shaded
    assert (np.hypot(*gear.vertices_m[dark][:, [0, 2]].T) < 0.9 * rim_m).sum() > 0


def _dots(look):
    return next(part for part in build_vehicle(look).parts if part.surface == "destination")


def test_the_display_shows_the_route_and_destination_over_the_windscreen():
    look = draw_look(302, "bus")
    dots = _dots(look)
    width_m, height_m = SIGN_SIZE_M
    quads = dots.vertices_m.reshape(-1, 4, 3)
    assert np.allclose(quads[:, :, 0], quads[0, 0, 0]) and quads[0, 0, 0] > look.length_m / 2  # on the front
    assert np.all(dots.normals == (1.0, 0.0, 0.0))
    assert np.abs(quads[:, :, 1]).max() < width_m / 2
    glass_top_m = PROFILES["bus"].front_cap_glass[1] * look.height_m
    assert quads[:, :, 2].min() > glass_top_m and quads[:, :, 2].max() < 0.93 * look.height_m
    # Dot by dot: each quad's rows and columns back on the matrix give the route's and destination's matrix.
    top_m = SIGN_TOP_SHARE * look.height_m - SIGN_PANEL_MARGIN_M
    read = np.zeros((MATRIX_ROWS, MATRIX_COLUMNS), bool)
    for quad in quads:
        row = int((top_m - quad[:, 2].mean()) / (height_m / MATRIX_ROWS))
        pitch_m = width_m / MATRIX_COLUMNS
        first, last = (quad[:, 1].min() + width_m / 2) / pitch_m, (quad[:, 1].max() + width_m / 2) / pitch_m
        read[row, round(first - 0.1) : round(last + 0.1)] = True
    expected = matrix(*destination_text(look.identity_seed))
    assert np.array_equal(read, expected)
    assert 0.1 < expected.mean() < 0.5
    # Another bus, another route or destination.
    assert destination_text(301) != destination_text(302)


@pytest.mark.opengl
def test_the_display_shines_amber_in_the_dark(renderer):
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from camgen.vehicles import LAMP_COLOUR_RGB
    from tests.render.conftest import camera_matrix, look_at, scene_from

    scene = scene_from(
        environment={"sky_luminance_cd_m2": 0.0, "shadows": False},
        lights=[{"type": "ambient", "illuminance_lux": 0.001}],  # a scene needs a light; 0.3 mcd/m² off white
        actors=[{"name": "bus", "class": "bus", "vehicle": {"seed": 302}, "path": {"waypoints_m": [[0, 0]]}}],
    )
    graph = build_scene_graph(scene)
    look = graph.vehicles[0].look
    T_vehicle = graph.vehicles[0].T_world_from_vehicle
    sign = (T_vehicle @ [look.length_m / 2, 0.0, 0.8 * look.height_m, 1.0])[:3]
    T = look_at(sign + 8.0 * T_vehicle[:3, 0], sign)  # 8 m ahead of the bus, facing its front
    passes = renderer.draw(graph, View(camera_matrix(300.0, 300.0, 79.5, 59.5), T, 160, 120), ("radiance",))
    lit = passes.radiance.max(axis=2) > 1.0
    # In the dark the display dims to its night level (`camgen.vehicles.sign.display_luminance_cd_m2`).
    expected = display_luminance_cd_m2(0.001) * np.asarray(LAMP_COLOUR_RGB["destination"])
    # The brightest pixels are whole dots: the display's emission, amber (red over green, no blue).
    brightest = passes.radiance[passes.radiance[..., 0] >= 0.99 * passes.radiance[..., 0].max()]
    np.testing.assert_allclose(np.median(brightest, axis=0), expected, rtol=0.02, atol=0.01)
    rows, cols = np.nonzero(lit)
    span_px = (cols.max() - cols.min() + 1, rows.max() - rows.min() + 1)
    width_px = 300.0 * SIGN_SIZE_M[0] / 8.0
    assert span_px[0] <= width_px + 2 and span_px[1] <= 300.0 * SIGN_SIZE_M[1] / 8.0 + 2
    assert span_px[0] > 0.6 * width_px and math.isclose(np.mean(cols), 79.5, abs_tol=0.25 * width_px)
