"""Depth-of-field cases: accuracy against time of the layered blur, and its cost per 1080p frame.

Accuracy: `layered_blur` at several bin settings against `reference_blur` (one layer per distinct
depth) on a small synthetic street scene; the error is the RMS over pixels and channels of the
relative error (L − L_ref)/L_ref, in %. Cost: one 1920×1080 frame (plus a 16 px margin each side) of
a synthetic scene — a textured ground plane receding from 2 m to 60 m, three boxes standing on it, a
street lamp and sky — through two lenses: the low-light camera the project targets and a PTZ at tele.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from camgen.bench.harness import Case
from camgen.optics.depth_of_field import layered_blur, reference_blur, signed_coc_px

STEP_SETTINGS = tuple((step_px, step_rel) for step_px in (0.5, 1.0) for step_rel in (0.05, 0.1, 0.2, 0.4))
"""(step_px, step_rel) pairs measured against the reference; (0.5, 0.1) is the default."""

ACCURACY_SIZE_PX = (160, 120)
FRAME_SIZE_PX = (1920, 1080)
FRAME_MARGIN_PX = 16
LENSES = {
    "low-light f 6 mm N 1.2 focus 4 m": {"focal_length_mm": 6.0, "f_number": 1.2, "focus_distance_m": 4.0},
    "PTZ tele f 30 mm N 1.6 focus 20 m": {"focal_length_mm": 30.0, "f_number": 1.6, "focus_distance_m": 20.0},
}
PIXEL_PITCH_UM = 2.9


def street_scene(
    width_px: int,
    height_px: int,
    *,
    near_m: float = 2.0,
    far_m: float = 60.0,
    focal_length_px: float = 2069.0,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """A synthetic street seen by a level camera: radiance (H, W, 3) cd/m² and depth (H, W) m, float32.

    The ground's depth runs from `far_m` at the horizon (30 % down the frame) to `near_m` at the bottom
    row with 1/z linear in the row, as for a plane; it carries a checker texture in ground metres.
    Above the horizon is sky (depth inf, 2000–3500 cd/m²). Three fronto-parallel boxes stand on the
    ground at 3, 8 and 25 m, and a 5·10⁴ cd/m² lamp sits just below the horizon.
    """
    rng = np.random.default_rng(seed)
    rows = np.arange(height_px, dtype=np.float64)[:, None]
    cols = np.arange(width_px, dtype=np.float64)[None, :]
    horizon_row = 0.3 * height_px
    fraction = (rows - horizon_row) / (height_px - 1 - horizon_row)
    with np.errstate(divide="ignore"):
        ground_m = 1.0 / (1.0 / far_m + (1.0 / near_m - 1.0 / far_m) * fraction)
    depth_m = np.broadcast_to(np.where(rows >= horizon_row, ground_m, np.inf), (height_px, width_px)).copy()

    lateral_m = (cols - width_px / 2) * np.minimum(depth_m, far_m) / focal_length_px
    checker = (np.sin(3.0 * lateral_m) * np.sin(3.0 * np.minimum(depth_m, far_m)) > 0.0).astype(np.float64)
    grain = rng.uniform(0.0, 10.0, size=(height_px, width_px))
    ground = (60.0 + 40.0 * checker + grain)[..., None] * np.array([1.0, 0.9, 0.8])
    sky = np.array([2000.0, 2500.0, 3500.0])
    radiance = np.where(np.isfinite(depth_m)[..., None], ground, sky)

    scale = height_px / 1080.0  # keeps the boxes' share of the frame at any size
    for box_m, left_m, width_m, height_m, colour in (
        (25.0, -4.0, 3.0, 2.5, (150.0, 40.0, 30.0)),
        (8.0, 1.0, 1.5, 1.8, (30.0, 120.0, 200.0)),
        (3.0, -1.2, 0.6, 1.7, (200.0, 180.0, 60.0)),
    ):
        bottom_fraction = (1.0 / box_m - 1.0 / far_m) / (1.0 / near_m - 1.0 / far_m)
        bottom = horizon_row + bottom_fraction * (height_px - 1 - horizon_row)
        extent_px = 0.3 * focal_length_px / box_m * scale
        r0, r1 = int(max(bottom - height_m * extent_px, 0)), int(min(bottom, height_px))
        c0 = int(max(width_px / 2 + left_m * extent_px, 0))
        c1 = int(min(width_px / 2 + (left_m + width_m) * extent_px, width_px))
        depth_m[r0:r1, c0:c1] = box_m
        stripes = 1.0 + 0.3 * np.sin(cols[:, c0:c1] / 4.0)
        radiance[r0:r1, c0:c1] = np.array(colour) * stripes[..., None]
    lamp_row, lamp_col, lamp_px = int(horizon_row) + max(int(40 * scale), 2), width_px // 3, max(int(4 * scale), 1)
    radiance[lamp_row : lamp_row + lamp_px, lamp_col : lamp_col + lamp_px] = 5e4
    return radiance.astype(np.float32), depth_m.astype(np.float32)


def _rms_relative_error_pct(image: np.ndarray, reference: np.ndarray) -> float:
    """RMS over pixels and channels of (image − reference)/reference, in %; the reference is > 0."""
    relative = (image.astype(np.float64) - reference) / reference
    return float(100.0 * np.sqrt(np.mean(relative * relative)))


def _lazy(make: Callable[[], tuple]) -> Callable[[], tuple]:
    """`make()` on the first call, its result afterwards."""
    store: list[tuple] = []

    def get() -> tuple:
        if not store:
            store.append(make())
        return store[0]

    return get


def _accuracy_inputs() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    width_px, height_px = ACCURACY_SIZE_PX
    radiance, depth_m = street_scene(width_px, height_px)
    # A lens that takes this scene to CoC ±12 px: −12.2 px at 2 m, +11.4 px at 60 m, +12.2 px for the sky.
    coc_px = signed_coc_px(depth_m, focal_length_mm=16.0, f_number=1.4, focus_distance_m=4.0, pixel_pitch_um=3.75)
    return radiance, coc_px, reference_blur(radiance, coc_px)


def _accuracy_case(get_inputs, step_px: float, step_rel: float) -> Case:
    def run() -> float:
        radiance, coc_px, reference = get_inputs()
        return _rms_relative_error_pct(layered_blur(radiance, coc_px, step_px=step_px, step_rel=step_rel), reference)

    width_px, height_px = ACCURACY_SIZE_PX
    return Case(
        name=f"DoF layered {width_px}×{height_px} step_px {step_px:g} step_rel {step_rel:g} vs reference",
        run=run,
        setup=get_inputs,
        error_unit="% RMS rel",
        baseline=f"DoF layered {width_px}×{height_px} step_px 0.5 step_rel 0.1 vs reference",
    )


def _frame_case(lens_name: str, lens: dict[str, float]) -> Case:
    def make() -> tuple[np.ndarray, np.ndarray]:
        width_px, height_px = (n + 2 * FRAME_MARGIN_PX for n in FRAME_SIZE_PX)
        radiance, depth_m = street_scene(width_px, height_px)
        return radiance, signed_coc_px(depth_m, pixel_pitch_um=PIXEL_PITCH_UM, **lens)

    get_inputs = _lazy(make)

    def run() -> None:
        layered_blur(*get_inputs())

    width_px, height_px = FRAME_SIZE_PX
    return Case(
        name=f"DoF layered {width_px}×{height_px}+{FRAME_MARGIN_PX} px margin, {lens_name}, {PIXEL_PITCH_UM} µm",
        run=run,
        setup=get_inputs,
        repeats=3,
    )


def dof_cases() -> list[Case]:
    """Accuracy against time for each step setting, then the cost of a 1080p frame for each lens."""
    get_inputs = _lazy(_accuracy_inputs)
    cases = [_accuracy_case(get_inputs, step_px, step_rel) for step_px, step_rel in STEP_SETTINGS]
    width_px, height_px = ACCURACY_SIZE_PX
    cases.append(
        Case(
            name=f"DoF brute-force reference {width_px}×{height_px} (one layer per depth)",
            run=lambda: _discard(reference_blur(*get_inputs()[:2])),
            setup=get_inputs,
            repeats=3,
        )
    )
    cases += [_frame_case(name, lens) for name, lens in LENSES.items()]
    return cases


def _discard(_result) -> None:
    """Cases time the work, not its result."""
