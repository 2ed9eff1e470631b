"""Pillars between a vehicle's panes (`camgen.vehicles.body._screen_pillars`): the windscreen, the rear window
and the side windows are separate panes of glass, paint between them (A-, B- and C-pillars), as on every
real car; before, the windscreen wrapped round its corners into the front side windows as one pane. No
OpenGL."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.config.scene import VEHICLE_BODY_TYPES
from camgen.vehicles.body import BLACK_PILLAR_SHARE, PROFILES, UNDERBODY_RGB, build_vehicle, shell
from camgen.vehicles.look import draw_look

CLASS_OF = {body: cls for cls, bodies in VEHICLE_BODY_TYPES.items() for body in bodies}
SIDE_NORMAL_Y = 0.75
"""A glass face is side glass where its normal's |y| exceeds this (the shell's own split, `_glass_by_quad`)."""
CARS = ("sedan", "hatchback", "estate", "suv", "pickup")
SCREENED = (*CARS, "van", "box_truck")
"""Body types whose windscreen is part of the lofted tube (a bus's is its flat front end)."""


def _panes(body: str, seed: int):
    """(face normals (G, 3), face centres (G, 3), component label (G,)) of the shell's glass faces, faces
    sharing an edge in one component."""
    look = draw_look(seed, CLASS_OF[body], pinned={"body_type": body})
    vertices, faces, _, kind = shell(look)
    glass = trimesh.Trimesh(vertices, faces[kind == 1], process=False)
    labels = trimesh.graph.connected_component_labels(glass.face_adjacency, node_count=len(glass.faces))
    return glass.face_normals, glass.triangles_center, labels


@pytest.mark.parametrize("body", SCREENED)
@pytest.mark.parametrize("seed", [1, 2])
def test_screens_are_panes_of_their_own(body, seed):
    normals, centres, labels = _panes(body, seed)
    screens = [("windscreen", 1.0)]
    if PROFILES[body].rear_window != (0.0, 0.0):
        screens.append(("rear window", -1.0))
    for name, ahead in screens:
        middle = (np.abs(centres[:, 1]) < 0.1) & (ahead * normals[:, 0] > 0.3) & (ahead * centres[:, 0] > 0)
        assert middle.any(), (body, name)
        (label,) = np.unique(labels[middle])  # the screen's middle is one pane
        pane = labels == label
        # No side window in it: a screen wrapping into the side glass reached |n_y| 0.98 (sedan).
        assert np.abs(normals[pane, 1]).max() < SIDE_NORMAL_Y, (body, name)


@pytest.mark.parametrize("body", CARS)
def test_cars_have_front_and_rear_side_windows_on_each_side(body):
    normals, _, labels = _panes(body, 1)
    for side in (1.0, -1.0):
        windows = {
            label for label in np.unique(labels) if (side * normals[labels == label, 1] > SIDE_NORMAL_Y).mean() > 0.5
        }
        assert len(windows) >= 2, (body, side, len(windows))
    # Windscreen, rear window (or tailgate glass) and at least two side windows a side.
    assert labels.max() + 1 >= 6, (body, labels.max() + 1)


@pytest.mark.parametrize("body", ["sedan", "estate", "bus", "hatchback"])
def test_narrow_pillars_between_side_windows_are_black(body):
    """A car's B-pillar and a bus's window pillars (bands of `Profile.pillars` at most `BLACK_PILLAR_SHARE`
    of the length) are black trim (kind 2) in the side windows' rows, above the beltline; a hatchback's wide
    D-pillar stays paint."""
    look = draw_look(1, CLASS_OF[body], pinned={"body_type": body})
    vertices, faces, _, kind = shell(look)
    centres = vertices[faces].mean(axis=1)
    u = centres[:, 0] / look.length_m + 0.5
    black = kind == 2
    narrow = [band for band in PROFILES[body].pillars if band[1] - band[0] <= BLACK_PILLAR_SHARE]
    assert black.any() and narrow
    in_narrow = np.any([(u > lo - 0.01) & (u < hi + 0.01) for lo, hi in narrow], axis=0)
    assert np.all(in_narrow[black])
    assert np.all(centres[black, 2] > PROFILES[body].belt * look.height_m)
    for lo, hi in narrow:  # every narrow band is black on both sides (a bus's glazed doors are glass on one)
        here = black & (u > lo - 0.01) & (u < hi + 0.01)
        sides = int((centres[here, 1] > 0).any()) + int((centres[here, 1] < 0).any())
        assert sides == 2 or (body == "bus" and sides == 1)
    wide = [band for band in PROFILES[body].pillars if band[1] - band[0] > BLACK_PILLAR_SHARE]
    for lo, hi in wide:
        assert not (black & (u > lo + 0.01) & (u < hi - 0.01)).any()
    # Drawn black: the built vehicle's running gear holds them in the underbody's black plastic.
    gear = next(part for part in build_vehicle(look).parts if part.name == "running_gear")
    dark = gear.vertices_m[np.all(np.isclose(gear.colours, UNDERBODY_RGB), axis=1)]
    assert (dark[:, 2] >= PROFILES[body].belt * look.height_m - 1e-9).sum() >= len(np.unique(faces[black]))
