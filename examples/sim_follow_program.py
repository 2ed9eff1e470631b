"""The scene's own follow-target PTZ program driven through camgen's stepping API: the baseline that the
examples written against the documented API are compared with.

camgen's follow-target controller (`camgen.motion.programs.Follow`, the YAML ``program: {type: follow}``
that ``camgen render`` replays, with its dead zone, reaction lag, target velocity extrapolation, zoom to
`target_height_frac` and hand-back to its fallback) existed before the stepping API; here it steers the
head of a `camgen.sim.Simulation` instead of the plan's simulated head. Each frame it is given the head's
GetStatus (position and rates) and the frame time, and its goal goes to the head as ONVIF AbsoluteMove
(at its `speed_deg_s` as a fraction of the head's fastest, or the fastest). What it sees is what the
programmed run sees: the target's **ground-truth world position** (the actor's route, `reaction_lag_s`
late), a perfect tracker, not the frames. Two things differ from the programmed run: the program is asked
once a frame (the plan asks at every control step), and its goal's feed-forward rate has no ONVIF
AbsoluteMove field, so the head brakes onto each goal; and the head's command latency comes on top of the
reaction lag.

Unlike `sim_follow.py` and `sim_handoff.py` this imports camgen internals (`camgen.motion`, `camgen.plan`,
`camgen.config`): it is the existing controller, not a user's.

Usage::

    python examples/sim_follow_program.py [SCENE] [--camera NAME] [--target NAME] [--resolution WxH]
                                          [--steps N] [--log FILE]

prints the same scores as `sim_follow.py`; the camera's own follow program is used when it has one
(`scenes/ptz_follow.yaml`'s dome does), else a follow program of `--target` with the defaults.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from camgen.config.ptz_program import FollowProgram
from camgen.errors import ConfigError
from camgen.motion.pose import R_world_from_mount
from camgen.motion.programs import Follow, FollowView, Position, build_controller
from camgen.motion.ptz import HeadPose
from camgen.motion.trajectory import actor_routes
from camgen.plan.ptz import actor_centre, head_limits
from camgen.sim import AbsoluteMove, Observations, Simulation, command_log, save_command_log
from camgen.sim.metrics import control_metrics, target_boxes

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = REPO / "scenes" / "ptz_follow.yaml"


class ProgramFollower:
    """`camgen.motion.programs.Follow` on a simulation's PTZ camera: `command(observations)` gives the
    AbsoluteMove of its goal for the head's status at that frame."""

    def __init__(self, sim: Simulation, camera: str, target: str | None = None):
        loaded = sim.loaded
        cameras = {c.name: c for c in loaded.scene.cameras}
        if camera not in cameras or cameras[camera].ptz is None:
            ptz = [name for name, c in cameras.items() if c.ptz is not None]
            raise ConfigError(
                f"{loaded.path}: camera {camera!r} is not a mechanical PTZ camera of the scene "
                f"(its PTZ cameras: {', '.join(ptz) or 'none'})"
            )
        config, profile = cameras[camera], loaded.profile_models[camera]
        program = config.ptz.program
        if not isinstance(program, FollowProgram) or (target is not None and program.target != target):
            if target is None:
                raise ConfigError(f"{loaded.path}: camera {camera!r} has no follow program; name the actor to follow")
            program = FollowProgram(type="follow", target=target)
        actors = {actor.name: actor for actor in loaded.scene.actors}
        if program.target not in actors:
            raise ConfigError(
                f"{loaded.path}: no actor {program.target!r} to follow (actors: {', '.join(actors) or 'none'})"
            )
        self.camera, self.target, self.program = camera, program.target, program
        self.limits = head_limits(config, profile)
        K = profile.camera_matrix_px(profile.lens.focal_length_min_mm)  # zoom 1, as the plan's follow sees it
        mount = config.mount
        view = FollowView(
            mount_position_m=tuple(mount.position_m),
            R_world_from_mount=R_world_from_mount(mount.yaw_deg, mount.pitch_deg, mount.roll_deg),
            fx_wide_px=float(K[0, 0]),
            fy_wide_px=float(K[1, 1]),
            width_px=profile.sensor.width_px,
            height_px=profile.sensor.height_px,
            zoom_max_x=profile.lens.zoom_max_x,
            fps=loaded.scene.fps,
        )
        target_at, height_m = actor_centre(
            actors[self.target], actor_routes(loaded.scene)[self.target], loaded.file_bounds
        )
        ptz = config.ptz
        self.controller = build_controller(
            program,
            Position(ptz.pan_deg, ptz.tilt_deg, ptz.zoom_x),
            ptz.presets,
            endless_pan=self.limits.pan.endless,
            follow=lambda program, fallback: Follow(program, view, target_at, height_m, fallback),
        )

    def command(self, observations: Observations) -> AbsoluteMove:
        status = observations[self.camera].status
        pose = HeadPose(
            status.pan_deg, status.tilt_deg, status.zoom_x, status.pan_deg_s, status.tilt_deg_s, status.log_zoom_per_s
        )
        goal = self.controller(observations.time_s, pose)
        cap = goal.pan_speed_cap_deg_s
        speed = 1.0 if cap is None else min(max(cap / self.limits.pan.speed_max, 1e-3), 1.0)
        return AbsoluteMove(pan_deg=goal.pan_deg, tilt_deg=goal.tilt_deg, zoom_x=goal.zoom_x, speed=speed)


def follow(sim: Simulation, camera: str, target: str | None, steps: int) -> tuple[str, list[Observations]]:
    """Run one episode (seed 0) of at most `steps` steps; returns the target's name and every frame's
    observations."""
    follower = ProgramFollower(sim, camera, target)
    observed = [sim.reset(seed=0)]
    while observed[-1].frame < steps and observed[-1].frame + 1 < sim.frame_count:
        observed.append(sim.step({camera: follower.command(observed[-1])}))
    return follower.target, observed


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, nargs="?", default=DEFAULT_SCENE, metavar="SCENE")
    parser.add_argument("--camera", default="pole_ptz")
    parser.add_argument("--target", help="actor to follow (default: the camera's follow program's)")
    parser.add_argument("--resolution", default="160x90", metavar="WxH")
    parser.add_argument("--steps", type=int, default=299, metavar="N", help="steps (default 299: the scene's 12 s)")
    parser.add_argument("--log", type=Path, metavar="FILE", help="save the command log here")
    args = parser.parse_args(argv)
    width_px, height_px = (int(v) for v in args.resolution.lower().split("x"))
    try:
        with Simulation(args.scene, ground_truth=True, resolution_px=(width_px, height_px)) as sim:
            target, observed = follow(sim, args.camera, args.target, args.steps)
            if args.log is not None:
                save_command_log(command_log(sim), args.log)
            fps = sim.fps
    except ConfigError as exc:
        for problem in exc.problems:
            print(f"error: {problem}", file=sys.stderr)
        return 2
    boxes, heights_m = target_boxes(observed, args.camera, target)
    scores = control_metrics(boxes, (width_px, height_px), fps, heights_m)
    print(
        f"follow program: {target} in frame {scores.in_frame_frac:.1%} of {scores.frames} frames; centring error "
        f"{scores.centring_error_px:.2f} px = {scores.centring_error_frac:.3f} of the half-diagonal "
        f"({width_px}×{height_px}); height {scores.height_frac:.3f} of the frame, "
        f"{scores.resolution_px_per_m:.1f} px/m; {scores.losses} loss(es)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
