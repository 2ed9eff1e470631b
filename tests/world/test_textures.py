"""Procedural surface textures: the sizes and reflectances they cite, tiles without seams, the same
seed the same surface, and a textured surface as bright on average as its plain colour."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.textures import (
    DEFAULT_TILE_M,
    TEXTURE_TYPES,
    TYPICAL_ALBEDO_RGB,
    encode_srgb8,
    fbm,
    surface_maps,
)

TEXELS = 256  # small tiles keep the tests fast; the patterns' sizes are in metres, not texels


@pytest.mark.parametrize("kind", TEXTURE_TYPES)
def test_maps_are_reproducible_bounded_and_seamless(kind):
    a, b = surface_maps(kind, 7, texels=TEXELS), surface_maps(kind, 7, texels=TEXELS)
    assert np.array_equal(a.albedo, b.albedo)
    assert not np.array_equal(a.albedo, surface_maps(kind, 8, texels=TEXELS).albedo)
    assert a.albedo.shape == (TEXELS, TEXELS, 3) and np.all(a.albedo >= 0)
    assert np.all((a.roughness >= 0) & (a.roughness <= 1)) and a.tile_m == DEFAULT_TILE_M[kind]
    # A tile repeats: across its edge the albedo changes no more than across the pattern's own edges
    # (a joint, a window frame) or between neighbouring texels inside it.
    grey = a.albedo.mean(axis=2)
    for axis in (0, 1):
        inner = np.abs(np.diff(grey, axis=axis)).mean(axis=1 - axis)
        across = np.abs(np.take(grey, 0, axis=axis) - np.take(grey, -1, axis=axis)).mean()
        assert across <= 1.1 * inner.max() + 0.01, (axis, across, inner.max())


def test_fbm_is_normalised_and_periodic():
    noise = fbm(np.random.default_rng(1), 128, 5, 4)
    assert abs(noise.mean()) < 1e-5 and noise.std() == pytest.approx(1.0, abs=1e-4)
    assert np.abs(noise[:, 0] - noise[:, -1]).mean() < 2 * np.abs(np.diff(noise, axis=1)).mean()


def test_bricks_and_slabs_have_their_standard_sizes():
    # Brick courses: 65 mm brick + 10 mm joint = 75 mm (BS EN 771-1); along a course 215 + 10 = 225 mm.
    maps = surface_maps("brick", 0, tile_m=2.0, texels=720)  # 2.5 mm per texel
    assert maps.tile_m == pytest.approx(1.8)  # rounded to 4 × 0.45 m: whole bricks and courses
    joint = maps.albedo[..., 2] > 1.5  # grey mortar is far bluer than red brick
    rows = joint.mean(axis=1) > 0.5
    starts = np.flatnonzero(np.diff(rows.astype(int)) == 1)
    assert np.median(np.diff(starts)) * maps.tile_m / 720 == pytest.approx(0.075, abs=0.003)
    # Paving flags: joints every 0.4 m (BS 7263).
    paving = surface_maps("paving", 0, tile_m=4.0, texels=800).albedo[..., 0]
    dark_columns = np.flatnonzero(paving.mean(axis=0) < 0.8)
    groups = dark_columns[np.concatenate([[True], np.diff(dark_columns) > 1])]
    assert np.median(np.diff(groups)) * 4.0 / 800 == pytest.approx(0.4, abs=0.01)


def test_facade_windows_cover_their_share_of_the_wall():
    maps = surface_maps("facade", 0, texels=480)  # 12 m: four storeys, four window bays
    glass = maps.roughness < 0.1
    # 1.2 m × 1.5 m panes less a 6 cm frame, one per 3 m × 3 m bay.
    expected = (1.2 - 0.12) * (1.5 - 0.12) / 9.0
    assert glass.mean() == pytest.approx(expected, rel=0.08)
    assert maps.albedo[glass].mean() < 0.3 * maps.albedo[~glass & (maps.roughness > 0.5)].mean()


def test_typical_reflectances_are_physical():
    for kind, rgb in TYPICAL_ALBEDO_RGB.items():
        assert all(0.02 <= c <= 0.5 for c in rgb), kind
    assert TYPICAL_ALBEDO_RGB["asphalt"][0] < TYPICAL_ALBEDO_RGB["concrete"][0]  # asphalt is the darker


def test_srgb_encoding_round_trips():
    linear = np.linspace(0, 1, 1001)
    code = encode_srgb8(linear).astype(float) / 255
    decoded = np.where(code <= 0.04045, code / 12.92, ((code + 0.055) / 1.055) ** 2.4)
    assert np.abs(decoded - linear).max() < 0.01


SUN_ELEVATION_DEG = 35.0


@pytest.mark.opengl
@pytest.mark.parametrize("sunlit", [False, True], ids=["sky", "sun-and-sky"])
def test_a_textured_surface_reflects_its_mean_colour(renderer, sunlit):
    """An overhead view of asphalt, textured and plain, of the same colour: equal mean radiance, and both
    the Lambertian ρ/π·(E_sun·sin h + E_sky) plus a rough dielectric's small specular lobe. Under the sun
    this catches a metallic-roughness map read from the wrong channels (glTF: roughness G, metalness B):
    read as pyrender reads it, the asphalt was a polished metal at 0.30 of its radiance."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    lights = [{"type": "ambient", "illuminance_lux": 10000}]
    if sunlit:
        lights.append({"type": "sun", "illuminance_lux": 60000, "elevation_deg": SUN_ELEVATION_DEG})
    means = []
    for texture in (None, {"type": "asphalt", "seed": 3}):
        material = {"color_rgb": [0.12, 0.12, 0.12], "roughness": 0.9}
        if texture:
            material["texture"] = texture
        graph = build_scene_graph(
            scene_from(
                environment={
                    "meshes": [{"type": "plane", "name": "g", "size_m": [16, 16], "material": material}],
                    "shadows": False,
                },
                lights=lights,
            )
        )
        view = View(camera_matrix(400, 400, 199.5, 199.5), look_at((0, 0, 8), (0, 0, 0)), 400, 400)
        means.append(renderer.draw(graph, view, ("radiance",)).radiance.mean())
    assert means[1] == pytest.approx(means[0], rel=0.03)
    lambert = 0.12 / math.pi * (10000 + (60000 * math.sin(math.radians(SUN_ELEVATION_DEG)) if sunlit else 0))
    assert lambert <= means[0] <= 1.15 * lambert
