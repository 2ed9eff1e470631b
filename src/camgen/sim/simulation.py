"""The stepping API: a scene that a controller drives frame by frame, as it would drive real cameras.

``Simulation(scene).reset(seed)`` delivers every camera's first frame; ``step(commands)`` gives PTZ
commands (`camgen.sim.commands`, ONVIF semantics) and advances the world by one frame period,
delivering the next frame of every camera. A frame is what ``camgen render`` makes of it: the scene
is compiled once (`camgen.plan.compile`, each PTZ program replaced by holding the start, because the
controller drives the heads now) and each frame runs the same machinery as `camgen.plan.execute`:
`CameraRenderer.frame` → `CameraPipeline` (lens, sensor with auto-exposure, ISP) → `Annotator`. Only
the camera states differ: where a job has precomputed every frame's `CameraState`, the simulation
builds the next frame's from its commanded head (`camgen.sim.head`) through the same
`camgen.plan.camera_state.camera_state`.

Determinism: the world (actors) is a function of time, and each frame's noise comes from
`frame_rng(seed, camera, frame)`, so the same seed and the same commands give byte-identical frames;
with no commands the frames are those ``camgen render`` writes for the scene with its heads held.

A turning head blurs its frames as a programmed one does: each mechanical PTZ camera's job carries a
motion-blur stage whose per-frame camera motion the simulation fills in from the head's rates before
the frame is drawn (zero while the head rests, which draws one sub-frame, exactly as the plan).

Not yet modelled (issue 21): the render margin is the start zoom's, so a lens whose distortion grows
as it zooms may sample beyond it at other zooms.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.config.loader import LoadedScene, load_scene
from camgen.config.profile import Profile
from camgen.config.scene import Camera, Scene
from camgen.errors import ConfigError
from camgen.isp.eptz import crop_and_scale
from camgen.job import CameraJob, CameraState, Job, PlanSettings, Stage
from camgen.motion.ptz import control_steps_per_frame
from camgen.motion.trajectory import actor_routes
from camgen.optics.remap import LensMapCache
from camgen.plan.annotations import Annotator, FrameAnnotations
from camgen.plan.camera_pipeline import CameraPipeline, frame_rng
from camgen.plan.camera_state import camera_image_speed_px_s, camera_state, head_pose, lens_state
from camgen.plan.compile import MOTION_SAMPLE_STEP_PX, MOTION_SAMPLES_MAX, actor_swept_boxes, compile, focus_distance_m
from camgen.plan.ptz import eptz_limits, head_limits, installed_focal_length_mm
from camgen.plan.visibility import box_corners, local_bounds, placement, visible_depth_range_m
from camgen.props import prop_box_corners
from camgen.render.renderer import Passes, Renderer
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer
from camgen.sim.commands import COMMAND_TYPES, Command, CommandError, GotoPreset, PtzStatus, SetPreset
from camgen.sim.head import CommandedHead

NOISE_THREADS = 2
"""Threads for the sensor's row bands and the tone lookup (the machines here have 2 cores)."""


TURN_CANVAS_MIN_PX = 320 * 240
"""Readout pixels from which a camera draws a turning head's frames from its turn canvas by default (`Simulation`'s
``turns_reprojected`` None): below it a step costs its fixed costs (ptz_follow: ~47 s of CPU for 300 steps at both
96×54 and 160×90), so the canvas saves nothing and its resampling is all it brings."""


@dataclass(frozen=True)
class CameraObservation:
    """What one camera delivers at one frame."""

    name: str
    frame: int
    time_s: float
    """Scene time of the frame (the middle of its exposure), s."""
    rgb8: np.ndarray
    """(H, W, 3) uint8: the delivered frame (lens, sensor, ISP; a virtual PTZ's stream)."""
    state: CameraState
    """Pose, K_px, distortion, pan/tilt/zoom, exposure actually used."""
    status: PtzStatus | None
    """The head's GetStatus at the frame time; None for a fixed camera."""
    raw_dn: np.ndarray | None = None
    """(H, W) uint16 raw mosaic, when the simulation was asked for it (`raw=True`)."""
    ground_truth: FrameAnnotations | None = None
    """Boxes, track ids, visibility, keypoints (`camgen.plan.annotations`), with `ground_truth=True`."""


