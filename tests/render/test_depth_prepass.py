"""A lit draw's depth pre-pass (`_PassRenderer.forward`, `_depth_prepass`): the opaque primitives' depth is drawn
first, then each pixel is shaded once, by the first primitive drawn at its final depth. Every pass of every kind
of draw is bit for bit the draw without it (`depth_prepass` False): whole, cropped, over a kept background,
through a mirrored view, with glass; where two surfaces lie at exactly the same depth the first drawn still wins."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

WIDTH_PX, HEIGHT_PX, F_PX = 240, 160, 200.0
PASSES = ("radiance", "depth_m", "instance_id")
TWIN = {"type": "box", "size_m": [1.0, 1.0, 1.5], "position_m": [2.5, 1.0, 0.75]}


@pytest.fixture(scope="module")
def graph():
    """Textured ground and wall, a sedan (glass, clear coat), two boxes of the same size and place, the red one
    listed first, and an actor's box there too (a moving node, drawn after them), under a sun that casts
    shadows and the sky."""
    environment = {
        "sky": "clear",
        "meshes": [
            {"type": "plane", "name": "ground", "size_m": [30, 30],
             "material": {"color_rgb": [0.3] * 3, "texture": {"type": "asphalt", "seed": 1}}},
            {"type": "box", "name": "wall", "size_m": [12, 0.4, 3], "position_m": [0, 6, 1.5],
             "material": {"color_rgb": [0.6] * 3, "texture": {"type": "brick", "seed": 2}}},
            {**TWIN, "name": "red_twin", "material": {"color_rgb": [0.8, 0.1, 0.1]}},
            {**TWIN, "name": "blue_twin", "material": {"color_rgb": [0.1, 0.1, 0.8]}},
        ],
    }  # fmt: skip
    vehicle = {"seed": 3, "body_type": "sedan", "colour": "white", "driver": True}
    scene = scene_from(
        environment=environment,
        lights=[
            {"type": "ambient", "illuminance_lux": 15000},
            {"type": "sun", "illuminance_lux": 60000, "elevation_deg": 35, "azimuth_deg": 200},
        ],
        actors=[
            {"name": "car", "class": "car", "vehicle": vehicle, "path": {"waypoints_m": [[-1.0, 1.0]]}},
            {
                "name": "green_twin",
                "class": "car",
                "path": {"waypoints_m": [TWIN["position_m"][:2]]},
                "shape": {
                    **TWIN,
                    "name": "body",
                    "position_m": [0, 0, TWIN["position_m"][2]],
                    "material": {"color_rgb": [0.1, 0.8, 0.1]},
                },
            },
        ],
    )
    graph = build_scene_graph(scene)
    graph.place_actors(0.0)
    return graph


def _view(mirrored: bool = False) -> View:
    T = look_at((0.5, -7.0, 2.5), (0.5, 1.0, 0.8))
    if mirrored:  # an improper pose, as the wet ground's mirror has (`camgen.render.wet`)
        T = T @ np.diag([-1.0, 1.0, 1.0, 1.0])
    K = camera_matrix(F_PX, F_PX, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2)
    return View(K, T, WIDTH_PX, HEIGHT_PX)


def _both(renderer, draw):
    """`draw()`'s passes and the target's coverage, with the pre-pass and without."""
    out, default = {}, renderer._renderer.depth_prepass
    for prepass in (True, False):
        renderer._renderer.depth_prepass = prepass
        try:
            out[prepass] = draw()
        finally:
            renderer._renderer.depth_prepass = default
    return out[True], out[False]


def test_the_prepass_is_on_for_llvmpipe_only(renderer):
    """Measured there (bit for bit and cheaper); a GPU culls hidden fragments itself (`_PassRenderer.depth_prepass`)."""
    assert renderer._renderer.depth_prepass == ("llvmpipe" in renderer.gl_renderer)


def _assert_same(with_prepass, without) -> None:
    for name in PASSES:
        a, b = getattr(with_prepass, name), getattr(without, name)
        if a is not None or b is not None:
            np.testing.assert_array_equal(a, b, err_msg=name)


@pytest.mark.parametrize("mirrored", [False, True])
def test_a_whole_draw_is_bit_for_bit_the_draw_without_a_prepass(renderer, graph, mirrored):
    view = _view(mirrored)
    with_prepass, without = _both(renderer, lambda: renderer.draw(graph, view, PASSES, clip_range_m=(0.1, 60.0)))
    _assert_same(with_prepass, without)
    ids = {graph.instance_ids[node]: node.name for node in graph.scene.mesh_nodes}
    seen = {ids.get(int(i)) for i in np.unique(with_prepass.instance_id)}
    # The twins tie at every pixel they cover: the first drawn (red) wins there, as the depth test alone keeps it.
    assert "environment:red_twin" in seen and not {"environment:blue_twin", "actor:green_twin"} & seen
    assert "actor:car" in seen
    assert np.isfinite(with_prepass.radiance).all()


def test_a_cropped_draw_and_one_over_a_kept_background_are_bit_for_bit(renderer, graph):
    view = _view()
    clip = (0.1, 60.0)
    crop = (37, 29, 181, 133)
    cropped = _both(renderer, lambda: renderer.draw(graph, view, PASSES, clip_range_m=clip, crop_px=crop))
    _assert_same(*cropped)
    whole = renderer.draw(graph, view, PASSES, clip_range_m=clip)
    x0, y0, x1, y1 = crop
    np.testing.assert_array_equal(cropped[0].radiance, whole.radiance[y0:y1, x0:x1])

    def composited():
        renderer.draw(graph, view, PASSES, nodes=graph.environment_nodes, keep_as="prepass test", read=False,
                      clip_range_m=clip)  # fmt: skip
        return renderer.draw(graph, view, PASSES, nodes=graph.actor_nodes, background="prepass test", clip_range_m=clip)

    try:
        over_kept = _both(renderer, composited)
    finally:
        renderer.forget("prepass test")
    _assert_same(*over_kept)
    _assert_same(over_kept[0], whole)  # the kept background keeps what it drew where the green twin ties with it
