"""The job's data types, kept importable here for code written against them before they moved to
`camgen.job`; import them from `camgen.job` (or the `camgen.plan` package)."""

from camgen.job import (
    CameraJob,
    CameraState,
    Decision,
    Frozen,
    Job,
    Matrix3,
    Matrix4,
    Pass,
    PlanSettings,
    RenderSpec,
    Stage,
)

__all__ = [
    "CameraJob",
    "CameraState",
    "Decision",
    "Frozen",
    "Job",
    "Matrix3",
    "Matrix4",
    "Pass",
    "PlanSettings",
    "RenderSpec",
    "Stage",
]