@dataclass(frozen=True)
class LoggedCommand:
    """One command the simulation accepted: given at the time of delivered frame `frame`."""

    frame: int
    time_s: float
    camera: str
    command: Command


@dataclass(frozen=True)
class Observations:
    """Every camera's frame at one frame time, and what the heads reported during the step."""

    frame: int
    time_s: float
    cameras: dict[str, CameraObservation]
    events: dict[str, list[str]] = field(default_factory=dict)
    """Per camera, what a controller must hear of: commands clamped to the head's range, moves stopped
    at a range end (empty lists are left out)."""

    def __getitem__(self, camera: str) -> CameraObservation:
        return self.cameras[camera]


def _held(camera: Camera) -> Camera:
    """The camera with its PTZ program removed: its head holds the start until commanded."""
    update = {}
    if camera.ptz is not None:
        update["ptz"] = camera.ptz.model_copy(update={"program": None})
    if camera.eptz is not None:
        update["eptz"] = camera.eptz.model_copy(update={"program": None})
    return camera.model_copy(update=update) if update else camera


def _binned(profile: Profile, resolution_px: tuple[int, int]) -> Profile:
    """The profile's sensor sampled at `resolution_px` over the same area (pixel pitch scaled, so the
    lens's field of view is kept), each pixel collecting the electrons one of the profile's own pixels
    collects (quantum efficiency divided by the area ratio): signal, noise and exposure per pixel stay
    the profile's, on a coarser grid."""
    sensor = profile.sensor
    width_px, height_px = resolution_px
    scale_x, scale_y = sensor.width_px / width_px, sensor.height_px / height_px
    qe = sensor.quantum_efficiency
    area_ratio = scale_x * scale_y
    update = {
        "width_px": width_px,
        "height_px": height_px,
        "pixel_pitch_um": sensor.pixel_pitch_um * scale_x,
        "pixel_pitch_y_um": sensor.pitch_y_um * scale_y,
        "principal_point_offset_px": (
            sensor.principal_point_offset_px[0] / scale_x,
            sensor.principal_point_offset_px[1] / scale_y,
        ),
        "quantum_efficiency": {"r": qe.r / area_ratio, "g": qe.g / area_ratio, "b": qe.b / area_ratio},
    }
    return Profile.model_validate({**profile.model_dump(), "sensor": {**sensor.model_dump(), **update}})


