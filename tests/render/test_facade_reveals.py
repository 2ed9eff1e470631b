"""The facade's recessed windows (`camgen.world.textures.REVEAL_DEPTH_M`) on a rendered wall under a low sun from
one side: the reveal facing the sun lit as a face turned 45° towards it (the splay of the height map), the one
facing away in its own shade, the wall between them as without the relief."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.world.textures import REVEAL_DEPTH_M, SILL_M, WINDOW_H_M, WINDOW_PITCH_M, WINDOW_W_M
from tests.render.conftest import lit_wall_radiance

pytestmark = pytest.mark.opengl

F_PX, DISTANCE_M, WIDTH_PX, HEIGHT_PX = 500.0, 12.0, 640, 480
SUN_AZIMUTH_DEG, SUN_ELEVATION_DEG = 60.0, 10.0


def _wall_radiance(renderer, relief: bool) -> tuple[np.ndarray, View]:
    """A 12 m facade's +x face (x = 0.5; texture u = y + 6 m, v = z) seen square-on from 12 m, under a sun 10° up
    from azimuth 60° (from +x towards +y): it reaches the face at 60° from its normal, from the +y side."""
    texture = {"type": "facade", "seed": 3}
    return lit_wall_radiance(
        renderer,
        texture,
        (1, 12, 9),
        SUN_AZIMUTH_DEG,
        SUN_ELEVATION_DEG,
        F_PX,
        DISTANCE_M,
        relief,
        (WIDTH_PX, HEIGHT_PX),
    )


def _pixels(view: View, y_m: np.ndarray, z_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    world = np.column_stack([np.full(y_m.size, 0.5), y_m.ravel(), z_m.ravel()])
    T = view.T_world_from_cam
    cam = (world - T[:3, 3]) @ T[:3, :3]
    px = cam[:, :2] / cam[:, 2:] * F_PX + [(WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2]
    return np.round(px[:, 1]).astype(int), np.round(px[:, 0]).astype(int)


def test_a_low_sun_lights_one_reveal_and_shades_the_other(renderer):
    relief, view = _wall_radiance(renderer, True)
    flat, _ = _wall_radiance(renderer, False)
    # The first- and second-storey windows of the four bays: each reveal's splay, REVEAL_DEPTH_M wide outside
    # the window's side, sampled along its middle over the window's height.
    x0 = (WINDOW_PITCH_M - WINDOW_W_M) / 2
    bays_u = np.arange(4) * WINDOW_PITCH_M
    z = np.concatenate([k * 3.0 + SILL_M + np.linspace(0.3, WINDOW_H_M - 0.3, 9) for k in (1, 2)])
    sides = {
        "left (faces +y, the sun)": x0 - REVEAL_DEPTH_M / 2,
        "right (faces -y)": x0 + WINDOW_W_M + REVEAL_DEPTH_M / 2,
    }
    towards_sun = np.array(
        [
            math.cos(math.radians(SUN_ELEVATION_DEG)) * math.cos(math.radians(SUN_AZIMUTH_DEG)),
            math.cos(math.radians(SUN_ELEVATION_DEG)) * math.sin(math.radians(SUN_AZIMUTH_DEG)),
            math.sin(math.radians(SUN_ELEVATION_DEG)),
        ]
    )
    wall_cos = towards_sun[0]
    ratios = {}
    for name, u_in_bay in sides.items():
        y = (bays_u[:, None] + u_in_bay - 6.0) * np.ones_like(z)[None, :]
        rows, cols = _pixels(view, y, np.broadcast_to(z, y.shape))
        ratios[name] = float(np.median(relief[rows, cols] / flat[rows, cols]))
    # The splay turns the normal 45° about z: towards +y on the left, −y on the right (n = (1, ±1, 0)/√2).
    lit = (towards_sun[0] + towards_sun[1]) / math.sqrt(2) / wall_cos
    assert ratios["left (faces +y, the sun)"] == pytest.approx(lit, rel=0.1)  # 1.93
    assert ratios["right (faces -y)"] < 0.1  # turned away from the sun: (0.17 − 0.85)/√2 < 0
    # Between the bays' openings the wall is flat, as without the relief.
    rows, cols = _pixels(view, np.linspace(-5.8, 5.8, 200), np.full(200, 3.0 + 0.3))
    np.testing.assert_allclose(np.median(relief[rows, cols] / flat[rows, cols]), 1.0, atol=0.01)
