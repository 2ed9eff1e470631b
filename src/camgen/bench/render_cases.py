"""Rendering cases: each pass alone and the shared draw, static background, supersampling, motion sub-frames.

All draw the parking-lot example as its PTZ camera sees it, at the camera's own intrinsics scaled to
720p or 1080p. A case's time is one frame: draw plus read-back of the asked passes.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case, relative_rms_pct
from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene

SIZES = {"720p": (1280, 720), "1080p": (1920, 1080)}
PASS_SETS = {
    "radiance": ("radiance",),
    "depth_m": ("depth_m",),
    "instance_id": ("instance_id",),
    "shared draw: radiance + depth_m + instance_id": ("radiance", "depth_m", "instance_id"),
}
AA_SIZE = (640, 360)
AA_REFERENCE = 8


@cache
def _renderer():
    from camgen.render.renderer import Renderer

    return Renderer()


def _parking_lot(repo: Path, shadows: bool, size: tuple[int, int] | None = None):
    """The parking lot's compiled job, its PTZ camera and scene graph; `size`: the sensor resized
    (`variants.resized_profile`, same field of view)."""
    from camgen.bench.variants import at_output_size
    from camgen.render.scene_graph import build_scene_graph

    loaded = load_scene(repo / "scenes/parking_lot.yaml")
    if size is not None:
        loaded = at_output_size(loaded, *size)
    scene = loaded.scene
    if not shadows:
        environment = scene.environment.model_copy(update={"shadows": False})
        scene = scene.model_copy(update={"environment": environment})
        loaded = type(loaded)(loaded.name, loaded.path, scene, loaded.profiles, loaded.file_bounds)
    job = compile_scene(loaded, PlanSettings())
    return job, job.cameras[0], build_scene_graph(job.scene)


def _view(camera, size, time_index: int = 0):
    from camgen.render.renderer import View

    state = camera.states[time_index]
    K = np.array(state.K_px)
    width, height = size
    scale = width / camera.width_px
    K[:2, :2] *= scale
    K[0, 2] = (K[0, 2] + 0.5) * scale - 0.5
    K[1, 2] = (K[1, 2] + 0.5) * scale - 0.5
    return View(K, np.array(state.T_world_from_cam), width, height)


def pass_cases(repo: Path) -> list[Case]:
    """Each pass alone and the three in one shared draw, at 720p and 1080p (1×)."""
    cases = []
    job, camera, graph = _parking_lot(repo, shadows=True)
    frames = iter(range(10**9))

    def draw(view, passes):
        graph.place_actors(next(frames) % job.frame_count / job.fps)
        _renderer().draw(graph, view, passes)

    for size_name, size in SIZES.items():
        view = _view(camera, size)
        for label, passes in PASS_SETS.items():
            cases.append(
                Case(
                    name=f"render {label}, parking lot {size_name}",
                    run=lambda v=view, p=passes: draw(v, p),
                    baseline=f"render radiance, parking lot {size_name}",
                )
            )
    return cases


def planned_frame_cases(repo: Path) -> list[Case]:
    job, camera, graph = _parking_lot(repo, shadows=True)
    return [_planned_frame_case(camera, graph, job)]


def supersampling_cases(repo: Path, camera, graph) -> list[Case]:
    """Radiance supersampling against 8×8, and the checkerboard calibration at each s."""
    return _supersampling_cases(camera, graph) + _calibration_cases(repo)


def static_background_cases(repo: Path) -> list[Case]:
    """Full draw vs the kept environment plus actors, and vs still frames (the last frame kept, what moved
    drawn again), 1080p, radiance + ids, shadows off; consecutive frames."""
    from camgen.render.sequence import CameraRenderer

    job, camera, graph = _parking_lot(repo, shadows=False)
    full = f"render frame, full draw, parking lot {camera.render.width_px}×{camera.render.height_px} no shadows"
    cases = []
    for label, static, moving_regions in (
        ("full draw", False, False),
        ("static background (environment kept, actors drawn)", True, True),
        ("still frames (last frame kept, what moved drawn again)", False, True),
    ):
        spec = camera.render.model_copy(update={"static_background": static})
        renderer = CameraRenderer(
            _renderer(), graph, camera.model_copy(update={"render": spec}), moving_regions=moving_regions
        )
        frames = iter(range(10**9))

        def run(r=renderer, f=frames) -> None:
            r.frame(next(f) % job.frame_count)

        name = f"render frame, {label}, parking lot {spec.width_px}×{spec.height_px} no shadows"
        cases.append(Case(name=name, run=run, baseline=None if name == full else full, repeats=3))
    return cases


def _supersampling_cases(camera, graph) -> list[Case]:
    """Radiance at s×s samples per pixel against an 8×8 reference: RMS error relative to the mean."""
    from camgen.render.sequence import box_downsample

    view = _view(camera, AA_SIZE)
    graph.place_actors(2.0)

    @cache
    def reference():
        fine = _renderer().draw(graph, view.scaled(AA_REFERENCE), ("radiance",)).radiance
        return box_downsample(fine, AA_REFERENCE).astype(np.float64)

    def run(s: int) -> float:
        graph.place_actors(2.0)
        radiance = box_downsample(_renderer().draw(graph, view.scaled(s), ("radiance",)).radiance, s)
        return relative_rms_pct(radiance, reference())

    return [
        Case(
            name=f"radiance supersampling {s}×{s}, {AA_SIZE[0]}×{AA_SIZE[1]} (error vs {AA_REFERENCE}×{AA_REFERENCE})",
            run=lambda s=s: run(s),
            error_unit="% RMS",
            baseline=f"radiance supersampling 1×1, {AA_SIZE[0]}×{AA_SIZE[1]} (error vs {AA_REFERENCE}×{AA_REFERENCE})",
        )
        for s in (1, 2, 3, 4)
    ]


def _calibration_cases(repo: Path) -> list[Case]:
    """Render the 14 checkerboard views at s×s and calibrate: the error is fx's, in % of the profile's.

    This is what the supersampling default for geometric work is chosen by; each case runs once.
    """
    from camgen.fit.checkerboard import calibrate, find_corners, gray8_from_radiance, inner_corners
    from camgen.render.sequence import crop_to_output, render_camera

    loaded = load_scene(repo / "scenes/checkerboard.yaml")

    def run(s: int) -> float:
        job = compile_scene(loaded, PlanSettings(supersampling=s))
        board = next(m for m in job.scene.environment.meshes if m.name == "board")
        corners = []
        for camera in job.cameras:
            radiance = next(render_camera(_renderer(), job, camera)).passes.radiance
            found = find_corners(gray8_from_radiance(crop_to_output(radiance, camera.render)), inner_corners(board))
            if found is not None:
                corners.append(found)
        camera = job.cameras[0]
        result = calibrate(board, corners, (camera.width_px, camera.height_px))
        return float(100 * abs(result.K_px[0, 0] / camera.states[0].K_px[0][0] - 1))

    return [
        Case(
            name=f"calibrate from 14 rendered board views, supersampling {s}×{s} (fx error)",
            run=lambda s=s: run(s),
            error_unit="%",
            repeats=1,
            warmup=0,
        )
        for s in (1, 2, 3)
    ]


def _planned_frame_case(camera, graph, job) -> Case:
    """One 1080p frame with every pass at the default plan settings: radiance at 2×2 samples per
    pixel, depth and ids at pixel centres (the static background off, shadows on)."""
    from camgen.render.sequence import CameraRenderer

    s = PlanSettings().supersampling
    spec = camera.render.model_copy(
        update={
            "width_px": camera.width_px,
            "height_px": camera.height_px,
            "margin_px": (0, 0, 0, 0),
            "passes": ("radiance", "depth_m", "instance_id"),
            "supersampling": s,
            "static_background": False,
        }
    )
    renderer = CameraRenderer(_renderer(), graph, camera.model_copy(update={"render": spec}))
    frames = iter(range(10**9))

    def run() -> None:
        renderer.frame(next(frames) % job.frame_count)

    return Case(
        name=f"render frame as planned: radiance {s}×{s} + depth_m + instance_id, parking lot 1080p",
        run=run,
        repeats=3,
    )


MOTION_SIZE_PX = (640, 360)
MOTION_EXPOSURE_S = 0.25
"""A long exposure, so the walkers and the car smear over many pixels at this size."""
MOTION_SUB_FRAMES = 8
MOTION_REFERENCE = (32, 4)
"""Reference: 32 sub-frames, each 4×4 supersampled."""


def motion_sampling_cases(camera, graph) -> list[Case]:
    """Motion blur with supersampling 2: each sub-frame drawn 2×2 finer and averaged (grid) against
    each drawn at 1× through one of the 2×2 sub-pixel positions in turn (jittered, the default), and
    1× without the jitter; the error is the RMS against 32 sub-frames each 4×4 supersampled."""
    from camgen.optics.motion_blur import sub_frame_offsets
    from camgen.render.sequence import box_downsample, jittered_samples, shifted

    view = _view(camera, MOTION_SIZE_PX)
    t0 = 2.0

    def draw(offset: float, v) -> np.ndarray:
        graph.place_actors(t0 + offset * MOTION_EXPOSURE_S)
        return _renderer().draw(graph, v, ("radiance",)).radiance

    def grid(count: int, s: int) -> np.ndarray:
        frames = [box_downsample(draw(t, view.scaled(s)), s) for t in sub_frame_offsets(count)]
        return np.mean(frames, axis=0, dtype=np.float64)

    @cache
    def reference() -> np.ndarray:
        return grid(*MOTION_REFERENCE)

    def jittered() -> float:
        samples = jittered_samples(MOTION_SUB_FRAMES, 2)
        frames = [draw(t, shifted(view, dx, dy)) for t, dx, dy in samples]
        return relative_rms_pct(np.mean(frames, axis=0, dtype=np.float64), reference())

    label = (
        f"{MOTION_SIZE_PX[0]}×{MOTION_SIZE_PX[1]}, {MOTION_SUB_FRAMES} sub-frames, supersampling 2 (error vs 32 × 4×4)"
    )
    grid_name = f"motion sub-frames each 2×2 (grid), {label}"
    return [
        Case(
            name=grid_name,
            run=lambda: relative_rms_pct(grid(MOTION_SUB_FRAMES, 2), reference()),
            setup=reference,
            error_unit="% RMS",
            repeats=5,
        ),
        Case(
            name=f"motion sub-frames 1× jittered over 2×2 (default), {label}",
            run=jittered,
            error_unit="% RMS",
            repeats=5,
            baseline=grid_name,
        ),
        Case(
            name=f"motion sub-frames 1× without jitter, {label}",
            run=lambda: relative_rms_pct(grid(MOTION_SUB_FRAMES, 1), reference()),
            error_unit="% RMS",
            repeats=5,
            baseline=grid_name,
        ),
    ]
