"""Black plastic on a vehicle's ends (`camgen.vehicles.body._black_trim`): a car's, van's or truck's front
shows a radiator grille between its head lamps and a lower intake round its front plate, a car's rear a
black lower bumper under its rear plate; a bus's front neither (its windscreen and destination display
fill it). Checked on `lamps_and_plates`' parts: where the black pieces lie against the lamps, the plates and the end
faces. No OpenGL."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config.scene import VEHICLE_BODY_TYPES
from camgen.vehicles.body import (
    DIFFUSER_BODIES,
    GRILLE_BODIES,
    LAMP_DEPTH_M,
    REAR_BUMPER_BODIES,
    _end_heights,
    lamps_and_plates,
)
from camgen.vehicles.look import TWO_WHEELERS, draw_look

CLASS_OF = {body: cls for cls, bodies in VEHICLE_BODY_TYPES.items() for body in bodies if body not in TWO_WHEELERS}


def _ends(body: str):
    """(look, head lamps' vertices, the plates' corners, black trim vertices at the front (V, 3) and at the rear
    (V, 3), but the plate backings) of the ends as `lamps_and_plates` builds them."""
    look = draw_look(1, CLASS_OF[body], pinned={"body_type": body})
    lamps, plates, _, trim = lamps_and_plates(look)
    black = trim.vertices_m
    # The plate backings: 1 cm round each plate.
    backing = np.zeros(len(black), dtype=bool)
    for corners in plates.values():
        inside_y = np.abs(black[:, 1]) <= np.abs(corners[:, 1]).max() + 0.0101
        inside_z = (black[:, 2] >= corners[:, 2].min() - 0.0101) & (black[:, 2] <= corners[:, 2].max() + 0.0101)
        backing |= inside_y & inside_z & (np.abs(np.abs(black[:, 0]) - np.abs(corners[0, 0])) < LAMP_DEPTH_M)
    black = black[~backing]
    front = black[black[:, 0] > look.length_m / 2 - LAMP_DEPTH_M]
    rear = black[black[:, 0] < -look.length_m / 2 + LAMP_DEPTH_M]
    head = next(part for part in lamps if part.surface == "head").vertices_m
    return look, head, plates, front, rear


@pytest.mark.parametrize("body", sorted(CLASS_OF))
def test_grilles_intakes_and_lower_bumpers_sit_on_the_ends(body):
    look, head, plates, front, rear = _ends(body)
    (rear_low, _), (front_low, front_high) = _end_heights(look)
    if body not in GRILLE_BODIES:
        assert len(front) == 0
    else:
        # Between the head lamps, within the front face, and as wide as most of the gap between the lamps.
        gap = np.abs(head[:, 1]).min()
        assert np.abs(front[:, 1]).max() >= 0.8 * gap
        grille = front[front[:, 2] > head[:, 2].min()]  # the intake stays 4 cm under the grille
        assert len(grille) and np.abs(grille[:, 1]).max() < gap
        assert front[:, 2].min() > front_low and front[:, 2].max() < front_high
        # The lower intake reaches above the front plate, which lies in front of it.
        plate = plates["front"]
        assert front[:, 2].max() > plate[:, 2].max() and plate[0, 0] > front[:, 0].max()
    if body in REAR_BUMPER_BODIES:  # a van's black bumper with its step: tests/vehicles/test_van_rear.py
        assert len(rear) and rear[:, 2].max() <= plates["rear"][:, 2].min()
    elif body not in DIFFUSER_BODIES:
        assert len(rear) == 0
    else:
        # Under the rear plate, across most of the rear face.
        plate = plates["rear"]
        assert rear[:, 2].min() > rear_low and rear[:, 2].max() <= plate[:, 2].min()
        assert 2 * np.abs(rear[:, 1]).max() > 0.7 * look.width_m
