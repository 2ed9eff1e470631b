"""camgen as a simulator that a controller drives: reset/step, PTZ commands with ONVIF semantics,
and gymnasium environments (`camgen.sim.envs`, with the optional extra `sim`)."""

from camgen.sim.commands import (
    AbsoluteMove,
    CommandError,
    ContinuousMove,
    GotoPreset,
    PtzStatus,
    RelativeMove,
    SetPreset,
    Stop,
)
from camgen.sim.simulation import CameraObservation, Observations, Simulation, stream_size_px

__all__ = [
    "AbsoluteMove",
    "CameraObservation",
    "CommandError",
    "ContinuousMove",
    "GotoPreset",
    "Observations",
    "PtzStatus",
    "RelativeMove",
    "SetPreset",
    "Simulation",
    "Stop",
    "stream_size_px",
]
