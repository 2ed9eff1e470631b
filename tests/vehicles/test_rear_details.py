"""A car's rear beyond its lamps and plate (`camgen.vehicles.panels.rear_details`).

- Hatchbacks, estates and SUVs carry a rear wiper parked along the rear window's foot: it lies just over the rear
  window's glass (within a few centimetres, never under it), from the screen's middle `REAR_WIPER_REACH_M` to one
  side, dark; saloons carry none (their rear window is not wiped), nor do vans, trucks and buses here.
- The tailgate's (a saloon's boot lid's) shut lines lie on the flat rear end face, inside its outline: one across at
  the rear lamp clusters' lower edge and one up each cluster's inner edge, symmetric about the centre line.
"""

from __future__ import annotations

import numpy as np
import pytest

from camgen.vehicles.body import LOWER_POINTS, UPPER_POINTS, build_vehicle, shell
from camgen.vehicles.look import draw_look
from camgen.vehicles.panels import REAR_WIPER_BODIES, REAR_WIPER_REACH_M, SIDE_LIFT_M, rear_details
from camgen.vehicles.roof import SHUT_LINE_RGB, WIPER_RGB

CLASS_OF = {"van": "truck", "box_truck": "truck", "bus": "bus"}
COUNT = UPPER_POINTS + LOWER_POINTS


def _details(body: str, seed: int):
    look = draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})
    vertices, faces, _, kind = shell(look)
    pieces = rear_details(look, vertices, faces[kind == 1], COUNT)
    return look, (vertices, faces, kind), pieces


def _rear_glass(vertices, faces, kind):
    corners = vertices[faces[kind == 1]]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rear = (n[:, 0] < -0.35) & (corners.mean(axis=1)[:, 0] < 0)
    return corners[rear], n[rear]


@pytest.mark.parametrize("body", REAR_WIPER_BODIES)
@pytest.mark.parametrize("seed", [1, 5])
def test_a_rear_wiper_lies_over_the_rear_windows_foot(body, seed):
    look, shell_m, pieces = _details(body, seed)
    wipers = [mesh for mesh, rgb in pieces if rgb == WIPER_RGB]
    assert len(wipers) == 2  # the arm and blade, and the pivot's boss
    blade = max(wipers, key=lambda mesh: np.ptp(mesh.vertices[:, 1]))
    assert np.ptp(blade.vertices[:, 1]) == pytest.approx(REAR_WIPER_REACH_M, abs=0.03)
    corners, normals = _rear_glass(*shell_m)
    # Over the glass: each blade vertex's height over the rear window's plane nearest to it, along its normal.
    centres = corners.mean(axis=1)
    for point in blade.vertices:
        i = int(np.argmin(np.linalg.norm(centres - point, axis=1)))
        over = float(np.dot(point - corners[i, 0], normals[i]))
        assert 0.0 < over < 0.05, (body, seed, over)
    # At the screen's foot: within 0.15 m (along the car) of its lowest edge, in its lower half.
    foot_x = corners[:, :, 0].min()
    assert blade.vertices[:, 0].min() - foot_x < 0.15
    assert blade.vertices[:, 2].max() < (corners[:, :, 2].min() + corners[:, :, 2].max()) / 2
    assert all(np.isfinite(mesh.vertices).all() for mesh in wipers)
    # In the built vehicle (its running gear's dark pieces), the same every time.
    again = _details(body, seed)[2]
    assert all(np.array_equal(a.vertices, b.vertices) for (a, _), (b, _) in zip(pieces, again, strict=True))
    assert build_vehicle(look).parts


@pytest.mark.parametrize("body", ["sedan", "pickup", "van", "box_truck", "bus"])
def test_no_rear_wiper_elsewhere(body):
    _, _, pieces = _details(body, 1)
    assert not [mesh for mesh, rgb in pieces if rgb == WIPER_RGB]


@pytest.mark.parametrize("body", ["hatchback", "sedan", "estate", "suv"])
def test_tailgate_lines_lie_on_the_rear_end_face(body):
    look, (vertices, _, _), pieces = _details(body, 2)
    lines = [mesh for mesh, rgb in pieces if rgb == SHUT_LINE_RGB]
    assert len(lines) == 3
    rear_x = -look.length_m / 2
    # The rear end face's outline: the shell's first station.
    end = vertices[np.abs(vertices[:, 0] - rear_x) < 1e-9]
    for mesh in lines:
        assert np.allclose(mesh.vertices[:, 0], rear_x - SIDE_LIFT_M)
        assert np.all(mesh.face_normals[:, 0] < -0.99)  # facing back
        for y, z in mesh.vertices[:, 1:]:
            near = end[np.abs(end[:, 2] - z) < 0.06]
            assert abs(y) < np.abs(near[:, 1]).max(), (body, y, z)
    across = [mesh for mesh in lines if np.ptp(mesh.vertices[:, 1]) > 0.2]
    upright = [mesh for mesh in lines if np.ptp(mesh.vertices[:, 2]) > 0.05]
    assert len(across) == 1 and len(upright) == 2
    assert abs(across[0].vertices[:, 1].mean()) < 1e-9
    assert sum(mesh.vertices[:, 1].mean() for mesh in upright) == pytest.approx(0.0, abs=1e-9)
    # The upright lines rise from the line across.
    for mesh in upright:
        assert mesh.vertices[:, 2].min() == pytest.approx(across[0].vertices[:, 2].mean(), abs=0.01)
