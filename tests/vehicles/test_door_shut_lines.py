"""The doors' shut lines (`camgen.vehicles.panels`) against the shell they lie on.

- A car shows three upright shut lines on each side under its windows (the front door's leading edge, the B-pillar,
  the rear door's trailing edge), a van its cab door's two edges on both sides and on its nearside a sliding door
  `SLIDING_DOOR_WIDTH_M` wide (two upright edges, its top edge) and the door's rail behind it; trucks and buses none.
- Each line lies on the shell's side, `SIDE_LIFT_M` out along its normals (never under the paint, never standing off
  it), is `SHUT_LINE_WIDTH_M` wide, upright (one x along it) and dark (`SHUT_LINE_RGB`); a car's front door starts
  `FRONT_DOOR_BEHIND_ARCH_M` behind its front wheel arch; the same seed gives the same lines.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.vehicles.body import (
    ARCH_GAP_M,
    GREENHOUSE_SIDE_QUADS,
    LOWER_POINTS,
    UPPER_POINTS,
    nearside_sign,
    shell,
)
from camgen.vehicles.look import draw_look
from camgen.vehicles.panels import (
    DOOR_BODIES,
    FRONT_DOOR_BEHIND_ARCH_M,
    SIDE_LIFT_M,
    SLIDING_DOOR_WIDTH_M,
    door_shut_lines,
)
from camgen.vehicles.roof import SHUT_LINE_RGB, SHUT_LINE_WIDTH_M

CLASS_OF = {"van": "truck", "box_truck": "truck", "bus": "bus"}
COUNT = UPPER_POINTS + LOWER_POINTS


def _lines(body: str, seed: int):
    look = draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})
    vertices, faces, normals, _ = shell(look)
    lines = door_shut_lines(look, (vertices, normals, faces), COUNT, UPPER_POINTS, GREENHOUSE_SIDE_QUADS)
    return look, (vertices, faces), lines


def _side_y(vertices: np.ndarray, faces: np.ndarray, points_xz: np.ndarray) -> np.ndarray:
    """(n,) how far out the shell's left side (+y, facing +y) lies at each (x, z), m (NaN where none): each point's
    outward-facing triangles whose side view holds it, interpolated, the outermost."""
    corners = vertices[faces]
    normal_y = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 1]
    corners = corners[normal_y > 1e-12][:, :, [0, 2, 1]]  # (x, z, y)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    out = np.full(len(points_xz), np.nan)
    v0, v1 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2]
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    for i, point in enumerate(points_xz):
        v2 = point - a[:, :2]
        s = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        t = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        inside = (s >= -1e-9) & (t >= -1e-9) & (s + t <= 1 + 1e-9)
        if inside.any():
            y = a[inside, 2] + s[inside] * (b[inside, 2] - a[inside, 2]) + t[inside] * (c[inside, 2] - a[inside, 2])
            out[i] = y.max()
    return out


def _upright(mesh: trimesh.Trimesh) -> bool:
    """Upright: one x along it (its width, and the lift along normals that lean fore or aft), taller than 0.1 m."""
    return np.ptp(mesh.vertices[:, 0]) <= SHUT_LINE_WIDTH_M + 2 * SIDE_LIFT_M and np.ptp(mesh.vertices[:, 2]) > 0.1


@pytest.mark.parametrize("body", DOOR_BODIES)
@pytest.mark.parametrize("seed", [1, 2])
def test_shut_lines_lie_on_the_shells_side(body, seed):
    _, (vertices, faces), lines = _lines(body, seed)
    for mesh, rgb in lines:
        assert rgb == SHUT_LINE_RGB
        assert np.isfinite(mesh.vertices).all()
        # Every corner just outside the side (lifted along a normal mostly sideways).
        side = np.sign(mesh.vertices[:, 1].mean())
        y_m = _side_y(vertices * [1, side, 1], faces if side > 0 else faces[:, ::-1], mesh.vertices[:, [0, 2]])
        gap = np.abs(mesh.vertices[:, 1]) - y_m
        assert np.isfinite(gap).all() and gap.min() > 0.0 and gap.max() < 2 * SIDE_LIFT_M, (body, seed, gap)
        # Its faces face out (away from the vehicle's centre line, along the side's normal).
        outward = np.sign(mesh.vertices[:, 1].mean())
        assert np.all(mesh.face_normals[:, 1] * outward > 0.3)
        if _upright(mesh):  # SHUT_LINE_WIDTH_M wide (its two edges, one on each side of its middle)
            x = mesh.vertices[:, 0]
            assert np.median(x[x > x.mean()]) - np.median(x[x < x.mean()]) == pytest.approx(SHUT_LINE_WIDTH_M, abs=2e-3)
    again = _lines(body, seed)[2]
    assert all(np.array_equal(a.vertices, b.vertices) for (a, _), (b, _) in zip(lines, again, strict=True))


@pytest.mark.parametrize("body", ["hatchback", "sedan", "estate", "suv", "pickup"])
def test_a_car_shows_three_door_edges_each_side(body):
    look, _, lines = _lines(body, 3)
    upright = [mesh for mesh, _ in lines if _upright(mesh)]
    for side in (1, -1):
        here = sorted(mesh.vertices[:, 0].mean() for mesh in upright if np.sign(mesh.vertices[:, 1].mean()) == side)
        assert len(here) == 3, (body, side, here)
        arch_rear_m = look.front_axle_x_m - look.wheel_radius_m - ARCH_GAP_M
        assert here[-1] == pytest.approx(arch_rear_m - FRONT_DOOR_BEHIND_ARCH_M, abs=SIDE_LIFT_M)
        assert look.rear_axle_x_m - look.wheel_radius_m < here[0] < here[1] < here[2]


def test_a_van_has_a_sliding_door_on_its_nearside_only():
    look, _, lines = _lines("van", 4)
    near = nearside_sign(look)
    meshes = [mesh for mesh, _ in lines]
    far_side = [m for m in meshes if np.sign(m.vertices[:, 1].mean()) != near]
    near_side = [m for m in meshes if np.sign(m.vertices[:, 1].mean()) == near]
    assert len(far_side) == 2 and all(_upright(m) for m in far_side)  # the cab door's edges
    tall = sorted((m for m in near_side if _upright(m) and m.vertices[:, 2].max() > 0.7 * look.height_m),
                  key=lambda m: m.vertices[:, 0].mean())  # fmt: skip
    assert len(tall) == 2
    width_m = tall[1].vertices[:, 0].mean() - tall[0].vertices[:, 0].mean()
    assert width_m == pytest.approx(SLIDING_DOOR_WIDTH_M, abs=SIDE_LIFT_M)
    level = [m for m in near_side if not _upright(m)]
    assert len(level) == 2  # the door's top edge and its rail
    for mesh in level:
        assert np.ptp(mesh.vertices[:, 2]) < 0.03  # level along the side
    # The rail runs from behind the door back towards the rear.
    rail = min(level, key=lambda m: m.vertices[:, 2].mean())
    assert rail.vertices[:, 0].max() <= tall[0].vertices[:, 0].mean() + 1e-6
    assert rail.vertices[:, 0].min() < -look.length_m / 2 + 0.3


@pytest.mark.parametrize("body", ["box_truck", "bus"])
def test_trucks_and_buses_draw_no_door_lines_here(body):
    assert _lines(body, 1)[2] == []
