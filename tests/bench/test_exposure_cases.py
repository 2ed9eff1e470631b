"""The exposure check's measures (`camgen.bench.exposure_cases`) against independent references."""

from __future__ import annotations

import cv2
import numpy as np

from camgen.bench.exposure_cases import (
    CameraExposure,
    core_box,
    exposure_table,
    is_silhouette,
    readout_px,
    ring_boxes,
)
from camgen.world.night import luma_bt601


def test_luma_is_bt601_as_opencv_computes_it():
    rgb = np.random.default_rng(0).integers(0, 256, (16, 24, 3), dtype=np.uint8)
    assert np.allclose(luma_bt601(rgb), cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), atol=0.51)


def test_core_box_is_the_middle_half_and_sixty_percent():
    assert core_box((100.0, 200.0, 140.0, 300.0)) == (110, 220, 130, 280)


def test_a_silhouette_stands_in_dark_surroundings_under_a_bright_sky():
    assert is_silhouette(20.0, 230.0)
    assert not is_silhouette(20.0, 120.0)  # a dark frame all over (night): not a silhouette
    assert not is_silhouette(90.0, 240.0)  # a well exposed street (the object itself may be dark: dark clothes)


def test_the_ring_is_the_grown_box_less_the_box():
    box = (100.0, 50.0, 120.0, 90.0)
    mask = np.zeros((200, 300), bool)
    for x0, y0, x1, y1 in ring_boxes(box, 300, 200):
        assert not mask[y0:y1, x0:x1].any()  # the parts do not overlap
        mask[y0:y1, x0:x1] = True
    grown = np.zeros_like(mask)
    grown[30:110, 90:130] = True
    grown[50:90, 100:120] = False
    assert np.array_equal(mask, grown)
    parts = ring_boxes((0.0, 0.0, 20.0, 40.0), 300, 200)  # clipped at the frame's corner
    assert all(x0 >= 0 and y0 >= 0 for x0, y0, _, _ in parts)


def test_readout_bins_to_at_most_640_wide_keeping_the_aspect():
    assert readout_px(2560, 1440) == (640, 360)
    assert readout_px(3840, 2160) == (640, 360)
    assert readout_px(1920, 1080) == (640, 360)
    assert readout_px(640, 480) == (640, 480)
    w, h = readout_px(2688, 1520)
    assert w <= 640 and abs(w / h - 2688 / 1520) < 0.02
    assert readout_px(3840, 2160, stream_width_px=1280) == (1280, 720)  # a virtual PTZ's stream crops the readout


def test_the_table_names_the_silhouettes():
    row = CameraExposure("s", "cam", "by day in clear air", 0.002, 3.0, False, 150.0, 235.0, 0.01, 0.0)
    row.objects += [("walker_1", "person", 25.0, 30.0), ("car_1", "car", 120.0, 140.0)]
    table = exposure_table([row])
    expected = (
        "| s | cam | by day in clear air | 2.00 ms, 3.0 dB | 150 | 235 | 1.0% | 0.0% | 2: 25–120 (30–140) | walker_1 |"
    )
    assert expected in table
