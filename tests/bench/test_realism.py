"""Scoring detections as the pedestrian benchmark does (camgen.bench.realism.score_frame): counted people
by IoU, ignore regions by intersection over the detection's area (Dollár et al. 2012)."""

from __future__ import annotations

import pytest

from camgen.bench.realism import ioa, iou, score_frame


def test_ioa_is_the_intersection_over_the_detections_area():
    assert ioa((0, 0, 10, 20, 0.9), (0, 0, 40, 40)) == 1.0  # wholly inside
    assert ioa((30, 0, 50, 10, 0.9), (0, 0, 40, 40)) == pytest.approx(0.5)  # half inside
    assert ioa((0, 0, 100, 100, 0.9), (0, 0, 40, 40)) == pytest.approx(0.16)  # covers the region
    assert ioa((5, 5, 5, 9, 0.9), (0, 0, 40, 40)) == 0.0  # empty box


def test_a_detection_inside_an_ignore_region_is_no_false_alarm():
    """A small detection on a crowd region: IoU 0.125 (a false alarm by IoU), IoA 1 (ignored)."""
    region, detection = (0, 0, 40, 40), (0, 0, 10, 20, 0.8)
    assert iou(detection, region) < 0.5
    assert score_frame([detection], [], [region]) == (0, 0)


def test_an_ignore_region_absorbs_many_detections_and_a_big_box_over_it_is_a_false_alarm():
    region = (0, 0, 40, 40)
    inside = [(0, 0, 10, 20, 0.9), (20, 10, 40, 40, 0.7), (15, 5, 25, 35, 0.6)]
    assert score_frame(inside, [], [region]) == (0, 0)
    assert score_frame([(0, 0, 100, 100, 0.9)], [], [region]) == (0, 1)  # IoA 0.16


def test_counted_people_are_matched_first_once_each_by_iou():
    person = (100, 100, 140, 200)
    region = (90, 90, 150, 210)  # an ignored person around the counted one
    near = (102, 104, 142, 204, 0.9)  # IoU 0.87 with the person
    twin = (101, 102, 141, 202, 0.5)  # a second box on the same person: inside the ignore region
    assert score_frame([near, twin], [person], [region]) == (1, 0)
    assert score_frame([near, twin], [person], []) == (1, 1)
    assert score_frame([(0, 0, 30, 60, 0.9)], [person], [region]) == (0, 1)
