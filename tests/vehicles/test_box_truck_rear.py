"""A box truck's rear and sides (`camgen.vehicles.body`): its load floor raised over the road from its cab's back, over
its rear wheels (`Profile.rear_floor_m`); between its wheels the side guards of UN Regulation No. 73 (rails whose
lower edge is at most 550 mm over the road, at most 300 mm apart, the upper edge at most 350 mm under the floor, ends
at most 300 mm from the tyres, outer faces at most 120 mm inside the body's side) and mudguards over the rear tyres;
under its rear overhang the rear underrun guard of UN Regulation No. 58 (a horizontal bar, its lower
edge at most 550 mm over the road, at most 100 mm inside the rear tyres' outer faces on each side, near the rear end)
on the chassis frame's rails, so that seen from behind the road and the rear tyres show under the body. Checked on
`build_vehicle`'s parts. No OpenGL."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from camgen.vehicles.body import (
    FLOOR_STEP_M,
    PROFILES,
    TRIM_RGB,
    TYRE_WIDTH_SHARE,
    build_vehicle,
    floor_start_x_m,
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
    behind = paint[paint[:, 0] < floor_start_x_m(look) - FLOOR_STEP_M - 1e-6]
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


R73_LOWER_EDGE_MAX_M = 0.55
R73_RAIL_GAP_MAX_M = 0.30
R73_RAIL_MIN_M = 0.05
R73_UNDER_BODY_MAX_M = 0.35
R73_TYRE_GAP_MAX_M = 0.30
R73_INSET_MAX_M = 0.12


@pytest.mark.parametrize("seed", SEEDS)
def test_the_side_guards_meet_un_r73(seed):
    look, model = _truck(seed)
    gear = next(p for p in model.parts if p.name == "running_gear")
    r = look.wheel_radius_m
    # Between the tyres, clear of the rear mudguards (which reach 0.125 m past the tyres).
    x = gear.vertices_m[:, 0]
    between = (x > look.rear_axle_x_m + r + 0.15) & (x < look.front_axle_x_m - r)
    for side in (1, -1):
        # The guard: the black trim under the floor near this side (not the cab's or the floor's underbody).
        here = between & (gear.wheel < 0) & (side * gear.vertices_m[:, 1] > look.width_m / 2 - R73_INSET_MAX_M)
        here &= np.all(np.isclose(gear.colours, TRIM_RGB), axis=1)
        here &= gear.vertices_m[:, 2] < PROFILES["box_truck"].rear_floor_m - 0.05
        guard = gear.vertices_m[here]
        assert len(guard) > 0
        assert look.width_m / 2 - np.abs(guard[:, 1]).max() <= R73_INSET_MAX_M
        assert guard[:, 2].min() <= R73_LOWER_EDGE_MAX_M
        # The rails: the heights their outward faces cover, merged into bands; the gaps between them and up to the
        # floor within R73's.
        faces = gear.faces[here[gear.faces].all(axis=1)]
        spans = sorted((float(z.min()), float(z.max())) for z in gear.vertices_m[faces][:, :, 2])
        bands = [list(spans[0])]
        for low, high in spans[1:]:
            if low <= bands[-1][1] + 1e-9:
                bands[-1][1] = max(bands[-1][1], high)
            else:
                bands.append([low, high])
        assert len(bands) >= 2, bands
        assert all(high - low >= R73_RAIL_MIN_M for low, high in bands)
        assert all(b[0] - a[1] <= R73_RAIL_GAP_MAX_M for a, b in itertools.pairwise(bands))
        assert PROFILES["box_truck"].rear_floor_m - bands[-1][1] <= R73_UNDER_BODY_MAX_M
        # Its ends near the tyres.
        assert guard[:, 0].min() - (look.rear_axle_x_m + r) <= R73_TYRE_GAP_MAX_M  # at most 0.15 m past the mudguard
        assert (look.front_axle_x_m - r) - guard[:, 0].max() <= R73_TYRE_GAP_MAX_M


@pytest.mark.parametrize("seed", SEEDS)
def test_the_rear_tyres_run_under_the_floor_with_mudguards_over_them(seed):
    look, model = _truck(seed)
    floor_m = PROFILES["box_truck"].rear_floor_m
    r = look.wheel_radius_m
    assert 2 * r < floor_m  # the tyres' tops under the floor: no wheel arch in the box
    gear = next(p for p in model.parts if p.name == "running_gear")
    v = gear.vertices_m
    for side in (1, -1):
        over = (gear.wheel < 0) & (np.abs(v[:, 0] - look.rear_axle_x_m) < r + 0.2) & (side * v[:, 1] > 0)
        over &= np.abs(np.abs(v[:, 1]) - look.track_m / 2) < TYRE_WIDTH_SHARE * look.width_m / 2 + 0.05
        over &= (v[:, 2] > 2 * r) & (v[:, 2] < floor_m - 0.1)
        assert over.any() and np.allclose(gear.colours[over], TRIM_RGB)  # the mudguard over the tyre
