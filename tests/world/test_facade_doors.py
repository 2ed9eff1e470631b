"""The facade's entrance doors and recessed openings (`camgen.world.textures._facade`): doors where their
published sizes put them (Approved Document M's 1.0 m clear leaf, 2.1 m high, a glazed vision panel), one
per `DOOR_EVERY_BAYS` bays in the ground storey only, and every window and door set back `REVEAL_DEPTH_M`
in the height map behind the normal map, the wall keeping its mean reflectance of 1."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.world.textures import (
    DOOR_CLEAR_W_M,
    DOOR_EVERY_BAYS,
    DOOR_FRAME_M,
    DOOR_H_M,
    DOOR_PANEL_M,
    DOOR_ROUGHNESS,
    FACADE_STOREY_M,
    GLASS_SET_BACK_M,
    REVEAL_DEPTH_M,
    SILL_M,
    WINDOW_H_M,
    WINDOW_PITCH_M,
    WINDOW_W_M,
    surface_maps,
)

M_PER_TEXEL = 0.01  # 10 mm texels: every edge of the layout within a texel of a multiple of it


def _maps(tile_m: float, seed: int = 0):
    return surface_maps("facade", seed, tile_m, texels=round(tile_m / M_PER_TEXEL))


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of each run of True."""
    padded = np.concatenate([[False], flags, [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2], edges[1::2] - 1, strict=True))


def _door_columns(maps) -> list[tuple[int, int]]:
    """Column runs of painted leaf (a door's roughness) in the ground storey."""
    ground = maps.roughness[: round(FACADE_STOREY_M / M_PER_TEXEL)]
    leaf = np.isclose(ground, DOOR_ROUGHNESS).any(axis=0)
    return _runs(leaf)


@pytest.mark.parametrize(("tile_m", "doors"), [(3.0, 1), (6.0, 1), (12.0, 1), (24.0, 2), (36.0, 3)])
def test_one_door_per_four_bays_in_the_ground_storey_only(tile_m, doors):
    """Within one tile; the tile repeats up a wall taller than it, door storey included (a 3 m tile is one
    storey: a door on every storey of the wall), which the README says."""
    maps = _maps(tile_m)
    bays = round(tile_m / WINDOW_PITCH_M)
    assert doors == max(1, round(bays / DOOR_EVERY_BAYS))
    assert len(_door_columns(maps)) == doors
    above = maps.roughness[round(FACADE_STOREY_M / M_PER_TEXEL) :]
    assert above.shape[0] == round((tile_m - FACADE_STOREY_M) / M_PER_TEXEL)  # the storeys above, if any
    assert not np.isclose(above, DOOR_ROUGHNESS).any()  # no door above the ground storey
    if tile_m > FACADE_STOREY_M:  # and their windows are there: what the check looks at holds texels of the wall
        assert (above < 0.1).any()


