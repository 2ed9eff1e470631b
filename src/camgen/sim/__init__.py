"""camgen as a simulator that a controller drives: reset/step, PTZ commands with ONVIF semantics,
command logs and their replay (`camgen.sim.log`), the metrics papers report (`camgen.sim.metrics`),
a gymnasium environment (`camgen.sim.envs`) and a PettingZoo camera network (`camgen.sim.multi_env`),
the last two with the optional extra `sim`."""

from camgen.sim.commands import (
    AbsoluteMove,
    Clamp,
    CommandError,
    ContinuousMove,
    GotoPreset,
    PtzStatus,
    RelativeMove,
    SetPreset,
    Stop,
)
from camgen.sim.log import CommandLog, command_log, load_command_log, replay, save_command_log
from camgen.sim.simulation import CameraObservation, LoggedCommand, Observations, Simulation, stream_size_px

__all__ = [
    "AbsoluteMove",
    "CameraObservation",
    "Clamp",
    "CommandError",
    "CommandLog",
    "ContinuousMove",
    "GotoPreset",
    "LoggedCommand",
    "Observations",
    "PtzStatus",
    "RelativeMove",
    "SetPreset",
    "Simulation",
    "Stop",
    "command_log",
    "load_command_log",
    "replay",
    "save_command_log",
    "stream_size_px",
]
