"""PTZ programs as controllers: each call says where the head should go now (`camgen.motion.ptz`).

A controller is called at every control step, in time order, with the head's pose (pan unwrapped on
an endless head) and returns a `Command`. Controllers keep the little state a camera's firmware
keeps (which tour stop, when it arrived, whether it follows a target); everything else is a pure
function of time, so a program replays identically.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from camgen.config.ptz_program import (
    FollowProgram,
    HoldProgram,
    KeyframeProgram,
    PresetProgram,
    PtzPreset,
    ScanProgram,
    TourProgram,
)
from camgen.motion.pose import R_HEAD_FROM_CV, R_mount_from_head
from camgen.motion.ptz import Command, Controller, HeadPose, bearing_deg, wrap_deg

ARRIVED_DEG = 1e-3
"""A move has arrived when pan and tilt are this close to the goal, degrees …"""
ARRIVED_LOG_ZOOM = 1e-4
"""… the zoom this close in ln(zoom) …"""
ARRIVED_DEG_S = 1e-2
"""… and the head this slow, deg/s (the discrete braking curve lands exactly, so these are tight)."""
CARROT_DEG = 170.0
"""A sweep longer than half a turn is driven by a goal this far ahead (short way = intended way)."""
ZOOM_DEADBAND = 1.25
"""Follow-target re-zooms when the wanted zoom differs from the current goal by more than this factor."""


@dataclass(frozen=True)
class Position:
    pan_deg: float
    tilt_deg: float
    zoom_x: float


def _arrived(pose: HeadPose, goal: Position) -> bool:
    return (
        abs(float(wrap_deg(goal.pan_deg - pose.pan_deg))) <= ARRIVED_DEG
        and abs(goal.tilt_deg - pose.tilt_deg) <= ARRIVED_DEG
        and abs(math.log(goal.zoom_x / pose.zoom_x)) <= ARRIVED_LOG_ZOOM
        and abs(pose.pan_deg_s) <= ARRIVED_DEG_S
        and abs(pose.tilt_deg_s) <= ARRIVED_DEG_S
    )


def _goto(goal: Position, mode: str, speed_deg_s: float | None = None) -> Command:
    return Command(
        goal.pan_deg,
        goal.tilt_deg,
        goal.zoom_x,
        pan_speed_cap_deg_s=speed_deg_s,
        tilt_speed_cap_deg_s=speed_deg_s,
        mode=mode,
    )


class Hold:
    def __init__(self, home: Position):
        self.home = home

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        return _goto(self.home, "hold" if _arrived(pose, self.home) else "move")


class GotoPreset:
    def __init__(self, home: Position, preset: Position, start_s: float):
        self.home, self.preset, self.start_s = home, preset, start_s

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        goal = self.preset if time_s >= self.start_s else self.home
        return _goto(goal, "hold" if _arrived(pose, goal) else "move")


class Tour:
    """Move to each stop, dwell `dwell_s` after arriving, go on (looping or staying at the last)."""

    def __init__(self, home: Position, stops: Sequence[tuple[Position, float]], loop: bool, start_s: float, speed):
        self.home, self.stops, self.loop, self.start_s, self.speed = home, list(stops), loop, start_s, speed
        self.index = 0
        self.arrived_s: float | None = None

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        if time_s < self.start_s:
            return _goto(self.home, "hold" if _arrived(pose, self.home) else "move")
        goal, dwell_s = self.stops[self.index]
        if self.arrived_s is None and _arrived(pose, goal):
            self.arrived_s = time_s
        if self.arrived_s is not None and time_s - self.arrived_s >= dwell_s:
            last = self.index == len(self.stops) - 1
            if not last or self.loop:
                self.index = (self.index + 1) % len(self.stops)
                self.arrived_s = None
                goal, dwell_s = self.stops[self.index]
        return _goto(goal, "move" if self.arrived_s is None else "dwell", self.speed)


class Scan:
    """Sweep pan between two angles at `speed_deg_s`, dwelling at the ends; endless rotation when the
    two angles coincide on an endless head. The sweep direction is kept by driving the head with a goal
    at most `CARROT_DEG` ahead on the unwrapped pan axis."""

    def __init__(self, home: Position, program: ScanProgram, endless: bool):
        self.home, self.program, self.endless = home, program, endless
        start, end = program.pan_range_deg
        if endless:
            span = float((end - start) % 360.0) or 360.0
        else:
            span = end - start
        self.span_deg = span
        self.phase = "approach"  # approach the start, then sweep out and back
        self.ends_unwrapped: list[float] = []
        self.index = 0
        self.arrived_s: float | None = None

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        p = self.program
        start = Position(p.pan_range_deg[0], p.tilt_deg, p.zoom_x)
        if time_s < p.start_s:
            return _goto(self.home, "hold" if _arrived(pose, self.home) else "move")
        if self.phase == "approach":
            if not _arrived(pose, start):
                return _goto(start, "move")
            if self.endless:
                first = pose.pan_deg + float(wrap_deg(start.pan_deg - pose.pan_deg))
                self.ends_unwrapped = [first, first + self.span_deg]
            else:  # a limited head sweeps between the angles as given, inside its range
                self.ends_unwrapped = [start.pan_deg, p.pan_range_deg[1]]
            self.phase, self.index, self.arrived_s = "sweep", 1, None
        if self.endless and self.span_deg == 360.0:
            return Command(
                pose.pan_deg + CARROT_DEG, p.tilt_deg, p.zoom_x, pan_speed_cap_deg_s=p.speed_deg_s, mode="scan"
            )
        target = self.ends_unwrapped[self.index % 2]
        remaining = target - pose.pan_deg
        if self.arrived_s is None and abs(remaining) <= ARRIVED_DEG and abs(pose.pan_deg_s) <= ARRIVED_DEG_S:
            self.arrived_s = time_s
        if self.arrived_s is not None and time_s - self.arrived_s >= p.dwell_s:
            self.index += 1
            self.arrived_s = None
            target = self.ends_unwrapped[self.index % 2]
            remaining = target - pose.pan_deg
        goal = pose.pan_deg + max(-CARROT_DEG, min(CARROT_DEG, remaining)) if self.endless else target
        return Command(
            goal,
            p.tilt_deg,
            p.zoom_x,
            pan_speed_cap_deg_s=p.speed_deg_s,
            mode="scan" if self.arrived_s is None else "dwell",
        )


class Keyframes:
    """Follow the piecewise-linear path through the keys (feed-forward of its rate)."""

    def __init__(self, program: KeyframeProgram, endless: bool = True):
        keys = program.keys
        self.times_s = np.array([k.time_s for k in keys])
        pans = [keys[0].pan_deg]
        for key in keys[1:]:  # the short way on an endless head; a limited one cannot cross its ends
            pans.append(pans[-1] + float(wrap_deg(key.pan_deg - pans[-1])) if endless else key.pan_deg)
        self.pan_deg = np.array(pans)
        self.tilt_deg = np.array([k.tilt_deg for k in keys])
        self.log_zoom = np.log([k.zoom_x for k in keys])

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        t = self.times_s
        pan, tilt, log_zoom = (float(np.interp(time_s, t, v)) for v in (self.pan_deg, self.tilt_deg, self.log_zoom))
        rates = (0.0, 0.0, 0.0)
        if len(t) > 1 and t[0] <= time_s < t[-1]:
            i = int(np.searchsorted(t, time_s, side="right")) - 1
            span = t[i + 1] - t[i]
            rates = tuple((v[i + 1] - v[i]) / span for v in (self.pan_deg, self.tilt_deg, self.log_zoom))
        return Command(pan, tilt, math.exp(log_zoom), *rates, mode="keyframes")


@dataclass(frozen=True)
class FollowView:
    """What follow-target needs to know about the camera: where it is and what it sees."""

    mount_position_m: tuple[float, float, float]
    R_world_from_mount: np.ndarray
    fx_wide_px: float
    """Focal length at zoom 1, px (x and y)."""
    fy_wide_px: float
    width_px: int
    height_px: int
    zoom_max_x: float
    fps: float


def _inside_polygon(point_xy: np.ndarray, polygon: Sequence[tuple[float, float]]) -> bool:
    """Even–odd rule."""
    x, y = float(point_xy[0]), float(point_xy[1])
    inside = False
    n = len(polygon)
    for i in range(n):
        (x1, y1), (x2, y2) = polygon[i], polygon[(i + 1) % n]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


class Follow:
    """Follow-target (see `camgen.config.ptz_program.FollowProgram` for the behaviour).

    Dead zone: the goal direction moves only when the predicted target leaves a window half the size
    of the dead zone around it, and then just enough to bring it back to the window's edge, with the
    target's angular rate fed forward. The other half of the dead zone absorbs the prediction error,
    the head's lag and acceleration, so the target's centre stays inside the dead zone.
    """

    def __init__(
        self,
        program: FollowProgram,
        view: FollowView,
        target_at: Callable[[float], np.ndarray],
        target_height_m: float,
        fallback: Callable[[float], Controller],
        in_view: Callable[[np.ndarray, HeadPose], bool] | None = None,
    ):
        self.program, self.view, self.target_at = program, view, target_at
        self.in_view = in_view or self._in_image
        self.target_height_m = target_height_m
        self.make_fallback = fallback
        self.fallback = fallback(0.0)
        self.following = False
        self.last_seen_s = 0.0
        self.goal = Position(0.0, 0.0, 1.0)

    def _in_image(self, point_m: np.ndarray, pose: HeadPose) -> bool:
        v = self.view
        R = v.R_world_from_mount @ R_mount_from_head(pose.pan_deg, pose.tilt_deg) @ R_HEAD_FROM_CV
        p = (point_m - np.asarray(v.mount_position_m)) @ R
        if p[2] <= 1e-6:
            return False
        u = p[0] / p[2] * v.fx_wide_px * pose.zoom_x
        w = p[1] / p[2] * v.fy_wide_px * pose.zoom_x
        return abs(u) <= v.width_px / 2 and abs(w) <= v.height_px / 2

    def _bearing(self, point_m: np.ndarray) -> tuple[float, float]:
        pan, tilt = bearing_deg(point_m, self.view.mount_position_m, self.view.R_world_from_mount)
        return float(pan), float(tilt)

    def __call__(self, time_s: float, pose: HeadPose) -> Command:
        p, v = self.program, self.view
        seen_s = max(time_s - p.reaction_lag_s, 0.0)
        observed = self.target_at(seen_s)
        in_region = p.acquire_region_m is None or _inside_polygon(observed[:2], p.acquire_region_m)
        visible = in_region and self.in_view(observed, pose)
        if not self.following:
            if not visible:
                return self.fallback(time_s, pose)
            self.following, self.last_seen_s = True, time_s
            self.sighting = (seen_s, observed, np.zeros(3))
            self.goal = Position(pose.pan_deg, pose.tilt_deg, pose.zoom_x)
        interval_s = 1.0 / v.fps
        if visible:
            self.last_seen_s = time_s
            velocity = (observed - self.target_at(max(seen_s - interval_s, 0.0))) / interval_s
            self.sighting = (seen_s, observed, velocity)
        elif not in_region or time_s - self.last_seen_s > p.lost_after_s:
            self.following = False
            self.fallback = self.make_fallback(time_s)  # hand back: the fallback starts again
            return self.fallback(time_s, pose)
        # Predict where the target is now from the last (late) sighting and its velocity: out of
        # view, the tracker coasts on what it last saw rather than on where the target really is.
        sighted_s, position, velocity = self.sighting
        predicted = position + velocity * (time_s - sighted_s)
        pan, tilt = self._bearing(predicted)
        pan_before, tilt_before = self._bearing(predicted - velocity * interval_s)
        pan_rate = float(wrap_deg(pan - pan_before)) / interval_s
        tilt_rate = (tilt - tilt_before) / interval_s
        # Dead zone as angles at the current zoom (pan angles shrink on the image by cos(tilt)).
        zoom = pose.zoom_x
        half_w = math.degrees(math.atan(p.dead_zone_frac * v.width_px / 2 / (v.fx_wide_px * zoom)))
        half_h = math.degrees(math.atan(p.dead_zone_frac * v.height_px / 2 / (v.fy_wide_px * zoom)))
        window_pan = 0.5 * half_w / max(math.cos(math.radians(tilt)), 0.05)
        window_tilt = 0.5 * half_h
        goal_pan, goal_tilt, goal_zoom = self.goal.pan_deg, self.goal.tilt_deg, self.goal.zoom_x
        error = float(wrap_deg(pan - goal_pan))
        feed_pan = 0.0
        if abs(error) > window_pan:
            goal_pan += error - math.copysign(window_pan, error)
            feed_pan = pan_rate
        error = tilt - goal_tilt
        feed_tilt = 0.0
        if abs(error) > window_tilt:
            goal_tilt += error - math.copysign(window_tilt, error)
            feed_tilt = tilt_rate
        goal_tilt = min(max(goal_tilt, -90.0), 90.0)
        if p.target_height_frac is not None:
            distance_m = float(np.linalg.norm(predicted - np.asarray(v.mount_position_m)))
            wanted = p.target_height_frac * v.height_px * distance_m / (self.target_height_m * v.fy_wide_px)
            wanted = min(max(wanted, 1.0), v.zoom_max_x)
            if abs(math.log(wanted / goal_zoom)) > math.log(ZOOM_DEADBAND):
                goal_zoom = wanted
        self.goal = Position(goal_pan, goal_tilt, goal_zoom)
        return Command(
            goal_pan,
            goal_tilt,
            goal_zoom,
            pan_deg_s=feed_pan,
            tilt_deg_s=feed_tilt,
            pan_speed_cap_deg_s=p.speed_deg_s,
            tilt_speed_cap_deg_s=p.speed_deg_s,
            mode="follow",
            target=p.target,
        )


def build_controller(
    program,
    home: Position,
    presets: Sequence[PtzPreset],
    *,
    endless_pan: bool,
    start_s: float = 0.0,
    follow: Callable[[FollowProgram, Callable[[float], Controller]], Controller] | None = None,
) -> Controller:
    """The controller of a program (None holds `home`). `start_s` shifts a program's clock (a
    fallback restarted at hand-back); `follow` builds follow-target controllers (it needs the scene)."""
    by_name = {p.name: Position(p.pan_deg, p.tilt_deg, p.zoom_x) for p in presets}
    if program is None or isinstance(program, HoldProgram):
        return Hold(home)
    if isinstance(program, PresetProgram):
        return GotoPreset(home, by_name[program.preset], start_s + program.start_s)
    if isinstance(program, TourProgram):
        stops = [(by_name[stop.preset], stop.dwell_s) for stop in program.stops]
        return Tour(home, stops, program.loop, start_s + program.start_s, program.speed_deg_s)
    if isinstance(program, ScanProgram):
        return Scan(home, program.model_copy(update={"start_s": start_s + program.start_s}), endless_pan)
    if isinstance(program, KeyframeProgram):
        keys = [k.model_copy(update={"time_s": k.time_s + start_s}) for k in program.keys]
        return Keyframes(program.model_copy(update={"keys": keys}), endless_pan)
    if isinstance(program, FollowProgram):
        if follow is None:
            raise ValueError("a follow program needs the scene (pass `follow`)")

        def fallback(at_s: float) -> Controller:
            return build_controller(program.fallback, home, presets, endless_pan=endless_pan, start_s=at_s)

        return follow(program, fallback)
    raise TypeError(f"unknown PTZ program {type(program).__name__}")
