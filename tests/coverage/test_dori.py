"""The IEC 62676-4:2014 DORI thresholds and the classification at their edges."""

from __future__ import annotations

import numpy as np

from camgen.coverage.dori import DORI_CLASSES, DORI_THRESHOLDS_PX_M, class_index, class_name, dori_class


def test_thresholds_are_the_standards():
    # IEC 62676-4:2014: detect 25, observe 62, recognise 125, identify 250 px/m.
    assert dict(zip(DORI_CLASSES, DORI_THRESHOLDS_PX_M, strict=True)) == {
        "detect": 25.0,
        "observe": 62.0,
        "recognise": 125.0,
        "identify": 250.0,
    }


def test_class_at_each_edge_and_for_nan():
    density = np.array([[0.0, 24.999, 25.0, 61.99], [62.0, 124.9, 125.0, 249.9], [250.0, 1e4, np.nan, -1.0]])
    assert dori_class(density).tolist() == [[0, 0, 1, 1], [2, 2, 3, 3], [4, 4, 0, 0]]
    assert [class_name(class_index(n)) for n in DORI_CLASSES] == list(DORI_CLASSES)
    assert class_name(0) == "none"
