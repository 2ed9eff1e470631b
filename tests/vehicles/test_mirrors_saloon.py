"""Exterior mirrors (`camgen.vehicles.body.door_mirrors`) and a bus's saloon
(`camgen.vehicles.cabin.bus_interior_part`): what stands out of a vehicle's outline and what shows through a bus's
windows. A vehicle's width over its mirrors is the makers'; each head sits at the front side window's lower front
corner (a bus's on an arm ahead of the front), fixed to the door by a stalk rather than floating, its glass facing
back. No OpenGL.

References: makers' technical data give the width without and with mirrors: a VW Golf 8 1,789 and 2,073 mm, a
Ford Transit (large van) 2,059 and 2,474 mm."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from camgen.vehicles import VehicleRig
from camgen.vehicles.body import MIRROR_GLASS_RGB, MIRRORS, PROFILES, TRIM_RGB, build_vehicle, shell
from camgen.vehicles.cabin import (
    BUS_AISLE_STANDING,
    BUS_FLOOR_M,
    BUS_PASSENGERS,
    BUS_SEAT_PITCH_M,
    BUS_SEAT_RGB,
    DRIVER_FACES,
    HANDRAIL_RADIUS_M,
    HANDRAIL_RGB,
    bus_passengers_part,
    driver_part,
)
from camgen.vehicles.look import CLASS_BODY_TYPES, draw_look

CLASS_OF = {body: cls for cls, bodies in CLASS_BODY_TYPES.items() for body in bodies}


class _Parked:
    """A route that stands still at the origin, heading +x."""

    moves = False

    def at(self, time_s):
        return np.zeros(2), 0.0

    def distance_at(self, time_s):
        return 0.0

    def standing(self, time_s):
        return None


def _winding_number(vertices, faces, point) -> float:
    """The generalised winding number of a closed mesh about `point`: its triangles' signed solid angles
    (Van Oosterom & Strackee 1983) over 4π; 1 inside an outward-wound closed surface, 0 outside."""
    a, b, c = (vertices[faces[:, k]] - point for k in range(3))
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731
    denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb
    return float(np.sum(2 * np.arctan2(det, denominator)) / (4 * np.pi))


def _mirror_vertices(look):
    """(painted or black housings' vertices, glass panes' vertices) of a built vehicle, m."""
    model = build_vehicle(look)
    parts = {part.name: part for part in model.parts}
    gear = parts["running_gear"]
    glass = np.all(np.isclose(gear.colours, MIRROR_GLASS_RGB), axis=1)
    housings = parts["mirrors"].vertices_m if "mirrors" in parts else None
    return model, housings, gear.vertices_m[glass]


@pytest.mark.parametrize(("body", "width_m", "with_mirrors_m"), [("hatchback", 1.789, 2.073), ("van", 2.059, 2.474)])
def test_the_width_over_the_mirrors_is_the_makers(body, width_m, with_mirrors_m):
    look = replace(draw_look(3, CLASS_OF[body], pinned={"body_type": body}), width_m=width_m)
    rig = VehicleRig(build_vehicle(look), _Parked())
    # The posed vehicle's extent across, shaded ground left out (as its box in an image).
    assert np.ptp(rig.box_vertices_m[:, 1]) == pytest.approx(with_mirrors_m, abs=0.005)
    # The shell alone keeps the width without mirrors.
    assert np.ptp(shell(look)[0][:, 1]) == pytest.approx(width_m, rel=0.02)


@pytest.mark.parametrize("body", ["hatchback", "sedan", "estate", "suv", "pickup", "van", "box_truck"])
def test_each_head_sits_on_the_door_at_the_front_side_window(body):
    look = draw_look(5, CLASS_OF[body], pinned={"body_type": body})
    profile = PROFILES[body]
    model, housings, glass = _mirror_vertices(look)
    gear = next(part for part in model.parts if part.name == "running_gear")
    black = np.all(np.isclose(gear.colours, TRIM_RGB), axis=1)
    black = gear.vertices_m[black & (np.abs(gear.vertices_m[:, 1]) > 0.4 * look.width_m)]
    # The stalks and black housings, not the bumpers' trim (nor a box truck's side guards, under its floor).
    black = black[black[:, 2] > max(0.3 * look.height_m, (profile.rear_floor_m or 0.0) + 0.05)]
    if housings is None:  # a black housing is drawn with the running gear
        housings = black
    vertices, faces, _, _ = shell(look)
    for side in (1, -1):
        head = housings[np.sign(housings[:, 1]) == side]
        assert len(head), (body, side)
        # Just behind the front side window's front end, over the beltline, under the window's top.
        window_front_m = (profile.side_glass[1] - 0.5) * look.length_m
        assert window_front_m - 0.35 < head[:, 0].min() and head[:, 0].max() < window_front_m + 0.05
        belt_m = profile.belt * look.height_m
        assert belt_m < head[:, 2].min() and head[:, 2].max() < belt_m + 0.6
        # Fixed to the door: the stalk's inner end lies inside the closed shell, and the stalk reaches into the head;
        # the head's tip lies `reach_m` outside the body's width.
        stalk = black[np.sign(black[:, 1]) == side]
        inner = stalk[np.argmin(np.abs(stalk[:, 1]))]
        assert _winding_number(vertices, faces, inner) == pytest.approx(1.0, abs=1e-6), (body, inner)
        assert np.abs(stalk[:, 1]).max() > np.abs(head[:, 1]).min() + 0.02
        tip = head[np.argmax(np.abs(head[:, 1]))]
        assert _winding_number(vertices, faces, tip) == pytest.approx(0.0, abs=1e-6)
        assert np.abs(tip[1]) == pytest.approx(look.width_m / 2 + MIRRORS[body].reach_m, abs=1e-6)
        # The head is a head, not a bar: about as long across as a real one (0.2–0.35 m).
        assert 0.15 < np.ptp(head[:, 1]) < 0.4, (body, np.ptp(head[:, 1]))
        # The glass faces back: it lies at the head's rear face.
        pane = glass[np.sign(glass[:, 1]) == side]
        assert pane[:, 0].max() <= head[:, 0].min() + 0.01


def test_a_bus_carries_its_mirrors_on_arms_ahead_of_its_front():
    look = draw_look(2, "bus")
    _, housings, glass = _mirror_vertices(look)
    assert housings is None  # black heads on black arms
    front_m = look.length_m / 2
    for side in (1, -1):
        pane = glass[np.sign(glass[:, 1]) == side]
        # Beside the windscreen's upper half, ahead of the front face, just outside the body's width.
        assert pane[:, 0].min() > front_m + 0.1
        assert np.abs(pane[:, 1]).max() > look.width_m / 2
        assert (
            0.5 * look.height_m < pane[:, 2].min()
            and pane[:, 2].max() < PROFILES["bus"].front_cap_glass[1] * look.height_m
        )


def test_the_mirrors_are_mirror_images():
    look = draw_look(9, "car", pinned={"body_type": "suv"})
    _, housings, glass = _mirror_vertices(look)
    for points in (housings, glass):
        left = points[points[:, 1] > 0]
        right = points[points[:, 1] < 0] * [1, -1, 1]
        assert np.allclose(np.sort(left, axis=0), np.sort(right, axis=0))


def test_a_bus_saloon_has_rows_of_seats_and_yellow_handrails_inside_its_shell():
    """Through a city bus's windows: pairs of seats at a seat pitch of makers' plans, none in the standing space
    opposite door 2, yellow handrails from floor to roof; all inside the closed shell, so that the bus's box and
    mask stay the shell's."""
    look = draw_look(4, "bus")
    saloon = next(part for part in build_vehicle(look).parts if part.name == "cabin")
    vertices, faces, _, _ = shell(look)
    seats = saloon.vertices_m[np.all(np.isclose(saloon.colours, BUS_SEAT_RGB), axis=1)]
    rails = saloon.vertices_m[np.all(np.isclose(saloon.colours, HANDRAIL_RGB), axis=1)]
    assert len(seats) and len(rails)
    for point in np.concatenate([seats, rails])[::3]:
        assert _winding_number(vertices, faces, point) == pytest.approx(1.0, abs=1e-6), point
    # The seat backs' rear faces (facing back, taller than a cushion), one x per row: rows a seat pitch apart, or a
    # standing space apart.
    corners = saloon.vertices_m[saloon.faces]
    seat_face = np.all(np.isclose(saloon.colours[saloon.faces[:, 0]], BUS_SEAT_RGB), axis=1)
    facing_back = saloon.normals[saloon.faces[:, 0]][:, 0] < -0.99
    tall = np.ptp(corners[:, :, 2], axis=1) > 0.3
    rows = np.unique(np.round(corners[seat_face & facing_back & tall][:, 0, 0], 6))
    gaps = np.diff(rows)
    assert np.allclose(gaps[gaps < 1.0], BUS_SEAT_PITCH_M)
    assert len(rows) >= 9  # a 12 m bus seats about 25–30 (Citaro: 26–32 seats)
    standing = [(u - 0.5) * look.length_m for u in BUS_AISLE_STANDING]
    assert not np.any((seats[:, 0] > standing[0] + 0.5) & (seats[:, 0] < standing[1] - 0.5))
    # Handrails from the floor (or a podium over a wheel arch) nearly to the roof, beside the aisle.
    assert rails[:, 2].min() == pytest.approx(BUS_FLOOR_M, abs=1e-6)
    assert rails[:, 2].max() - rails[:, 2].min() > 2.0
    assert rails[:, 2].max() > look.height_m - 0.5
    assert np.abs(rails[:, 1]).max() < look.width_m / 2 - 0.6
    # A gangway between the pairs of seats (UN R107 gauges a class I bus's with a cylinder about 0.45 m across), and
    # the handrails on its edges, not in it.
    assert 2 * np.abs(seats[:, 1]).min() >= 0.45
    assert 2 * np.abs(rails[:, 1]).min() >= 0.45 - 2 * HANDRAIL_RADIUS_M - 1e-9


