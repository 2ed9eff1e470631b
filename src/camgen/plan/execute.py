"""Run a compiled Job: render each camera's planned passes and write what this version can write.

Implemented so far: the render stage (ideal pinhole radiance, depth, ids), the lens stages
(`camgen.plan.lens_stages`) and a preview video of the radiance (global exposure, sRGB;
`camgen.isp.preview`) encoded with the profile's codec. The sensor, ISP and annotation stages come
with their issues; `unimplemented_stages` names those a job
plans but this version skips, so callers can say so.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.io.files import atomic_path, write_text_atomic
from camgen.isp.preview import preview_exposure_scale, preview_srgb8
from camgen.optics.remap import LensMapCache
from camgen.plan.job import CameraJob, Job
from camgen.plan.lens_stages import LensStages
from camgen.render.renderer import Renderer
from camgen.render.scene_graph import instance_table
from camgen.render.sequence import render_camera

IMPLEMENTED_STAGES = frozenset(
    {
        "render",
        "optics.motion_blur",
        "optics.depth_of_field",
        "optics.axial_ca",
        "optics.diffraction",
        "optics.remap",
        "optics.vignetting",
        "io.video",
    }
)


@dataclass
class CameraResult:
    name: str
    directory: Path
    frames: int = 0
    files: list[Path] = field(default_factory=list)
    render_s: float = 0.0
    """Time spent drawing and reading back passes, s."""
    total_s: float = 0.0


def job_directory_name(job: Job) -> str:
    """`<scene>-<first 8 hex digits of the job hash>`: readable, and distinct for distinct jobs."""
    return f"{job.scene_name}-{job.job_id[:8]}"


def unimplemented_stages(camera: CameraJob) -> list[str]:
    return [stage.name for stage in camera.stages if stage.name not in IMPLEMENTED_STAGES]


def execute(
    job: Job,
    out_dir: str | Path,
    *,
    renderer: Renderer,
    frames: Iterable[int] | None = None,
    cameras: Iterable[str] | None = None,
    resolve_path: Callable[[str], Path] | None = None,
    save_passes: bool = False,
    on_frame: Callable[[str, int], None] | None = None,
) -> list[CameraResult]:
    """Render `job` into ``out_dir/<scene>-<hash>/<camera>/`` and return what was written.

    frames: frame indices to render (default: all). save_passes: also write each frame's passes,
    through the lens into the output frame, as ``passes/<frame>.npz`` (radiance_cd_m2, depth_m, instance_id).
    on_frame(camera, index) is called after each frame (for progress).
    """
    job_dir = Path(out_dir) / job_directory_name(job)
    indices = list(range(job.frame_count) if frames is None else frames)
    wanted = None if cameras is None else set(cameras)
    results = []
    maps = LensMapCache()  # cameras with the same lens and zoom share their maps
    for camera in job.cameras:
        if wanted is not None and camera.name not in wanted:
            continue
        results.append(
            _execute_camera(
                job, camera, job_dir / camera.name, renderer, indices, resolve_path, save_passes, on_frame, maps
            )
        )
    # Written last: a job directory with job.json in it holds a complete render.
    write_text_atomic(job_dir / "job.json", job.to_json())
    return results


def _execute_camera(
    job, camera, directory, renderer, indices, resolve_path, save_passes, on_frame, maps
) -> CameraResult:
    from camgen.io.video import VideoWriter

    result = CameraResult(camera.name, directory)
    started = time.perf_counter()
    spec = camera.render
    wants_video = "radiance" in spec.passes and job.scene.outputs.video
    video = None
    exposure_scale = None
    frames = render_camera(renderer, job, camera, frames=indices, resolve_path=resolve_path)
    lens = LensStages(camera, maps)
    try:
        while True:
            tick = time.perf_counter()
            frame = next(frames, None)
            result.render_s += time.perf_counter() - tick
            if frame is None:
                break
            passes = lens.apply(camera.states[frame.index], frame.passes)
            if wants_video:
                radiance = passes.radiance
                if video is None:
                    exposure_scale = preview_exposure_scale(radiance)
                    video = VideoWriter(
                        directory / "video.mp4",
                        width_px=camera.width_px,
                        height_px=camera.height_px,
                        fps=job.fps,
                        codec=camera.profile.codec,
                    )
                video.write(preview_srgb8(radiance, exposure_scale))
            if save_passes:
                if result.frames == 0:
                    table = [vars(instance) for instance in instance_table(job.scene)]
                    write_text_atomic(directory / "passes" / "instances.json", json.dumps(table, indent=1))
                _save_passes(directory / "passes" / f"{frame.index:06d}.npz", passes, result)
            result.frames += 1
            if on_frame is not None:
                on_frame(camera.name, frame.index)
        if video is not None:
            video.close()
            result.files.append(directory / "video.mp4")
    except BaseException:
        if video is not None:
            video.abort()
        raise
    finally:
        frames.close()
    result.total_s = time.perf_counter() - started
    return result


def _save_passes(path: Path, passes, result: CameraResult) -> None:
    arrays = {
        key: value
        for key, value in (
            ("radiance_cd_m2", passes.radiance),
            ("depth_m", passes.depth_m),
            ("instance_id", passes.instance_id),
        )
        if value is not None
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)
    result.files.append(path)
