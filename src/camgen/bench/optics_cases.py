"""Lens-stage cases: ms per 1080p frame for each stage, run time against error for the remap's
interpolation (nearest, linear, cubic, Lanczos) against a 4×-supersampled reference, and building the
lens maps by Newton on every pixel against the checked spline of Newton (`lens_map_cases`).

The interpolation reference: the parking lot drawn as the PTZ camera sees it through a strong barrel
lens (k1 = −0.3) at 960×540, rendered with its margin at 4× per axis, resampled at 4× through the same
lens (linear, exact in OpenCV for float images) and box-averaged down. Each candidate is the render as
planned (2×2 supersampled, averaged to 1×) resampled through the 1× map; the error is the RMS
difference relative to the reference's mean, so it includes what 2× supersampling itself leaves.
"""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case, relative_rms_pct
from camgen.optics.diffraction import diffraction_blur
from camgen.optics.intrinsics import camera_matrix_px
from camgen.optics.remap import (
    INTERPOLATIONS,
    SUPPORT_PX,
    LensGeometry,
    LensMaps,
    lens_maps,
    output_grid_px,
    remap_image,
    source_grid_px,
    source_overshoot_px,
    source_points_px,
)

BARREL = (-0.3, 0.08, 0.001, -0.0008, 0.0, 0.0, 0.0, 0.0)
CA_SCALES = (1.0008, 1.0, 0.9992)
REFERENCE_FACTOR = 4
HD = (1920, 1080)
K_HD = ((1400.0, 0.0, (HD[0] - 1) / 2), (0.0, 1400.0, (HD[1] - 1) / 2), (0.0, 0.0, 1.0))
"""The camera matrix of the 1080p stage cases, px."""


def interpolation_cases(repo: Path) -> list[Case]:
    from camgen.bench.render_cases import _parking_lot, _renderer, _view
    from camgen.plan import PlanSettings
    from camgen.render.renderer import View
    from camgen.render.sequence import box_downsample

    size = (960, 540)

    @cache
    def inputs() -> tuple[np.ndarray, np.ndarray, LensMaps]:
        _, camera, graph = _parking_lot(repo, shadows=True)
        graph.place_actors(2.0)
        view = _view(camera, size)
        probe = LensGeometry(tuple(map(tuple, view.K_px)), BARREL, (1.0,), *size, (0, 0, 0, 0))
        margin = tuple(math.ceil(x) + max(SUPPORT_PX.values()) for x in source_overshoot_px(probe))
        geometry = LensGeometry(probe.K_px, BARREL, (1.0,), *size, margin)
        left, top, right, bottom = margin
        K = view.K_px.copy()
        K[0, 2] += left
        K[1, 2] += top
        pinhole = View(K, view.T_world_from_cam, size[0] + left + right, size[1] + top + bottom)
        s = PlanSettings().supersampling
        planned = box_downsample(_renderer().draw(graph, pinhole.scaled(s), ("radiance",)).radiance, s)
        f = REFERENCE_FACTOR
        fine = _renderer().draw(graph, pinhole.scaled(f), ("radiance",)).radiance
        # Output pixel centres of the 4× grid, in 1× output coordinates, through the lens, to 4× render pixels.
        grid = (output_grid_px(size[0] * f, size[1] * f) + 0.5) / f - 0.5
        (source,) = source_points_px(geometry, grid)
        fine_maps = LensMaps(
            ((f * (source[..., 0] + left + 0.5) - 0.5).astype(np.float32),),
            ((f * (source[..., 1] + top + 0.5) - 0.5).astype(np.float32),),
            (np.zeros(1, np.int32), np.zeros(1, np.int32)),
            np.zeros((1, 1, 2)),
        )
        reference = box_downsample(remap_image(fine, fine_maps, "linear"), f).astype(np.float64)
        return planned, reference, lens_maps(geometry)

    def run(method: str) -> float:
        planned, reference, maps = inputs()
        out = remap_image(planned, maps, method)
        return relative_rms_pct(out, reference)

    label = f"{size[0]}×{size[1]}, barrel k1 = −0.3, vs {REFERENCE_FACTOR}× reference"
    return [
        Case(
            name=f"remap {method}, {label}",
            run=lambda m=method: run(m),
            error_unit="% RMS",
            baseline=f"remap linear, {label}",
        )
        for method in INTERPOLATIONS
    ]


