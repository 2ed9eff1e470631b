"""A 1× draw that stands for s × s samples of a pixel (motion blur's jittered sub-frames) samples textures at
the level of detail of the s× draw it replaces (`Renderer.draw(texture_lod_bias=-log2 s)`): the mean of the
s² jittered draws then matches the supersampled frame, where it was a mip level blurrier."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.sequence import box_downsample, jittered_samples, shifted
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

S = 2


@pytest.fixture(scope="module")
def draws(renderer):
    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(
        scene_from(
            environment={
                "sky_luminance_cd_m2": 2000,
                "meshes": [
                    {
                        "type": "plane",
                        "name": "ground",
                        "size_m": [40.0, 40.0],
                        "material": {"color_rgb": [0.4, 0.4, 0.38], "texture": {"type": "paving", "seed": 3}},
                    }
                ],
            },
            lights=[{"type": "ambient", "illuminance_lux": 10000}],
        )
    )
    view = View(camera_matrix(200.0, 200.0, 79.5, 59.5), look_at((0.0, 0.0, 1.5), (0.0, 6.0, 0.0)), 160, 120)
    supersampled = box_downsample(renderer.draw(graph, view.scaled(S), ("radiance",)).radiance, S)
    jitters = jittered_samples(S * S, S)

    def jittered_mean(bias: float) -> np.ndarray:
        drawn = [
            renderer.draw(graph, shifted(view, dx, dy), ("radiance",), texture_lod_bias=bias).radiance
            for _, dx, dy in jitters
        ]
        return np.mean(drawn, axis=0)

    ground = np.zeros((120, 160), bool)
    ground[70:, :] = True  # below the horizon: textured ground only
    return supersampled[ground], jittered_mean(-np.log2(S))[ground], jittered_mean(0.0)[ground]


def relative_p99(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.percentile(np.abs(a - b).max(axis=-1) / np.maximum(b.max(axis=-1), 1e-6), 99))


def test_jittered_draws_with_the_bias_match_the_supersampled_frame(draws):
    supersampled, biased, unbiased = draws
    with_bias, without = relative_p99(biased, supersampled), relative_p99(unbiased, supersampled)
    print(f"99th percentile relative difference: {with_bias:.4f} with the bias, {without:.4f} without")
    assert with_bias < 0.5 * without
    assert with_bias < 0.05
