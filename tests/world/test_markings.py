"""Road-marking geometry (`camgen.world.markings`) against closed forms: dashes along a polyline, bay
lines, crosswalk bars, the worn paint's area, and wet paint's reflectance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.config.markings import BaysMarking, CrossingMarking, LineMarking
from camgen.world.markings import (
    PAINT_LIFT_M,
    PAINT_RGB,
    WATER_EXTERNAL_DIFFUSE_REFLECTANCE,
    bay_rects,
    crossing_rects,
    line_rects,
    marking_paint,
    marking_rects,
    paint_mesh,
    value_noise,
    wet_reflectance,
)


def _tuples(rects):
    return [(*r.centre_m, *r.axis, r.length_m, r.width_m) for r in rects]


@pytest.mark.parametrize(("length_m", "count", "last_m"), [(100.0, 9, 2.48), (98.0, 9, 0.48), (96.0, 8, 3.05)])
def test_dashes_along_a_straight_line(length_m, count, last_m):
    """Dashes of d = 3.05 every d + g = 12.19 m from the start: ⌈L / 12.19⌉ of them, the last
    min(d, L − (n − 1)·12.19) long (100 m: the ninth starts at 97.52 and is cut to 2.48)."""
    dash, gap = 3.05, 9.14
    rects = line_rects([[0, 0], [length_m, 0]], 0.1, dash, gap)
    assert len(rects) == count
    starts = [r.centre_m[0] - r.length_m / 2 for r in rects]
    np.testing.assert_allclose(starts, np.arange(count) * (dash + gap), atol=1e-9)
    np.testing.assert_allclose([r.length_m for r in rects[:-1]], dash)
    assert rects[-1].length_m == pytest.approx(last_m)
    assert all(r.width_m == 0.1 and r.centre_m[1] == 0 for r in rects)


def test_the_dash_pattern_runs_on_around_a_bend():
    """An L of 10 + 10 m, dashes 4 m every 8 m: [0, 4], [8, 12] (2 m before the corner, 2 m after), [16, 20]."""
    rects = line_rects([[0, 0], [10, 0], [10, 10]], 0.1, 4.0, 4.0)
    expected = [
        (2.0, 0.0, 1.0, 0.0, 4.0),
        (9.0, 0.0, 1.0, 0.0, 2.0),
        (10.0, 1.0, 0.0, 1.0, 2.0),
        (10.0, 8.0, 0.0, 1.0, 4.0),
    ]
    np.testing.assert_allclose([t[:5] for t in _tuples(rects)], expected, atol=1e-9)


def test_a_solid_polyline_is_one_rectangle_per_segment():
    rects = line_rects([[0, 0], [3, 4], [3, 10]], 0.45)
    np.testing.assert_allclose(_tuples(rects), [(1.5, 2, 0.6, 0.8, 5, 0.45), (3, 7, 0, 1, 6, 0.45)], atol=1e-12)


def test_perpendicular_bays_lines_between_and_around_them():
    """3 bays 2.4 × 4.8 from (1, 2) heading +y: lines along y at x = 1 + 1.2, 1 − 1.2, 1 − 3.6, 1 − 6.0 (the
    row runs to the left of +y, −x), each 4.8 long, centred on the bays' middle y = 2."""
    rects = bay_rects([1, 2], 90, 3, 2.4, 4.8, 0.1)
    np.testing.assert_allclose(_tuples(rects), [(x, 2, 0, 1, 4.8, 0.1) for x in (2.2, -0.2, -2.6, -5.0)], atol=1e-12)


def test_a_closed_row_has_a_front_line_that_the_side_lines_meet():
    """Closed: a line across the bays' front end (x = L/2 for heading 0), 3·w + line width long; the side lines
    run from the back (x = −L/2) to the front line's near edge, so the paint neither overlaps nor gaps."""
    w, L, lw = 2.5, 5.0, 0.1
    rects = bay_rects([0, 0], 0, 3, w, L, lw, closed=True)
    sides, front = rects[:4], rects[4]
    assert front.centre_m == pytest.approx((L / 2, w))
    assert front.axis == pytest.approx((0, 1))
    assert front.length_m == pytest.approx(3 * w + lw)
    for side in sides:
        assert side.centre_m[0] - side.length_m / 2 == pytest.approx(-L / 2)
        assert side.centre_m[0] + side.length_m / 2 == pytest.approx(L / 2 - lw / 2)
    np.testing.assert_allclose([s.centre_m[1] for s in sides], [-1.25, 1.25, 3.75, 6.25])


