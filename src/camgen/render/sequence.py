"""Render the passes of one camera of a compiled Job, frame by frame, as its RenderSpec says.

- The pinhole render is larger than the output by the plan's margin (for distortion, CA and blur):
  the principal point moves by the left/top margin, so output pixel (u, v) is render pixel
  (u + left, v + top) and the output's own camera matrix still holds after cropping.
- Supersampling s > 1: radiance is drawn s× finer per axis and box-averaged, which integrates each
  pixel's area as a sensor pixel does. depth_m and instance_id stay point samples at pixel centres
  (exact values, no mixed ids), drawn together at 1× in one cheap geometry-only draw.
- Static background: the environment is drawn once per camera and kept on the GPU; each frame starts
  from a copy of it and draws only the actors, depth-tested against it.
- Motion blur (when planned): radiance integrates the exposure as the mean of sub-frames at evenly
  spread times, so each sub-frame only redraws the actors over the kept background. With
  supersampling s > 1, the sub-frames carry the spatial samples too (`jittered_samples`): each is
  drawn at 1× through one of the s×s sub-pixel positions, in turn, and their number is rounded up to
  a multiple of s², so a static pixel gets exactly the s×s box average at 1/s² of the cost per
  sub-frame (time and area sampled together, as a distribution ray tracer does).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from camgen.actors.character import CharacterRig
from camgen.config.placement import box_corners, local_bounds, placement
from camgen.config.scene import actor_shape
from camgen.errors import ConfigError
from camgen.job import CameraJob, CameraState, Job, RenderSpec
from camgen.motion.pose import R_HEAD_FROM_CV, R_mount_from_head
from camgen.optics.motion_blur import sub_frame_count, sub_frame_offsets
from camgen.render.renderer import Passes, Renderer, View, clip_planes_m
from camgen.render.scene_graph import SceneGraph, build_scene_graph


def render_view(state: CameraState, spec: RenderSpec) -> View:
    """The pinhole view of the margin-enlarged render for one camera state."""
    K = np.array(state.K_px, dtype=np.float64)
    left, top, _, _ = spec.margin_px
    K[0, 2] += left
    K[1, 2] += top
    return View(K, np.array(state.T_world_from_cam, dtype=np.float64), spec.width_px, spec.height_px)


def view_at(state: CameraState, spec: RenderSpec, offset_s: float) -> View:
    """The view `offset_s` after the frame time, with the head moving at the state's rates.

    The mount is recovered from the frame's pose (R_world_from_cam = R_mount·R_head(pan, tilt)·R_cv),
    pan and tilt advance linearly, and the zoom scales the focal lengths about the principal point.
    """
    still = state.pan_deg_s == 0.0 and state.tilt_deg_s == 0.0 and state.log_zoom_per_s == 0.0
    if offset_s == 0.0 or still or state.window_px is not None:  # a virtual PTZ moves no optics
        return render_view(state, spec)
    view = render_view(state, spec)
    T = view.T_world_from_cam.copy()
    R_mount = T[:3, :3] @ R_HEAD_FROM_CV.T @ R_mount_from_head(state.pan_deg, state.tilt_deg).T
    head = R_mount_from_head(state.pan_deg + state.pan_deg_s * offset_s, state.tilt_deg + state.tilt_deg_s * offset_s)
    T[:3, :3] = R_mount @ head @ R_HEAD_FROM_CV
    K = view.K_px.copy()
    scale = math.exp(state.log_zoom_per_s * offset_s)
    K[0, 0] *= scale
    K[1, 1] *= scale
    K[0, 1] *= scale
    return View(K, T, view.width_px, view.height_px)


def jittered_samples(samples: int, supersampling: int) -> list[tuple[float, float, float]]:
    """(time offset as a fraction of the exposure, dx px, dy px) of each sub-frame when `samples`
    time samples and `supersampling`² area samples per pixel are drawn together at 1×.

    The count is rounded up to a multiple of s²; sub-frame i takes sub-pixel position i mod s² (the
    s×s grid's centres, row by row), so every run of s² consecutive times covers the whole grid and
    each position is used equally often.
    """
    s = supersampling
    count = math.ceil(samples / s**2) * s**2
    times = sub_frame_offsets(count)
    return [(float(t), ((i % s) + 0.5) / s - 0.5, ((i // s) % s + 0.5) / s - 0.5) for i, t in enumerate(times)]


def shifted(view: View, dx_px: float, dy_px: float) -> View:
    """The view whose pixel (u, v) sees what `view` sees at (u + dx, v + dy)."""
    K = view.K_px.copy()
    K[0, 2] -= dx_px
    K[1, 2] -= dy_px
    return View(K, view.T_world_from_cam, view.width_px, view.height_px)


def box_downsample(image: np.ndarray, factor: int) -> np.ndarray:
    """Mean over factor×factor blocks, (H·f, W·f, …) → (H, W, …); float32 in, float32 out."""
    if factor == 1:
        return image
    h, w = image.shape[0] // factor, image.shape[1] // factor
    return cv2.resize(image, (w, h), interpolation=cv2.INTER_AREA)


@dataclass
class Frame:
    index: int
    time_s: float
    passes: Passes
    """At the render size (output plus margin)."""


class CameraRenderer:
    """Draws the planned passes of one camera; keeps its static background between frames."""

    def __init__(self, renderer: Renderer, graph: SceneGraph, camera: CameraJob):
        self.renderer, self.graph, self.camera = renderer, graph, camera
        self.spec = camera.render
        self._kept_views: dict[str, View] = {}
        self._reach_points_m, self._reach_radius_m = _reach(graph)
        motion = [stage.params for stage in camera.stages if stage.name == "optics.motion_blur"]
        self._motion = motion[0] if motion else None
        self._nir: SceneGraph | None = None
        """The NIR graph of a night-mode camera (`camgen.render.nir`), built at its first night frame."""
        spec = self.spec
        s = spec.supersampling if "radiance" in spec.passes else 1
        largest = max(spec.width_px, spec.height_px)
        if largest * s > renderer.max_size_px:
            raise ConfigError(
                f"camera {camera.name!r}: its {spec.width_px}×{spec.height_px} render at supersampling {s} needs "
                f"{largest * s} pixels per side, more than this OpenGL implementation's {renderer.max_size_px}; "
                f"use supersampling {max(1, renderer.max_size_px // largest)} or less"
            )

    def clip_range_m(self, view: View) -> tuple[float, float]:
        """Near and far planes that hold for the whole sequence (everything any actor reaches), so
        that the kept background and each frame's actors share one depth mapping."""
        distance = np.linalg.norm(self._reach_points_m - view.T_world_from_cam[:3, 3], axis=1) + self._reach_radius_m
        return clip_planes_m(float(distance.max()))

    def close(self) -> None:
        """Free the kept background draws."""
        for kept in self._kept_views:
            self.renderer.forget(kept)
        self._kept_views.clear()

    def _draw(self, view: View, passes: tuple[str, ...], key: str) -> Passes:
        graph, renderer = self.graph, self.renderer
        clip = self.clip_range_m(view)
        if not self.spec.static_background:
            return renderer.draw(graph, view, passes, clip_range_m=clip)
        kept = f"{self.camera.name}:{key}"
        if kept not in self._kept_views or not _same_view(self._kept_views[kept], view):
            renderer.draw(
                graph, view, passes, nodes=graph.environment_nodes, keep_as=kept, read=False, clip_range_m=clip
            )
            self._kept_views[kept] = view
        return renderer.draw(graph, view, passes, nodes=graph.actor_nodes, background=kept, clip_range_m=clip)

    def motion_samples(self, state: CameraState) -> int:
        """Sub-frames for this frame's exposure: the plan's largest motion scales with the exposure
        actually used (the longest possible one is what the plan measured)."""
        if self._motion is None:
            return 1
        p = self._motion
        camera_px = p["camera_motion_px"][state.frame] if "camera_motion_px" in p else 0.0
        displacement_px = (p["displacement_max_px"] + camera_px) * state.exposure_time_s / p["exposure_longest_s"]
        return sub_frame_count(
            displacement_px, step_px=p["sample_step_px"], samples_max=p["samples_max"], threshold_px=p["threshold_px"]
        )

    def frame(self, index: int, state: CameraState | None = None) -> Frame:
        """The planned passes of one frame. With motion blur planned, radiance is the mean of
        `samples` sub-frames spread evenly over the exposure, which is centred on the frame time;
        depth and ids are the scene at the frame time.

        `state`: the frame's camera state with the exposure actually used (auto-exposure decides it
        while rendering); default the plan's state of frame `index`."""
        state = self.camera.states[index] if state is None else state
        self.graph.set_daylight(state.time_s)
        spec = self.spec
        view = render_view(state, spec)
        passes = spec.passes
        s = spec.supersampling
        samples = self.motion_samples(state)
        if s == 1 and samples == 1:
            self.graph.place_actors(state.time_s)
            drawn = self._draw(view, passes, "shared")
            if "radiance" in passes and state.night_mode:
                drawn.radiance = drawn.radiance + self._nir_radiance(view, state)
            if "radiance" in passes and self.graph.rain_rate_mm_h is not None:
                drawn.radiance = self._rain(view, state, drawn.radiance, drawn.depth_m)
            return Frame(index, state.time_s, drawn)
        result = Passes()
        if "radiance" in passes:
            # (time offset, sub-pixel shift, draw factor, kept-background key) of each sub-frame.
            if s > 1 and samples > 1:  # the sub-frames carry the area samples too (module docstring)
                draws = [
                    (t, dx_px, dy_px, 1, f"radiance jitter {i % s**2}")
                    for i, (t, dx_px, dy_px) in enumerate(jittered_samples(samples, s))
                ]
            else:
                key = "radiance" if s == 1 else f"radiance {s}x"
                draws = [(float(t), 0.0, 0.0, s, key) for t in sub_frame_offsets(samples)]
            for offset, dx_px, dy_px, factor, key in draws:
                self.graph.place_actors(state.time_s + offset * state.exposure_time_s)
                # The head moves during the exposure too.
                sub_view = shifted(view_at(state, spec, offset * state.exposure_time_s), dx_px, dy_px)
                if factor > 1:
                    sub_view = sub_view.scaled(factor)
                radiance = box_downsample(self._draw(sub_view, ("radiance",), key).radiance, factor)
                result.radiance = radiance if result.radiance is None else result.radiance + radiance
            if len(draws) > 1:
                result.radiance /= len(draws)
        if "radiance" in passes and state.night_mode:
            result.radiance = result.radiance + self._nir_radiance(view, state)
        geometric = tuple(p for p in passes if p != "radiance")
        if geometric:
            self.graph.place_actors(state.time_s)
            coarse = self._draw(view, geometric, "geometric")
            result.depth_m, result.instance_id = coarse.depth_m, coarse.instance_id
        if "radiance" in passes and self.graph.rain_rate_mm_h is not None:
            result.radiance = self._rain(view, state, result.radiance, result.depth_m)
        return Frame(index, state.time_s, result)

    def _rain(self, view: View, state: CameraState, radiance: np.ndarray, depth_m: np.ndarray | None) -> np.ndarray:
        """The frame's radiance in the scene's rain (`camgen.render.rain`): streaks over the exposure the
        frame is taken with (`state.exposure_time_s`, what auto-exposure decided), depth-tested against the
        planned depth pass (the plan draws one for rain)."""
        from camgen.render.rain import rainy_radiance

        if depth_m is None:
            raise ValueError(f"camera {self.camera.name!r}: rain needs the depth pass, which the plan did not draw")
        return rainy_radiance(self.graph, view, radiance, depth_m, state.time_s, state.exposure_time_s)

    def _nir_radiance(self, view: View, state: CameraState) -> np.ndarray:
        """The IR illuminator's light returned by the scene at the frame time, in the visible pass's
        units (`camgen.render.nir`), drawn supersampled as the radiance is; (H, W, 3)."""
        from camgen.render.nir import aim_illuminator, build_nir_graph

        if self._nir is None:
            if self.graph.source is None:
                raise ValueError(
                    f"camera {self.camera.name!r} is in night mode, but its scene graph has no source scene"
                )
            scene, resolve_path = self.graph.source
            self._nir = build_nir_graph(scene, self.camera.profile, resolve_path)
            if self._nir is None:
                raise ValueError(f"camera {self.camera.name!r} is in night mode, but its profile has no IR illuminator")
        graph = self._nir
        graph.place_actors(state.time_s)
        aim_illuminator(graph, view.T_world_from_cam)
        s = self.spec.supersampling
        drawn = self.renderer.draw(
            graph, view.scaled(s) if s > 1 else view, ("radiance",), clip_range_m=self.clip_range_m(view)
        )
        return box_downsample(drawn.radiance, s)


def _reach(graph: SceneGraph) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 3) and radii (N,) such that all geometry, at any time, lies within a radius of a
    point: environment mesh corners (radius 0), and every point each actor's route visits with the
    actor's own extent (a route runs along straight segments, whose farthest point from a camera is
    an end; a resolved random walk covers the whole sequence)."""
    points, radii = [], []
    for node in graph.environment_nodes:
        points.append(box_corners(*node.mesh.bounds, graph.scene.get_pose(node)))
        radii.append(np.zeros(8))
    for index, (actor, route, node, local) in enumerate(
        zip(graph.actors, graph.actor_routes, graph.actor_nodes, graph.actor_local_poses, strict=True)
    ):
        rig = graph.rig(index)
        if isinstance(rig, CharacterRig):  # posed in the world: its reach over its clips bounds it
            radius = rig.envelope_radius_m()
        elif rig is not None:  # a person's or a vehicle's mesh is posed in the world: its envelope bounds it
            shape = actor_shape(actor)
            radius = float(np.max(np.linalg.norm(box_corners(*local_bounds(shape), placement(shape)), axis=1)))
        else:
            radius = float(np.max(np.linalg.norm(box_corners(*node.mesh.bounds, local), axis=1)))
        visited = route.points_m
        points.append(np.column_stack([visited, np.zeros(len(visited))]))
        radii.append(np.full(len(visited), radius))
    if not points:
        return np.zeros((1, 3)), np.zeros(1)
    return np.concatenate(points), np.concatenate(radii)


def _same_view(a: View, b: View) -> bool:
    return (
        (a.width_px, a.height_px) == (b.width_px, b.height_px)
        and np.array_equal(a.K_px, b.K_px)
        and np.array_equal(a.T_world_from_cam, b.T_world_from_cam)
    )


def render_camera(
    renderer: Renderer,
    job: Job,
    camera: CameraJob,
    *,
    frames: Iterable[int] | None = None,
    resolve_path: Callable[[str], Path] | None = None,
) -> Iterator[Frame]:
    """Yield the planned passes of `camera` for each frame index (default: every frame)."""
    graph = build_scene_graph(job.scene, resolve_path)
    camera_renderer = CameraRenderer(renderer, graph, camera)
    try:
        for index in range(job.frame_count) if frames is None else frames:
            yield camera_renderer.frame(index)
    finally:
        camera_renderer.close()


def crop_to_output(image: np.ndarray, spec: RenderSpec) -> np.ndarray:
    """The output frame of a margin-enlarged render (ideal pinhole: no lens stage has run)."""
    left, top, right, bottom = spec.margin_px
    return image[top : image.shape[0] - bottom, left : image.shape[1] - right]
