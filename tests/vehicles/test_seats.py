"""The seats seen through a vehicle's glass (`camgen.vehicles.cabin.seats_part`).

- Cars carry two front seats and a rear bench, vans two front seats; trucks and buses none here (a bus's saloon:
  `bus_interior_part`). Every seat lies inside the closed shell (its vertices' winding number 1), so the vehicle's
  silhouette, box and mask are the shell's, and inside its lining (`LINING_INSET_M` in from the shell).
- The front head restraints' tops stand at least 0.75 m from the H-point along the torso line (UN Regulation No. 17's
  least height of a front head restraint in its lowest position).
- The rear bench's restraints lie `COUPLE_DISTANCE_M` behind the front ones; the upholstery is dark (`SEAT_RGB`);
  the same seed gives the same seats.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.vehicles.body import ARCH_GAP_M, build_vehicle, shell
from camgen.vehicles.cabin import (
    CLEARANCE_M,
    COUPLE_DISTANCE_M,
    H_POINT_BEFORE_BACK_M,
    HEAD_ABOVE_H_POINT_M,
    SEAT_BACK_M,
    SEAT_BODIES,
    SEAT_RGB,
    SEATS,
    seats_part,
    windscreen_x_m,
)
from camgen.vehicles.look import draw_look
from tests.vehicles.test_mirrors_saloon import _winding_number

CLASS_OF = {"van": "truck", "box_truck": "truck", "bus": "bus"}
R17_HEIGHT_M = 0.75


def _look(body: str, seed: int):
    return draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})


def _restraint_tops(part, h_point_z_m: float) -> np.ndarray:
    """(n, 3) the highest vertex of each seat's head restraint, per side, front seats and rear bench (the seats'
    parts 0.3 m over the H-points: backs and restraints; the front ones within 0.45 m of the foremost)."""
    v = part.vertices_m
    high = v[v[:, 2] > h_point_z_m + 0.3]
    front = high[:, 0] > high[:, 0].max() - 0.45
    tops = []
    for side in (1, -1):
        for group in (front, ~front):
            here = high[group & (side * high[:, 1] > 0.05)]
            if len(here):
                tops.append(here[np.argmax(here[:, 2])])
    return np.array(tops)


@pytest.mark.parametrize("body", SEAT_BODIES)
@pytest.mark.parametrize("seed", [1, 2])
def test_seats_lie_inside_the_shell_and_under_its_lining(body, seed):
    look = _look(body, seed)
    part = seats_part(look)
    assert part is not None and np.allclose(part.colours, SEAT_RGB)
    vertices, faces, _, _ = shell(look)
    points = np.unique(np.round(part.vertices_m, 9), axis=0)
    winding = np.array([_winding_number(vertices, faces, p) for p in points])
    assert np.allclose(winding, 1.0, atol=1e-6), (body, seed, points[np.abs(winding - 1) > 1e-6][:3])
    again = seats_part(look)
    assert np.array_equal(part.vertices_m, again.vertices_m)
    assert any(p.name == "cabin" for p in build_vehicle(look).parts)


@pytest.mark.parametrize("body", SEAT_BODIES)
def test_head_restraints_meet_un_r17s_height(body):
    look = _look(body, 3)
    seat = SEATS[body]
    part = seats_part(look)
    tops = _restraint_tops(part, seat.h_point_z_m)
    front = tops[tops[:, 0] > tops[:, 0].max() - 0.45]
    assert len(front) == 2
    # Along the torso line (A40 from the vertical) from the H-point (its place behind the driver's head: `SEATS`).
    h_x = windscreen_x_m(look)[0] - seat.head_behind_windscreen_m + HEAD_ABOVE_H_POINT_M * math.sin(seat.back_angle_rad)
    torso = np.array([-math.sin(seat.back_angle_rad), math.cos(seat.back_angle_rad)])
    along = (front[:, [0, 2]] - [h_x, seat.h_point_z_m]) @ torso
    assert np.all(along >= R17_HEIGHT_M), (body, along)
    rear = tops[tops[:, 0] < tops[:, 0].max() - 0.45]
    if body == "van":
        assert len(rear) == 0
    else:
        assert len(rear) == 2
        # COUPLE_DISTANCE_M behind, or nearer where that keeps the bench clear of the rear wheel arches (the
        # smallest hatchbacks'), never under 0.6 m (a city car's rear legroom).
        arch_front = look.rear_axle_x_m + look.wheel_radius_m + ARCH_GAP_M
        clear = h_x - (arch_front + H_POINT_BEFORE_BACK_M + SEAT_BACK_M[1] + CLEARANCE_M)
        couple = front[:, 0].mean() - rear[:, 0].mean()
        assert couple == pytest.approx(min(COUPLE_DISTANCE_M, clear), abs=0.05)
        assert couple > 0.6


@pytest.mark.parametrize("body", ["box_truck", "bus"])
def test_no_seats_drawn_here_for_trucks_and_buses(body):
    assert seats_part(_look(body, 1)) is None