def lens_map_cases() -> list[Case]:
    """Building the 1080p lens maps: Newton on every pixel (``exact=True``) against the default, a
    bicubic spline through Newton's solutions on a node grid, checked between the nodes.

    The error is the spline's largest |source − Newton's| over every pixel and channel, px, in float64
    before the float32 cast; it depends on the lens only, so it is measured once, in the setup. The
    lenses: the 30× PTZ module at its wide end (the one whose maps change every frame while it zooms),
    and the strong barrel lens of the other cases with one channel and with lateral CA.
    """
    W, H = HD
    ptz_K = tuple(map(tuple, camera_matrix_px(4.5, 2.9, 2.9, W, H).tolist()))
    lenses = {
        "PTZ 4.5 mm k1 = −0.12, lateral CA": LensGeometry(
            ptz_K, (-0.12, 0.03, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), (1.0004, 1.0, 0.9995), W, H, (60, 40, 60, 40)
        ),
        "barrel k1 = −0.3, one channel": LensGeometry(K_HD, BARREL, (1.0,), W, H, (80, 80, 80, 80)),
        "barrel k1 = −0.3, lateral CA": LensGeometry(K_HD, BARREL, CA_SCALES, W, H, (80, 80, 80, 80)),
    }
    errors_px: dict[LensGeometry, float] = {}

    def measure_error(geometry: LensGeometry) -> None:
        pairs = zip(source_grid_px(geometry), source_grid_px(geometry, exact=True), strict=True)
        errors_px[geometry] = max(float(np.max(np.abs(fast - exact))) for fast, exact in pairs)

    def run_spline(geometry: LensGeometry) -> float:
        lens_maps(geometry)
        return errors_px[geometry]

    cases = []
    for label, geometry in lenses.items():
        newton = f"lens maps, build 1080p, {label}: Newton on every pixel"
        cases.append(Case(name=newton, run=lambda g=geometry: _discard(lens_maps(g, exact=True)), repeats=3))
        cases.append(
            Case(
                name=f"lens maps, build 1080p, {label}: checked spline of Newton",
                setup=lambda g=geometry: measure_error(g),
                run=lambda g=geometry: run_spline(g),
                error_unit="px",
                repeats=15,
                baseline=newton,
            )
        )
    return cases


def stage_cases() -> list[Case]:
    W, H = HD
    rng = np.random.default_rng(0)
    image = rng.random((H + 2 * 80, W + 2 * 80, 3), dtype=np.float32) * 100

    @cache
    def maps(with_ca: bool) -> LensMaps:
        return lens_maps(LensGeometry(K_HD, BARREL, CA_SCALES if with_ca else (1.0,), W, H, (80, 80, 80, 80)))

    gain = np.linspace(0.5, 1.0, W * H, dtype=np.float32).reshape(H, W)
    cases = []
    for method in INTERPOLATIONS:
        for with_ca in (False, True):
            what = "per-channel maps (lateral CA)" if with_ca else "one map"
            cases.append(
                Case(
                    name=f"remap 1080p {method}, {what}",
                    setup=lambda c=with_ca: _discard(maps(c)),
                    run=lambda m=method, c=with_ca: _discard(remap_image(image, maps(c), m)),
                    baseline="remap 1080p linear, one map",
                )
            )
    output = image[80:-80, 80:-80]
    cases.append(Case(name="vignetting gain 1080p", run=lambda: _discard(output * gain[..., None])))
    cases.append(
        Case(
            name="diffraction blur 1080p, f/8 on 2.9 µm pixels",
            run=lambda: _discard(diffraction_blur(image, f_number=8.0, pixel_pitch_um=2.9)),
        )
    )
    return cases


def _discard(_result) -> None:
    """Cases time the work, not its result."""