def test_parallel_bays_follow_one_another_along_the_heading():
    """Parallel bays 2.2 × 6 heading −y from (−2.4, 19): end lines across at y = 22, 16, 10, each 2.2 − 0.05
    long, and the closing line on the left of −y (+x) at x = −2.4 + 1.1."""
    rects = bay_rects([-2.4, 19], 270, 2, 2.2, 6.0, 0.1, layout="parallel", closed=True)
    ends, side = rects[:3], rects[3]
    np.testing.assert_allclose([r.centre_m[1] for r in ends], [22, 16, 10], atol=1e-9)
    np.testing.assert_allclose([r.length_m for r in ends], 2.15)
    assert side.centre_m == pytest.approx((-1.3, 16))
    assert side.length_m == pytest.approx(12.1)


@pytest.mark.parametrize(("span_m", "count"), [(8.0, 7), (7.79, 6), (0.6, 1), (10.0, 8)])
def test_crosswalk_bars_count_and_centring(span_m, count):
    """n = ⌊(L + g) / (s + g)⌋ bars of s across the road, s + g apart, centred between the kerbs."""
    stripe, gap = 0.6, 0.6
    rects = crossing_rects([0, -span_m / 2], [0, span_m / 2], 3.0, stripe, gap)
    assert len(rects) == count == math.floor((span_m + gap) / (stripe + gap) + 1e-9)
    ys = np.array([r.centre_m[1] for r in rects])
    np.testing.assert_allclose(np.diff(ys), stripe + gap)
    assert ys.mean() == pytest.approx(0.0, abs=1e-12)
    assert all(r.width_m == stripe and r.length_m == 3.0 and r.axis == pytest.approx((-1, 0)) for r in rects)


def _triangle_areas(mesh):
    a, b, c = (mesh.vertices_m[mesh.faces[:, k]].astype(np.float64) for k in range(3))
    return np.cross(b - a, c - a)[:, 2] / 2


def test_unworn_paint_covers_each_rectangle_exactly():
    rects = crossing_rects([0, -4], [0, 4], 3.0, 0.6, 0.6)
    mesh = paint_mesh(rects, "white", height_m=0.013, wear=0.0, seed=1)
    areas = _triangle_areas(mesh)
    assert np.all(areas > 0)  # counter-clockwise from above: facing up
    assert areas.sum() == pytest.approx(7 * 0.6 * 3.0, rel=1e-5)
    assert mesh.painted_area_m2 == pytest.approx(mesh.design_area_m2)
    assert len(mesh.faces) == 2 * sum(round(r.width_m / 0.01) for r in rects)  # one run per 1 cm row
    np.testing.assert_allclose(mesh.vertices_m[:, 2], 0.013)


@pytest.mark.parametrize("wear", [0.1, 0.3, 0.6])
def test_worn_paint_leaves_the_share_asked_for_mostly_off_the_edges(wear):
    rects = line_rects([[0, 0], [20, 0]], 0.12, 3.0, 1.0)
    mesh = paint_mesh(rects, "yellow", height_m=0.0, wear=wear, seed=5)
    assert _triangle_areas(mesh).sum() == pytest.approx(mesh.painted_area_m2, rel=1e-5)
    assert mesh.painted_area_m2 / mesh.design_area_m2 == pytest.approx(1 - wear, abs=0.005)
    # Edge rows (|y| > 0.04 m) lose more than the middle rows: frayed edges.
    centres = mesh.vertices_m.reshape(-1, 4, 3).mean(axis=1)
    quad_areas = _triangle_areas(mesh).reshape(2, -1).sum(axis=0)
    edge = np.abs(centres[:, 1]) > 0.04
    kept_edge = quad_areas[edge].sum() / (2 / 6 * mesh.design_area_m2)
    kept_middle = quad_areas[~edge].sum() / (4 / 6 * mesh.design_area_m2)
    assert kept_edge < kept_middle


