"""A spot light low down (a headlamp, 0.6 m up) casts shadows only within its cone: a mover outside the cone
keeps its moving regions (`CameraRenderer.moving_rects_px`), where a light not above a moving box used to send
every sub-frame to be drawn whole, and the composited frame still equals every sub-frame drawn whole. The
moving-regions scene (tests/render/test_moving_regions.py) with a low lamp aimed away from the mover."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render import sequence
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer, jittered_samples, render_view
from tests.conftest import write
from tests.render.test_moving_regions import FRAME, SCENE, SMALL_PROFILE

pytestmark = pytest.mark.opengl

LOW_LAMP = (
    "  - {type: spot, intensity_cd: 20000, position_m: [0, 12, 0.6], target_m: [0, 22, 0.2], cone_half_angle_deg: 25}\n"
)
"""0.6 m up, 3 m beyond the mover's lane (y = 9), aimed away from it along +y: the mover, 1.4 m tall, stands above
it, and behind it, outside its cone."""


@pytest.fixture(scope="module")
def low_lamp(renderer, tmp_path_factory):
    root = tmp_path_factory.mktemp("spot_cone")
    write(root, "profiles/fixed.yaml", SMALL_PROFILE)
    text = SCENE.replace("lights:\n", "lights:\n" + LOW_LAMP, 1)
    job = compile_scene(load_scene(write(root, "scenes/s.yaml", text)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    graph = build_scene_graph(job.scene)
    return camera, graph, CameraRenderer(renderer, graph, camera)


def test_a_mover_outside_a_low_lamps_cone_keeps_its_moving_regions(low_lamp, renderer):
    camera, graph, composited = low_lamp
    state = camera.states[FRAME]
    view = render_view(state, camera.render)
    samples = composited.motion_samples(state)
    assert samples > 4
    offsets = [t for t, _, _ in jittered_samples(samples, camera.render.supersampling)]
    rects = composited.moving_rects_px(state, view, offsets, composited.shadow_fit(view))
    assert rects, rects  # None before: the lamp is not above the mover, so it could not be bounded
    fast = composited.frame(FRAME).passes.radiance
    reference = CameraRenderer(renderer, graph, camera, moving_regions=False).frame(FRAME).passes.radiance
    assert np.abs(fast - reference).max() <= 1e-5 * reference.max()


AIMED_LAMP = (
    "  - {type: spot, intensity_cd: 20000, position_m: [-4, 4, 0.6], target_m: [2, 9, 0.6], cone_half_angle_deg: 30}\n"
)
"""A headlamp's height, 0.6 m up, aimed across the mover's lane (y = 9) at the wall behind it (y = 16): the mover,
1.4 m tall, stands in its cone, above it, and throws its shadow up the wall and over it."""


def test_a_mover_in_a_low_lamps_cone_is_bounded_by_the_surfaces(renderer, tmp_path, monkeypatch):
    """Inside the cone, the rays over the lamp's height never reach the ground: the mover's shadow volume is
    bounded by the box that holds every surface (`_shadow_slices`' `box_m`), and the composited frame still
    equals every sub-frame drawn whole (the shadow on the wall included). Without that box it could not be
    bounded, and every sub-frame was drawn whole."""
    write(tmp_path, "profiles/fixed.yaml", SMALL_PROFILE)
    text = SCENE.replace("lights:\n", "lights:\n" + AIMED_LAMP, 1)
    job = compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", text)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    graph = build_scene_graph(job.scene)
    composited = CameraRenderer(renderer, graph, camera)
    state = camera.states[FRAME]
    view = render_view(state, camera.render)
    offsets = [t for t, _, _ in jittered_samples(composited.motion_samples(state), camera.render.supersampling)]
    rects = composited.moving_rects_px(state, view, offsets, composited.shadow_fit(view))
    assert rects, rects
    fast = composited.frame(FRAME).passes.radiance
    reference = CameraRenderer(renderer, graph, camera, moving_regions=False).frame(FRAME).passes.radiance
    assert np.abs(fast - reference).max() <= 1e-5 * reference.max()
    real = sequence._shadow_slices
    monkeypatch.setattr(
        sequence, "_shadow_slices", lambda scene, node, corners, z, box=None: real(scene, node, corners, z)
    )
    assert composited.moving_rects_px(state, view, offsets, composited.shadow_fit(view)) is None
