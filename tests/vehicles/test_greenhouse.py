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

from camgen.vehicles.body import LOWER_POINTS, PROFILES, UPPER_POINTS, _end_heights, build_vehicle, shell
from camgen.vehicles.look import draw_look

CARS = ("hatchback", "sedan", "estate", "suv")
CLASS_OF = {"van": "truck"}


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


@pytest.mark.parametrize("body", (*CARS, "pickup", "van"))
@pytest.mark.parametrize("seed", [1, 7])
def test_headlamp_units_reach_back_over_the_nose(body, seed):
    """Seen from above, a car's front corners are its headlamps: each unit's top lies on the nose's surface (just
    outside the closed shell, the shell just under it, at points all over its triangles, not only its corners),
    from the front face back about 0.18 m and 0.3–0.5 m across from the shoulder in at each station (0.42 m at the
    middle one, where its rows are chosen; a van's steeper nose less); the grille's width stays between them."""
    from tests.vehicles.test_mirrors_saloon import _winding_number

    look = draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})
    unit = next(part for part in build_vehicle(look).parts if part.name == "lamp_units")
    corners = unit.vertices_m[unit.faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    front_m = look.length_m / 2
    _, (_, front_high_m) = _end_heights(look)
    # The faces over the front face's top edge: the tops (the boxes on the face end 2.5 cm under the edge and stand
    # 2.5 cm proud of the face).
    top = np.all(corners[:, :, 0] > 0, axis=1) & np.all(corners[:, :, 0] < front_m + 0.015, axis=1)
    top &= (corners[:, :, 2].min(axis=1) > front_high_m - 0.02) & (normal[:, 2] > 0)
    vertices, faces, _, _ = shell(look)
    rng = np.random.default_rng(0)
    for side in (1, -1):
        mine = corners[top & (np.sign(corners[:, :, 1]).sum(axis=1) == 3 * side)]
        points = mine.reshape(-1, 3)
        assert len(mine) > 10
        assert front_m - 0.2 < points[:, 0].min() < front_m - 0.15 and abs(points[:, 0].max() - front_m) < 0.01
        widths = [np.ptp(points[np.isclose(points[:, 0], x, atol=1e-3), 1]) for x in np.unique(points[:, 0].round(3))]
        # A van's nose is steeper: the rows facing up over it span 0.14–0.17 m of the unit's width.
        assert (0.1 if body == "van" else 0.3) < np.median(widths) and max(widths) < 0.5, widths
        # Points inside its triangles (barycentric), not only its corners: outside the shell, the shell 1 cm in.
        weights = rng.dirichlet(np.ones(3), size=len(mine))
        inward = -normal[top & (np.sign(corners[:, :, 1]).sum(axis=1) == 3 * side)]
        inward /= np.linalg.norm(inward, axis=1, keepdims=True)
        for point, into in list(zip(np.einsum("fk,fkd->fd", weights, mine), inward, strict=True))[::3]:
            assert _winding_number(vertices, faces, point) == pytest.approx(0.0, abs=1e-6), (body, point)
            assert _winding_number(vertices, faces, point + 0.01 * into) == pytest.approx(1.0, abs=1e-6)
    assert np.abs(corners[top][:, :, 1]).min() > 0.15  # the grille between them, 0.3 m or more
