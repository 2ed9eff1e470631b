"""A car's greenhouse (`camgen.vehicles.body`): its roof narrower than its body, its side glass filling the
greenhouse's height and its windscreen most of its width, as on real cars; and its lamp units. No OpenGL.

References (makers' dimensions and side, front and rear views of current C-segment cars, e.g. a VW Golf 8:
1.789 m wide, 1.456 m high, beltline about 0.98 m up; a Toyota Corolla: 1.79 m wide): the roof, over its
rails, is about 1.2–1.35 m wide (0.65–0.78 of the body's width); the side glass runs from the beltline to
within about 0.1 m of the roof line; the windscreen is about 1.3–1.45 m wide at its base (0.72–0.82 of the
width)."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.vehicles.body import LOWER_POINTS, PROFILES, UPPER_POINTS, build_vehicle, shell
from camgen.vehicles.look import draw_look

CARS = ("hatchback", "sedan", "estate", "suv")


def _grid(look):
    vertices, _, _, kind = shell(look)
    count = UPPER_POINTS + LOWER_POINTS
    stations = len(vertices) // count
    quads = (stations - 1) * count
    grid = vertices[: stations * count].reshape(stations, count, 3)
    return grid, kind[:quads].reshape(stations - 1, count)


@pytest.mark.parametrize("body", CARS)
def test_the_roof_is_narrower_than_the_body(body):
    look = draw_look(7, "car", pinned={"body_type": body})
    grid, _ = _grid(look)
    top = grid[..., 2].max(axis=1)
    roofed = top > 0.97 * look.height_m  # stations under the roof's flat
    # The roof's width at the height 5 cm under its top, against the body's widest.
    widths = []
    for station in grid[roofed]:
        high = station[station[:, 2] > station[:, 2].max() - 0.05]
        widths.append(np.ptp(high[:, 1]))
    ratio = np.median(widths) / look.width_m
    assert 0.62 < ratio < 0.8, ratio


@pytest.mark.parametrize("body", CARS)
def test_the_side_glass_fills_the_greenhouse_and_the_windscreen_its_width(body):
    look = draw_look(7, "car", pinned={"body_type": body})
    profile = PROFILES[body]
    grid, kind = _grid(look)
    glass = kind == 1
    belt_m, roof_m = profile.belt * look.height_m, look.height_m
    # Side glass: the highest glass point on a side (|y| beyond the roof's half width) in the side windows' band.
    side = []
    for s in range(len(kind)):
        u = grid[s, 0, 0] / look.length_m + 0.5
        if profile.side_glass[0] + 0.05 < u < profile.side_glass[1] - 0.05 and grid[s, :, 2].max() > 0.97 * roof_m:
            quads = np.flatnonzero(glass[s, : UPPER_POINTS // 2])  # the +y side's rows
            if quads.size:
                side.append(grid[s, quads + 1, 2].max())
    reach = (np.nanmedian(side) - belt_m) / (roof_m - belt_m)
    assert reach > 0.7, reach
    # Windscreen: the run of glass quads across the centreline, at the stations of its lower half.
    lo, hi = profile.windscreen
    widths = []
    centre = UPPER_POINTS // 2
    for s in range(len(kind)):
        u = grid[s, 0, 0] / look.length_m + 0.5
        if lo < u < hi and grid[s, :, 2].max() < 0.9 * roof_m and glass[s, centre]:
            first = last = centre
            while first > 0 and glass[s, first - 1]:
                first -= 1
            while last < UPPER_POINTS - 1 and glass[s, last + 1]:
                last += 1
            widths.append(grid[s, first, 1] - grid[s, last + 1, 1])
    assert widths
    assert 0.6 < np.median(widths) / look.width_m < 0.85, np.median(widths) / look.width_m


def test_cars_have_lamp_units_at_their_corners():
    look = draw_look(7, "car", pinned={"body_type": "hatchback"})
    units = [part for part in build_vehicle(look).parts if part.surface == "lens"]
    assert len(units) == 1
    vertices = units[0].vertices_m
    front, rear = vertices[vertices[:, 0] > 0], vertices[vertices[:, 0] < 0]
    for end in (front, rear):
        # One unit at each corner, out to the end face's edge.
        assert (end[:, 1] > 0.2).any() and (end[:, 1] < -0.2).any()
        assert np.ptp(end[:, 1]) > 0.8 * PROFILES["hatchback"].end_width * look.width_m
    red = units[0].colours[vertices[:, 0] < 0]
    assert (red[:, 0] > 5 * red[:, 1]).any() and (red[:, 0] < 2 * red[:, 1]).any()  # red lenses, a clear one
    bus = draw_look(7, "bus")
    assert not any(part.surface == "lens" for part in build_vehicle(bus).parts)
