"""Compile scenes and profiles into frozen, serialisable render jobs."""

from camgen.plan.compile import compile, compile_scene
from camgen.plan.job import CameraJob, CameraState, Decision, Job, PlanSettings, RenderSpec, Stage

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
