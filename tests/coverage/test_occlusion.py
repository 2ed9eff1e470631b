"""Occlusion by the scene's meshes against an exact geometric reference: points sampled densely along each
sight line, tested for lying inside the solid."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.coverage.frustum import image_plane_density
from camgen.coverage.grid import make_grid
from camgen.coverage.network import camera_coverage
from camgen.coverage.occlusion import inside_solids, scene_occluders, sight_blocked
from tests.coverage.conftest import look_at_pitch_deg, pinhole_view, scene_with

CAMERA_M = np.array([-10.0, 0.5, 3.0])
SOLIDS = {
    "box": {
        "type": "box",
        "name": "van",
        "size_m": [1.0, 3.0, 1.5],
        "position_m": [0, 0, 0.75],
        "rotation_deg": [0, 0, 20],
    },
    "cylinder": {"type": "cylinder", "name": "post", "radius_m": 0.6, "height_m": 2.0, "position_m": [0, 0, 1.0]},
    "sphere": {"type": "sphere", "name": "ball", "radius_m": 1.0, "position_m": [0, 0, 1.2]},
}


def _reference_blocked(targets: np.ndarray, occluders) -> np.ndarray:
    """A target is hidden when a point of its sight line (sampled every ~2 mm, the last 5 cm left out)
    lies inside the solid."""
    s = np.linspace(0.0, 1.0, 6000)
    blocked = np.zeros(len(targets), dtype=bool)
    for i, target in enumerate(targets):
        line = CAMERA_M + s[:, None] * (target - CAMERA_M)
        keep = np.linalg.norm(line - target, axis=1) > 0.05
        blocked[i] = inside_solids(line[keep], occluders).any()
    return blocked


@pytest.mark.parametrize("solid", sorted(SOLIDS))
def test_a_solid_between_camera_and_ground_hides_exactly_the_cells_behind_it(solid):
    occluders = scene_occluders(scene_with([SOLIDS[solid]]))
    grid = make_grid((-1.0, 9.0, -4.0, 4.0), 0.5, 0.0)
    points = grid.points_m()
    outside = ~inside_solids(points, occluders)
    got = sight_blocked(CAMERA_M, points[outside], occluders)
    expected = _reference_blocked(points[outside], occluders)
    assert got.sum() > 10  # a real shadow
    assert np.mean(got == expected) >= 0.99
    assert np.array_equal(got, expected)


def test_coverage_marks_the_shadow_of_a_box_occluded_and_the_ground_plane_does_not_hide_itself():
    ground = {"type": "plane", "name": "ground", "size_m": [40, 40]}
    occluders = scene_occluders(scene_with([ground, SOLIDS["box"]]))
    view = pinhole_view(CAMERA_M, pitch_deg=look_at_pitch_deg(3.0, 12.0))
    grid = make_grid((-1.0, 9.0, -4.0, 4.0), 0.5, 0.0)
    coverage = camera_coverage(grid, view, occluders)
    points = grid.points_m()
    in_view = coverage.in_view.ravel()
    outside = ~inside_solids(points, occluders)  # under the box: hidden, but the reference's 5 cm blurs it
    expected = in_view & ~_reference_blocked(points, occluders[1:])
    assert np.array_equal(coverage.visible.ravel()[outside], expected[outside])
    assert not coverage.visible.ravel()[~outside].any()
    assert (in_view & ~coverage.visible.ravel()).sum() > 10
    # Without the box, every cell in view is visible: the ground plane under the points hides none.
    assert np.array_equal(camera_coverage(grid, view, occluders[:1]).visible, coverage.in_view)


def test_a_plane_hides_from_its_front_only_and_a_camera_inside_a_solid_sees_out():
    wall = {"type": "plane", "name": "wall", "size_m": [4, 4], "position_m": [0, 0, 2], "rotation_deg": [0, -90, 0]}
    occluders = scene_occluders(scene_with([wall]))  # faces -x: seen from the camera at x = -10
    target = np.array([[5.0, 0.5, 2.0]])
    assert sight_blocked(CAMERA_M * [1, 1, 0] + [0, 0, 2], target, occluders)[0]
    assert not sight_blocked(target[0], (CAMERA_M * [1, 1, 0] + [0, 0, 2])[None], occluders)[0]
    housing = scene_occluders(
        scene_with([{"type": "sphere", "name": "dome", "radius_m": 0.3, "position_m": [0, 0, 3]}])
    )
    assert not sight_blocked(np.array([0.0, 0.0, 3.0]), np.array([[5.0, 0.0, 0.0]]), housing)[0]


def test_a_road_laid_over_the_ground_does_not_hide_it_and_a_plate_above_it_does():
    # intersection_two_cameras lays its roads 1 cm over the ground plane: the camera sees the road at those
    # ground points. A plate 10 or 50 cm up (more than SURFACE_LAYER_M: something above the ground) hides
    # them: it covers every sight line's last 2 m.
    ground = {"type": "plane", "name": "ground", "size_m": [40, 40]}
    view = pinhole_view(CAMERA_M, pitch_deg=look_at_pitch_deg(3.0, 12.0))
    grid = make_grid((-1.0, 9.0, -4.0, 4.0), 0.5, 0.0)
    sky_and_ground_hidden = image_plane_density(view, scene_occluders(scene_with([ground])), 0.0)[3].sum()
    for over_m, hides in ((0.01, False), (0.1, True), (0.5, True)):
        road = {"type": "plane", "name": "road", "size_m": [16, 40], "position_m": [4, 0, over_m]}
        occluders = scene_occluders(scene_with([ground, road]))
        coverage = camera_coverage(grid, view, occluders)
        assert coverage.in_view.sum() > 100
        assert np.array_equal(coverage.visible, coverage.in_view & (not hides))
        # The image-plane plot's rays agree: they hide more than the ground alone (the sky) only for a plate.
        hidden = image_plane_density(view, occluders, 0.0)[3]
        assert (hidden.sum() > sky_and_ground_hidden) == hides


def test_a_camera_mounted_on_a_box_sees_what_lies_away_from_it():
    # A wall camera on the corner of a building (scenes/eptz_follow.yaml's box camera): its sight lines run
    # along the faces they leave, touching the box without entering it; the ones into the box are hidden.
    building = {"type": "box", "name": "building", "size_m": [30, 8, 10], "position_m": [0, 24, 5]}
    occluders = scene_occluders(scene_with([building]))
    camera = np.array([-15.0, 20.0, 9.0])
    away = np.array([[-15.0, 5.0, 0.0], [-20.0, 20.0, 0.0], [-5.0, 10.0, 0.0], [-18.0, 0.0, 0.0]])
    assert not sight_blocked(camera, away, occluders).any()
    assert sight_blocked(camera, np.array([[5.0, 30.0, 0.0], [0.0, 26.0, 11.0]]), occluders).all()
