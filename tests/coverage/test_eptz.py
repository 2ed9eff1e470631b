"""A virtual PTZ's coverage is its stream's: the window the plan crops (its camera matrix K' from
`camgen.plan`), and px/m that count the sensor's detail only (a window scaled up to a larger stream adds
none)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.coverage.density import densities
from camgen.coverage.views import home_view, view_at
from camgen.plan import PlanSettings, compile_scene
from tests.conftest import FIXED_PROFILE, SCENE, write

POINT_M = np.array([[0.5, 4.0, 0.0]])  # in front of the camera, seen in every window below


def eptz_scene(workspace: Path, pan_deg: float, tilt_deg: float, zoom_x: float) -> Path:
    """The test scene's camera as a virtual PTZ (a 320 × 240 stream of the 640 × 480 sensor) behind a
    barrel lens."""
    barrel = FIXED_PROFILE.replace("  focal_length_mm: 4.0\n", "  focal_length_mm: 4.0\n  distortion: {k1: -0.1}\n")
    write(workspace, "profiles/fixed.yaml", barrel)
    head = f"pan_deg: {pan_deg}, tilt_deg: {tilt_deg}, zoom_x: {zoom_x}"
    eptz = f"    eptz: {{output_size_px: [320, 240], zoom_max_x: 8, {head}}}\n"
    return write(workspace, f"scenes/eptz_{zoom_x:g}.yaml", SCENE + eptz)


@pytest.mark.parametrize(("pan_deg", "tilt_deg", "zoom_x"), [(0, 0, 1), (5, -3, 2), (-4, 2, 4)])
def test_the_home_view_is_the_stream_the_plan_delivers(workspace: Path, pan_deg, tilt_deg, zoom_x):
    loaded = load_scene(eptz_scene(workspace, pan_deg, tilt_deg, zoom_x))
    camera, profile = loaded.scene.cameras[0], loaded.profile_models["cam"]
    view = home_view(camera, profile)
    (camera_job,) = compile_scene(loaded, PlanSettings()).cameras
    state = camera_job.states[0]
    np.testing.assert_allclose(view.K_px, np.array(state.output_K_px), rtol=1e-12)
    np.testing.assert_allclose(view.T_world_from_cam, np.array(state.T_world_from_cam), atol=1e-12)
    assert (view.width_px, view.height_px) == (320, 240)
    # px/m against the sensor's own at the same point: the stream scales them by 320 / window width, and
    # above the sensor's resolution (a window narrower than the stream) no further.
    sensor = view_at("cam", profile, camera.mount, profile.lens.focal_length_mm)
    window_width_px = state.window_px[2]
    ratio = densities(POINT_M, 0.0, view)[1].vertical_px_m / densities(POINT_M, 0.0, sensor)[1].vertical_px_m
    assert ratio[0] == pytest.approx(min(1.0, 320 / window_width_px), rel=1e-6)
    assert window_width_px == round(640 / zoom_x)


def test_the_simulation_sees_a_virtual_ptz_frame_as_coverage_sees_its_home_view(workspace: Path):
    from types import SimpleNamespace

    from camgen.sim.ground_coverage import delivered_view

    loaded = load_scene(eptz_scene(workspace, 5, -3, 4))
    home = home_view(loaded.scene.cameras[0], loaded.profile_models["cam"])
    state = compile_scene(loaded, PlanSettings()).cameras[0].states[0]
    delivered = delivered_view("cam", SimpleNamespace(state=state, rgb8=np.zeros((240, 320, 3), np.uint8)))
    for key in ("K_px", "distortion", "T_world_from_cam"):
        np.testing.assert_allclose(getattr(delivered, key), getattr(home, key), atol=1e-12)
    assert delivered.detail_scale == home.detail_scale == 0.5  # a 160 px window in a 320 px stream
    assert home.distortion[0] == -0.1


def test_a_virtual_ptz_reaches_what_its_sensor_sees_at_up_to_the_sensors_detail(workspace: Path):
    from camgen.coverage.dori import DORI_THRESHOLDS_PX_M
    from camgen.coverage.report import scene_coverage

    loaded = load_scene(eptz_scene(workspace, 0, 0, 1))
    camera, profile = loaded.scene.cameras[0], loaded.profile_models["cam"]
    coverage = scene_coverage(loaded.scene, loaded.profile_models, cell_m=0.5, with_ptz_reach=True)
    (reach,) = coverage.planes[0].reaches
    sensor = view_at("cam", profile, camera.mount, profile.lens.focal_length_mm)
    points = coverage.planes[0].grid.points_m()
    _, dens = densities(points, 0.0, sensor)
    native = dens.person_px_m.reshape(reach.reached.shape)
    assert reach.reached.sum() > 100 and np.all(np.isfinite(native[reach.reached]))
    # The 320 px stream of a 640 px wide zoom-1 window: half the sensor's px/m; at 8× (an 80 px window)
    # the sensor's own, not 4× them.
    np.testing.assert_allclose(reach.person_wide_px_m[reach.reached], native[reach.reached] / 2, rtol=1e-12)
    np.testing.assert_allclose(reach.person_tele_px_m[reach.reached], native[reach.reached], rtol=1e-12)
    # observe (t px/m) needs zoom 2·t/native where the sensor has the detail, none elsewhere.
    t, seen = DORI_THRESHOLDS_PX_M[1], native[reach.reached]
    needed = reach.zoom_needed_x[1][reach.reached]
    np.testing.assert_allclose(needed, np.where(seen >= t, np.maximum(2 * t / seen, 1), np.nan), rtol=1e-12)
    assert (needed > 1).any() and (needed == 1).any()
    identify = reach.zoom_needed_x[3][reach.reached]  # 250 px/m: beyond the sensor's detail somewhere
    assert np.array_equal(np.isnan(identify), seen < DORI_THRESHOLDS_PX_M[3]) and np.isnan(identify).any()
