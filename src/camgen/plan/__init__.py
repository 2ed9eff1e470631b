"""Compile scenes and profiles into frozen, serialisable render jobs."""

from camgen.job import CameraJob, CameraState, Decision, Job, PlanSettings, RenderSpec, Stage
from camgen.plan.compile import compile, compile_scene

__all__ = [
    "CameraJob",
    "CameraState",
    "Decision",
    "Job",
    "PlanSettings",
    "RenderSpec",
    "Stage",
    "compile",
    "compile_scene",
]
