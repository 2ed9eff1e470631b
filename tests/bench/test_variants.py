"""Bench variants of the example scenes keep what they claim to keep."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.bench.e2e_cases import run_frames, spread_frames
from camgen.bench.variants import at_output_size, one_camera
from camgen.config import load_scene
from camgen.plan import compile_scene
from tests.conftest import REPO


def test_a_resized_sensor_keeps_its_width_in_mm_and_the_horizontal_field_of_view():
    loaded = load_scene(REPO / "scenes/intersection_two_cameras.yaml")
    camera = loaded.scene.cameras[0].name
    original = compile_scene(one_camera(loaded, camera)).cameras[0]
    resized = compile_scene(at_output_size(one_camera(loaded, camera), 1280, 720)).cameras[0]
    assert (resized.width_px, resized.height_px) == (1280, 720)
    assert resized.profile.sensor.width_mm == pytest.approx(original.profile.sensor.width_mm)
    K0, K1 = np.array(original.states[0].K_px), np.array(resized.states[0].K_px)
    hfov = [2 * np.arctan(w / 2 / K[0, 0]) for w, K in ((original.width_px, K0), (1280, K1))]
    assert hfov[1] == pytest.approx(hfov[0], rel=1e-9)


def test_a_virtual_ptz_keeps_its_sensor_and_changes_its_stream():
    loaded = load_scene(REPO / "scenes/eptz_follow.yaml")
    camera = compile_scene(at_output_size(loaded, 1920, 1080)).cameras[0]
    assert camera.output_size_px == (1920, 1080) and camera.width_px == 3840


def test_spread_frames_start_at_the_first_and_end_at_the_last():
    assert spread_frames(200, 3) == [0, 100, 199]
    assert spread_frames(1, 3) == [0]


def test_run_frames_are_consecutive_from_the_middle():
    assert run_frames(200, 3) == [100, 101, 102]
    assert run_frames(4, 3) == [1, 2, 3]
    assert run_frames(2, 5) == [0, 1]
