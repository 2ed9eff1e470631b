"""The procedural brick's normal map (`camgen.world.textures.normal_map_from_height`) on a rendered wall
under a low, grazing sun: each recessed joint's edge that faces the sun lit, the one that faces away
darker, as a groove in a real wall is; the wall as bright on average as without its relief."""

from __future__ import annotations

import numpy as np
import pytest

from tests.render.conftest import lit_wall_radiance

pytestmark = pytest.mark.opengl

F_PX, DISTANCE_M = 1200.0, 2.0
COURSE_M, BRICK_PITCH_M, JOINT_M = 0.075, 0.225, 0.010  # BS EN 771-1 work sizes, as the texture draws them


def _wall_radiance(renderer, relief: bool) -> np.ndarray:
    """A brick wall's +x face (x = 0.5, y across, z up from the ground) seen square-on from 2 m, lit by a
    sun from the right (+y) and above, 20° over the horizon."""
    return lit_wall_radiance(renderer, {"type": "brick"}, (1, 6, 3), 70, 20, F_PX, DISTANCE_M, relief)[0]


def test_joints_are_lit_from_the_suns_side(renderer):
    relief, flat = _wall_radiance(renderer, True), _wall_radiance(renderer, False)
    assert relief.mean() == pytest.approx(flat.mean(), rel=0.01)
    change = (relief - flat) / flat.mean()
    # The face's texture: u = y + 3 m (right-handed with v up), v = z; row 0 of the tile at v = 0, so
    # bed joints span z ∈ [k, k + 10 mm] per 75 mm course and head joints u ∈ [k, k + 10 mm] per 225 mm
    # (shifted half a brick every other course).
    rows, cols = np.mgrid[0:480, 0:640]
    z = 1.5 - (rows - 239.5) * DISTANCE_M / F_PX
    u = 3.0 + (cols - 319.5) * DISTANCE_M / F_PX
    in_course = np.mod(z, COURSE_M)
    lower_edge = (in_course < 0.003) | (in_course > COURSE_M - 0.002)  # the brick below's top: faces up
    upper_edge = (in_course > JOINT_M - 0.003) & (in_course < JOINT_M + 0.002)  # the brick above's underside
    assert change[lower_edge].mean() > 0.1 and change[upper_edge].mean() < -0.1
    in_brick = np.mod(u + np.where(np.floor(z / COURSE_M) % 2 == 1, BRICK_PITCH_M / 2, 0.0), BRICK_PITCH_M)
    mid_course = (in_course > JOINT_M + 0.01) & (in_course < COURSE_M - 0.01)
    left_edge = mid_course & ((in_brick < 0.003) | (in_brick > BRICK_PITCH_M - 0.002))  # faces +u, the sun
    right_edge = mid_course & (in_brick > JOINT_M - 0.003) & (in_brick < JOINT_M + 0.002)
    assert change[left_edge].mean() > 0.1 and change[right_edge].mean() < -0.1
