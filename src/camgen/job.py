"""The compiled render job: frozen, JSON-serialisable, content-hashed.

A Job holds everything a worker needs: the scene, each camera's resolved profile, per-frame camera
states, the ordered stages with the render passes they consume, and every skip decision with its
reason. Its content hash is the job id (the cache and resume key).

These are data types only, built on `camgen.config` and nothing else, so that the packages that make
a job (`plan`) and those that carry it out (`render`, `batch`, `io`) all import them downward. One
module, not a package: the types are one concept and read together; `camgen.plan` re-exports them as
its public API (`from camgen.plan import Job, PlanSettings`).
"""

from __future__ import annotations

import hashlib
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from camgen.config.profile import Profile
from camgen.config.scene import Scene

Pass = Literal["radiance", "depth_m", "instance_id"]
Matrix3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
Matrix4 = tuple[
    tuple[float, float, float, float],
    tuple[float, float, float, float],
    tuple[float, float, float, float],
    tuple[float, float, float, float],
]


class Frozen(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class PlanSettings(Frozen):
    """Thresholds under which an effect counts as invisible and its stage is left out."""

    geometry_tolerance_px: Annotated[float, Field(gt=0)] = 0.01
    """Largest image displacement (distortion, lateral CA) that may be ignored, px. Tight, because
    annotations and camera metadata must describe the pixels exactly."""
    blur_diameter_threshold_px: Annotated[float, Field(gt=0)] = 0.5
    """Blur spot diameter (defocus, motion) below which blur is skipped, px. Diffraction is kept wherever its
    kernel changes a pixel (`camgen.optics.diffraction.diffraction_effect_rel`)."""
    illumination_tolerance_rel: Annotated[float, Field(gt=0)] = 0.005
    """Largest relative illumination change (vignetting) that may be ignored."""
    supersampling: Annotated[int, Field(ge=1, le=8)] = 2
    """Radiance anti-aliasing: render at this factor per axis and average down. 2 by measurement
    (BENCHMARKS.md): against 8×8, 1× errs 4.4 % RMS and biases a checkerboard calibration's fx by
    0.24 %; 2× errs 1.6 % and 0.016 % at 2.65× the time."""
    remap_interpolation: Literal["nearest", "linear", "cubic", "lanczos"] = "linear"
    """Interpolation of the distortion/CA resampling of radiance (BENCHMARKS.md: run time against
    error for each). Depth and instance ids always take the nearest pixel's exact value."""
    dof_step_px: Annotated[float, Field(gt=0)] = 0.5
    """Depth-of-field layers: the widest blur-diameter bin, px, for small blur circles."""
    dof_step_rel: Annotated[float, Field(gt=0, le=1)] = 0.1
    """Depth-of-field layers: bin width relative to the blur diameter, for large blur circles."""
    gaussian_above_e: Annotated[float, Field(gt=0)] = 20.0
    """Expected electrons above which shot noise is drawn as a Gaussian (exact Poisson below).
    BENCHMARKS.md: run time against error by photon level."""
    auto_exposure_start: Literal["converged", "profile"] = "converged"
    """Where auto-exposure starts: settled on the first frame's view (as a camera that has been
    running), or at the profile's exposure (to watch it adapt from there)."""
    force_all_stages: bool = False
    """Plan every stage regardless of its effect (for checking that skipping changes nothing)."""


class CameraState(Frozen):
    """One camera at one frame. Exposure: the manual value, or where auto-exposure starts."""

    frame: int
    time_s: float
    pan_deg: float
    tilt_deg: float
    zoom_x: float
    focal_length_mm: float
    f_number: float
    focus_distance_m: float
    exposure_time_s: float
    gain_db: float
    K_px: Matrix3
    distortion: tuple[float, float, float, float, float, float, float, float]
    """OpenCV order (k1, k2, p1, p2, k3, k4, k5, k6), as applied to the pixels."""
    T_world_from_cam: Matrix4
    pan_deg_s: float = 0.0
    """Head rates at the frame time (PTZ cameras): pan and tilt in deg/s, zoom in ln(zoom_x)/s."""
    tilt_deg_s: float = 0.0
    log_zoom_per_s: float = 0.0
    ptz_mode: str | None = None
    """What the PTZ program does at this frame: hold, move, dwell, scan, keyframes or follow."""
    follow_target: str | None = None
    """The actor the camera follows at this frame, if any."""
    window_px: tuple[int, int, int, int] | None = None
    """Virtual PTZ: the sensor window (x0, y0, width, height) the stream shows, px."""
    output_K_px: Matrix3 | None = None
    """Virtual PTZ: the camera matrix of the stream (the scaled window); K_px is the sensor's."""
    night_mode: bool = False
    """The camera is in IR night mode (`camgen.world.night`): IR-cut filter out, illuminator on,
    monochrome stream."""


class Decision(Frozen):
    """Why a stage or pass is in the plan or not, with the measured effect and its threshold."""

    stage: str
    included: bool
    reason: str
    effect: float | None = None
    threshold: float | None = None
    unit: str = ""


class Stage(Frozen):
    name: str
    passes: tuple[Pass, ...] = ()
    """Render passes this stage consumes."""
    params: dict[str, Any] = {}


class RenderSpec(Frozen):
    """The ideal pinhole render: larger than the output by a margin when later stages need it."""

    width_px: int
    height_px: int
    margin_px: tuple[int, int, int, int]
    """(left, top, right, bottom) pixels beyond the output frame."""
    passes: tuple[Pass, ...]
    supersampling: int
    static_background: bool
    """The camera does not move: render the environment once, composite actors per frame."""


class CameraJob(Frozen):
    name: str
    profile_name: str
    profile: Profile
    serial: int
    width_px: int
    height_px: int
    exposure_mode: Literal["manual", "auto"]
    output_size_px: tuple[int, int] | None = None
    """Virtual PTZ: (width, height) of the stream, a scaled window of the width_px × height_px sensor."""
    render: RenderSpec
    stages: tuple[Stage, ...]
    decisions: tuple[Decision, ...]
    states: tuple[CameraState, ...]


class Job(Frozen):
    camgen_version: str
    scene_name: str
    scene: Scene
    settings: PlanSettings
    frame_count: int
    fps: float
    seed: int
    cameras: tuple[CameraJob, ...]
    job_id: str = ""

    def content_hash(self) -> str:
        """SHA-256 of the compact JSON of everything but the id itself.

        The JSON is pydantic's serialisation: fields in their declared order, mappings in the order they
        were given (a scene whose YAML lists a mapping's keys in another order is another job, rendered
        again rather than resumed). It replaced a key-sorted `json.dumps` of `model_dump`, which took 24 s
        of an hour-long sequence's plan (90,000 frames' states) against about 1 s."""
        text = self.model_dump_json(by_alias=True, exclude={"job_id"})
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def to_json(self) -> str:
        return self.model_dump_json(by_alias=True, indent=1)

    @classmethod
    def from_json(cls, text: str) -> Job:
        return cls.model_validate_json(text)
