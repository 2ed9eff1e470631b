"""Numerical stress over the schema's valid ranges (hypothesis): extreme coefficients, focal lengths of
1–1000 mm, images of 1×1 to 8K. A lens the profile validation accepts must give finite, checked
inverse maps that stay inside the planned render; one it refuses must be refused with a message."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from camgen.config.loader import load_profile
from camgen.config.profile import Profile
from camgen.optics.depth_of_field import signed_coc_px
from camgen.optics.intrinsics import camera_matrix_px
from camgen.optics.projection import distort_points
from camgen.optics.remap import (
    SUPPORT_PX,
    LensGeometry,
    check_inside,
    lens_maps,
    source_overshoot_px,
    source_points_px,
)
from camgen.optics.vignetting import relative_illumination
from tests.conftest import REPO
from tests.stress import stress_settings

BASE = load_profile(REPO / "profiles/lowlight_2mp_1p2in.yaml").profile.model_dump()
SIZES = st.sampled_from([(1, 1), (2, 3), (17, 5), (64, 48), (640, 480), (1920, 1080), (3840, 2160), (7680, 4320)])

coefficient = st.floats(-1.0, 1.0, allow_nan=False)
lens_strategy = st.fixed_dictionaries(
    {
        "k1": coefficient,
        "k2": coefficient,
        "p1": st.floats(-0.02, 0.02),
        "p2": st.floats(-0.02, 0.02),
        "k3": st.floats(-0.5, 0.5),
        "k4": st.one_of(st.just(0.0), st.floats(-0.5, 0.5)),
        "k5": st.just(0.0),
        "k6": st.just(0.0),
    }
)


def _profile(distortion: dict, focal_length_mm: float, pitch_um: float, size: tuple[int, int]) -> Profile | None:
    data = {**BASE}
    data["sensor"] = {**BASE["sensor"], "width_px": size[0], "height_px": size[1], "pixel_pitch_um": pitch_um}
    data["lens"] = {**BASE["lens"], "focal_length_mm": focal_length_mm, "distortion": distortion}
    data["lens"]["min_focus_distance_m"] = 0.3
    try:
        return Profile.model_validate(data)
    except ValidationError as error:
        assert "folds over" in str(error) or "distortion" in str(error)
        return None


def _border_and_interior(width: int, height: int, rng: np.random.Generator) -> np.ndarray:
    edge_u = np.linspace(-0.5, width - 0.5, 64)
    edge_v = np.linspace(-0.5, height - 0.5, 64)
    border = np.concatenate(
        [
            np.column_stack([edge_u, np.full(64, -0.5)]),
            np.column_stack([edge_u, np.full(64, height - 0.5)]),
            np.column_stack([np.full(64, -0.5), edge_v]),
            np.column_stack([np.full(64, width - 0.5), edge_v]),
        ]
    )
    interior = rng.uniform([-0.5, -0.5], [width - 0.5, height - 0.5], size=(256, 2))
    return border, interior


@stress_settings(80)
@given(
    distortion=lens_strategy,
    focal_length_mm=st.floats(1.0, 1000.0),
    pitch_um=st.floats(1.0, 10.0),
    size=SIZES,
    scales=st.tuples(st.floats(0.995, 1.005), st.floats(0.995, 1.005)),
)
def test_accepted_lenses_give_finite_checked_maps_inside_the_render(
    distortion, focal_length_mm, pitch_um, size, scales
):
    profile = _profile(distortion, focal_length_mm, pitch_um, size)
    if profile is None:
        return
    W, H = size
    K = camera_matrix_px(focal_length_mm, pitch_um, pitch_um, W, H)
    dist = profile.lens.distortion.as_array()
    geometry = LensGeometry(tuple(map(tuple, K)), tuple(dist), (scales[0], 1.0, scales[1]), W, H, (0, 0, 0, 0))
    border, interior = _border_and_interior(W, H, np.random.default_rng(0))
    overshoot = source_overshoot_px(geometry, border)  # raises if any residual exceeds 1e-3 px
    assert np.isfinite(overshoot).all()
    support = SUPPORT_PX["linear"]
    margin = tuple(math.ceil(x) + support for x in overshoot)
    left, top, right, bottom = margin
    inside = source_points_px(geometry, interior)
    for channel, scale in zip(inside, (scales[0], 1.0, scales[1]), strict=True):
        assert np.isfinite(channel).all()
        assert (channel[:, 0] + left >= 0).all() and (channel[:, 0] + left <= W + left + right - 1).all()
        assert (channel[:, 1] + top >= 0).all() and (channel[:, 1] + top <= H + top + bottom - 1).all()
        # The residual check holds: the source distorts back onto the (un-magnified) output point.
        shrunk = K[:2, 2] + (interior - K[:2, 2]) / scale
        assert np.max(np.abs(distort_points(channel, K, dist) - shrunk)) <= 1e-3
    if W * H <= 64 * 48:
        maps = lens_maps(LensGeometry(geometry.K_px, geometry.distortion, geometry.ca_scales, W, H, margin))
        check_inside(maps, W + left + right, H + top + bottom, support)
        corner = np.hypot((W / 2) / K[0, 0], (H / 2) / K[1, 1])
        gain = relative_illumination(
            maps.undistorted_normalized,
            maps.undistorted_normalized,
            corner_radius_normalized=corner,
            natural_cos4=True,
            polynomial=(-0.5, 0.0, 0.0),
            weight=1.0,
        )
        assert np.isfinite(gain).all() and (gain > 0).all()


@stress_settings(60)
@given(
    focal_length_mm=st.floats(1.0, 1000.0),
    f_number=st.floats(0.5, 64.0),
    focus_factor=st.floats(1.5, 1e4),
    pitch_um=st.floats(1.0, 10.0),
)
def test_blur_circle_is_finite_over_the_valid_ranges(focal_length_mm, f_number, focus_factor, pitch_um):
    f_m = focal_length_mm * 1e-3
    focus_m = f_m * focus_factor
    depth = np.array([f_m * 1.01, focus_m, 10 * focus_m, 1e6, np.inf], dtype=np.float32)
    coc = signed_coc_px(
        depth, focal_length_mm=focal_length_mm, f_number=f_number, focus_distance_m=focus_m, pixel_pitch_um=pitch_um
    )
    assert np.isfinite(coc).all()
    assert abs(coc[1]) < 1e-3 * max(1.0, abs(coc[0]))  # sharp at the focus distance
    assert coc[0] < 0 < coc[2] <= coc[4]