def test_paint_stays_inside_its_rectangles_and_is_seeded():
    rects = bay_rects([3, 4], 30, 4, 2.4, 4.8, 0.1, closed=True)
    first = paint_mesh(rects, "white", height_m=0.0, wear=0.2, seed=9)
    again = paint_mesh(rects, "white", height_m=0.0, wear=0.2, seed=9)
    other = paint_mesh(rects, "white", height_m=0.0, wear=0.2, seed=10)
    np.testing.assert_array_equal(first.vertices_m, again.vertices_m)
    np.testing.assert_array_equal(first.colours, again.colours)
    assert first.vertices_m.shape != other.vertices_m.shape or np.any(first.vertices_m != other.vertices_m)
    # Every vertex lies in (or on the border of) one of the rectangles.
    xy = first.vertices_m[:, :2].astype(np.float64)
    inside = np.zeros(len(xy), dtype=bool)
    for r in rects:
        d = xy - np.asarray(r.centre_m)
        u = d @ np.asarray(r.axis)
        v = d @ np.array([-r.axis[1], r.axis[0]])
        inside |= (np.abs(u) <= r.length_m / 2 + 1e-4) & (np.abs(v) <= r.width_m / 2 + 1e-4)
    assert inside.all()
    # The colour varies a little about the paint's (dirt), never more than ±8 %.
    ratio = first.colours / np.asarray(PAINT_RGB["white"], dtype=np.float32)
    assert 0.92 - 1e-6 <= ratio.min() < 0.97 and 1.03 < ratio.max() <= 1.08 + 1e-6


def test_value_noise_is_a_seeded_continuous_field_in_the_unit_interval():
    xy = np.random.default_rng(0).uniform(-50, 50, (20000, 2))
    values = value_noise(xy, 0.4, 7)
    assert values.min() >= 0 and values.max() < 1 and 0.4 < values.mean() < 0.6
    np.testing.assert_array_equal(values, value_noise(xy, 0.4, 7))
    assert not np.allclose(values, value_noise(xy, 0.4, 8))
    near = value_noise(xy + 1e-4, 0.4, 7)
    assert np.max(np.abs(near - values)) < 0.01  # continuous: 0.1 mm moves it little


def test_markings_of_the_config_and_their_height():
    line = LineMarking(type="line", along_m=[[0, 0], [10, 0]], dash_m=2, gap_m=4, surface_height_m=0.011)
    bays = BaysMarking(type="bays", first_centre_m=[0, 0], count=2, layout="parallel")
    crossing = CrossingMarking(type="crossing", from_m=[0, 0], to_m=[8, 0])
    assert len(marking_rects(line)) == 2
    assert [r.length_m for r in marking_rects(bays)] == pytest.approx([2.0, 2.0, 2.0])  # 2.0 × 6.0 by default
    assert len(marking_rects(crossing)) == 7
    paint = marking_paint(line, scene_seed=3, index=0)
    np.testing.assert_allclose(paint.vertices_m[:, 2], 0.011 + PAINT_LIFT_M, rtol=1e-6)
    assert not np.array_equal(paint.vertices_m, marking_paint(line, scene_seed=3, index=1).vertices_m)


def test_wet_paint_follows_the_water_film_model():
    """Ångström / Lekner–Dorf: 0 stays 0, a white reflector keeps 1 − r_e, asphalt (0.1) keeps 0.516 and white
    paint (0.5) 0.644 of its reflectance; brighter surfaces keep more."""
    assert wet_reflectance(0.0) == 0.0
    assert wet_reflectance(1.0) == pytest.approx(1 - WATER_EXTERNAL_DIFFUSE_REFLECTANCE)
    assert wet_reflectance(0.1) / 0.1 == pytest.approx(0.516, abs=0.001)
    assert wet_reflectance(0.5) / 0.5 == pytest.approx(0.644, abs=0.001)
    a = np.linspace(0.01, 1, 50)
    assert np.all(np.diff(wet_reflectance(a) / a) > 0)
    assert wet_reflectance(np.ones((2, 3))).shape == (2, 3)
