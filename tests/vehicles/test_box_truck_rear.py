"""A box truck's rear (`camgen.vehicles.body`): its load floor raised over the road behind the rear wheels
(`Profile.rear_floor_m`) and, under it, the rear underrun guard of UN Regulation No. 58 (a horizontal bar, its lower
edge at most 550 mm over the road, at most 100 mm inside the rear tyres' outer faces on each side, near the rear end)
on the chassis frame's rails, so that seen from behind the road and the rear tyres show under the body. Checked on
`build_vehicle`'s parts. No OpenGL."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.vehicles.body import (
    ARCH_GAP_M,
    FLOOR_STEP_M,
    PROFILES,
    TRIM_RGB,
    TYRE_WIDTH_SHARE,
    build_vehicle,
)
from camgen.vehicles.look import draw_look

SEEDS = range(6)
R58_LOWER_EDGE_MAX_M = 0.55
R58_SECTION_MIN_M = 0.10
R58_INSET_MAX_M = 0.10
R58_SETBACK_MAX_M = 0.40


def _truck(seed: int):
    look = draw_look(seed, "truck", pinned={"body_type": "box_truck"})
    return look, build_vehicle(look)


def _guard_m(look, model) -> np.ndarray:
    """The black pieces under the floor behind the rear tyres and lower than the frame: the guard's bar, (V, 3)."""
    gear = next(p for p in model.parts if p.name == "running_gear")
    behind = gear.vertices_m[:, 0] < look.rear_axle_x_m - look.wheel_radius_m - 0.1
    low = gear.vertices_m[:, 2] < 0.8
    assert np.allclose(gear.colours[behind & low], TRIM_RGB)
    return gear.vertices_m[behind & low & (gear.wheel < 0)]


@pytest.mark.parametrize("seed", SEEDS)
def test_the_underrun_guard_meets_un_r58(seed):
    look, model = _truck(seed)
    bar = _guard_m(look, model)
    bottom, top = bar[:, 2].min(), bar[:, 2].max()
    assert bottom <= R58_LOWER_EDGE_MAX_M and top - bottom >= R58_SECTION_MIN_M
    # Horizontal: its lowest points span its whole width at one height.
    lowest = bar[np.isclose(bar[:, 2], bottom)]
    assert lowest[:, 1].max() == pytest.approx(bar[:, 1].max()) and lowest[:, 1].min() == pytest.approx(bar[:, 1].min())
    tyre_outer_m = look.track_m / 2 + TYRE_WIDTH_SHARE * look.width_m / 2
    assert tyre_outer_m - R58_INSET_MAX_M <= bar[:, 1].max() <= tyre_outer_m
    assert bar[:, 0].min() - (-look.length_m / 2) <= R58_SETBACK_MAX_M


@pytest.mark.parametrize("seed", SEEDS)
def test_the_floor_is_raised_behind_the_rear_wheels_and_the_tyres_show_from_behind(seed):
    look, model = _truck(seed)
    floor_m = PROFILES["box_truck"].rear_floor_m
    paint = next(p for p in model.parts if p.name == "body_paint").vertices_m
    arch_end = look.rear_axle_x_m - look.wheel_radius_m - ARCH_GAP_M - FLOOR_STEP_M
    behind = paint[paint[:, 0] < arch_end - 1e-6]
    assert behind[:, 2].min() == pytest.approx(floor_m)
    assert floor_m > _guard_m(look, model)[:, 2].max() + 0.2
    # Nothing of the body (but the guard's bar, over the wheel centre) lies behind a rear tyre lower than its axle:
    # seen from behind its lower half shows.
    parts = [p for p in model.parts if p.surface != "shade" and (p.wheel < 0).any()]
    body = np.concatenate([p.vertices_m[p.wheel < 0] for p in parts])
    half_tyre_m = TYRE_WIDTH_SHARE * look.width_m / 2
    inner, outer = look.track_m / 2 - half_tyre_m, look.track_m / 2 + half_tyre_m
    in_line = (np.abs(body[:, 1]) > inner) & (np.abs(body[:, 1]) < outer)
    behind_tyre = body[in_line & (body[:, 0] < look.rear_axle_x_m - look.wheel_radius_m)]
    assert behind_tyre[:, 2].min() > look.wheel_radius_m