def test_a_bus_in_service_carries_seated_passengers_inside_its_shell():
    """A driven bus carries 2–8 seated passengers (`BUS_PASSENGERS`), drawn from its identity seed (the same bus, the
    same passengers), each on a seat: hips over a cushion, feet on the floor, head under the roof, all inside the
    closed shell (so the bus's box and mask are the shell's); a parked bus carries none."""
    look = draw_look(4, "bus")
    cabin = {part.name: part for part in build_vehicle(look, driver=True).parts}["cabin"]
    passengers = bus_passengers_part(look)
    people = len(passengers.faces) / DRIVER_FACES
    assert BUS_PASSENGERS[0] - 0.5 < people < BUS_PASSENGERS[1] + 0.5
    # In the cabin part, between the saloon and the driver (last).
    start = len(cabin.vertices_m) - len(driver_part(look).vertices_m) - len(passengers.vertices_m)
    assert np.array_equal(cabin.vertices_m[start : start + len(passengers.vertices_m)], passengers.vertices_m)
    assert np.array_equal(bus_passengers_part(look).vertices_m, passengers.vertices_m)
    assert not np.array_equal(bus_passengers_part(draw_look(5, "bus")).vertices_m[:50], passengers.vertices_m[:50])
    vertices, faces, _, _ = shell(look)
    for point in passengers.vertices_m[::25]:
        assert _winding_number(vertices, faces, point) == pytest.approx(1.0, abs=1e-6), point
    # Seated: nobody's lowest point under the floor, heads well under the roof.
    assert passengers.vertices_m[:, 2].min() > BUS_FLOOR_M - 0.02
    roof_m = max(z for _, z in PROFILES["bus"].top) * look.height_m
    assert passengers.vertices_m[:, 2].max() < roof_m - 0.2  # on a podium over a wheel arch too
    parked = {part.name: part for part in build_vehicle(look).parts}["cabin"]
    assert len(parked.vertices_m) == len(cabin.vertices_m) - len(passengers.vertices_m) - len(
        driver_part(look).vertices_m
    )
