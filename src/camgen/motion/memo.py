"""What a pure function of time gave at recent times, kept to be handed out again: a person's or a
vehicle's pose and lamps (`camgen.actors`, `camgen.vehicles`), a vehicle route's state and pose
(`camgen.motion.vehicle_route`).

The renderer places the actors at the same few tens of times several times over in a frame
(`camgen.render.sequence`: the frame time, the exposure's start, middle and end, each motion-blur
sub-frame once to bound what moves and once more to draw it), and a person's pose or a vehicle's
pose and lamps at a time are pure functions of that time; remembering them turns the repeats into
look-ups. The vertices are not kept (a frame's times would hold hundreds of MB of them): skinning
and moving them is redone from the kept pose.
"""

from __future__ import annotations

from typing import Generic, TypeVar

import numpy as np

POSE_MEMO_TIMES = 192
"""How many times' poses an actor keeps (a person's about 3.5 kB each, a vehicle's under 3 kB): more than the
distinct times one frame places the actors at, so that a frame's second pass over them finds them all. A frame
asks for its own time, the exposure's ends and each blur group's sub-frames, a multiple of s² up to
`camgen.plan.compile.MOTION_SAMPLES_MAX` (32) each: at most 3 + 4 + 8 + … + 32 = 147 times with 2 × 2
supersampling; the intersection's box camera asked for 82 at 720p."""

Value = TypeVar("Value")


class TimeMemo(Generic[Value]):
    """Values by exact time, s; the oldest forgotten beyond `limit` (first in, first out)."""

    def __init__(self, limit: int = POSE_MEMO_TIMES):
        if limit < 1:
            raise ValueError(f"a time memo keeps at least one time, got limit={limit}")
        self.limit = limit
        self._values: dict[float, Value] = {}

    def get(self, time_s: float) -> Value | None:
        return self._values.get(time_s)

    def put(self, time_s: float, value: Value) -> Value:
        """Keep `value` for `time_s` (forgetting the oldest time when full); `value`."""
        if time_s not in self._values and len(self._values) >= self.limit:
            del self._values[next(iter(self._values))]
        self._values[time_s] = value
        return value

    def __len__(self) -> int:
        return len(self._values)


def frozen(*values):
    """`values` with each array made read-only (numpy scalars are already), as a tuple, so that a kept value
    handed out again cannot be changed in place."""
    for value in values:
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    return values