class Simulation:
    """A scene stepped frame by frame under PTZ commands (see the module docstring).

    Parameters
    ----------
    scene : path or LoadedScene
        The scene (YAML) or a scene loaded by `camgen.config.load_scene`.
    ground_truth : bool
        Annotate every frame (boxes, track ids, visibility, keypoints): one more draw per actor in view.
    raw : bool
        Also deliver the raw mosaic (uint16 DN) of each frame.
    resolution_px : (int, int) or None
        Read every camera out at (W, H) over the same sensor area (the field of view is kept), for
        speed: binned, so at most each sensor's own size (a `ConfigError` otherwise); None keeps the
        profiles' resolutions.
    renderer : Renderer or None
        An OpenGL renderer to draw with (shared with the caller); default: the simulation opens its
        own, closed by `close`.
    settings : PlanSettings or None
        The plan's thresholds, as `camgen render` takes them.
    cameras : names or None
        The cameras that deliver frames (default all); the others' heads still take commands.
    turns_reprojected : bool or None
        While a head turns, draw each frame from a turn canvas (a draw of a view wider than the frame, brought
        up to the frame time in crops: the edges the turn brings into view and whatever moved since, with its
        shadows) warped to the frame's view by a homography (`camgen.render.sequence`'s turned frames; a head
        turns about its centre of projection), resampled bicubically. A held head's frames are drawn exactly,
        as `camgen render` draws them (auto-exposure still remembers the turned frames). False: every turned
        frame is drawn whole (BENCHMARKS.md's sim section gives both steps' time and the frames' difference).
        None (the default): a camera read out at `TURN_CANVAS_MIN_PX` pixels or more uses the canvas, a smaller
        one draws whole, where a step's cost is its fixed costs, not its pixels, and a resampling would buy
        nothing (a CamShift tracker at 80×60 lost its window in 6 of 15 steps on the canvas's frames, 4 drawn whole).
    """

    def __init__(
        self,
        scene: str | Path | LoadedScene,
        *,
        ground_truth: bool = False,
        raw: bool = False,
        resolution_px: tuple[int, int] | None = None,
        renderer: Renderer | None = None,
        settings: PlanSettings | None = None,
        cameras: Iterable[str] | None = None,
        profile_dirs: Sequence[Path] = (),
        turns_reprojected: bool | None = None,
    ):
        loaded = scene if isinstance(scene, LoadedScene) else load_scene(scene, profile_dirs)
        self.loaded = loaded
        self.ground_truth, self.raw = ground_truth, raw
        self.turns_reprojected = turns_reprojected
        source = loaded.scene
        outputs = source.outputs.model_copy(
            update={
                "video": True,  # the ISP runs (nothing is written)
                "frames": None,
                "raw_dng": False,
                "depth": None,
                "radiance": None,
                "flow": None,
                "scene_flow": False,
                "annotations": ["mot"] if ground_truth else [],
                "mot_detections": False,
                "camera_metadata": False,
            }
        )
        held: Scene = source.model_copy(
            update={"cameras": [_held(camera) for camera in source.cameras], "outputs": outputs}
        )
        profiles = loaded.profile_models
        if resolution_px is not None:
            width_px, height_px = resolution_px
            if not (isinstance(width_px, int) and isinstance(height_px, int) and width_px >= 2 and height_px >= 2):
                raise ConfigError(f"resolution_px must be two whole numbers ≥ 2 (W, H), got {resolution_px!r}")
            for camera, profile in profiles.items():  # binning keeps each pixel's electrons: only coarser
                sensor = profile.sensor
                if width_px > sensor.width_px or height_px > sensor.height_px:
                    raise ConfigError(
                        f"{loaded.name}: resolution_px {width_px}×{height_px} is finer than the sensor of camera "
                        f"{camera!r} ({sensor.width_px}×{sensor.height_px} px, profile "
                        f"{loaded.profile_names[camera]!r}): the simulation reads a sensor out at its own size or "
                        f"binned to a coarser one; ask for at most {sensor.width_px}×{sensor.height_px}, or None "
                        "for each profile's own"
                    )
            profiles = {name: _binned(profile, (width_px, height_px)) for name, profile in profiles.items()}
        self.resolution_px = None if resolution_px is None else (int(resolution_px[0]), int(resolution_px[1]))
        """The readout size every camera was asked for, or None (the profiles' own)."""
        job = compile(
            held,
            profiles,
            scene_name=loaded.name,
            profile_names=loaded.profile_names,
            settings=settings,
            file_bounds=loaded.file_bounds,
        )
        # The plan saw held heads; a commanded head turns, so its frames integrate the turn (below).
        self._camera_blur_px: dict[int, tuple[list[float], float]] = {}
        """Per mechanical PTZ camera: its blur stage's per-frame camera motion (px) and the exposure it
        is measured over, s."""
        blurred = tuple(self._with_camera_blur(i, camera, held, job) for i, camera in enumerate(job.cameras))
        self.job: Job = job.model_copy(update={"cameras": blurred})
        self.scene = held
        self.fps = self.job.fps
        self.frame_count = self.job.frame_count
        self._own_renderer = renderer is None
        self.renderer = Renderer() if renderer is None else renderer
        self._executor = ThreadPoolExecutor(NOISE_THREADS)
        self._maps = LensMapCache()
        resolve = loaded.path.parent.joinpath
        self._cameras = {camera.name: i for i, camera in enumerate(self.job.cameras)}
        self._delivering = list(range(len(self.job.cameras))) if cameras is None else [self._index(c) for c in cameras]
        self._drawers = {
            i: CameraRenderer(
                self.renderer,
                build_scene_graph(self.job.scene, resolve),
                self.job.cameras[i],
                turns_reprojected=(
                    turns_reprojected
                    if turns_reprojected is not None
                    else self.job.cameras[i].width_px * self.job.cameras[i].height_px >= TURN_CANVAS_MIN_PX
                ),
            )
            for i in self._delivering
        }
        routes = actor_routes(held)
        self._depth_boxes = (
            [box_corners(*local_bounds(mesh, loaded.file_bounds), placement(mesh)) for mesh in held.environment.meshes]
            + prop_box_corners(held.environment, scene_seed=held.seed)
            + [
                box
                for actor in held.actors
                for box in actor_swept_boxes(actor, routes[actor.name], loaded.file_bounds, held.duration_s)
            ]
        )
        self.seed = self.job.seed
        self.frame = -1
        self._heads: list[CommandedHead | None] = []
        self._pipelines: dict[int, CameraPipeline] = {}
        self._annotators: dict[int, Annotator | None] = {}
        self._focus_dioptres: list[float] = []
        self.commands: list[LoggedCommand] = []
        """Every command accepted since `reset`, in the order given (`camgen.sim.log` saves and replays them)."""

    # --- lifecycle ---------------------------------------------------------------------------------

    def close(self) -> None:
        for drawer in self._drawers.values():
            drawer.close()
        self._executor.shutdown()
        if self._own_renderer:
            self.renderer.close()

    def __enter__(self) -> Simulation:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def camera_names(self) -> list[str]:
        return list(self._cameras)

    @property
    def time_s(self) -> float:
        """Scene time of the last delivered frame, s."""
        return self.frame / self.fps

    def camera_job(self, camera: str) -> CameraJob:
        return self.job.cameras[self._index(camera)]

    def stage_seconds(self, camera: str) -> list[dict[str, float]]:
        """Per delivered frame since `reset`, the wall time of each stage of `camera`'s frame, s
        (`render`, the lens, sensor and ISP stages of `camgen.plan.camera_pipeline`, `annotate`)."""
        index = self._index(camera)
        return list(self._pipelines[index].clock.frames) if index in self._pipelines else []

    def reset(self, seed: int | None = None) -> Observations:
        """Start over at time 0 (heads at their start, auto-exposure settled on the first view) and
        deliver frame 0. `seed`: the noise seed (default the scene's)."""
        if seed is not None and not (isinstance(seed, (int, np.integer)) and seed >= 0):
            raise ConfigError(f"seed must be a whole number ≥ 0, got {seed!r}")
        self.seed = self.job.seed if seed is None else int(seed)
        self.frame = 0
        self.commands = []
        self._heads = [self._head(camera) for camera in self.job.cameras]
        self._pipelines = {
            i: CameraPipeline(self.job, self.job.cameras[i], maps=self._maps, executor=self._executor)
            for i in self._delivering
        }
        self._annotators = {
            i: Annotator(self._drawers[i], self._pipelines[i].lens) if self.ground_truth else None
            for i in self._delivering
        }
        self._focus_dioptres = [1.0 / camera.states[0].focus_distance_m for camera in self.job.cameras]
        return self._observe({})

    def step(self, commands: Mapping[str, Command | Iterable[Command]] | None = None) -> Observations:
        """Give `commands` (camera name → a command or a sequence of them, in order) at the time of the
        last delivered frame, advance one frame period and deliver the next frame of every camera.

        Raises `CommandError` for an unknown camera, a PTZ command to a fixed camera, or a malformed
        command, before anything moves: the world is as it was, and a corrected step may follow."""
        if self.frame < 0:
            raise RuntimeError("call reset() before step()")
        if self.frame + 1 >= self.frame_count:
            raise RuntimeError(
                f"the scene ends after frame {self.frame_count - 1} ({self.scene.duration_s:g} s at {self.fps:g} fps); "
                "call reset() to start over, or lengthen the scene's duration_s"
            )
        accepted = self._check(commands or {})
        for index, command, where in accepted:
            self._heads[index].command(command, self.time_s, where)
            self.commands.append(LoggedCommand(self.frame, self.time_s, self.job.cameras[index].name, command))
        steps = control_steps_per_frame(1.0 / self.fps)
        dt = 1.0 / (self.fps * steps)
        events = {}
        for camera, head in zip(self.job.cameras, self._heads, strict=True):
            if head is not None:
                happened = head.advance(self.time_s, steps, dt)
                if happened:
                    events[camera.name] = happened
        self.frame += 1
        return self._observe(events)

    def status(self, camera: str) -> PtzStatus:
        """GetStatus of a PTZ camera's head now (the time of the last delivered frame)."""
        head = self._heads[self._index(camera)] if self._heads else None
        if head is None:
            self._ptz_index(camera, "GetStatus")  # names the problem
            raise RuntimeError("call reset() before status()")
        return head.status(self.time_s)

    # --- internals ---------------------------------------------------------------------------------

    def _index(self, camera: str) -> int:
        if camera not in self._cameras:
            raise CommandError(f"no camera {camera!r} in {self.loaded.path} (cameras: {', '.join(self._cameras)})")
        return self._cameras[camera]

    def _ptz_index(self, camera: str, what: str) -> int:
        index = self._index(camera)
        if self.scene.cameras[index].head is None:
            ptz = [c.name for c in self.scene.cameras if c.head is not None]
            raise CommandError(
                f"camera {camera!r} is a fixed camera (no ptz or eptz block in {self.loaded.path}); {what} needs a "
                f"PTZ camera ({', '.join(ptz) or 'the scene has none'})"
            )
        return index

    def _check(self, commands: Mapping) -> list[tuple[int, Command, str]]:
        if not isinstance(commands, Mapping):
            raise CommandError(f"commands must map camera names to commands, got {type(commands).__name__}")
        accepted = []
        stored: dict[int, set[str]] = {}
        for camera, given in commands.items():
            if not isinstance(camera, str):
                raise CommandError(f"commands must map camera names (str) to commands, got the key {camera!r}")
            if isinstance(given, COMMAND_TYPES):
                listed = [given]
            elif isinstance(given, Iterable) and not isinstance(given, (str, bytes, Mapping)):
                listed = list(given)
            else:
                raise CommandError(f"{camera}: expected a PTZ command or a list of them, got {given!r}")
            for k, command in enumerate(listed):
                where = f"{camera}: command {k} ({type(command).__name__})"
                if not isinstance(command, COMMAND_TYPES):
                    names = ", ".join(t.__name__ for t in COMMAND_TYPES)
                    raise CommandError(f"{where}: not a PTZ command; use one of camgen.sim's {names}")
                index = self._ptz_index(camera, type(command).__name__)
                command.check(where)
                if isinstance(command, SetPreset):
                    stored.setdefault(index, set()).add(command.name)
                head = self._heads[index]
                if isinstance(command, GotoPreset) and command.name not in {*head.presets, *stored.get(index, ())}:
                    names = ", ".join(sorted(head.presets)) or "none stored"
                    raise CommandError(
                        f"{where}: no preset {command.name!r} (presets: {names}); store it with SetPreset"
                    )
                accepted.append((index, command, where))
        return accepted

    def _with_camera_blur(self, index: int, camera_job: CameraJob, scene: Scene, job: Job) -> CameraJob:
        """A mechanical PTZ camera's job with a motion-blur stage whose per-frame camera motion the
        simulation fills in from the head's rates as it goes (zero until the head turns, which draws
        exactly what the plan draws: one sub-frame when nothing moves). A stage added here, where the plan
        found no motion to blur, blurs the head's turns only (``actors_blur`` False): a held head's frames are
        the plan's, whose actors move too little to blur, without testing each mover's path at every step."""
        camera = scene.cameras[index]
        if camera.ptz is None or camera.eptz is not None or "radiance" not in camera_job.render.passes:
            return camera_job
        stages = list(camera_job.stages)
        names = [stage.name for stage in stages]
        blur = [0.0] * job.frame_count
        if "optics.motion_blur" in names:
            planned = stages[names.index("optics.motion_blur")]
            stages[names.index("optics.motion_blur")] = Stage(
                name=planned.name, passes=planned.passes, params={**planned.params, "camera_motion_px": blur}
            )
        else:
            exposure = camera_job.profile.exposure
            longest_s = (
                exposure.exposure_time_s
                if exposure.mode == "manual"
                else min(exposure.exposure_time_max_s, 1.0 / job.fps)
            )
            params = {
                "displacement_max_px": 0.0,
                "actors_blur": False,
                "camera_motion_px": blur,
                "exposure_longest_s": longest_s,
                "sample_step_px": MOTION_SAMPLE_STEP_PX,
                "samples_max": MOTION_SAMPLES_MAX,
                "threshold_px": job.settings.blur_diameter_threshold_px,
            }
            stages.insert(
                names.index("render") + 1, Stage(name="optics.motion_blur", passes=("radiance",), params=params)
            )
        updated = camera_job.model_copy(update={"stages": tuple(stages)})
        params = next(stage for stage in updated.stages if stage.name == "optics.motion_blur").params
        self._camera_blur_px[index] = params["camera_motion_px"], params["exposure_longest_s"]
        return updated

    def _head(self, camera_job: CameraJob) -> CommandedHead | None:
        camera = self.scene.cameras[self._cameras[camera_job.name]]
        settings = camera.head
        if settings is None:
            return None
        profile = camera_job.profile
        limits = eptz_limits(camera, profile) if camera.eptz is not None else head_limits(camera, profile)
        latency_s = profile.ptz.command_latency_s if profile.ptz is not None else 0.0
        presets = {p.name: (p.pan_deg, p.tilt_deg, p.zoom_x) for p in settings.presets}
        return CommandedHead(limits, settings.pan_deg, settings.tilt_deg, settings.zoom_x, latency_s, presets)

    def _state(self, index: int) -> CameraState:
        """The camera's state at the current frame: the job's for a fixed camera, else built from the
        head's status through `camera_state` (the function the plan builds every state with)."""
        camera_job, head, frame = self.job.cameras[index], self._heads[index], self.frame
        planned = camera_job.states[frame]
        if head is None:
            return planned
        camera = self.scene.cameras[index]
        profile = camera_job.profile
        status = head.status(self.time_s)
        virtual = camera.eptz is not None
        focal_length_mm = (
            installed_focal_length_mm(camera, profile) if virtual else profile.lens.focal_length_min_mm * status.zoom_x
        )
        lens = lens_state(profile, focal_length_mm)
        pose = (
            head_pose(camera, 0.0, 0.0)
            if virtual
            else head_pose(camera, round(status.pan_deg, 9), round(status.tilt_deg, 9))
        )
        view = (status.pan_deg, status.tilt_deg, status.zoom_x)
        if view == (planned.pan_deg, planned.tilt_deg, planned.zoom_x):
            focus_m = planned.focus_distance_m  # the plan's own (with its autofocus lag)
        else:
            focus_m = self._focus_m(index, camera, profile, lens, pose)
        self._focus_dioptres[index] = 1.0 / focus_m
        exposure = profile.exposure
        distortion_applied = any(d.stage == "optics.distortion" and d.included for d in camera_job.decisions)
        eptz_sizes = None
        if virtual:
            eptz_sizes = ((camera_job.width_px, camera_job.height_px), tuple(camera_job.output_size_px))
        return camera_state(
            frame=frame,
            time_s=planned.time_s,
            pan_deg=status.pan_deg,
            tilt_deg=status.tilt_deg,
            zoom_x=status.zoom_x,
            lens=lens,
            T_world_from_cam_=pose,
            focus_distance_m=focus_m,
            exposure_time_s=exposure.exposure_time_s,
            gain_db=exposure.gain_db,
            apply_distortion=distortion_applied,
            eptz_sizes_px=eptz_sizes,
            pan_deg_s=status.pan_deg_s,
            tilt_deg_s=status.tilt_deg_s,
            log_zoom_per_s=status.log_zoom_per_s,
            ptz_mode="hold" if status.pan_tilt == "IDLE" and status.zoom == "IDLE" else "move",
        )

    def _focus_m(self, index: int, camera: Camera, profile: Profile, lens, pose: np.ndarray) -> float:
        """Where the lens focuses on a new view: as the plan focuses (balanced between the nearest and
        farthest visible surfaces), followed with the profile's autofocus lag (first order in dioptres)."""
        camera_job = self.job.cameras[index]
        left, top, right, bottom = camera_job.render.margin_px
        K_seen = lens.K.copy()
        K_seen[0, 2] += left
        K_seen[1, 2] += top
        depth_range = visible_depth_range_m(
            self._depth_boxes,
            pose,
            K_seen,
            camera_job.width_px + left + right,
            camera_job.height_px + top + bottom,
        )
        wanted_m, _ = focus_distance_m(camera, profile, lens.focal_length_mm, lens.f_number, depth_range)
        time_constant_s = profile.ptz.autofocus_time_s if profile.ptz is not None else 0.0
        automatic = camera.focus_distance_m is None and profile.lens.focus_distance_m is None
        if not automatic or time_constant_s <= 0:
            return wanted_m
        alpha = 1.0 - math.exp(-1.0 / (self.fps * time_constant_s))
        previous = self._focus_dioptres[index]
        return 1.0 / (previous + alpha * (1.0 / wanted_m - previous))

    def _observe(self, events: dict[str, list[str]]) -> Observations:
        cameras = {}
        for index in self._delivering:
            cameras[self.job.cameras[index].name] = self._deliver(index)
        return Observations(self.frame, self.frame / self.fps, cameras, events)

    def _deliver(self, index: int) -> CameraObservation:
        """One camera's frame, as `camgen.plan.execute` makes it."""
        camera_job, drawer, pipeline = self.job.cameras[index], self._drawers[index], self._pipelines[index]
        head = self._heads[index]
        planned = self._state(index)
        state = planned.model_copy(
            update={"exposure_time_s": pipeline.setting.exposure_time_s, "gain_db": pipeline.setting.gain_db}
        )
        if index in self._camera_blur_px:  # the head's turn during the longest exposure, as the plan measures it
            blur_px, longest_s = self._camera_blur_px[index]
            speed_px_s = camera_image_speed_px_s(
                state.pan_deg_s,
                state.tilt_deg_s,
                state.log_zoom_per_s,
                np.array(state.K_px),
                camera_job.width_px,
                camera_job.height_px,
            )
            blur_px[self.frame] = round(speed_px_s * longest_s, 3)
        clock = pipeline.clock
        metering = (
            self.frame == 0
            and camera_job.exposure_mode == "auto"
            and self.job.settings.auto_exposure_start == "converged"
        )
        with clock("render"):
            # A frame drawn to meter the view is drawn sharp: its exposure is the profile's guess.
            frame = drawer.frame(self.frame, state, sharp=metering)
        if metering:
            # Start as a camera that has watched this view for a while, not from the profile's guess.
            pipeline.converge_exposure(state, frame.passes)
            settled = planned.model_copy(
                update={"exposure_time_s": pipeline.setting.exposure_time_s, "gain_db": pipeline.setting.gain_db}
            )
            if drawer.redraws_settled(state, settled):
                with clock("render"):
                    frame = drawer.frame(self.frame, settled)  # the blur spans the settled exposure
            state = settled
        captured = pipeline.process(state, frame.passes, rng=frame_rng(self.seed, index, self.frame))
        rgb8 = captured.rgb8
        if state.window_px is not None:
            with clock("isp.eptz"):
                rgb8 = crop_and_scale(rgb8, state.window_px, camera_job.output_size_px)
        truth = None
        annotator = self._annotators[index]
        if annotator is not None:
            window = state.window_px

            def to_stream(image):
                return (
                    image if window is None else crop_and_scale(image, window, camera_job.output_size_px, nearest=True)
                )

            with clock("annotate"):
                lensed = pipeline.lens.apply(state, Passes(instance_id=frame.passes.instance_id))
                stream = Passes(instance_id=to_stream(lensed.instance_id))
                truth = annotator.annotate(state, stream, post=None if window is None else to_stream)
        clock.end_frame()
        return CameraObservation(
            name=camera_job.name,
            frame=self.frame,
            time_s=state.time_s,
            rgb8=rgb8,
            state=state,
            status=None if head is None else head.status(self.time_s),
            raw_dn=captured.raw_dn if self.raw else None,
            ground_truth=truth,
        )


def stream_size_px(camera_job: CameraJob) -> tuple[int, int]:
    """(W, H) of a camera's delivered frames."""
    return (
        tuple(camera_job.output_size_px)
        if camera_job.output_size_px is not None
        else (
            camera_job.width_px,
            camera_job.height_px,
        )
    )