def test_a_door_has_its_published_size_frame_and_vision_panel():
    maps = _maps(12.0, seed=3)
    ((first, last),) = _door_columns(maps)
    # The leaf: 1.0 m clear, centred in its 3 m bay, from the floor to 2.1 m.
    width_m = (last - first + 1) * M_PER_TEXEL
    assert width_m == pytest.approx(DOOR_CLEAR_W_M, abs=2 * M_PER_TEXEL)
    centre_m = (first + last + 1) / 2 * M_PER_TEXEL
    assert centre_m % WINDOW_PITCH_M == pytest.approx(WINDOW_PITCH_M / 2, abs=M_PER_TEXEL)
    column = (first + last) // 2
    painted_rows = _runs(np.isclose(maps.roughness[:, column + 45], DOOR_ROUGHNESS))  # beside the panel
    assert len(painted_rows) == 1 and painted_rows[0][0] == 0
    assert (painted_rows[-1][1] + 1) * M_PER_TEXEL == pytest.approx(DOOR_H_M, abs=M_PER_TEXEL)
    # The glazed panel: glass (roughness 0.05) between 0.5 and 1.9 m up the leaf's middle.
    ((bottom, top),) = _runs(maps.roughness[: round(FACADE_STOREY_M / M_PER_TEXEL), column] < 0.1)
    assert bottom * M_PER_TEXEL == pytest.approx(DOOR_PANEL_M[1], abs=1.5 * M_PER_TEXEL)
    assert (top + 1) * M_PER_TEXEL == pytest.approx(DOOR_PANEL_M[2], abs=1.5 * M_PER_TEXEL)
    # The frame: dark (a window frame's reflectance) for 70 mm either side of the leaf, then the wall.
    row = round(1.0 / M_PER_TEXEL)
    frame = maps.albedo[row, first - round(DOOR_FRAME_M / M_PER_TEXEL) + 1 : first, 0]
    assert np.all(frame < 0.3)
    assert maps.albedo[row, first - round(DOOR_FRAME_M / M_PER_TEXEL) - 2, 0] > 0.8
    # No ground-storey window in the door's bay; the other bays keep theirs.
    over_doors = round((DOOR_H_M + DOOR_FRAME_M + SILL_M + WINDOW_H_M) / 2 / M_PER_TEXEL)  # 2.29 m
    glass_columns = _runs(maps.roughness[over_doors] < 0.1)
    assert len(glass_columns) == 12.0 / WINDOW_PITCH_M - 1
    assert all(not (a <= column <= b) for a, b in glass_columns)


def _slope_u(maps, row: int, columns: slice) -> np.ndarray:
    """∂h/∂u along a row of texels, from the normal map: n ∝ (−∂h/∂u, −∂h/∂v, 1)."""
    normal = maps.normal[row, columns]
    return -normal[:, 0] / normal[:, 2]


def test_openings_are_recessed_by_their_reveal_depth_in_the_height_map():
    maps = _maps(12.0, seed=3)
    assert maps.normal is not None
    # A row through the middle of the first storey's windows: integrating the slope from the wall in front of
    # a window's left reveal to its frame gives the reveal's depth, and on to the glass the glazing's set-back.
    row = round((FACADE_STOREY_M + SILL_M + WINDOW_H_M / 2) / M_PER_TEXEL)
    left = round(((WINDOW_PITCH_M - WINDOW_W_M) / 2) / M_PER_TEXEL)  # the window's left edge, texels
    start = left - round(2 * REVEAL_DEPTH_M / M_PER_TEXEL)
    to_frame = _slope_u(maps, row, slice(start, left + 3)).sum() * M_PER_TEXEL
    assert to_frame == pytest.approx(-REVEAL_DEPTH_M, rel=0.03)
    to_glass = _slope_u(maps, row, slice(start, left + 12)).sum() * M_PER_TEXEL
    assert to_glass == pytest.approx(-REVEAL_DEPTH_M - GLASS_SET_BACK_M, rel=0.03)
    # The reveal is a splay as wide as it is deep: its normals lean 45° towards the opening.
    splay = _slope_u(maps, row, slice(left - round(0.8 * REVEAL_DEPTH_M / M_PER_TEXEL), left - 2))
    np.testing.assert_allclose(splay, -1.0, atol=0.05)
    # The wall between openings is flat, and a door is recessed as a window is (across its left jamb).
    wall_row = round((FACADE_STOREY_M + 0.3) / M_PER_TEXEL)
    np.testing.assert_allclose(maps.normal[wall_row, :, 2], 1.0, atol=1e-6)
    ((first, _),) = _door_columns(maps)
    jamb = first - round(DOOR_FRAME_M / M_PER_TEXEL)
    door_row = round(1.0 / M_PER_TEXEL)
    across = _slope_u(maps, door_row, slice(jamb - round(2 * REVEAL_DEPTH_M / M_PER_TEXEL), jamb + 3)).sum()
    assert across * M_PER_TEXEL == pytest.approx(-REVEAL_DEPTH_M, rel=0.03)


def test_the_wall_keeps_its_mean_reflectance():
    maps = _maps(12.0, seed=5)
    wall = (maps.roughness > 0.8) & (maps.albedo[..., 0] > 0.5)  # not glass, paint or frames
    assert maps.albedo[wall].mean() == pytest.approx(1.0, abs=0.01)
