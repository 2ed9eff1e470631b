"""What compiling a job will take, checked before anything is allocated.

`compile` builds every camera's state at every frame up front (a `CameraState` with its pose, camera
matrix and head position), so a long scene at a high frame rate asks for memory in proportion to
frames × cameras. A day at 30 fps is 2.6 million frames per camera: about 40 GiB, which would run a
machine out of memory minutes into `camgen plan` rather than be refused at once.
"""

from __future__ import annotations

import os

from camgen.config.scene import Scene
from camgen.errors import ConfigError, Problem

BYTES_PER_CAMERA_FRAME = 16 * 1024
"""Peak memory of compiling one camera at one frame, bytes. Measured with tracemalloc over `compile`
(the job's content hash included): 9.5–15.6 KiB for a fixed camera, a PTZ patrol and an ePTZ follow at
500 and 5000 frames; `camgen plan`'s resident memory grew by 8.3 KiB per frame. Rounded up."""

MEMORY_SHARE = 0.5
"""Share of the machine's memory the compiled states may take; rendering needs the rest."""


def memory_bytes() -> tuple[int, str] | None:
    """The memory a job may use and what that figure is: psutil's available memory where psutil is
    installed, else the physical memory (POSIX ``sysconf``); None where neither is known."""
    try:
        import psutil
    except ImportError:
        psutil = None
    if psutil is not None:
        return int(psutil.virtual_memory().available), "available"
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"), "physical"
    except (AttributeError, ValueError, OSError):
        return None


def compile_memory_bytes(scene: Scene) -> int:
    """Estimated peak memory of compiling `scene`, bytes (`BYTES_PER_CAMERA_FRAME` per camera and frame)."""
    return scene.frame_count * len(scene.cameras) * BYTES_PER_CAMERA_FRAME


def check_job_size(scene: Scene, memory: tuple[int, str] | None = None) -> None:
    """Refuse a scene whose compiled states would not fit in `memory` (default: `memory_bytes()`).

    Raises
    ------
    ConfigError
        At ``duration_s``, with the estimate, the memory and the longest duration that fits.
    """
    memory = memory_bytes() if memory is None else memory
    if memory is None:
        return
    have, what = memory
    need = compile_memory_bytes(scene)
    allowed = MEMORY_SHARE * have
    if need <= allowed:
        return
    cameras = len(scene.cameras)
    frames_fit = int(allowed // (cameras * BYTES_PER_CAMERA_FRAME))
    gib = 2.0**30
    raise ConfigError(
        [
            Problem(
                ("duration_s",),
                f"× fps = {scene.duration_s:g} s × {scene.fps:g} Hz = {scene.frame_count} frames for each of "
                f"{cameras} camera(s), whose compiled states need about {need / gib:.3g} GiB, more than "
                f"{MEMORY_SHARE:.0%} of this machine's {have / gib:.3g} GiB of {what} memory. At most "
                f"{frames_fit} frames per camera fit (duration_s ≤ {frames_fit / scene.fps:.0f} s at this fps): "
                "shorten duration_s or lower fps, or split the sequence into shorter scenes and render them "
                "as a dataset (camgen batch)",
            )
        ]
    )
