"""Lens stress: distortion inversion, float32 maps far from the principal point, and the thin-lens
figures over the profile schema's ranges (focal length > 0, f-number 0.5–64, pitch ≤ 100 µm).

tests/optics/test_stress.py covers maps staying inside the planned render and the blur circle's sign;
these add the inverse's residual and branch at principal-point offsets and non-square pixels, the
refusal message of a lens the validation rejects, the float32 cast at 8K, and the closed forms.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import event, example, given
from hypothesis import strategies as st
from pydantic import ValidationError

from camgen.config.loader import load_profile
from camgen.config.profile import Profile
from camgen.optics.depth_of_field import signed_coc_px
from camgen.optics.diffraction import airy_sigma_px
from camgen.optics.distortion import distort_normalized, undistort_normalized
from camgen.optics.intrinsics import (
    angular_fov_deg,
    aperture_diameter_mm,
    blur_circle_diameter_mm,
    camera_matrix_px,
    hyperfocal_distance_m,
)
from camgen.optics.projection import INVERSE_RESIDUAL_MAX_PX, distort_points, undistort_points
from camgen.optics.remap import LensGeometry, border_points_px, lens_maps, source_overshoot_px, source_points_px
from tests.conftest import REPO
from tests.stress import stress_settings

BASE = load_profile(REPO / "profiles/lowlight_2mp_1p2in.yaml").profile.model_dump()

coefficient = st.floats(-1.0, 1.0)
lenses = st.fixed_dictionaries(
    {
        "k1": coefficient,
        "k2": st.floats(-0.5, 0.5),
        "p1": st.floats(-0.02, 0.02),
        "p2": st.floats(-0.02, 0.02),
        "k3": st.floats(-0.2, 0.2),
        "k4": st.one_of(st.just(0.0), st.floats(-0.5, 0.5)),
        "k5": st.just(0.0),
        "k6": st.just(0.0),
    }
)
SIZES = st.sampled_from([(1, 1), (2, 3), (17, 5), (64, 48), (640, 480), (1920, 1080), (3840, 2160), (7680, 4320)])


def validate(distortion: dict, focal_length_mm: float, pitch_um: float, pitch_y_um: float, size, offset_px):
    """The profile with this lens and sensor geometry, or the ValidationError it raises."""
    data = {**BASE}
    data["sensor"] = {
        **BASE["sensor"],
        "width_px": size[0],
        "height_px": size[1],
        "pixel_pitch_um": pitch_um,
        "pixel_pitch_y_um": pitch_y_um,
        "principal_point_offset_px": offset_px,
    }
    data["lens"] = {**BASE["lens"], "focal_length_mm": focal_length_mm, "distortion": distortion}
    try:
        return Profile.model_validate(data)
    except ValidationError as error:
        return error


@stress_settings(60)
@given(
    distortion=lenses,
    focal_length_mm=st.floats(1.0, 1000.0),
    pitch_um=st.floats(0.8, 10.0),
    aspect=st.floats(0.8, 1.25),
    size=SIZES,
    offset_frac=st.tuples(st.floats(-0.25, 0.25), st.floats(-0.25, 0.25)),
)
@example(  # strong barrel on a wide 8K sensor, axis a quarter frame off centre
    distortion={"k1": -0.3, "k2": 0.08, "p1": 0.001, "p2": -0.001, "k3": -0.01, "k4": 0.0, "k5": 0.0, "k6": 0.0},
    focal_length_mm=8.0,
    pitch_um=1.0,
    aspect=1.0,
    size=(7680, 4320),
    offset_frac=(0.25, -0.25),
)
def test_accepted_lenses_invert_on_their_monotone_branch_and_refused_ones_say_why(
    distortion, focal_length_mm, pitch_um, aspect, size, offset_frac
):
    """Every lens the profile validation accepts inverts everywhere in the image (corners of an 8K
    frame with the principal point a quarter frame off centre, non-square pixels) to the documented
    residual `INVERSE_RESIDUAL_MAX_PX` = 1e-3 px, on the branch the rays reach: positive Jacobian and
    the same side of the axis. A refused lens is refused with a message naming the distortion key and
    the reason, never with NaN."""
    offset_px = (offset_frac[0] * size[0], offset_frac[1] * size[1])
    profile = validate(distortion, focal_length_mm, pitch_um, pitch_um * aspect, size, offset_px)
    event("refused" if isinstance(profile, ValidationError) else "accepted")
    if isinstance(profile, ValidationError):
        (error,) = profile.errors()
        assert error["ctx"]["subpath"] == "lens.distortion"
        assert "folds over" in error["msg"] or "cannot be inverted" in error["msg"]
        return
    W, H = size
    K = profile.camera_matrix_px(focal_length_mm)
    coefficients = profile.lens.distortion.as_array()
    rng = np.random.default_rng(0)
    points = np.concatenate(
        [border_points_px(W, H, step_px=max(W, H) / 32), rng.uniform(-0.5, [W - 0.5, H - 0.5], (64, 2))]
    )
    undistorted = undistort_points(points, K, coefficients)  # raises LensInversionError past 1e-3 px
    assert np.isfinite(undistorted).all()
    residual_px = np.hypot(*(distort_points(undistorted, K, coefficients) - points).T)
    assert residual_px.max() <= INVERSE_RESIDUAL_MAX_PX
    # The normalised solution reports the same convergence: residual and Jacobian on the branch.
    target = np.stack([(points[:, 0] - K[0, 2]) / K[0, 0], (points[:, 1] - K[1, 2]) / K[1, 1]], -1)
    solved = undistort_normalized(target, coefficients)
    assert np.all(solved.residual * max(K[0, 0], K[1, 1]) <= INVERSE_RESIDUAL_MAX_PX)
    assert np.all(solved.jacobian_det > 0)
    assert np.all(np.sum(solved.points * target, axis=-1) >= 0)
    np.testing.assert_allclose(distort_normalized(solved.points, coefficients), target, rtol=0, atol=1e-3 / K[0, 0])


@stress_settings(6)
@given(
    distortion=lenses,
    focal_length_mm=st.floats(2.0, 1000.0),
    pitch_um=st.floats(0.8, 6.0),
    size=st.sampled_from([(7, 5), (64, 48), (321, 77), (640, 480)]),
    offset_frac=st.tuples(st.floats(-0.25, 0.25), st.floats(-0.25, 0.25)),
    ca=st.tuples(st.floats(0.995, 1.005), st.floats(0.995, 1.005)),
)
@example(  # 8K, strong barrel, the axis a quarter frame off: source coordinates beyond 8192 px
    distortion={"k1": -0.3, "k2": 0.08, "p1": 0.001, "p2": -0.001, "k3": -0.01, "k4": 0.0, "k5": 0.0, "k6": 0.0},
    focal_length_mm=8.0,
    pitch_um=1.0,
    size=(7680, 4320),
    offset_frac=(0.25, 0.0),
    ca=(1.0, 1.0),
)
def test_float32_maps_stay_within_the_documented_error_of_newton(
    distortion, focal_length_mm, pitch_um, size, offset_frac, ca
):
    """`lens_maps` stores float32 source positions built from a checked spline: each is within
    1e-3 px of Newton's float64 inverse (`lens_maps` Notes) plus half a float32 ulp of its value (the
    cast, 2.4e-4 px above 4096 px, 4.9e-4 px above 8192 px) — at the corners of an 8K frame too."""
    offset_px = (offset_frac[0] * size[0], offset_frac[1] * size[1])
    profile = validate(distortion, focal_length_mm, pitch_um, None, size, offset_px)
    event("refused" if isinstance(profile, ValidationError) else "accepted")
    if isinstance(profile, ValidationError):
        return
    W, H = size
    K = profile.camera_matrix_px(focal_length_mm)
    scales = (ca[0], 1.0, ca[1])
    geometry = LensGeometry(tuple(map(tuple, K)), tuple(profile.lens.distortion.as_array()), scales, W, H, (0, 0, 0, 0))
    margin = tuple(math.ceil(x) + 1 for x in source_overshoot_px(geometry))
    geometry = LensGeometry(geometry.K_px, geometry.distortion, scales, W, H, margin)
    maps = lens_maps(geometry)
    rows = np.unique(np.r_[0, H - 1, np.random.default_rng(1).integers(0, H, 16)])
    cols = np.unique(np.r_[0, W - 1, np.random.default_rng(2).integers(0, W, 16)])
    v, u = np.meshgrid(rows, cols, indexing="ij")
    exact = source_points_px(geometry, np.stack([u, v], -1).astype(np.float64))
    for map_x, map_y, newton in zip(maps.map_x, maps.map_y, exact, strict=True):
        stored = np.stack([map_x[v, u], map_y[v, u]], -1).astype(np.float64)
        assert np.isfinite(stored).all()
        shifted = newton + np.array(margin[:2], np.float64)
        bound = 1e-3 + 0.5 * np.spacing(np.abs(stored).astype(np.float32)).astype(np.float64)
        assert np.all(np.abs(stored - shifted) <= bound)


@stress_settings(100)
@given(
    focal_length_mm=st.floats(0.5, 2000.0),
    f_number=st.floats(0.5, 64.0),
    pitch_um=st.floats(0.5, 100.0),
    sensor_mm=st.floats(0.1, 100.0),
    focus_factor=st.floats(1.01, 1e5),
)
def test_thin_lens_figures_are_finite_and_monotone_over_the_schema(
    focal_length_mm, f_number, pitch_um, sensor_mm, focus_factor
):
    """Aperture D = f/N, hyperfocal H = f²/(N·c) + f, AFOV = 2·atan(w/2f), Airy σ = 0.42·λ·N/p and the
    CoC are finite and positive over the ranges, and move the way optics says: the CoC at infinity
    grows with the aperture diameter (opening one stop multiplies it by √2 exactly), H falls as N
    rises, the AFOV narrows as f grows and stays in (0°, 180°)."""
    coc_mm = 2.0 * pitch_um * 1e-3
    diameter = aperture_diameter_mm(focal_length_mm, f_number)
    assert math.isfinite(diameter) and diameter == focal_length_mm / f_number
    hyperfocal = hyperfocal_distance_m(focal_length_mm, f_number, coc_mm)
    assert math.isfinite(hyperfocal) and hyperfocal > focal_length_mm * 1e-3
    assert hyperfocal_distance_m(focal_length_mm, f_number * 1.01, coc_mm) < hyperfocal
    afov = angular_fov_deg(sensor_mm, focal_length_mm)
    assert 0.0 < afov < 180.0 and angular_fov_deg(sensor_mm, focal_length_mm * 1.01) < afov
    sigma = airy_sigma_px(f_number, pitch_um, 0.55)
    assert math.isfinite(sigma) and sigma == 0.42 * 0.55 * f_number / pitch_um
    focus_m = focal_length_mm * 1e-3 * focus_factor
    depths = np.array([np.inf, 1e9, 2.0 * focus_m], dtype=np.float64)
    coc = signed_coc_px(
        depths, focal_length_mm=focal_length_mm, f_number=f_number, focus_distance_m=focus_m, pixel_pitch_um=pitch_um
    )
    assert np.isfinite(coc).all() and np.all(coc > 0)
    wider = signed_coc_px(
        depths,
        focal_length_mm=focal_length_mm,
        f_number=f_number / math.sqrt(2),
        focus_distance_m=focus_m,
        pixel_pitch_um=pitch_um,
    )
    np.testing.assert_allclose(wider / coc, math.sqrt(2), rtol=1e-6)
    closed_form = blur_circle_diameter_mm(depths[1:], focal_length_mm, f_number, focus_m) / (pitch_um * 1e-3)
    np.testing.assert_allclose(coc[1:], closed_form, rtol=1e-6)


@stress_settings(30)
@given(
    focal_length_mm=st.floats(0.5, 2000.0),
    f_number=st.floats(0.5, 64.0),
    focus_factor=st.floats(0.0, 1.0),
)
def test_blur_circle_refuses_points_and_focus_not_beyond_the_focal_length(focal_length_mm, f_number, focus_factor):
    """A thin lens forms no real image of a point at or inside its front focal point: a focus distance
    or depth ≤ f is refused with ValueError (not an infinite or sign-flipped CoC)."""
    f_m = focal_length_mm * 1e-3
    kwargs = {"focal_length_mm": focal_length_mm, "f_number": f_number, "pixel_pitch_um": 3.0}
    try:
        signed_coc_px(np.array([10.0 * f_m]), focus_distance_m=f_m * focus_factor, **kwargs)
    except ValueError as error:
        assert "focus_distance_m" in str(error)
    else:
        raise AssertionError("a focus distance inside the focal length was accepted")
    try:
        signed_coc_px(np.array([f_m * focus_factor, 10.0 * f_m]), focus_distance_m=2.0 * f_m, **kwargs)
    except ValueError as error:
        assert "depth_m" in str(error)
    else:
        raise AssertionError("a depth inside the focal length was accepted")


def test_camera_matrix_keeps_the_principal_point_at_the_centre_plus_offset():
    """Reference for the geometry above: K places the axis at ((W−1)/2, (H−1)/2) + offset."""
    K = camera_matrix_px(8.0, 1.0, 2.0, 7680, 4320, (10.0, -5.0))
    assert (K[0, 0], K[1, 1], K[0, 2], K[1, 2]) == (8000.0, 4000.0, 3849.5, 2154.5)
