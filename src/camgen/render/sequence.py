"""Render the passes of one camera of a compiled Job, frame by frame, as its RenderSpec says.

- The pinhole render is larger than the output by the plan's margin (for distortion, CA and blur):
  the principal point moves by the left/top margin, so output pixel (u, v) is render pixel
  (u + left, v + top) and the output's own camera matrix still holds after cropping.
- Supersampling s > 1: radiance integrates each pixel's area as a sensor pixel does, over s × s samples:
  one draw s× finer, box-averaged (`box_downsample`, each block summed in one fixed order), for a frame
  drawn without motion blur, whole or in crops of the whole (a still frame's base, below: each crop is the
  fine draw scissored to the rectangle grown to the fine draw's sky grid, so the same pixels bit for bit);
  where sub-frames are drawn for motion blur, the mean of draws at 1× each through one of the s × s
  sub-pixel positions (`jittered_samples`; textures at the s× draw's mip level), and a still frame's base
  is drawn so too around them, so that no seam shows at their rectangles' edges. One fine draw costs its
  fixed costs once: a 720p turning sim step 2.6 s with four 1× draws against 2.1 s with one 2× draw (load
  4), a held one 0.70 → 0.51 s (median of 8 steps, twice, quiet) once a still frame's base was drawn so
  too (it was four jittered 1× draws per rectangle). The two samplings agree to ~1e-3 of a pixel's value
  (the sky's grid and the texture level differ slightly). depth_m and instance_id stay
  point samples at pixel centres (exact values, no mixed ids), drawn together at 1× in one cheap
  geometry-only draw.
- Static background: the environment is drawn once per camera and kept on the GPU; each frame starts
  from a copy of it and draws only the actors (and the props swaying in the wind,
  `SceneGraph.moving_nodes`), depth-tested against it.
- Motion blur (when planned): radiance integrates the exposure as the mean of sub-frames at evenly
  spread times. With supersampling s > 1, the sub-frames carry the spatial samples too
  (`jittered_samples`): each is drawn at 1× through one of the s×s sub-pixel positions, in turn, and
  their number is rounded up to a multiple of s², so a static pixel gets exactly the s×s box average at
  1/s² of the cost per sub-frame (time and area sampled together, as a distribution ray tracer does).
  Through a moving head every sub-frame is drawn whole, their number from the plan's bound on the image
  motion, each smeared over its share of the exposure by the head's own turn where the count is capped
  (`_smeared`: no ghost copies on a fast pan); through a still one, only where something moves fast
  enough to blur (still frames, below).
- Moving regions (`CameraRenderer.moving_rects_px`): when the camera and the lights hold still, a pixel
  that no moving node (actor, swaying prop) and no shadow of one reaches is the same at every time. The
  rectangles bound each moving node's box over the times asked and its shadow volume down to the lowest
  surface; what lies outside them is drawn once, and the rest in crops of them (`Renderer.draw`'s
  `crop_px`: the whole view's draw scissored to them, so the same pixels bit for bit). All of a frame's
  draws fit their shadow maps alike (`ShadowFit`), so that a shadow map's texels move with neither the
  actors nor the crop. (First measured when the s² whole sub-frames were composited with the others in
  rectangles, load 3–5: the intersection's 4K box camera, 32 sub-frames, 146 → 78 s at frame 0; the
  parking lot's PTZ at its preset 16.9 → 8.3 s.)
- Still frames (`CameraRenderer._still_radiance`): through a head that holds still during the exposure,
  each moving node (actor, swaying prop) is blurred by what it needs: the longest image path, px, over
  the exposure (start, middle, end) of one of its vertices or of that vertex's shadow on the lowest
  surface sets its sub-frames (`sub_frame_count` with the plan's step and threshold), so a frame with
  nothing fast in view draws none, and a walker beside a
  racing car stays sharp (its image moves less than the threshold) while the car is drawn
  sub-frame by sub-frame in its own rectangles (`moving_rects_px` of that node alone, over its
  sub-frames and the frame time). Everything else is the base: the fine draw at the frame time. The base
  is kept for the next frame: under the same view and daylight (`_daylight_state`: lights, ambient,
  sky, sun), only the rectangles that bound each node that changed between the two frame times (at both,
  with its shadows) are drawn again, cropped from the whole draws, so a frame is bit for bit the frame
  drawn alone, whatever came before it (tests/render/test_still_frames.py). Where the plan keeps a
  static background (no shadows), a whole base is drawn over it. Measured end to end (`camgen render`'s
  path, auto-exposure, every output) on the parking lot's PTZ at 1080p, four consecutive frames, the
  2-core machine quiet: 3.47 s a frame before, 2.59 s after (the first frame 16.1 s, 6.3 s); the kept
  rectangles are 35 % of the frame, nearly all the six swaying trees and their shadows.
  What a still frame does besides drawing is kept small, deciding exactly as before: the actors are placed
  three times (the blur test's start and end, then the frame time that the rectangles and draws share); what
  changed since the kept frame is told from the looks kept with it (`_Looks`, shared while a node's
  `SceneGraph.look_versions` holds), not by placing the actors at its time again; the blur test skips a node
  whose look holds over the exposure (a parked car), and one whose image path `_path_bound_px` bounds under
  the threshold, and projects the others vertex by vertex; and the rectangles merge by their draws' pixels
  (`RECT_MERGE_SLACK_PX`) and start on the grid that lands on the fine draw's sky grid (`_fine_step_px`). A held
  720p sim step of ptz_follow, stepped in turn with the code before (30 steps each, load 8): 1.11 → 0.86 s
  (×0.78 step by step); the blur test 96 → 42 ms, the rectangles 48 → 2 ms, placing the actors 61 → 34 ms, the
  draws 864 → 734 ms; the same frames bit for bit.
  depth_m and instance_id are kept too (`CameraRenderer._geometry`): under the same view, only the rectangles
  that bound each moving node whose look changed since the kept frame (its box at both times; shadows play no
  part) are drawn again, each the whole geometry-only draw scissored to it, so the same point samples bit for bit
  (tests/render/test_still_frames.py). On the parking lot's PTZ at 1080p the whole draw's 60–82 ms of CPU a
  frame (llvmpipe's threads included, load 9–10) became 48 ms: five crops covering 15 % of the frame, whose cost
  is mostly the swaying crowns' leaves they reach, and the two copies a frame gets. Each lit draw, crop or whole,
  first draws its depth alone and then shades each pixel once (`camgen.render.renderer._PassRenderer._depth_prepass`):
  a crop over a swaying crown no longer shades the facade behind it and the leaves behind its leaves. The parking
  lot's PTZ at 1080p, `frame()` by CPU a frame (llvmpipe's threads included; A/B interleaved, 3 rounds of 5
  frames each): with the kept depth and ids alone 900, 910, 830 ms, with the pre-pass too 826, 870, 786 ms (load
  3.6–4.3); before both 900, 908, 858 ms, after both 850, 818, 798 ms (load 5–9). The blur test bends a swaying
  prop to the exposure's ends only where `_sway_bound_px` (its frame-time vertices and `PropSway.moved_bound_m`, a
  bound of the bend and the flutter between two times) leaves its path above the threshold: the parking lot's six
  trees in a 4 m/s wind are settled at 0.02–0.05 px and bent once a frame instead of three times, the same
  decisions; `frame()` 779 → 743 ms of CPU a frame (mean of the 4 frames after the first, 3 interleaved rounds,
  load 4.0–4.3). The three together against the code before them, 3 interleaved rounds (load 4.1–4.8): 898, 876,
  852 → 758, 808, 752 ms. What is left there is mostly shading the six crops at 2×: the largest (1089 × 921 fine
  pixels) is the three trees before the facade merged (each one's crown box and its shadow volume; the convex
  hulls cover 96 % of the rectangles, so masking to them would save little).
- Turned frames (`CameraRenderer(turns_reprojected=True)`; `camgen.sim` turns it on from 320×240): a head turns
  about its centre of projection, so what one view sees, another view sees at the pixel a homography takes it to
  (`_homography`: no parallax; the sky, shadows, fog and speculars alike, a surface's view direction unchanged).
  While the head turns (the view differs from the last frame's by a pan or tilt; not a zoom, which would
  magnify), each frame's base is its turn canvas (`_TurnCanvas`) warped to its view by bicubic resampling: a
  draw through one view (anchored where the head, turning on at its present rates, will look a little later,
  so that the frames sweep across its axis) grown by a quarter of the frame on each side, filled lazily. A
  frame first brings the canvas up to its time: each moving node that changed since, at both times, with its
  shadows (`_rects_of` through the canvas's view), where the canvas is filled; what the frame and the next
  `TURN_LOOKAHEAD_S` of the turn will read and the canvas lacks (the strips a turn brings into view, in crops a
  few frames wide); each crop drawn through a view of its own, s× finer, box-averaged, with the canvas's shadow
  fit, so the canvas is a whole draw of its view at the frame time where it is filled (tested to 3e-5). A new
  canvas is started when the frame leaves the canvas or its warp would stretch a pixel by more than
  `TURN_SCALE_TOLERANCE`, when the camera matrix changes, or when bringing it up to date would draw more than a
  frame; where the lights or the sky change from one frame to the next (a dusk lit frame by frame; a car's lamps
  are part of its look, not lights), turned frames are drawn whole. A crop whose draw s× finer would pass the
  renderer's largest target (the canvas is half as wide again as the frame) is drawn in tiles. The first frame
  of a held head (still during its exposure, even where it turned since the last frame) is drawn whole (and
  kept: still frames), so a held head's draws are the
  plan's bit for bit. A turned frame differs from the frame drawn whole by the
  resampling alone: ~40 dB PSNR on the sim's 720p step of ptz_follow (the tradeoff is in BENCHMARKS.md's sim
  section), where high-frequency texture aliases at another sampling phase; each turned frame depends on the
  canvas's history, so a run's frames are reproducible from its start (the same commands give the same bytes),
  not frame by frame as still frames are. Where the plan blurs the actors' own motion and the exposure needs
  more than one sub-frame, a turned frame is drawn whole as before.
"""

from __future__ import annotations

import itertools
import math
import sys
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
from camgen.render.renderer import (
    NEAR_CLIP_M,
    SKY_STEP_PX,
    Passes,
    Renderer,
    ShadowFit,
    View,
    clip_planes_m,
    shadow_map_size_texels,
    sun_cascade_matrices,
)
from camgen.render.scene_graph import SceneGraph, build_scene_graph
from camgen.world.rain import wet_ground_height_m


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


