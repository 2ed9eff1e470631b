"""Frames through a head that holds still (`CameraRenderer._still_radiance`): the last frame's radiance is kept
and only what moved since is drawn again, bit for bit the frame drawn alone; motion blur's sub-frames are
drawn only for the movers whose image moves by more than the plan's threshold during the exposure."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer, render_view
from tests.conftest import write
from tests.render.test_moving_regions import SCENE as MOVING_REGIONS_SCENE
from tests.render.test_moving_regions import SMALL_PROFILE

pytestmark = pytest.mark.opengl

ACTORS = """\
actors:
  - name: racer
    class: car
    shape: {type: box, name: body, size_m: [1.6, 0.8, 1.4], position_m: [0, 0, 0.7],
            material: {color_rgb: [0.8, 0.1, 0.1]}}
    path: {waypoints_m: [[-60, 9], [30, 9]], speed_m_s: 30, motion: linear}
  - name: stroller
    class: person
    path: {waypoints_m: [[-3, 12], [3, 12]], speed_m_s: 0.3, motion: linear}
"""
# The moving-regions scene (textured ground and wall, a CIE sky, a sun and a spot light) with a racing car
# and a slow walker, for 3 s, under a higher sun.
_head, _rest = MOVING_REGIONS_SCENE.split("actors:\n")
SCENE = (
    _head.replace("duration_s: 2", "duration_s: 3").replace("elevation_deg: 12", "elevation_deg: 25")
    + ACTORS
    + _rest[_rest.index("outputs:") :]
)
FRAME = 20  # t = 2 s: the racer at x = 0, in front of the camera; at t = 0 it is 60 m to the left, out of view


@pytest.fixture(scope="module")
def job(tmp_path_factory):
    root = tmp_path_factory.mktemp("still_frames")
    write(root, "profiles/fixed.yaml", SMALL_PROFILE)
    job = compile_scene(load_scene(write(root, "scenes/s.yaml", SCENE)), PlanSettings(supersampling=2))
    assert any(stage.name == "optics.motion_blur" for stage in job.cameras[0].stages)
    return job


def _renderer_of(job, renderer):
    return CameraRenderer(renderer, build_scene_graph(job.scene), job.cameras[0])


def _counting(renderer, monkeypatch) -> list:
    """The crop of every radiance draw from now on (None: a whole draw)."""
    crops = []
    draw = renderer.draw

    def counted(graph, view, passes, **options):
        if "radiance" in passes:
            crops.append(options.get("crop_px"))
        return draw(graph, view, passes, **options)

    monkeypatch.setattr(renderer, "draw", counted)
    return crops


def _assert_drawn_from_the_kept_frame_as_alone(job, renderer, monkeypatch, frame, before, alone) -> None:
    """Frame `frame` drawn after the frames `before` is drawn in rectangles only and equals `alone` bit for bit."""
    after = _renderer_of(job, renderer)
    for index in before:
        after.frame(index)
    crops = _counting(renderer, monkeypatch)
    kept = after.frame(frame).passes.radiance
    assert crops and None not in crops, "the frame was drawn from the kept one, in rectangles only"
    np.testing.assert_array_equal(kept, alone)


def test_a_frame_after_others_is_bit_for_bit_the_frame_drawn_alone(job, renderer, monkeypatch):
    alone = _renderer_of(job, renderer).frame(FRAME).passes.radiance
    # A gap: what moved in between is bounded by where it was and is.
    _assert_drawn_from_the_kept_frame_as_alone(job, renderer, monkeypatch, FRAME, [FRAME - 5, FRAME - 1], alone)


def test_a_frame_with_nothing_blurred_is_drawn_finely_and_bit_for_bit_alike(job, renderer, monkeypatch):
    """Early frames (the racer far out of view, the stroller too slow to blur): the base is one draw s× finer,
    and a frame after others, drawn in crops of that draw, is bit for bit the frame drawn alone."""
    camera = job.cameras[0]
    frame = 3
    state = camera.states[frame]
    alone_drawer = _renderer_of(job, renderer)
    assert alone_drawer._blurred_groups(state, render_view(state, camera.render)) == {}
    alone = alone_drawer.frame(frame).passes.radiance
    assert alone_drawer._kept_base.fine
    _assert_drawn_from_the_kept_frame_as_alone(job, renderer, monkeypatch, frame, [frame - 2], alone)


def test_a_changed_light_draws_the_frame_whole(job, renderer, monkeypatch):
    first = _renderer_of(job, renderer)
    first.frame(FRAME - 1)
    sun = next(node for node in first.graph.scene.light_nodes if type(node.light).__name__ == "DirectionalLight")
    sun.light.intensity *= 0.5
    crops = _counting(renderer, monkeypatch)
    dimmed = first.frame(FRAME).passes.radiance
    assert None in crops, "a kept frame under another light is not reused"
    fresh = _renderer_of(job, renderer)
    fresh_sun = next(n for n in fresh.graph.scene.light_nodes if type(n.light).__name__ == "DirectionalLight")
    fresh_sun.light.intensity *= 0.5
    np.testing.assert_array_equal(dimmed, fresh.frame(FRAME).passes.radiance)


def test_only_the_fast_mover_gets_sub_frames_and_only_while_it_is_in_view(job, renderer):
    drawer = _renderer_of(job, renderer)
    camera = job.cameras[0]
    racer, stroller = (drawer.graph.moving_nodes.index(node) for node in drawer.graph.actor_nodes)
    state = camera.states[FRAME]
    groups = drawer._blurred_groups(state, render_view(state, camera.render))
    assert {k for nodes in groups.values() for k in nodes} == {racer}
    # 30 m/s over the 20 ms exposure is 0.6 m at about 12 m: several pixels, each sub-frame ≤ 1 px apart;
    # its shadow, stretched away from the 25° sun, sweeps farther (the plan's bound counts the car alone).
    assert drawer.motion_samples(state) >= 3
    start = camera.states[0]
    assert drawer.motion_samples(start) == 1  # the racer is 60 m to the left
    assert drawer._plan_samples(start) > 1  # the plan's bound holds for the whole sequence
    assert stroller not in {k for nodes in groups.values() for k in nodes}


def test_a_metering_frame_is_drawn_sharp(job, renderer):
    """`sharp`: the frame that auto-exposure meters (at the profile's guessed exposure) draws no sub-frame;
    it is the frame of the camera planned without motion blur."""
    camera = job.cameras[0]
    stages = tuple(s for s in camera.stages if s.name != "optics.motion_blur")
    sharp_camera = camera.model_copy(update={"stages": stages})
    metered = _renderer_of(job, renderer).frame(FRAME, sharp=True).passes.radiance
    blurred = _renderer_of(job, renderer).frame(FRAME).passes.radiance
    without = CameraRenderer(renderer, build_scene_graph(job.scene), sharp_camera).frame(FRAME).passes.radiance
    np.testing.assert_array_equal(metered, without)
    assert np.abs(blurred - metered).max() > 0.05 * metered.max()  # the racer is smeared in the blurred one


def _with_geometry(job):
    """The job's camera drawing depth_m and instance_id besides radiance."""
    camera = job.cameras[0]
    render = camera.render.model_copy(update={"passes": ("radiance", "depth_m", "instance_id")})
    return camera.model_copy(update={"render": render})


def _geometric_crops(renderer, monkeypatch) -> list:
    """The crop of every draw of depth and ids alone from now on (None: a whole draw)."""
    crops = []
    draw = renderer.draw

    def counted(graph, view, passes, **options):
        if "radiance" not in passes:
            crops.append(options.get("crop_px"))
        return draw(graph, view, passes, **options)

    monkeypatch.setattr(renderer, "draw", counted)
    return crops


def test_depth_and_ids_after_other_frames_are_bit_for_bit_those_drawn_alone(job, renderer, monkeypatch):
    """The geometric passes of a frame after others are the kept ones with the rectangles of what moved drawn again
    (`CameraRenderer._geometry`): bit for bit the frame's drawn alone, and each rectangle is needed (leaving out
    the largest leaves stale pixels)."""
    camera = _with_geometry(job)
    alone = CameraRenderer(renderer, build_scene_graph(job.scene), camera).frame(FRAME).passes
    assert np.isfinite(alone.depth_m).any() and len(np.unique(alone.instance_id)) > 2  # ground, wall, movers

    def after_others(drop_largest: bool):
        drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
        for index in (FRAME - 5, FRAME - 1):
            drawer.frame(index)
        if drop_largest:
            rects_of = drawer._geometry_rects

            def fewer(*args):
                rects = rects_of(*args)
                largest = max(rects, key=lambda r: (r[2] - r[0]) * (r[3] - r[1]))
                return [r for r in rects if r != largest]

            monkeypatch.setattr(drawer, "_geometry_rects", fewer)
        with monkeypatch.context() as patched:
            crops = _geometric_crops(renderer, patched)
            passes = drawer.frame(FRAME).passes
        return passes, crops

    kept, crops = after_others(drop_largest=False)
    assert crops and None not in crops, "depth and ids were drawn from the kept frame's, in rectangles only"
    np.testing.assert_array_equal(kept.depth_m, alone.depth_m)
    np.testing.assert_array_equal(kept.instance_id, alone.instance_id)
    stale, _ = after_others(drop_largest=True)
    assert not np.array_equal(stale.instance_id, alone.instance_id)


def test_depth_and_ids_through_a_moved_view_are_drawn_whole(job, renderer, monkeypatch):
    camera = _with_geometry(job)
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    drawer.frame(FRAME - 1)
    state = camera.states[FRAME]
    T = np.array(state.T_world_from_cam)
    T[0, 3] += 0.5  # the camera half a metre to the side
    moved = state.model_copy(update={"T_world_from_cam": tuple(map(tuple, T))})
    crops = _geometric_crops(renderer, monkeypatch)
    passes = drawer.frame(FRAME, moved).passes
    assert crops == [None]
    fresh = CameraRenderer(renderer, build_scene_graph(job.scene), camera).frame(FRAME, moved).passes
    np.testing.assert_array_equal(passes.depth_m, fresh.depth_m)
    np.testing.assert_array_equal(passes.instance_id, fresh.instance_id)
