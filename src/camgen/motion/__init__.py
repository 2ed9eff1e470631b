"""Camera heads and actor trajectories: pure functions of time."""