def aligned_rect_px(
    rect_px: tuple[int, int, int, int], width_px: int, height_px: int, step_px: int = SKY_STEP_PX
) -> tuple[int, int, int, int]:
    """`rect_px` grown so that a draw cropped to it evaluates the sky on the whole view's grid
    (`camgen.render.renderer.sky_view`: nodes every `SKY_STEP_PX` pixels from the draw's corner, plus its
    last pixel, interpolated between): its left and top on a multiple of `step_px` (`SKY_STEP_PX`; a
    rectangle whose crops are drawn s× finer needs `SKY_STEP_PX` / gcd(`SKY_STEP_PX`, s), `_fine_step_px`),
    its last column and row on one too or at the view's edge."""
    step = step_px

    def end(last: int, size: int) -> int:
        return min(size, -(-last // step) * step + 1)

    x0, y0, x1, y1 = rect_px
    return (x0 // step) * step, (y0 // step) * step, end(x1 - 1, width_px), end(y1 - 1, height_px)


def _fine_step_px(supersampling: int) -> int:
    """The grid, px, that a rectangle's left and top lie on when it is drawn as crops of a draw `supersampling`
    times finer (`CameraRenderer._fine_crops`): times the factor, they lie on that draw's sky grid."""
    return SKY_STEP_PX // math.gcd(SKY_STEP_PX, supersampling)


def merged_rects_px(rects: list[tuple[int, int, int, int]], slack_px: float) -> list[tuple[int, int, int, int]]:
    """Rectangles (x0, y0, x1, y1) merged pairwise while one rectangle around two costs no more than the two
    apart plus `slack_px` (a draw's fixed cost, in pixels). Rectangles left overlapping are both drawn
    (the same pixels twice: correct, at some cost)."""
    rects = list(rects)

    def area(r):
        return (r[2] - r[0]) * (r[3] - r[1])

    merging = True
    while merging:
        merging = False
        for i in range(len(rects)):
            for j in range(i + 1, len(rects)):
                a, b = rects[i], rects[j]
                both = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
                if area(both) <= area(a) + area(b) + slack_px:
                    rects[i] = both
                    del rects[j]
                    merging = True
                    break
            if merging:
                break
    return rects


MOVING_AREA_MAX_FRACTION = 0.85
"""Above this share of the frame inside the moving regions, every sub-frame is drawn whole: the crops
would save less than their fixed costs (a shadow-map pass each, the sky and far ground per draw)."""
RECT_MERGE_SLACK_PX = 80 * 80
"""Two moving regions are drawn as one when that adds no more than this many pixels of the draw (a crop of a
draw s× finer counts s² per pixel of the frame): a stand-in for a cropped draw's fixed cost (Python, the sky
and far-ground set-up, the vertices of what reaches the crop; its shadow maps are drawn once per frame).
Measured on llvmpipe (2 cores, load 8), 16², 128² and 256² crops of the 720p sim step's 2× draw (shadow maps
kept) on a car, a walker, bare ground and a facade: 5–11 ms, and 0.8–2.3 µs per pixel more, a fixed cost of
5–8 thousand pixels. 256² pixels of the frame (the figure chosen before) merged a walker and a passing car with
its cyclist, 300 pixels apart, into one rectangle 40 % larger than the two."""
RECT_PAD_PX = 2
"""Pixels added around a projected bound: half a pixel of sub-pixel jitter, half a pixel of rasterisation
to the nearest centre, and one spare."""
SHADOW_TEXEL_MARGIN = 3.0
"""Shadow-map texels a caster's box grows by before its shadow is projected: the shader's filtered lookup
(`texture2DShadowPCF` in `linear_mesh.frag`, 3 × 3 bilinear taps) reaches two texels past a caster's
rasterised texels, plus one spare."""


def box_downsample(image: np.ndarray, factor: int) -> np.ndarray:
    """Mean over factor×factor blocks, (H·f, W·f, …) → (H, W, …); float32 in, float32 out. Each block is summed in
    one fixed order (its rows, then its columns) whatever the image's size, so a crop's blocks come out bit for bit
    as the whole image's (`CameraRenderer._fine_crops`)."""
    if factor == 1:
        return image
    h, w = image.shape[0] // factor, image.shape[1] // factor
    total = None
    for dy, dx in itertools.product(range(factor), range(factor)):
        block = image[dy : h * factor : factor, dx : w * factor : factor]
        total = block.copy() if total is None else np.add(total, block, out=total)
    return total * np.float32(1.0 / factor**2)


@dataclass
class Frame:
    index: int
    time_s: float
    passes: Passes
    """At the render size (output plus margin)."""


class CameraRenderer:
    """Draws the planned passes of one camera; keeps its static background between frames."""

    def __init__(
        self,
        renderer: Renderer,
        graph: SceneGraph,
        camera: CameraJob,
        *,
        moving_regions: bool = True,
        turns_reprojected: bool = False,
    ):
        self.renderer, self.graph, self.camera = renderer, graph, camera
        self.spec = camera.render
        self.moving_regions = moving_regions
        """Draw still frames from the last one and motion sub-frames only where something moves (module
        docstring: still frames); False draws every frame, and each of its sub-frames, whole."""
        self.turns_reprojected = turns_reprojected
        """While the head turns, draw a frame as its turn canvas (brought up to the frame time in crops) warped to the
        frame's view (module docstring: turned frames); False draws every turned frame whole. Needs
        `moving_regions`."""
        self._last_view: View | None = None
        """The view of the last base drawn (`_base_radiance`): a turned frame is one whose view turned since."""
        self._lamp_owner = {
            id(lamp.node): id(graph.actor_nodes[lamp.actor_index]) for lamp in getattr(graph, "headlamps", [])
        }
        """id() of each headlamp's light node → id() of its vehicle's node, which casts no shadow in its light."""
        self._last_daylight: list[np.ndarray] | None = None
        """The daylight of the last base drawn (`_daylight_state`): a turned frame is drawn from a canvas only while
        it holds from frame to frame (a dusk lit frame by frame would start a canvas at every frame)."""
        self._canvas: _TurnCanvas | None = None
        """What a turning head's frames are warped from (`_turned_radiance`)."""
        self._kept_views: dict[str, View] = {}
        self._reach_points_m, self._reach_radius_m = _reach(graph)
        reach = self._reach_radius_m[:, None]
        self._caster_box_m = (
            (self._reach_points_m - reach).min(axis=0),
            (self._reach_points_m + reach).max(axis=0),
        )
        """A box holding every shadow caster at any time: the shadow maps span it (`ShadowFit`)."""
        environment_z = [
            box_corners(*n.mesh.bounds, graph.scene.get_pose(n))[:, 2].min() for n in graph.environment_nodes
        ]
        self._lowest_z_m = float(min([0.0, *environment_z]))
        """The lowest surface a shadow can fall on (the ground, or the lowest environment mesh), m."""
        motion = [stage.params for stage in camera.stages if stage.name == "optics.motion_blur"]
        self._motion = motion[0] if motion else None
        self._nir: SceneGraph | None = None
        """The NIR graph of a night-mode camera (`camgen.render.nir`), built at its first night frame."""
        self._wet_ground_m = wet_ground_height_m(graph.source[0].environment) if graph.source is not None else None
        """The height of a wet ground that mirrors the scene (`camgen.render.wet`), m; None when dry."""
        self._snow = graph.source[0].environment.snow if graph.source is not None else None
        """The scene's snow (`camgen.render.snow`); None without."""
        self._wet_view = None
        """The last view's `camgen.render.wet.view_geometry` (a held camera's frames share it)."""
        self._flat_node_ids: frozenset[int] | None = None
        """id() of the environment nodes lying flat on the wet ground, left out of its mirror (found once)."""
        self._kept_base: _KeptBase | None = None
        """The last still frame's radiance (`_base_radiance`)."""
        self._kept_geometry: _KeptGeometry | None = None
        """The last frame's depth_m and instance_id (`_geometry`)."""
        self._sun_texels_m: dict[int, tuple[tuple, float]] = {}
        """Per sun light node (by id), what its last `_sun_texel_m` depended on, and its value."""
        self._vertices_m: dict[int, tuple[int, np.ndarray]] = {}
        """Per moving node, its look version and its vertices then (`_world_vertices_m`)."""
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

    def shadow_fit(self, view: View) -> ShadowFit:
        """What every draw of a frame seen through `view` fits its shadow maps to."""
        return ShadowFit(view, *self._caster_box_m)

    def _draw(
        self,
        view: View,
        passes: tuple[str, ...],
        key: str,
        fit: ShadowFit | None = None,
        lod_bias: float = 0.0,
        maps_kept: bool = False,
        leave_out: frozenset[int] = frozenset(),
    ) -> Passes:
        """One draw of `view`, over the kept background `key` when the plan keeps one; `maps_kept`: the last
        draw's shadow maps stand (`Renderer.draw`'s `shadow_maps_kept`); `leave_out`: id() of nodes not drawn
        (the wet ground's mirror leaves out what lies flat on the ground)."""
        graph, renderer = self.graph, self.renderer
        fit = self.shadow_fit(view) if fit is None else fit
        # Every draw of this view shares the depth mapping, the shadow fit and the texture detail.
        shared = {"clip_range_m": self.clip_range_m(view), "shadow_fit": fit, "texture_lod_bias": lod_bias}
        if not self.spec.static_background:
            every = graph.environment_nodes + graph.actor_nodes
            nodes = [n for n in every if id(n) not in leave_out] if leave_out else None
            return renderer.draw(graph, view, passes, nodes=nodes, shadow_maps_kept=maps_kept, **shared)
        still = [n for n in graph.still_nodes if id(n) not in leave_out]
        moving = [n for n in graph.moving_nodes if id(n) not in leave_out]
        kept = f"{self.camera.name}:{key}"
        if kept not in self._kept_views or not _same_view(self._kept_views[kept], view):
            renderer.draw(graph, view, passes, nodes=still, keep_as=kept, read=False, **shared)
            self._kept_views[kept] = view
        return renderer.draw(graph, view, passes, nodes=moving, background=kept, **shared)

    def motion_samples(self, state: CameraState) -> int:
        """Sub-frames for this frame's exposure (the most that any part of it needs). Through a head that
        holds still under lights that hold, what the fastest moving node needs (`_blurred_groups`);
        otherwise the plan's largest motion, scaled with the exposure actually used (the longest possible
        one is what the plan measured)."""
        if self._motion is None:
            return 1
        groups = self._blurred_groups(state, render_view(state, self.spec))
        return self._plan_samples(state) if groups is None else max(groups, default=1)

    def redraws_settled(self, metered: CameraState, settled: CameraState) -> bool:
        """Whether a frame drawn sharp to meter the view (`frame(sharp=True)` at `metered`, the profile's
        guessed exposure) is drawn again at the exposure auto-exposure settled on: where that blurs, or where
        rain's or snow's streaks span another exposure."""
        changed = settled.exposure_time_s != metered.exposure_time_s
        falling = self.graph.rain_rate_mm_h is not None or self._snow is not None
        return self.motion_samples(settled) > 1 or (falling and changed)

    def _turn_from_base(self, state: CameraState, sharp: bool) -> bool:
        """Whether a frame through a head that moves during its exposure (`_blurred_groups` is None) is its base at
        the frame time (`_base_radiance`, reprojected from the kept one: `turns_reprojected`): drawn `sharp`, or
        with nothing that blurs (one sub-frame by the plan's bound, the head's turn included), or smeared by the
        head's turn alone (a motion-blur stage whose ``actors_blur`` is False: `camgen.sim`'s for a head's turns)."""
        if not (self.turns_reprojected and self.moving_regions):
            return False
        p = self._motion
        return sharp or p is None or not p.get("actors_blur", True) or self._plan_samples(state) == 1

    def _plan_samples(self, state: CameraState) -> int:
        """Sub-frames for this frame's exposure by the plan's bound on the image motion (`motion_samples`)."""
        p = self._motion
        if p is None:
            return 1
        camera_px = p["camera_motion_px"][state.frame] if "camera_motion_px" in p else 0.0
        displacement_px = (p["displacement_max_px"] + camera_px) * state.exposure_time_s / p["exposure_longest_s"]
        return sub_frame_count(
            displacement_px, step_px=p["sample_step_px"], samples_max=p["samples_max"], threshold_px=p["threshold_px"]
        )

    def frame(self, index: int, state: CameraState | None = None, *, sharp: bool = False) -> Frame:
        """The planned passes of one frame. With motion blur planned, radiance is the mean of
        `samples` sub-frames spread evenly over the exposure, which is centred on the frame time;
        depth and ids are the scene at the frame time.

        `state`: the frame's camera state with the exposure actually used (auto-exposure decides it
        while rendering); default the plan's state of frame `index`. `sharp`: no motion blur (a frame drawn
        only to meter the view, whose exposure is not yet the camera's)."""
        state = self.camera.states[index] if state is None else state
        self.graph.set_daylight(state.time_s)
        spec = self.spec
        view = render_view(state, spec)
        passes = spec.passes
        s = spec.supersampling
        groups = self._blurred_groups(state, view, blur=not sharp) if "radiance" in passes else None
        if groups is not None and self.moving_regions:
            radiance = self._still_radiance(state, view, groups)
            if radiance is not None:
                return self._finished(index, state, view, radiance)
        elif groups is None and "radiance" in passes and self._turn_from_base(state, sharp):
            # The exposure is the frame time's base, smeared by the head's turn where the actors are not blurred.
            base = self._base_radiance(state, view, self.shadow_fit(view), fine=True, turning=True)
            p = self._motion
            smear = not sharp and p is not None and not p.get("actors_blur", True)
            radiance = self._smeared(state, base, 0.0, 1.0, 0.0, 0.0, whole=True) if smear else base
            return self._finished(index, state, view, base.copy() if radiance is base else radiance)
        samples = 1 if sharp else self._plan_samples(state) if groups is None else max(groups, default=1)
        if s == 1 and samples == 1:
            self.graph.place_actors(state.time_s)
            drawn = self._draw(view, passes, "shared")
            return self._finished(index, state, view, drawn.radiance, geometry=drawn)
        result = Passes()
        if "radiance" in passes:
            # (time offset, sub-pixel shift, draw factor, kept-background key) of each sub-frame.
            if s > 1 and samples > 1:  # the sub-frames carry the area samples too (module docstring)
                draws = [
                    (t, dx_px, dy_px, 1, f"radiance jitter {i % s**2}")
                    for i, (t, dx_px, dy_px) in enumerate(jittered_samples(samples, s))
                ]
            else:  # one draw s× finer, box-averaged: the same samples at a quarter of the draws' fixed costs
                draws = [(float(t), 0.0, 0.0, s, _fine_key(s)) for t in sub_frame_offsets(samples)]
            result.radiance = self._sub_frame_mean(state, view, draws, self.shadow_fit(view))
        return self._finished(index, state, view, result.radiance)

    def _finished(
        self, index: int, state: CameraState, view: View, radiance: np.ndarray | None, geometry: Passes | None = None
    ) -> Frame:
        """The frame from its drawn daylight radiance (None without a radiance pass): the IR illuminator's
        light added in night mode, the geometric passes drawn at the frame time (or taken from `geometry`,
        drawn with the radiance), and the rain or snow."""
        passes, result = self.spec.passes, Passes()
        result.radiance = radiance
        if "radiance" in passes and state.night_mode:
            result.radiance = result.radiance + self._nir_radiance(view, state)
        geometric = tuple(p for p in passes if p != "radiance")
        if geometry is not None:
            result.depth_m, result.instance_id = geometry.depth_m, geometry.instance_id
        elif geometric:
            self.graph.place_actors(state.time_s)
            coarse = self._geometry(view, geometric)
            result.depth_m, result.instance_id = coarse.depth_m, coarse.instance_id
        if "radiance" in passes and self._wet_ground_m is not None:
            result.radiance = self._wet(view, state, result.radiance, result.depth_m)
        if "radiance" in passes and self.graph.rain_rate_mm_h is not None:
            result.radiance = self._rain(view, state, result.radiance, result.depth_m)
        if "radiance" in passes and self._snow is not None:
            from camgen.render.snow import snowy_radiance

            result.radiance = snowy_radiance(
                self.graph, view, result.radiance, result.depth_m, state, self.camera.profile
            )
        return Frame(index, state.time_s, result)

    def _geometry(self, view: View, passes: tuple[str, ...]) -> Passes:
        """depth_m and instance_id (those of `passes`) of `view` with the actors placed as they are now: the kept
        ones of the last frame (`_KeptGeometry`) where the view is the same, with the rectangles that bound each
        moving node whose look changed since (its box then and now, `_geometry_rects`) drawn again, each the whole
        draw scissored to it (`Renderer.draw`'s `crop_px`: point samples at pixel centres, the same values bit for
        bit); else one whole draw, kept. Without `moving_regions`, or over a kept static background, drawn whole."""
        if not self.moving_regions or self.spec.static_background:
            return self._draw(view, passes, "geometric")
        graph, kept, base = self.graph, self._kept_geometry, self._kept_base
        # Shared with the radiance's base where a node's look is the one it drew (its version the same).
        looks = _Looks.now(graph, base.looks if base is not None else (None if kept is None else kept.looks))
        rects = None
        if kept is not None and kept.passes == passes and _same_view(kept.view, view):
            rects = self._geometry_rects(view, kept.looks, looks)
        if rects is None:
            drawn = self._draw(view, passes, "geometric")
            depth_m, ids = (None if a is None else a.copy() for a in (drawn.depth_m, drawn.instance_id))
            self._kept_geometry = _KeptGeometry(view, passes, depth_m, ids, looks)
            return drawn
        clip = self.clip_range_m(view)
        for x0, y0, x1, y1 in rects:
            part = self.renderer.draw(graph, view, passes, clip_range_m=clip, crop_px=(x0, y0, x1, y1))
            if part.depth_m is not None:
                kept.depth_m[y0:y1, x0:x1] = part.depth_m
            if part.instance_id is not None:
                kept.instance_id[y0:y1, x0:x1] = part.instance_id
        kept.looks = looks
        # The kept arrays stay this renderer's: the frame gets copies, which its consumers may change.
        return Passes(
            depth_m=None if kept.depth_m is None else kept.depth_m.copy(),
            instance_id=None if kept.instance_id is None else kept.instance_id.copy(),
        )

    def _geometry_rects(self, view: View, before: _Looks, now: _Looks) -> list[tuple[int, int, int, int]] | None:
        """The rectangles of `view` outside which no pixel's depth or id differs between the moving nodes' looks
        `before` and `now`: each changed node's box at both (`_projected_rect_px`, padded by `RECT_PAD_PX`), merged
        as the radiance's rectangles are (`merged_rects_px`); None where they would cover most of the frame."""
        rects = []
        for k in range(len(now.versions)):
            if now.differ(before, k):
                rect = _projected_rect_px(np.concatenate([before.boxes[k], now.boxes[k]]), view, NEAR_CLIP_M)
                if rect is not None:
                    rects.append(rect)
        rects = merged_rects_px(rects, RECT_MERGE_SLACK_PX)
        if (
            sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rects)
            > MOVING_AREA_MAX_FRACTION * view.width_px * view.height_px
        ):
            return None
        return rects

    def _still_radiance(self, state: CameraState, view: View, groups: dict[int, set[int]]) -> np.ndarray | None:
        """The frame's radiance through a camera that holds still during the exposure under lights that do
        not change in it (module docstring: "Still frames"), where `groups` (`_blurred_groups`) need motion
        blur; None when their moving regions cannot be bounded or cover most of the frame (then the caller
        draws every sub-frame whole)."""
        s = self.spec.supersampling
        fit = self.shadow_fit(view)
        blurred = {}
        for samples, nodes in sorted(groups.items()):
            # The frame time too: outside the rectangles the frame is the base drawn then.
            offsets = [0.0] + [t for t, _, _ in jittered_samples(samples, s)]
            rects = self.moving_rects_px(state, view, offsets, fit, only=nodes)
            if rects is None:
                return None
            blurred[samples] = rects
        area = sum((x1 - x0) * (y1 - y0) for rects in blurred.values() for x0, y0, x1, y1 in rects)
        if area > MOVING_AREA_MAX_FRACTION * view.width_px * view.height_px:
            return None
        # A frame with blurred movers samples its base as their sub-frames sample the still world around them
        # (jittered 1× draws), so that no seam shows at their rectangles' edges; one without, by the fine draw.
        radiance = self._base_radiance(state, view, fit, fine=not blurred).copy()
        for samples, rects in blurred.items():  # fewest samples first: where two overlap, the most win
            draws = jittered_samples(samples, s)
            parts = self._mean_of_draws(state, view, fit, draws, rects)
            for (x0, y0, x1, y1), part in zip(rects, parts, strict=True):
                radiance[y0:y1, x0:x1] = part
        return radiance

    def _blurred_groups(self, state: CameraState, view: View, blur: bool = True) -> dict[int, set[int]] | None:
        """The moving nodes (indices into `SceneGraph.moving_nodes`) whose image moves by more than the
        plan's threshold during the exposure, grouped by the sub-frames each needs (`sub_frame_count` of
        the longest image path, px, over the exposure's start, middle and end, of one of its vertices or of
        where that vertex's shadow falls on the lowest surface in the light of a sun or spot light: a shadow
        can sweep the view faster than its caster, or while the caster is out of view); {} when the plan has
        no motion blur or `blur` is False; None when the head moves or a light changes during the exposure.

        The same decision at a fraction of the cost: the actors are placed at the start and the end first and
        at the frame time last (where the frame's draws want them), the swaying props bent to the frame time only
        and to the ends only where `_sway_bound_px` does not settle them; a node whose look holds over the three
        (`SceneGraph.look_versions`: a parked car) moves by 0 px; a node whose paths `_path_bound_px` bounds
        under the threshold is not projected; the others are, vertex by vertex. A stage whose ``actors_blur`` is
        False (`camgen.sim` adds one for a head's turns to a plan that blurs nothing) blurs no node: {}."""
        p, graph, spec = self._motion, self.graph, self.spec
        exposure_s = state.exposure_time_s
        ends = (-0.5, 0.0, 0.5)
        if any(not _same_view(view_at(state, spec, offset * exposure_s), view) for offset in ends):
            return None
        if p is None or not blur or not p.get("actors_blur", True):
            return {}
        scene, moving = graph.scene, graph.moving_nodes
        casting = _shadow_lights(scene) if graph.shadows else []
        first_prop = len(graph.actor_nodes)  # the swaying props follow the actors in `moving`
        placed = {}
        for offset in (-0.5, 0.5, 0.0):
            # The swaying props are bent at the exposure's ends only where `_sway_bound_px` does not settle them.
            graph.place_actors(state.time_s + offset * exposure_s, props=offset == 0.0)
            placed[offset] = (
                _light_state(scene),
                [scene.get_pose(light).copy() for light in casting],
                list(graph.look_versions),
                [
                    self._world_vertices_m(k, node) if offset == 0.0 or k < first_prop else None
                    for k, node in enumerate(moving)
                ],
            )
        lights, light_poses, versions, vertices = zip(*(placed[offset] for offset in ends), strict=True)
        if not _same_arrays(lights[0], lights[-1]):
            return None
        lights_held = _same_arrays(lights[0], lights[1])
        step_px, most, threshold = p["sample_step_px"], p["samples_max"], p["threshold_px"]

        def samples_of(path_px: float) -> int:
            return sub_frame_count(path_px, step_px=step_px, samples_max=most, threshold_px=threshold)

        groups: dict[int, set[int]] = {}
        for k in range(len(moving)):
            node_vertices = [vertices[i][k] for i in range(3)]
            lit = self._shadowing(moving[k], casting)
            lights_k = [casting[i] for i in lit]
            poses_k = [[poses[i] for i in lit] for poses in light_poses]
            if k >= first_prop:
                if lights_held and threshold >= 0.0:
                    bound_px = self._sway_bound_px(k, node_vertices[1], view, lights_k, poses_k[1], state, exposure_s)
                    if bound_px <= threshold:
                        continue
                node_vertices = self._bent_vertices_m(k, [state.time_s + offset * exposure_s for offset in ends])
            if lights_held and threshold >= 0.0:  # a path at or under the threshold needs 1 sub-frame
                if k < first_prop and versions[0][k] == versions[1][k] == versions[2][k]:
                    continue  # the same points at the three times: every path is 0 px
                if _path_bound_px(node_vertices, view, lights_k, poses_k[0], self._lowest_z_m) <= threshold:
                    continue
            (uv0, front0), (uv1, front1), (uv2, front2) = (
                _node_pixels(node_vertices[i], view, lights_k, poses_k[i], self._lowest_z_m) for i in range(3)
            )
            seen = front0 & front1 & front2 & _near_view(uv1, view)
            if not seen.any():
                continue
            path_px = np.hypot(*(uv1 - uv0)[:, seen]) + np.hypot(*(uv2 - uv1)[:, seen])
            samples = samples_of(float(path_px.max()))
            if samples > 1:
                groups.setdefault(samples, set()).add(k)
        return groups

    def _sway_bound_px(
        self,
        k: int,
        middle_m: np.ndarray,
        view: View,
        casting: list,
        light_poses: list[np.ndarray],
        state: CameraState,
        exposure_s: float,
    ) -> float:
        """An upper bound, px, of `_path_bound_px` for swaying prop `k` of `SceneGraph.moving_nodes` over the
        exposure, from its vertices at the frame time, `middle_m` (N, 3, world), alone: each end's vertices lie
        within `PropSway.moved_bound_m` of them, plus the rounding of the float32 positions the prop's primitive
        holds (an ulp of the largest coordinate at each end), times the pose's largest stretch; so the least depth
        at an end is at least the middle's less that, and a sun's shadow (`_path_bound_px`: P + ((P_z −
        z_low)/(−d_z))·d) moves by at most (1 + 1/|d_z|) times it, its depth by at most (1 + |d·axis|/|d_z|) times
        it. Where this is at or under the threshold, so is `_path_bound_px` of the vertices at the ends, and the
        blur test need not bend the prop to them (the same decision); inf where `_path_bound_px` is (a spot light
        casts)."""
        if any(type(light.light).__name__ != "DirectionalLight" for light in casting):
            return math.inf
        if len(middle_m) == 0:
            return 0.0
        graph = self.graph
        prop = graph.swaying[k - len(graph.actor_nodes)]
        T = view.T_world_from_cam
        gain = _path_gain_px(view)
        axis_m, origin_m = T[:3, 2], T[:3, 3]
        stretch = float(np.linalg.norm(graph.scene.get_pose(prop.node)[:3, :3], 2))
        height_frac_max = max(0.0, float(prop.rest_vertices_m[:, 2].max()) / prop.sway.height_m)
        rounding_m = 2.0**-22 * (float(np.abs(prop.rest_vertices_m).max()) + prop.sway.reach_m())
        depth_m = (middle_m - origin_m) @ axis_m
        suns = [-pose[:3, 2] for pose in light_poses if -pose[2, 2] < -1e-6]
        kinds = [0.0] * (1 + len(suns))
        for offset in (-0.5, 0.5):
            moved_m = stretch * (
                prop.sway.moved_bound_m(state.time_s + offset * exposure_s, state.time_s, height_frac_max) + rounding_m
            )
            kinds[0] += moved_m / max(NEAR_CLIP_M, float(depth_m.min()) - moved_m)
            for j, d in enumerate(suns, start=1):
                shadow_depth_m = depth_m + (middle_m[:, 2] - self._lowest_z_m) / -d[2] * float(d @ axis_m)
                shadow_moved_m = moved_m * (1.0 + 1.0 / abs(d[2]))
                nearest_m = float(shadow_depth_m.min()) - moved_m * (1.0 + abs(float(d @ axis_m)) / abs(d[2]))
                kinds[j] += shadow_moved_m / max(NEAR_CLIP_M, nearest_m)
        bound = gain * max(kinds)
        return bound * (1.0 + PATH_BOUND_MARGIN) + PATH_BOUND_MARGIN if math.isfinite(bound) else math.inf

    def _bent_vertices_m(self, k: int, times_s: list[float]) -> list[np.ndarray]:
        """The world vertices of swaying prop `k` of `SceneGraph.moving_nodes` bent to each of `times_s` (the
        exposure's start, middle and end), left bent to the middle (the frame time, where the draws want it)."""
        graph = self.graph
        index, node = k - len(graph.actor_nodes), graph.moving_nodes[k]
        bent = {}
        for time_s in (times_s[0], times_s[2], times_s[1]):
            graph.bend_prop(index, time_s)
            bent[time_s] = self._world_vertices_m(k, node)
        return [bent[time_s] for time_s in times_s]

    def _shadowing(self, node, casting: list) -> list[int]:
        """Indices into `casting` of the lights in which `node` can cast a shadow: all but its own headlamps' (they
        shine ahead of the vehicle, from it)."""
        return [i for i, light in enumerate(casting) if self._lamp_owner.get(id(light)) != id(node)]

    def _world_vertices_m(self, k: int, node) -> np.ndarray:
        """(N, 3) world positions of the vertices of moving node `k` (`node`) as placed now, every primitive's in
        turn; kept while its look holds (`SceneGraph.look_versions`)."""
        version = self.graph.look_versions[k]
        kept = self._vertices_m.get(k)
        if kept is not None and kept[0] == version:
            return kept[1]
        positions = [np.asarray(primitive.positions, np.float64) for primitive in node.mesh.primitives]
        pose = self.graph.scene.get_pose(node)
        vertices = np.concatenate(positions) @ pose[:3, :3].T + pose[:3, 3]
        self._vertices_m[k] = (version, vertices)
        return vertices

    def _base_radiance(
        self, state: CameraState, view: View, fit: ShadowFit, *, fine: bool, turning: bool = False
    ) -> np.ndarray:
        """The radiance at the frame time with s × s area samples per pixel, kept for the next frame: `fine`, one
        draw s× finer, box-averaged; else s² draws at 1×, one through each sub-pixel position, as motion blur's
        sub-frames sample them. When the view, the daylight and the sampling are the kept one's, only the
        rectangles that bound what moved between the two (`moving_rects_px` at the two times) are drawn again,
        each cropped from the whole view's draws (`_fine_crops`, `_mean_of_draws`: the same pixels, bit for
        bit). What moved is told from the looks kept with the last frame (`_Looks`), so the actors are placed at the
        frame time only. `turning`: the head turns during this frame's exposure; then, where the view turned since
        the last base (`turns_reprojected`), the base is the turn canvas's (`_turned_radiance`). A head that holds
        still during the exposure is drawn so, even where it turned since the last frame (the first frame after it
        stopped): a held head's bases are the plan's bit for bit."""
        graph, s = self.graph, self.spec.supersampling
        graph.place_actors(state.time_s)
        daylight = _daylight_state(graph)
        last, self._last_view = self._last_view, view
        steady = self._last_daylight is not None and _same_arrays(self._last_daylight, daylight)
        self._last_daylight = daylight
        if (
            fine
            and turning
            and self.turns_reprojected
            and last is not None
            and not _same_view(last, view)
            and _turned_only(last, view)
        ):
            turned = self._turned_radiance(state, view, daylight) if steady else None
            if turned is not None:
                return turned
            if not steady:
                self._canvas = None  # the lights or the sky change frame by frame (a dusk): drawn whole
        kept, rects = self._kept_base, None
        looks = _Looks.now(graph, None if kept is None else kept.looks)
        if (
            kept is not None
            and kept.fine == fine
            and _same_view(kept.view, view)
            and _same_arrays(kept.daylight, daylight)
        ):
            changed = [looks.differ(kept.looks, k) for k in range(len(looks.versions))]
            boxes = [[kept.looks.boxes[k], looks.boxes[k]] if moved else [] for k, moved in enumerate(changed)]
            slack_px = RECT_MERGE_SLACK_PX / s**2 if fine else RECT_MERGE_SLACK_PX  # in the draws' pixels
            rects = self._rects_of(view, fit, boxes, changed, slack_px, _fine_step_px(s) if fine else SKY_STEP_PX)
        positions = [] if fine else [(0.0, dx_px, dy_px) for _, dx_px, dy_px in jittered_samples(s * s, s)]
        if rects is None:  # over the kept background of each draw, where the plan keeps one
            if fine:
                draws = [(0.0, 0.0, 0.0, s, _fine_key(s))]
            else:
                draws = [(0.0, dx, dy, 1, f"radiance jitter {i}") for i, (_, dx, dy) in enumerate(positions)]
            radiance = self._sub_frame_mean(state, view, draws, fit)
        else:
            radiance, self._kept_base = kept.radiance, None  # written in place: no half-written base is kept
            parts = (
                self._fine_crops(state, view, fit, rects)
                if fine
                else self._mean_of_draws(state, view, fit, positions, rects)
            )
            for (x0, y0, x1, y1), part in zip(rects, parts, strict=True):
                radiance[y0:y1, x0:x1] = part
        self._kept_base = _KeptBase(view, daylight, radiance, fine, looks)
        return radiance

    def _turned_radiance(self, state: CameraState, view: View, daylight: list[np.ndarray]) -> np.ndarray | None:
        """The fine base at the frame time through a head that turned since the last frame (module docstring:
        turned frames), under `daylight` (`_daylight_state`, the same as at the last frame; the actors placed at the
        frame time): the canvas (`_TurnCanvas`) brought up to the frame time and warped to this view. A new canvas is
        started when there is none, the daylight or the view's camera matrix or centre changed, or the frame reaches
        past the canvas or would be resampled by more than `TURN_SCALE_TOLERANCE`. None (the caller draws the frame
        whole, and the canvas is dropped) where bringing the canvas up to date would draw more pixels than a whole
        frame, or what moved cannot be bounded: a new canvas would draw more than the frame."""
        graph, spec = self.graph, self.spec
        canvas = self._canvas
        fresh = (
            canvas is None
            or not _same_arrays(canvas.daylight, daylight)
            or not _turned_only(canvas.anchor, view)
            or not canvas.holds(view)
        )
        # Where this frame needs what the canvas lacks, what the head's turn at its present rates will show over the
        # next `TURN_LOOKAHEAD_S` is drawn too: a turn's strips come a few frames wide, each crop's fixed cost once.
        ahead = [view, *(view_at(state, spec, k * TURN_LOOKAHEAD_S / 4) for k in range(1, 5))]
        if not fresh:
            looks = _Looks.now(graph, canvas.looks)
            moved = canvas.moved_rects(self, looks)
            missing = canvas.unfilled_rects([view])
            if missing:
                missing = canvas.unfilled_rects(ahead)
            rects = (
                None if moved is None else merged_rects_px(moved + missing, RECT_MERGE_SLACK_PX / spec.supersampling**2)
            )
            if rects is None or sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rects) > view.width_px * view.height_px:
                self._canvas = None
                return None
        if fresh:
            for ahead_s in TURN_ANCHOR_AHEAD_S:  # the farthest ahead that holds this frame
                anchor = view_at(state, spec, ahead_s)
                canvas = _TurnCanvas.at(anchor, daylight, self.shadow_fit, spec.supersampling)
                if ahead_s == 0.0 or (_turned_only(anchor, view) and canvas.holds(view)):
                    break
            self._canvas = canvas
            looks = _Looks.now(graph, None)
            rects = canvas.unfilled_rects(ahead)
        canvas.draw(self, state, rects, looks)
        return canvas.warped(view)

    def _fine_crops(self, state: CameraState, view: View, fit: ShadowFit, rects: list) -> list[np.ndarray]:
        """The radiance at the frame time in each of `rects` (x0, y0, x1, y1, their left and top on the grid of
        `_fine_step_px`) as the whole view's one draw s× finer, box-averaged, gives it (`_sub_frame_mean`):
        each rectangle's crop of that draw, grown to the fine draw's sky grid and the growth (right and bottom
        only) dropped, so the same pixels bit for bit. Shadow maps are drawn once."""
        s = self.spec.supersampling
        fine = view.scaled(s)
        clip = self.clip_range_m(view)
        self.graph.place_actors(state.time_s)
        parts = []
        step = _fine_step_px(s)
        for k, (x0, y0, x1, y1) in enumerate(rects):
            if x0 % step or y0 % step:
                raise ValueError(f"rectangle {(x0, y0, x1, y1)} does not start on the {step}-pixel grid")
            crop = aligned_rect_px((x0 * s, y0 * s, x1 * s, y1 * s), fine.width_px, fine.height_px)
            drawn = self.renderer.draw(
                self.graph, fine, ("radiance",), clip_range_m=clip, shadow_fit=fit, crop_px=crop,
                shadow_maps_kept=k > 0,
            ).radiance  # fmt: skip
            parts.append(box_downsample(drawn[: (y1 - y0) * s, : (x1 - x0) * s], s))
        return parts

    def _mean_of_draws(
        self, state: CameraState, view: View, fit: ShadowFit, draws: list[tuple[float, float, float]], rects: list
    ) -> list[np.ndarray]:
        """The mean radiance of `draws` (time offset as a fraction of the exposure, sub-pixel shift dx, dy px),
        each drawn at 1× (standing for s × s samples: textures at the s× draw's mip level), cropped to each
        of `rects` (x0, y0, x1, y1), one mean per rectangle. The sums run in the order of `draws`, as
        `_sub_frame_mean`'s over the whole view do, so a crop's mean is the whole view's, bit for bit.
        Shadow maps are drawn once per placement."""
        totals: list[np.ndarray | None] = [None] * len(rects)
        clip, lod_bias = self.clip_range_m(view), -math.log2(self.spec.supersampling)
        placed = None
        for offset, dx_px, dy_px in draws:
            maps_kept = offset == placed
            if not maps_kept:
                self.graph.place_actors(state.time_s + offset * state.exposure_time_s)
                placed = offset
            sub_view = shifted(view, dx_px, dy_px)
            for k, crop in enumerate(rects):
                part = self.renderer.draw(
                    self.graph,
                    sub_view,
                    ("radiance",),
                    clip_range_m=clip,
                    shadow_fit=fit,
                    crop_px=crop,
                    shadow_maps_kept=maps_kept or k > 0,
                    texture_lod_bias=lod_bias,
                ).radiance
                if totals[k] is None:
                    totals[k] = part  # the draw's own array, free to sum into
                else:
                    totals[k] += part
        return [total / np.float32(len(draws)) for total in totals]

    def _sub_frame_mean(self, state: CameraState, view: View, draws: list, fit: ShadowFit) -> np.ndarray:
        """The mean radiance of `draws` (time offset, sub-pixel shift, draw factor, kept-background key),
        each drawn whole (shadow maps once per placement)."""
        spec, total, placed = self.spec, None, None
        for offset, dx_px, dy_px, factor, key in draws:
            maps_kept = offset == placed
            if not maps_kept:
                self.graph.place_actors(state.time_s + offset * state.exposure_time_s)
                placed = offset
            # The head moves during the exposure too.
            sub_view = shifted(view_at(state, spec, offset * state.exposure_time_s), dx_px, dy_px)
            if factor > 1:
                sub_view = sub_view.scaled(factor)
            # A 1× draw that stands for s × s samples samples textures at the s× draw's mip level.
            lod_bias = math.log2(factor / spec.supersampling)
            drawn = self._draw(sub_view, ("radiance",), key, fit, lod_bias, maps_kept)
            radiance = box_downsample(drawn.radiance, factor)
            if factor == 1 and len(draws) > 1:  # its share of the exposure, smeared by the head's turn
                radiance = self._smeared(state, radiance, offset, 1.0 / len(draws), dx_px, dy_px)
            total = radiance if total is None else total + radiance
        return total / len(draws) if len(draws) > 1 else total

    def _smeared(
        self,
        state: CameraState,
        radiance: np.ndarray,
        offset: float,
        share: float,
        dx_px: float,
        dy_px: float,
        *,
        whole: bool = False,
    ) -> np.ndarray:
        """A sub-frame drawn at `offset` (a fraction of the exposure) spread over its `share` of the exposure
        by the head's own motion, where the head turns or zooms by more than the plan's sample step in it.

        A head turns about its centre of projection (`view_at` keeps the camera's position), so the still
        world seen at another time of the exposure is this sub-frame warped by the homography
        K_b·R_bᵀ·R_a·K_a⁻¹ (no parallax; the sky, shadows and fog alike): the mean of ⌈shift / step⌉ warps,
        evenly spread over the share, is the blur a sub-frame count capped at the plan's `samples_max`
        leaves out, and a fast pan shows a smear instead of that many ghost copies of every edge. Moving
        actors are smeared as the still world is within one share (their own motion there is the plan's
        step or less of what the sub-frames already sample). A warp samples the draw bilinearly, and the
        edge pixels stand in for what lies beyond the render (a band as wide as one share's shift).

        `whole`: the draw stands for the whole exposure (`share` 1; a turned frame's base, `frame`), smeared by as
        many warps as the plan would draw sub-frames for the head's turn (`sub_frame_count` with its step and
        threshold, not capped: each is a warp, not a draw)."""
        spec, exposure_s = self.spec, state.exposure_time_s
        here = shifted(view_at(state, spec, offset * exposure_s), dx_px, dy_px)
        start = shifted(view_at(state, spec, (offset - share / 2) * exposure_s), dx_px, dy_px)
        end = shifted(view_at(state, spec, (offset + share / 2) * exposure_s), dx_px, dy_px)
        p = self._motion
        step_px = p["sample_step_px"] if p is not None else 1.0
        shift_px = _head_shift_px(start, end)
        if whole:
            threshold_px = p["threshold_px"] if p is not None else 0.5
            count = sub_frame_count(shift_px, step_px=step_px, samples_max=sys.maxsize, threshold_px=threshold_px)
        else:
            count = math.ceil(shift_px / step_px)
        if count <= 1:
            return radiance
        h, w = radiance.shape[:2]
        total = np.zeros_like(radiance)
        for k in range(count):
            at = shifted(view_at(state, spec, (offset + share * ((k + 0.5) / count - 0.5)) * exposure_s), dx_px, dy_px)
            H = _homography(at, here)  # a pixel of the view at `at` → where this draw saw the same direction
            total += cv2.warpPerspective(
                radiance, H, (w, h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE
            )
        return total / np.float32(count)

    def moving_rects_px(
        self, state: CameraState, view: View, offsets: list[float], fit: ShadowFit, only: set[int] | None = None
    ) -> list[tuple[int, int, int, int]] | None:
        """Rectangles (x0, y0, x1, y1) of `view` outside which no sub-frame of the exposure (at `offsets`,
        fractions of it) differs from another of the same sub-pixel position; None when that cannot be
        bounded, or the rectangles would cover most of the frame (then every sub-frame is drawn whole).

        Each actor (and each prop swaying in the wind, `SceneGraph.moving_nodes`) whose mesh, pose or
        lamps change during the exposure is bounded by its box swept over
        the sub-frame times, grown by two shadow-map texels, and by that box's shadow volume down to the
        lowest surface (`_shadow_slices`: along a sun's direction, or along the rays from a spot light;
        point lights cast no shadows in this renderer), as a few convex hulls whose parts in front of
        the near plane are projected, each to a rectangle. Falls back when the head moves (pan, tilt,
        zoom), a light moves or changes, a sun is at or below the horizon, or a spot light is not above a
        moving box."""
        exposure_s = state.exposure_time_s
        if any(not _same_view(view_at(state, self.spec, offset * exposure_s), view) for offset in offsets):
            return None
        return self._moving_rects_at(view, [state.time_s + offset * exposure_s for offset in offsets], fit, only)

    def _moving_rects_at(
        self, view: View, times_s: list[float], fit: ShadowFit, only: set[int] | None
    ) -> list[tuple[int, int, int, int]] | None:
        """`moving_rects_px` over the actors placed at `times_s`, through `view` (which holds for them all),
        for the moving nodes `only` (indices into `SceneGraph.moving_nodes`; None: all of them)."""
        graph, scene = self.graph, self.graph.scene
        lights_before = _light_state(scene)
        moving = graph.moving_nodes
        boxes: list[list[np.ndarray]] = [[] for _ in moving]
        first: dict[int, tuple] = {}
        changed = [False] * len(moving)
        for step, time_s in enumerate(times_s):
            graph.place_actors(time_s)
            for k, node in enumerate(moving):
                if only is not None and k not in only:
                    continue
                look = _actor_look(scene, node)
                if step == 0:
                    first[k] = look
                elif not changed[k]:
                    changed[k] = not _same_arrays(first[k], look)
                boxes[k].append(box_corners(*node.mesh.bounds, scene.get_pose(node)))
        if not _same_arrays(lights_before, _light_state(scene)):
            return None
        return self._rects_of(view, fit, boxes, changed, RECT_MERGE_SLACK_PX, SKY_STEP_PX)

    def _rects_of(
        self,
        view: View,
        fit: ShadowFit,
        boxes: list[list[np.ndarray]],
        changed: list[bool],
        slack_px: float,
        step_px: int,
    ) -> list[tuple[int, int, int, int]] | None:
        """The rectangles of `moving_rects_px` for the moving nodes whose look `changed`, each bounded by its box
        corners `boxes` (8, 3 each) at the times it was placed at, aligned to `step_px` (`aligned_rect_px`) and
        merged while a rectangle around two costs no more than the two apart plus `slack_px` (`merged_rects_px`,
        in the pixels of `view`)."""
        from pyrender.light import DirectionalLight

        scene = self.graph.scene
        near_m, far_m = self.clip_range_m(view)
        casting = _shadow_lights(scene) if self.graph.shadows else []
        surfaces = _projected_rect_px(box_corners(*self._caster_box_m, np.eye(4)), view, NEAR_CLIP_M)
        rects = []
        for k, moved in enumerate(changed):
            if not moved:
                continue
            corners = np.concatenate(boxes[k])
            low, high = corners.min(axis=0), corners.max(axis=0)
            texels_m = []
            lights_k = [casting[i] for i in self._shadowing(self.graph.moving_nodes[k], casting)]
            for node in lights_k:
                if isinstance(node.light, DirectionalLight):  # the same for every caster, kept (`_sun_texel_m`)
                    texels_m.append(self._sun_texel_m(node, fit, (near_m, far_m)))
                else:
                    texels_m.append(_shadow_texel_m(scene, node, fit, (near_m, far_m), self._caster_box_m, corners))
            grow_m = SHADOW_TEXEL_MARGIN * max(texels_m, default=0.0)
            swept = box_corners(low - grow_m, high + grow_m, np.eye(4))
            hulls = [swept]
            for node in lights_k:
                slices = _shadow_slices(scene, node, swept, self._lowest_z_m, self._caster_box_m)
                if slices is None:
                    return None
                hulls += slices
            for hull in hulls:
                rect = _projected_rect_px(hull, view, NEAR_CLIP_M)
                if rect is not None and surfaces is not None:  # a shadow falls on surfaces, all in the box
                    rect = _rect_intersection(rect, surfaces)
                if rect is not None:
                    rects.append(aligned_rect_px(rect, view.width_px, view.height_px, step_px))
        rects = merged_rects_px(rects, slack_px)
        area = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rects)
        if area > MOVING_AREA_MAX_FRACTION * view.width_px * view.height_px:
            return None
        return rects

    def _sun_texel_m(self, node, fit: ShadowFit, clip_m: tuple[float, float]) -> float:
        """`_shadow_texel_m` of a sun light, which does not depend on the caster: kept while the sun, the fit
        and the clip range hold (a held view's frames ask for the same)."""
        pose = self.graph.scene.get_pose(node)
        key = (
            pose.tobytes(),
            fit.view.K_px.tobytes(),
            fit.view.T_world_from_cam.tobytes(),
            fit.view.width_px,
            fit.view.height_px,
            np.asarray(fit.low_m, np.float64).tobytes(),
            np.asarray(fit.high_m, np.float64).tobytes(),
            clip_m,
        )
        kept = self._sun_texels_m.get(id(node))
        if kept is None or kept[0] != key:
            texel_m = _shadow_texel_m(self.graph.scene, node, fit, clip_m, self._caster_box_m, np.zeros((1, 3)))
            kept = self._sun_texels_m[id(node)] = (key, texel_m)
        return kept[1]

    def _wet(self, view: View, state: CameraState, radiance: np.ndarray, depth_m: np.ndarray | None) -> np.ndarray:
        """The frame's radiance with the wet ground's mirror image in its water film (`camgen.render.wet`): the
        scene reflected in the ground drawn at the frame time, spread by the film on a coarse grid and added at the
        pixels that show the wet ground by the water's Fresnel reflectance (the plan draws depth for it)."""
        from camgen.render.wet import (
            block_means,
            block_view,
            film_blur,
            film_spread_px,
            flat_nodes,
            mirror_step_px,
            mirrored_view,
            reflected_radiance,
            view_geometry,
            wet_pixels,
        )

        if depth_m is None:
            raise ValueError(
                f"camera {self.camera.name!r}: the wet ground's reflections need the depth pass, which the plan "
                "did not draw"
            )
        height_m, graph = self._wet_ground_m, self.graph
        far_ground_m = graph.far_ground.height_m if graph.far_ground is not None else None
        if self._wet_view is None or self._wet_view.key != view.key():
            self._wet_view = view_geometry(view)
        geometry = self._wet_view
        wet = wet_pixels(view, depth_m, height_m, far_ground_m, geometry.rise_per_m)
        if not wet.any():
            return radiance
        sigmas_px = film_spread_px(view, float(np.median(geometry.cos_incidence[wet])))
        steps_px = (mirror_step_px(sigmas_px[0]), mirror_step_px(sigmas_px[1]))
        mirror = block_view(mirrored_view(view, height_m), *steps_px)
        if self._flat_node_ids is None:
            self._flat_node_ids = frozenset(flat_nodes(graph, height_m))
        graph.place_actors(state.time_s)
        # The still part of the mirror drawn once per view where the plan keeps a background, as the frame's.
        drawn = self._draw(
            mirror, ("radiance",), "wet mirror", fit=self.shadow_fit(view), leave_out=self._flat_node_ids
        )
        coarse = block_means(drawn.radiance, *steps_px)
        spread = film_blur(coarse, steps_px, sigmas_px, (view.width_px, view.height_px))
        return reflected_radiance(radiance, spread, wet, geometry.fresnel)

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
    point: environment mesh corners (radius 0; a swaying prop's at rest, with its sway's reach), and every
    point each actor's route visits with the actor's own extent (a route runs along straight segments,
    whose farthest point from a camera is an end; a resolved random walk covers the whole sequence)."""
    points, radii = [], []
    swaying = {id(prop.node): prop for prop in graph.swaying}
    for node in graph.environment_nodes:
        pose = graph.scene.get_pose(node)
        prop = swaying.get(id(node))
        if prop is None:
            points.append(box_corners(*node.mesh.bounds, pose))
            radii.append(np.zeros(8))
        else:  # its box at rest, and how far its sway can take a vertex from there
            rest = prop.rest_vertices_m
            points.append(box_corners(rest.min(axis=0), rest.max(axis=0), pose))
            radii.append(np.full(8, prop.sway.reach_m()))
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


def _fine_key(supersampling: int) -> str:
    """The kept-background key of a radiance draw s× finer (`CameraRenderer._draw`): whole frames and still
    frames' bases share it."""
    return "radiance" if supersampling == 1 else f"radiance {supersampling}x"


@dataclass
class _KeptBase:
    """The last frame's radiance at its frame time, before any motion blur (`CameraRenderer._base_radiance`)."""

    view: View
    daylight: list[np.ndarray]
    radiance: np.ndarray
    fine: bool
    """Drawn s× finer and box-averaged, or as s² jittered 1× draws (`CameraRenderer._base_radiance`)."""
    looks: _Looks
    """What each moving node drew then."""


@dataclass
class _KeptGeometry:
    """The last frame's geometric passes at its frame time (`CameraRenderer._geometry`)."""

    view: View
    passes: tuple[str, ...]
    depth_m: np.ndarray | None
    instance_id: np.ndarray | None
    looks: _Looks
    """What each moving node drew then."""


TURN_SCALE_TOLERANCE = 0.2
"""The most a turned frame's pixel may be magnified or shrunk when warped from its canvas (`_TurnCanvas.holds`), as
a fraction: a turn moves the view's edges to where the canvas's pixels subtend other angles (1/cos² off its axis).
On the 720p sim step of ptz_follow panning at 12°/s (40 steps against the frames drawn whole, load 3.5): 0.1 gave
40.3 dB PSNR and a mean step of 415 ms, 0.2 39.7 dB and 336 ms (a canvas lasting ~18 frames, not ~10)."""
TURN_ANCHOR_AHEAD_S = (0.4, 0.2, 0.1, 0.0)
"""A new turn canvas is anchored where the head, turning on at its present rates, will look this long after the frame
(the first of these that still holds the frame, `_TurnCanvas.holds`): the frames then sweep across its axis, so a
canvas lasts about twice as long for the same resampling."""
TURN_LOOKAHEAD_S = 0.16
"""A turned frame draws into its canvas what the head, turning on at its present rates, will show over this much more
time (`CameraRenderer._turned_radiance`): the strips a turn uncovers come in crops a few frames wide, each costing a
draw's fixed cost once."""
TURN_MARGIN_FRACTION = 0.25
"""A turn canvas's margin on each side, as a fraction of the larger side of the view it starts at."""
CANVAS_CROP_ROUND_PX = 64
"""A canvas crop is drawn through a view of its size rounded up to this, scissored to it (`_TurnCanvas.draw`), so
that crops of slowly changing sizes reuse the renderer's few kept targets instead of making new ones."""
TURN_WARP_INTERPOLATION = cv2.INTER_CUBIC
"""The turned frame's resampling of its canvas: bicubic keeps 0.76 of the high-frequency energy (the Laplacian's
variance) of a 720p parking-lot frame drawn exactly, bilinear 0.53, Lanczos-4 0.85 at 5× bicubic's 12 ms."""


@dataclass
class _TurnCanvas:
    """What a turning head's frames are drawn from (module docstring: turned frames): the still world and the moving
    nodes as of the last frame, drawn through one view (`anchor`: where the head, turning on at the rates of the frame
    that started the canvas, looks `TURN_ANCHOR_AHEAD_S` later) grown by a margin on each side (`view`), filled
    where frames have looked so far. A frame brings it up to date (the moving nodes that changed since, at both
    times, with their shadows, where it is filled; its own footprint and the lookahead's where it is not) and warps
    it to its view: the head turns about its centre of projection, so what the canvas's pixel (x, y)
    shows, the frame's pixel H⁻¹·(x, y) shows (`_homography`), the sky, shadows, fog and speculars alike."""

    anchor: View
    view: View
    margin_px: int
    daylight: list[np.ndarray]
    fit: ShadowFit
    """Every draw into the canvas fits its shadow maps alike."""
    supersampling: int
    radiance: np.ndarray
    """(H, W, 3) of `view`, valid where `filled`."""
    filled: np.ndarray
    """(H, W) bool."""
    looks: _Looks | None
    """The moving nodes' looks that the canvas shows (None before its first draw)."""
    filled_box: tuple[int, int, int, int] = (0, 0, 0, 0)
    """(x0, y0, x1, y1) around what is filled."""

    @staticmethod
    def at(view: View, daylight: list[np.ndarray], shadow_fit: Callable[[View], ShadowFit], supersampling: int):
        step = _fine_step_px(supersampling)
        margin = -(-int(TURN_MARGIN_FRACTION * max(view.width_px, view.height_px)) // step) * step
        grown = View(
            view.K_px + np.array([[0, 0, margin], [0, 0, margin], [0, 0, 0]], np.float64),
            view.T_world_from_cam,
            view.width_px + 2 * margin,
            view.height_px + 2 * margin,
        )
        shape = (grown.height_px, grown.width_px)
        return _TurnCanvas(
            view, grown, margin, daylight, shadow_fit(grown), supersampling,
            np.zeros((*shape, 3), np.float32), np.zeros(shape, bool), None,
        )  # fmt: skip

    def quad_px(self, view: View) -> np.ndarray | None:
        """(4, 2) where the corners of `view`'s pixels' area land in the canvas: the image of the view under the warp,
        a convex quadrilateral (a homography keeps lines straight); None where a corner lies behind the canvas."""
        w, h = view.width_px, view.height_px
        corners = np.array([[-0.5, -0.5, 1], [w - 0.5, -0.5, 1], [w - 0.5, h - 0.5, 1], [-0.5, h - 0.5, 1]])
        mapped = corners @ _homography(view, self.view).T
        return mapped[:, :2] / mapped[:, 2:] if np.all(mapped[:, 2] > 0) else None

    def footprint_px(self, view: View) -> tuple[int, int, int, int] | None:
        """The canvas's pixels (x0, y0, x1, y1) that `view`'s warp reads (the box around its quadrilateral, `quad_px`,
        grown by the bicubic's reach of 2 pixels, aligned to the fine draws' grid); None where they pass the canvas's
        edge."""
        quad = self.quad_px(view)
        if quad is None:
            return None
        u, v = quad[:, 0], quad[:, 1]
        rect = (math.floor(u.min()) - 2, math.floor(v.min()) - 2, math.ceil(u.max()) + 3, math.ceil(v.max()) + 3)
        W, H = self.view.width_px, self.view.height_px
        if rect[0] < 0 or rect[1] < 0 or rect[2] > W or rect[3] > H:
            return None
        return aligned_rect_px(rect, W, H, _fine_step_px(self.supersampling))

    def holds(self, view: View) -> bool:
        """Whether `view` can be warped from this canvas: its footprint lies inside, and the warp stretches or shrinks
        no pixel of it along any direction by more than `TURN_SCALE_TOLERANCE` (the singular values of the warp's
        Jacobian, at the view's corners and the middles of its edges, where they are largest: a pan by δ stretches a
        pixel θ off the axis across by cos²θ / cos²(θ + δ) and along by cos θ / cos(θ + δ))."""
        if self.footprint_px(view) is None:
            return False
        H = _homography(view, self.view)
        w, h = view.width_px, view.height_px
        limit = math.log1p(TURN_SCALE_TOLERANCE)
        for x in (0.0, (w - 1) / 2, w - 1.0):
            for y in (0.0, (h - 1) / 2, h - 1.0):
                p = H @ np.array([x, y, 1.0])
                J = (H[:2, :2] * p[2] - np.outer(p[:2], H[2, :2])) / p[2] ** 2  # d(p₀/p₂, p₁/p₂)/d(x, y)
                stretch = np.linalg.svd(J, compute_uv=False)
                if np.max(np.abs(np.log(stretch))) > limit:
                    return False
        return True

    def unfilled_rects(self, views: list[View]) -> list[tuple[int, int, int, int]]:
        """Rectangles holding every pixel of the canvas that the warp of any of `views` reads (the image of the view's
        pixels' area, a convex quadrilateral, grown by the bicubic's reach of 2 pixels; clipped to the canvas) and
        the canvas does not hold yet: per band of `UNCOVERED_BAND_ROWS` rows, one around each run of columns with such
        a pixel (a turn uncovers a strip along an edge, a roll a sliver along another), aligned to the fine draws'
        grid and merged while that costs no more than a draw's fixed cost (`RECT_MERGE_SLACK_PX`)."""
        height, width = self.filled.shape
        quads = [quad for quad in map(self.quad_px, views) if quad is not None]
        if not quads:
            return []
        # Only the box around the quadrilaterals, grown by the bicubic's reach, is looked at.
        every = np.concatenate(quads)
        x0, y0 = max(0, math.floor(every[:, 0].min()) - 3), max(0, math.floor(every[:, 1].min()) - 3)
        x1, y1 = min(width, math.ceil(every[:, 0].max()) + 4), min(height, math.ceil(every[:, 1].max()) + 4)
        if x0 >= x1 or y0 >= y1 or self.filled[y0:y1, x0:x1].all():
            return []  # the usual frame: all it reads is held
        reads = np.zeros((y1 - y0, x1 - x0), np.uint8)
        for quad in quads:
            points = np.round((quad - [x0, y0]) * 16).astype(np.int32)  # 4 fractional bits
            cv2.fillConvexPoly(reads, points, 1, lineType=cv2.LINE_8, shift=4)
        grown = cv2.dilate(reads, np.ones((5, 5), np.uint8)).view(bool)
        missing = grown & ~self.filled[y0:y1, x0:x1]
        step = _fine_step_px(self.supersampling)
        rects = []
        bands = -(-(y1 - y0) // UNCOVERED_BAND_ROWS)
        padded = np.zeros((bands * UNCOVERED_BAND_ROWS, x1 - x0), bool)
        padded[: y1 - y0] = missing
        by_band = padded.reshape(bands, UNCOVERED_BAND_ROWS, x1 - x0).any(axis=1)  # (bands, columns)
        for band in np.flatnonzero(by_band.any(axis=1)):
            columns = by_band[band]
            top = int(band) * UNCOVERED_BAND_ROWS
            bottom = min(y1 - y0, top + UNCOVERED_BAND_ROWS)
            edges = np.flatnonzero(np.diff(np.concatenate([[0], columns.astype(np.int8), [0]])))
            for start, end in zip(edges[::2], edges[1::2], strict=True):
                rect = (x0 + int(start), y0 + top, x0 + int(end), y0 + bottom)
                rects.append(aligned_rect_px(rect, width, height, step))
        # A strip's bands share their columns: join those first (one pass), then merge the few left.
        stacked: list[tuple[int, int, int, int]] = []
        for rect in sorted(rects, key=lambda r: (r[0], r[2], r[1])):
            last = stacked[-1] if stacked else None
            if last is not None and (last[0], last[2]) == (rect[0], rect[2]) and rect[1] <= last[3]:
                stacked[-1] = (last[0], last[1], last[2], max(last[3], rect[3]))
            else:
                stacked.append(rect)
        return merged_rects_px(stacked, RECT_MERGE_SLACK_PX / self.supersampling**2)

    def moved_rects(self, drawer: CameraRenderer, looks: _Looks) -> list[tuple[int, int, int, int]] | None:
        """The filled part of the rectangles of the canvas around each moving node that changed since it was drawn (at
        both times, with its shadows: `CameraRenderer._rects_of` through the canvas's view), for the moving nodes at
        `looks`; None when one cannot be bounded."""
        before = self.looks
        changed = [looks.differ(before, k) for k in range(len(looks.versions))]
        if not any(changed):
            return []
        step = _fine_step_px(self.supersampling)
        boxes = [[before.boxes[k], looks.boxes[k]] if moved else [] for k, moved in enumerate(changed)]
        rects = drawer._rects_of(self.view, self.fit, boxes, changed, RECT_MERGE_SLACK_PX / self.supersampling**2, step)
        if rects is None:
            return None
        width, height = self.view.width_px, self.view.height_px
        kept = (_intersection(rect, self.filled_box) for rect in rects)
        return [aligned_rect_px(rect, width, height, step) for rect in kept if rect is not None]

    def draw(self, drawer: CameraRenderer, state: CameraState, rects: list, looks: _Looks) -> None:
        """Draw `rects` of the canvas at the frame time (the actors placed there), each through a view of its own (the
        canvas's view cropped to it, its size rounded up to `CANVAS_CROP_ROUND_PX` and scissored back: the canvas's
        pixels to ~1e-3, `Renderer.draw`'s `crop_px`), s× finer and box-averaged, with the canvas's shadow fit. A
        rectangle whose draw s× finer would pass the renderer's largest target (`Renderer.max_size_px`: the canvas is
        half as wide again as the frame that `CameraRenderer` checked against it) is drawn in tiles that fit."""
        s, renderer, graph = self.supersampling, drawer.renderer, drawer.graph
        clip = drawer.clip_range_m(self.view)
        graph.place_actors(state.time_s)
        most = renderer.max_size_px // s  # the canvas's pixels across that one draw s× finer may span
        step = _fine_step_px(s)
        tile = most // CANVAS_CROP_ROUND_PX * CANVAS_CROP_ROUND_PX or most // step * step  # starts stay on the grid
        tiles = [
            (tx, ty, min(x1, tx + tile), min(y1, ty + tile))
            for x0, y0, x1, y1 in rects
            for ty in range(y0, y1, tile)
            for tx in range(x0, x1, tile)
        ]
        for k, (x0, y0, x1, y1) in enumerate(tiles):
            w, h = x1 - x0, y1 - y0
            rounded = (x0, y0, x0 + min(most, -(-w // CANVAS_CROP_ROUND_PX) * CANVAS_CROP_ROUND_PX),
                       y0 + min(most, -(-h // CANVAS_CROP_ROUND_PX) * CANVAS_CROP_ROUND_PX))  # fmt: skip
            fine = self.view.cropped(rounded).scaled(s)
            drawn = renderer.draw(
                graph, fine, ("radiance",), clip_range_m=clip, shadow_fit=self.fit, crop_px=(0, 0, w * s, h * s),
                shadow_maps_kept=k > 0,
            ).radiance  # fmt: skip
            self.radiance[y0:y1, x0:x1] = box_downsample(drawn, s)
            self.filled[y0:y1, x0:x1] = True
            a = self.filled_box
            self.filled_box = (x0, y0, x1, y1) if a[2] <= a[0] else (
                min(a[0], x0), min(a[1], y0), max(a[2], x1), max(a[3], y1)
            )  # fmt: skip
        self.looks = looks

    def warped(self, view: View) -> np.ndarray:
        """The canvas seen through `view` (`TURN_WARP_INTERPOLATION`). Where a lobe of the bicubic went under zero
        anywhere (a light, or the sun's glint on paint, over a dark surround), each pixel is held within the least and
        largest of the 2 × 2 canvas pixels around its lookup, as a ringing-free interpolation of those four would be:
        a lamp's 2 × 2 pixels at 20,000 cd/m² over a background of 0.3 gained 9–19 % of their energy, clipped at 0,
        and blacked out a ring of neighbours (measured). Elsewhere the ringing is a few % of an edge's contrast, and
        the clamp, 3–4× the warp's cost, is left out."""
        H, size = _homography(view, self.view), (view.width_px, view.height_px)
        interpolation = TURN_WARP_INTERPOLATION | cv2.WARP_INVERSE_MAP
        radiance = cv2.warpPerspective(self.radiance, H, size, flags=interpolation, borderMode=cv2.BORDER_REPLICATE)
        if radiance.min() >= 0.0:  # no lobe went under zero: the ringing is a few % of an edge's contrast
            return radiance
        # Over the frame's footprint, pixel (x, y) of the eroded (dilated) canvas holds the least (largest) of
        # (x..x+1, y..y+1); a lookup's cell starts at ⌊H·p⌋, which the nearest lookup of H·p − ½ finds.
        x0, y0, x1, y1 = self.footprint_px(view) or (0, 0, self.view.width_px, self.view.height_px)
        part = self.radiance[y0:y1, x0:x1]
        cell = np.array([[1.0, 0.0, -0.5 - x0], [0.0, 1.0, -0.5 - y0], [0.0, 0.0, 1.0]]) @ H
        kernel, flags = np.ones((2, 2), np.uint8), cv2.WARP_INVERSE_MAP | cv2.INTER_NEAREST
        low = cv2.erode(part, kernel, anchor=(0, 0), borderType=cv2.BORDER_REPLICATE)
        high = cv2.dilate(part, kernel, anchor=(0, 0), borderType=cv2.BORDER_REPLICATE)
        low = cv2.warpPerspective(low, cell, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)
        high = cv2.warpPerspective(high, cell, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)
        return np.clip(radiance, low, high, out=radiance)


def _intersection(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> tuple[int, int, int, int] | None:
    x0, y0, x1, y1 = max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])
    return (x0, y0, x1, y1) if x0 < x1 and y0 < y1 else None


@dataclass
class _Looks:
    """Each moving node's look (`_actor_look`), its version (`SceneGraph.look_versions`) and its box corners (8, 3),
    at one placement of the actors."""

    versions: list[int]
    looks: list[tuple]
    boxes: list[np.ndarray]

    @staticmethod
    def now(graph: SceneGraph, before: _Looks | None) -> _Looks:
        """The looks as the actors are placed now, sharing `before`'s where a node's version is the same (its look
        and box are then the same: only the others are copied)."""
        scene, versions = graph.scene, list(graph.look_versions)
        looks, boxes = [], []
        for k, node in enumerate(graph.moving_nodes):
            if before is not None and before.versions[k] == versions[k]:
                looks.append(before.looks[k])
                boxes.append(before.boxes[k])
            else:
                looks.append(_actor_look(scene, node))
                boxes.append(box_corners(*node.mesh.bounds, scene.get_pose(node)))
        return _Looks(versions, looks, boxes)

    def differ(self, other: _Looks, k: int) -> bool:
        """Whether node `k` looks different here and in `other`."""
        return self.looks[k] is not other.looks[k] and not _same_arrays(self.looks[k], other.looks[k])


def _daylight_state(graph: SceneGraph) -> list[np.ndarray]:
    """What a draw takes from the lights and the sky: every light's pose, colour and intensity, the ambient
    light, the sky's luminance and the sun's direction (`SceneGraph.set_daylight` moves them over a dusk)."""
    sun = graph.sun_direction
    return [
        *_light_state(graph.scene),
        np.asarray(graph.scene.ambient_light, np.float64),
        np.asarray(graph.sky_luminance_cd_m2, np.float64),
        np.zeros(0) if sun is None else np.asarray(sun, np.float64),
    ]


def _same_arrays(a, b) -> bool:
    """Whether two sequences of arrays are equal array by array (lights, daylight, an actor's look)."""
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def _node_pixels(
    vertices_m: np.ndarray, view: View, casting: list, light_poses: list[np.ndarray], lowest_z_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (2, N) of `view` where the world points `vertices_m` (N, 3: a node's vertices) project, then
    where each one's shadow falls on the plane z = `lowest_z_m` in the light of each node of `casting` (posed at
    `light_poses`; a sun's along its direction, a spot light's along its rays), and whether each lies in front
    of the near plane and is a point at all (a shadow of a vertex the light does not shine down past is not)
    (N,)."""
    vertices = vertices_m
    points, valid = [vertices], [np.ones(len(vertices), bool)]
    height_m = vertices[:, 2] - lowest_z_m
    for light, light_pose in zip(casting, light_poses, strict=True):
        if type(light.light).__name__ == "DirectionalLight":
            d = -light_pose[:3, 2]  # a light shines along its node's −Z
            reach = height_m / -d[2] if d[2] < -1e-6 else np.full(len(vertices), np.nan)
            points.append(vertices + reach[:, None] * d)
        else:
            L = light_pose[:3, 3]
            above = L[2] - vertices[:, 2]
            reach = np.divide(L[2] - lowest_z_m, above, out=np.full(len(vertices), np.nan), where=above > 1e-6)
            # Outside the cone its shadow map spans, the light casts no shadow (a headlamp's beam, aimed ahead).
            rays = vertices - L
            inside = rays @ -light_pose[:3, 2] >= np.cos(_spot_reach_rad(light.light)) * np.linalg.norm(rays, axis=1)
            reach = np.where(inside, reach, np.nan)
            points.append(L + reach[:, None] * (vertices - L))
        valid.append(np.isfinite(reach) & (height_m >= 0.0))
    camera = _camera_frame(np.nan_to_num(np.concatenate(points)), view)
    front = (camera[:, 2] >= NEAR_CLIP_M) & np.concatenate(valid)
    camera[~front, 2] = 1.0
    return np.stack(_pinhole_px(camera, view.K_px)), front


PATH_BOUND_MARGIN = 1e-6
"""Relative and absolute (px) margin `_path_bound_px` adds to its bound, far above the rounding of both it and
the vertex-by-vertex paths it stands for (~1e-12 px), so that a bound under the threshold stays a proof."""


def _path_gain_px(view: View) -> float:
    """‖A‖₂·√(1 + |q|²) at its largest over the box (−W, 2W) × (−H, 2H) of a view's pixels (A the upper 2×2 of K,
    q = A⁻¹(uv − c)): a world move of d m at depth z moves such a pixel by at most gain·d/z px (`_path_bound_px`)."""
    K = view.K_px
    A = np.array([[K[0, 0], K[0, 1]], [0.0, K[1, 1]]])
    w, h = view.width_px, view.height_px
    corners = np.array([[-w, -h], [2 * w, -h], [-w, 2 * h], [2 * w, 2 * h]], np.float64) - K[:2, 2]
    q = np.linalg.solve(A, corners.T)
    return float(np.linalg.norm(A, 2)) * math.sqrt(1.0 + float(np.max(np.sum(q * q, axis=0))))


def _path_bound_px(
    vertices_m: list[np.ndarray], view: View, casting: list, light_poses: list[np.ndarray], lowest_z_m: float
) -> float:
    """An upper bound, px, on the longest image path that `CameraRenderer._blurred_groups` measures for one node:
    over the points of `_node_pixels` (the vertices `vertices_m` at the exposure's start, middle and end, (N, 3)
    each, and their shadows in the light of `casting`, held at `light_poses`) that lie in front of the near plane
    at all three times and within a view's size of the view at the middle, |uv(middle) − uv(start)| +
    |uv(end) − uv(middle)|; inf where no bound is known (a spot light casts).

    For camera-frame points X_a, X_b (z_a > 0) with q = (x/z, y/z) and pixels uv = A·q + c (A the upper 2×2 of K),
    q_a − q_b = ((X_a − X_b)_xy − (z_a − z_b)·q_b) / z_a, so by Cauchy–Schwarz
    |uv_a − uv_b| ≤ ‖A‖₂·√(1 + |q_b|²)·|X_a − X_b| / z_a. At the middle, b, a counted point's pixel lies in the
    box (−W, 2W) × (−H, 2H), so |q_b| is at most its largest at the box's corners (|q| is convex); at an end, a,
    its depth is at least the near plane and at least the least depth of all the node's points then; and
    |X_a − X_b| is the world distance the point moved (the camera frame turns and shifts the world). A vertex's
    shadow in a sun shining along d is P + ((P_z − z_low)/(−d_z))·d, so it moves by ΔP + (ΔP_z/(−d_z))·d and
    lies at that depth. The bound takes, per end, the largest distance over the least depth, of the vertices and
    of each sun's shadows: the longest path is at most the sum over the two ends."""
    if any(type(light.light).__name__ != "DirectionalLight" for light in casting):
        return math.inf
    start, middle, end = vertices_m
    if len(middle) == 0:
        return 0.0
    T = view.T_world_from_cam
    gain = _path_gain_px(view)
    axis_m, origin_m = T[:3, 2], T[:3, 3]  # the camera's depth axis and centre, world
    suns = [-pose[:3, 2] for pose in light_poses if -pose[2, 2] < -1e-6]  # else no shadow (`_node_pixels`)
    kinds = [0.0] * (1 + len(suns))  # the bound of the vertices' paths, then of each sun's shadows'
    for vertices in (start, end):
        moved = vertices - middle
        depth_m = (vertices - origin_m) @ axis_m
        kinds[0] += _longest(moved) / max(NEAR_CLIP_M, float(depth_m.min()))
        for j, d in enumerate(suns, start=1):
            shadow_moved = moved + (moved[:, 2] / -d[2])[:, None] * d
            shadow_depth_m = depth_m + (vertices[:, 2] - lowest_z_m) / -d[2] * float(d @ axis_m)
            kinds[j] += _longest(shadow_moved) / max(NEAR_CLIP_M, float(shadow_depth_m.min()))
    bound = gain * max(kinds)
    return bound * (1.0 + PATH_BOUND_MARGIN) + PATH_BOUND_MARGIN if math.isfinite(bound) else math.inf


def _longest(vectors: np.ndarray) -> float:
    """The largest length of the rows of `vectors` (N, 3), N ≥ 1."""
    return float(np.sqrt(np.max(np.einsum("ij,ij->i", vectors, vectors))))


def _camera_frame(points_m: np.ndarray, view: View) -> np.ndarray:
    """(N, 3) camera-frame coordinates of world points (N, 3) seen through `view`."""
    T = view.T_world_from_cam
    return (points_m - T[:3, 3]) @ T[:3, :3]


def _pinhole_px(camera_m: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (u, v) of camera-frame points (N, 3) in front of the camera, through `K` (no lens)."""
    x, y = camera_m[:, 0] / camera_m[:, 2], camera_m[:, 1] / camera_m[:, 2]
    return K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]


def _near_view(uv: np.ndarray, view: View) -> np.ndarray:
    """Whether each pixel (2, N) lies within a view's width and height of the view (a vertex that far out
    can still belong to a triangle that crosses it)."""
    w, h = view.width_px, view.height_px
    return (uv[0] > -w) & (uv[0] < 2 * w) & (uv[1] > -h) & (uv[1] < 2 * h)


def _homography(a: View, b: View) -> np.ndarray:
    """3×3 H taking a pixel of view `a` to the pixel of view `b` that sees the same direction (the two share
    their centre of projection): K_b·R_bᵀ·R_a·K_a⁻¹, R = R_world_from_cam."""
    R_a, R_b = a.T_world_from_cam[:3, :3], b.T_world_from_cam[:3, :3]
    return b.K_px @ R_b.T @ R_a @ np.linalg.inv(a.K_px)


def _head_shift_px(a: View, b: View) -> float:
    """The largest distance, px, that a pixel of view `a` (its corners and centre) moves to in view `b`."""
    w, h = a.width_px, a.height_px
    points = np.array([[0, 0, 1], [w - 1, 0, 1], [0, h - 1, 1], [w - 1, h - 1, 1], [(w - 1) / 2, (h - 1) / 2, 1]])
    moved = points @ _homography(a, b).T
    return float(np.max(np.hypot(*(moved[:, :2] / moved[:, 2:] - points[:, :2]).T)))


def _light_state(scene) -> list[np.ndarray]:
    """Every light's pose, colour and intensity (what a sub-frame's draw takes from the lights)."""
    state = []
    for node in scene.light_nodes:
        light = node.light
        state += [scene.get_pose(node), np.asarray(light.color, np.float64), np.asarray(light.intensity, np.float64)]
    return state


def _actor_look(scene, node) -> tuple[np.ndarray, ...]:
    """What an actor's node draws: its pose, and each primitive's vertices, normals and emission."""
    look = [scene.get_pose(node).copy()]
    for primitive in node.mesh.primitives:
        look += [
            np.array(primitive.positions, copy=True),
            np.array(primitive.normals, copy=True) if primitive.normals is not None else np.zeros(0),
            np.asarray(primitive.material.emissiveFactor, np.float64).copy(),
        ]
    return tuple(look)


def _shadow_lights(scene) -> list:
    """The light nodes that cast shadow maps (`Renderer.draw`: suns and spot lights when shadows are on)."""
    from pyrender.light import DirectionalLight, SpotLight

    return [node for node in scene.light_nodes if isinstance(node.light, DirectionalLight | SpotLight)]


def _shadow_texel_m(scene, node, fit: ShadowFit, clip_m, box_m, corners_m: np.ndarray) -> float:
    """A light's shadow-map texel, m, at a caster whose box corners are `corners_m` (N, 3): across a sun's
    coarsest cascade (fitted as `Renderer.draw` fits them to `fit` and the clip range `clip_m`; its shadow
    may fall where any of them is read), or a spot light's field of view over the map's texels times the
    caster's farthest distance from it (a sun's maps have the fit's size, `shadow_map_size_texels`)."""
    from pyrender.constants import SHADOW_TEX_SZ
    from pyrender.light import DirectionalLight

    light, pose = node.light, scene.get_pose(node)
    if isinstance(light, DirectionalLight):
        size_texels = shadow_map_size_texels(fit.view)
        cascades = sun_cascade_matrices(pose[:3, :3], box_m, fit.view, *clip_m, size_texels)
        return max(2.0 / (min(P[0, 0], P[1, 1]) * size_texels) for _, P in cascades)
    fov = _spot_shadow_fov_rad(light)
    distance_m = float(np.linalg.norm(corners_m - pose[:3, 3], axis=1).max())
    return 2.0 * math.tan(fov / 2.0) / SHADOW_TEX_SZ * distance_m


SHADOW_SLICES_MAX = 16
"""Most pieces a caster's shadow volume is cut into along the light (`_shadow_slices`)."""


def _shadow_slices(
    scene, node, corners_m: np.ndarray, lowest_z_m: float, box_m: tuple[np.ndarray, np.ndarray] | None = None
) -> list[np.ndarray] | None:
    """Point sets (N, 3) whose convex hulls together hold the part of the shadow volume that the box with
    corners `corners_m` (8, 3) casts in the light of `node` that can fall on a surface: down to the plane
    z = `lowest_z_m`, and within `box_m` (low, high: a box holding every surface) where the light does not
    shine down past every corner (a spot light below the box's top, a vehicle's headlamp behind a walker:
    the rays over the lamp's height never reach the ground). None when a sun does not shine down, or a
    spot light does not shine down past every corner and no `box_m` is given.

    A sun shining along d moves a corner c to c + λd, λ ∈ [0, λ_ground(c)]; a spot light at L to
    L + κ(c − L), κ ∈ [1, κ_end(c)], κ_end the lesser of where the ray meets the ground (going down) and
    where it leaves `box_m` for good. The volume lies in the union over λ (κ) of the box moved (scaled)
    by it, and that union over an interval [a, b] lies in the hull of the box at a and at b (the box
    moved along a segment, or scaled about L between two factors), cut at the plane (`_above_plane`).
    Cutting the interval into pieces about as long as the box is wide bounds a long shadow by a chain of
    small hulls, not one long diagonal. The hulls of a spot light below the box's top reach out of `box_m`:
    what they bound is their projection's part inside the box's (`_rects_of`)."""
    from pyrender.light import DirectionalLight

    pose = scene.get_pose(node)
    width_m = max(float(np.ptp(corners_m[:, 0])), float(np.ptp(corners_m[:, 1])), 0.1)
    if isinstance(node.light, DirectionalLight):
        d = -pose[:3, 2]  # a light shines along its node's −Z
        if d[2] >= -1e-6:
            return None
        reach = max(float(np.max(corners_m[:, 2] - lowest_z_m)) / -d[2], 0.0)
        pieces = int(min(SHADOW_SLICES_MAX, max(1, math.ceil(reach * math.hypot(d[0], d[1]) / width_m))))
        ends = np.linspace(0.0, reach, pieces + 1)
        hulls = [np.concatenate([corners_m + a * d, corners_m + b * d]) for a, b in itertools.pairwise(ends)]
        return [_above_plane(hull, lowest_z_m) for hull in hulls]
    L = pose[:3, 3]
    centre = (corners_m.min(axis=0) + corners_m.max(axis=0)) / 2
    radius_m = float(np.linalg.norm(corners_m - centre, axis=1).max())
    distance_m = float(np.linalg.norm(centre - L))
    if distance_m > radius_m:  # the box's bounding sphere, seen from the light, wholly outside its cone: no shadow
        off_axis = math.acos(float(np.clip((centre - L) @ -pose[:3, 2] / distance_m, -1.0, 1.0)))
        if off_axis - math.asin(radius_m / distance_m) > _spot_reach_rad(node.light):
            return []
    if L[2] > corners_m[:, 2].max() + 1e-6:
        reach = float(np.max((L[2] - lowest_z_m) / (L[2] - corners_m[:, 2])))
    elif box_m is None:
        return None
    else:
        reach = float(np.max(_ray_ends(L, corners_m, lowest_z_m, box_m)))
    length_m = (reach - 1.0) * float(np.linalg.norm(corners_m - L, axis=1).max())
    pieces = int(min(SHADOW_SLICES_MAX, max(1, math.ceil(length_m / width_m))))
    ends = np.linspace(1.0, max(reach, 1.0), pieces + 1)
    hulls = [np.concatenate([L + a * (corners_m - L), L + b * (corners_m - L)]) for a, b in itertools.pairwise(ends)]
    return [_above_plane(hull, lowest_z_m) for hull in hulls]


def _ray_ends(
    L: np.ndarray, corners_m: np.ndarray, lowest_z_m: float, box_m: tuple[np.ndarray, np.ndarray]
) -> np.ndarray:
    """(N,) for each corner c of `corners_m` (N, 3), the least κ ≥ 1 from which the ray L + κ(c − L) from a light
    at `L` meets no surface: where it meets the plane z = `lowest_z_m` (going down) or leaves the box `box_m`
    (low, high) for good, whichever comes first; at least 1 (a corner outside the box)."""
    low, high = (np.asarray(b, np.float64) for b in box_m)
    d = corners_m - L  # (N, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        leave = np.where(d > 0, (high - L) / d, np.where(d < 0, (low - L) / d, np.inf))  # each slab's far side
        ground = np.where(d[:, 2] < 0, (lowest_z_m - L[2]) / d[:, 2], np.inf)
    return np.maximum(np.minimum(leave.min(axis=1), ground), 1.0)


def _spot_shadow_fov_rad(light) -> float:
    """The field of view, rad, across a spot light's square shadow map: pyrender's shadow camera, 2·outer cone + π/16,
    at most π."""
    return min(2.0 * light.outerConeAngle + math.pi / 16.0, math.pi)


def _spot_reach_rad(light) -> float:
    """The half-angle, rad, within which a spot light can cast a shadow: to the corners of its square shadow map
    (`_spot_shadow_fov_rad` across; its corners √2 times as far off the axis in tangent)."""
    half = _spot_shadow_fov_rad(light) / 2.0
    if half >= math.pi / 2.0 - 1e-9:
        return math.pi / 2.0
    return math.atan(math.sqrt(2.0) * math.tan(half))


def _above_plane(points_m: np.ndarray, z_m: float) -> np.ndarray:
    """Points whose convex hull is the part of the convex hull of `points_m` (N, 3) at or above z = `z_m`:
    those at or above it, and where each segment between two of them crosses it (every edge of the hull
    is such a segment)."""
    above = points_m[:, 2] >= z_m
    i, j = np.nonzero(above[:, None] & ~above[None, :])
    t = (z_m - points_m[i, 2]) / (points_m[j, 2] - points_m[i, 2])
    return np.concatenate([points_m[above], points_m[i] + t[:, None] * (points_m[j] - points_m[i])])


def _rect_intersection(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> tuple[int, int, int, int] | None:
    """The pixels (x0, y0, x1, y1; x1, y1 exclusive) rectangles `a` and `b` share; None when none."""
    x0, y0, x1, y1 = max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def _projected_rect_px(points_m: np.ndarray, view: View, near_m: float) -> tuple[int, int, int, int] | None:
    """The pixels (x0, y0, x1, y1; x1, y1 exclusive) of `view` that the convex hull of `points_m` (N, 3,
    world) can cover, padded by `RECT_PAD_PX`; the hull is clipped at the near plane first (every segment
    between two points crossing it adds its crossing); None when it misses the view."""
    camera = _camera_frame(points_m, view)
    z = camera[:, 2]
    front = camera[z >= near_m]
    i, j = np.nonzero((z[:, None] >= near_m) != (z[None, :] >= near_m))
    keep = i < j
    i, j = i[keep], j[keep]
    t = (near_m - z[i]) / (z[j] - z[i])
    crossings = camera[i] + t[:, None] * (camera[j] - camera[i])
    hull = np.concatenate([front, crossings])
    if len(hull) == 0:
        return None
    u, v = _pinhole_px(hull, view.K_px)
    x0 = max(0, math.floor(u.min()) - RECT_PAD_PX)
    y0 = max(0, math.floor(v.min()) - RECT_PAD_PX)
    x1 = min(view.width_px, math.ceil(u.max()) + RECT_PAD_PX + 1)
    y1 = min(view.height_px, math.ceil(v.max()) + RECT_PAD_PX + 1)
    if x0 >= x1 or y0 >= y1:
        return None
    return x0, y0, x1, y1


def _turned_only(a: View, b: View) -> bool:
    """Whether views `a` and `b` differ by a turn of the camera about its centre of projection alone: the same
    size, camera matrix and centre (a pan or tilt, not a zoom, whose warp would magnify the kept draw)."""
    return (
        (a.width_px, a.height_px) == (b.width_px, b.height_px)
        and np.array_equal(a.K_px, b.K_px)
        and np.array_equal(a.T_world_from_cam[:3, 3], b.T_world_from_cam[:3, 3])
    )


UNCOVERED_BAND_ROWS = 16
"""Rows per band in which `_TurnCanvas.unfilled_rects` bounds what a turn canvas does not hold yet."""


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
