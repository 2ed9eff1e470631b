"""Network and region figures: areas by class and camera count, hand-off overlap, blind spots, regions."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.path import Path as PolygonPath

from camgen.config.scene import Region
from camgen.coverage.grid import inside_polygon, make_grid
from camgen.coverage.network import network_figures, plane_coverage, region_figures
from tests.coverage.conftest import look_at_pitch_deg, pinhole_view


def test_inside_polygon_matches_matplotlib():
    rng = np.random.default_rng(3)
    polygon = np.array([[0, 0], [4, 0], [4, 3], [2, 1.5], [0, 3]], dtype=float)  # concave
    points = rng.uniform(-1, 5, size=(2000, 2))
    assert np.array_equal(inside_polygon(points, polygon), PolygonPath(polygon).contains_points(points))


def test_network_counts_area_by_class_and_cameras():
    grid = make_grid((0.0, 4.0, 0.0, 2.0), 1.0, 0.0)  # 2 × 4 cells of 1 m²
    classes = np.array([[[0, 1, 2, 4], [0, 0, 3, 1]], [[0, 1, 1, 0], [0, 2, 0, 0]]], dtype=np.int8)  # two cameras
    visible = classes > 0
    visible[0, 0, 0] = True  # seen, but below detect
    site = np.ones(grid.shape, bool)
    site[1, 3] = False  # a building's footprint
    figures = network_figures(classes, visible, site, grid)
    assert figures["site_area_m2"] == 7.0
    at_least = {k: v["area_m2"] for k, v in figures["area_at_least_class"].items()}
    assert at_least == {"detect": 5.0, "observe": 4.0, "recognise": 2.0, "identify": 1.0}
    assert figures["area_by_camera_count_m2"]["detect"] == {"0": 2.0, "1": 3.0, "2": 2.0, "3+": 0.0}
    assert figures["handoff_overlap"]["area_m2"] == 2.0
    assert figures["blind"]["area_m2"] == 2.0
    assert figures["blind"]["unseen_area_m2"] == 1.0
    assert figures["blind"]["below_detect_area_m2"] == 1.0
    assert figures["blind"]["largest"] == [{"area_m2": 2.0, "centroid_m": [0.5, 1.0]}]


def test_regions_report_best_class_and_share_meeting_it():
    view = pinhole_view((0.0, 0.0, 3.0), pitch_deg=look_at_pitch_deg(3.0, 6.0))
    grid = make_grid((-10.0, 12.0, -6.0, 6.0), 0.5, 0.0)
    plane = plane_coverage(grid, [view], [], [])
    camera = plane.cameras[0]
    regions = [
        Region(name="near", polygon_m=[[3, -1], [6, -1], [6, 1], [3, 1]], required_class="detect"),
        Region(name="far", polygon_m=[[3, -1], [11, -1], [11, 1], [3, 1]], required_class="observe"),
        Region(name="behind", polygon_m=[[-9, -2], [-5, -2], [-5, 2]], required_class="detect"),
    ]
    points = grid.points_m()[:, :2]
    masks = [inside_polygon(points, np.array(r.polygon_m)).reshape(grid.shape) for r in regions]
    near, far, behind = region_figures(regions, masks, camera.dori[None], plane.site, grid, ["cam"])
    assert near["share_meeting_required"] == 1.0 and near["best_class"] in ("observe", "recognise")
    assert near["cameras_reaching_required"] == ["cam"]
    expected = np.mean(camera.dori[masks[1]] >= 2)
    assert 0 < expected < 1
    assert far["share_meeting_required"] == pytest.approx(expected)
    assert far["area_m2"] == masks[1].sum() * 0.25
    assert behind["share_meeting_required"] == 0.0 and behind["best_class"] == "none"
    assert behind["share_handoff_at_required"] == 0.0
