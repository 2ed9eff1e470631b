"""A plane textured from image files (`FileTexture`): the rendered radiance of a texel against
E·ρ/π with ρ the texel's decoded sRGB value, the image repeated every tile_m with its top along +v, the
colour rescaled to color_rgb, and a normal map tilting the shading as n·l says."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.scene_graph import _box_faces, build_scene_graph
from tests.render.conftest import camera_matrix, scene_from

pytestmark = pytest.mark.opengl

BLOCK_TEXELS = 16
AMBIENT_LUX = 1000.0
CODES = np.array(  # 2 rows × 4 columns of 8-bit sRGB colours, row 0 the image's top
    [
        [(200, 40, 30), (30, 190, 60), (20, 60, 210), (128, 128, 128)],
        [(250, 250, 250), (90, 20, 120), (5, 5, 5), (160, 110, 40)],
    ],
    dtype=np.uint8,
)


def _srgb_to_linear(code: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1, written out here rather than taken from camgen."""
    x = np.asarray(code, dtype=np.float64) / 255.0
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def _blocks(values: np.ndarray) -> np.ndarray:
    return np.kron(values, np.ones((BLOCK_TEXELS, BLOCK_TEXELS, 1))).astype(values.dtype)


def _write_rgb(path: Path, rgb: np.ndarray) -> None:
    cv2.imwrite(str(path), np.ascontiguousarray(rgb[..., ::-1]))


def _overhead(width=640, height=480, f_px=60.0):
    """Straight down from 10 m: image x = world x, image y = world −y, f_px / 10 pixels a metre."""
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (0.0, 0.0, 10.0)
    view = View(camera_matrix(f_px, f_px, (width - 1) / 2, (height - 1) / 2), T, width, height)

    def pixel(x_m, y_m):
        return round((height - 1) / 2 - f_px / 10 * y_m), round((width - 1) / 2 + f_px / 10 * x_m)

    return view, pixel


def _plane(texture: dict, lights: list, color=None, size_m=(8.0, 8.0)):
    material = {"texture": texture, "roughness": 1.0}
    if color is not None:
        material["color_rgb"] = color
    return scene_from(
        environment={
            "ground_to_horizon": False,
            "meshes": [{"type": "plane", "name": "g", "size_m": list(size_m), "material": material}],
        },
        lights=lights,
    )


def test_texels_render_as_e_rho_over_pi_repeated_every_tile(renderer, tmp_path: Path):
    _write_rgb(tmp_path / "colour.png", _blocks(CODES))  # 64 × 32 texels
    tile_w, tile_h = 4.0, 2.0  # the image's aspect ratio: tile_m 4 alone gives the same
    rho = _srgb_to_linear(CODES)
    view, pixel = _overhead()
    for tile_m in (tile_w, [tile_w, tile_h]):
        scene = _plane(
            {"type": "file", "base_color_file": "colour.png", "tile_m": tile_m},
            [{"type": "ambient", "illuminance_lux": AMBIENT_LUX}],
        )
        radiance = renderer.draw(build_scene_graph(scene, tmp_path.joinpath), view, ("radiance",)).radiance
        # The plane's corner (−4, −4) is the tiles' origin; row r, column c of the image covers
        # u ∈ [c, c + 1]·w/4 and v ∈ [1 − (r + 1)/2, 1 − r/2]·h of each tile: the top row along +v.
        for repeat_x, repeat_y in ((0, 0), (1, 0), (0, 3), (1, 2)):
            for r in range(2):
                for c in range(4):
                    x = -4.0 + repeat_x * tile_w + (c + 0.5) * tile_w / 4
                    y = -4.0 + repeat_y * tile_h + (1 - (r + 0.5) / 2) * tile_h
                    expected = rho[r, c] * AMBIENT_LUX / math.pi
                    np.testing.assert_allclose(radiance[pixel(x, y)][:3], expected, rtol=0.01, atol=0.02)


def test_color_rgb_rescales_the_images_mean(renderer, tmp_path: Path):
    _write_rgb(tmp_path / "colour.png", _blocks(CODES))
    rho = _srgb_to_linear(CODES)
    wanted = np.array([0.1, 0.2, 0.3])
    scene = _plane(
        {"type": "file", "base_color_file": "colour.png", "tile_m": 4.0},
        [{"type": "ambient", "illuminance_lux": AMBIENT_LUX}],
        color=wanted.tolist(),
    )
    view, pixel = _overhead()
    radiance = renderer.draw(build_scene_graph(scene, tmp_path.joinpath), view, ("radiance",)).radiance
    expected = rho[0, 0] * wanted / rho.reshape(-1, 3).mean(axis=0) * AMBIENT_LUX / math.pi
    # 8-bit storage of the rescaled colour: a code is 0.4–1 % of its value at these levels.
    np.testing.assert_allclose(radiance[pixel(-3.5, -2.5)][:3], expected, rtol=0.02)


def _brdf_radiance(n, to_light, v, rho, e_lux, roughness=1.0, f0=0.04):
    """Lambert ρ/π plus GGX D, Schlick–Smith G (k = (r + 1)²/8) and Schlick F over 4 n·l n·v (glTF 2.0's
    metallic-roughness BRDF as pyrender writes it), times E n·l."""
    nl, nv = max(float(n @ to_light), 0.0), max(float(n @ v), 0.001)
    if nl == 0.0:
        return 0.0
    h = (to_light + v) / np.linalg.norm(to_light + v)
    nh, vh = max(float(n @ h), 0.0), max(float(v @ h), 0.0)
    k = (roughness + 1) ** 2 / 8
    a2 = roughness**4
    distribution = a2 / (math.pi * (nh * nh * (a2 - 1) + 1) ** 2)
    shadowing = nv / (nv * (1 - k) + k) * nl / (nl * (1 - k) + k)
    fresnel = f0 + (1 - f0) * (1 - vh) ** 5
    return e_lux * nl * (rho / math.pi + fresnel * shadowing * distribution / (4 * nl * nv + 0.001))


def test_a_normal_map_tilts_the_shading_as_n_dot_l(renderer, tmp_path: Path):
    tilt = math.radians(30)
    s, c = math.sin(tilt), math.cos(tilt)
    # Surface-frame normals (u, v, out), the OpenGL convention: +u right, +v up the image.
    normals = np.array([[(s, 0, c), (-s, 0, c), (0, 0, 1)], [(0, s, c), (0, -s, c), (0, 0, 1)]])
    codes = np.round((normals * 0.5 + 0.5) * 255).astype(np.uint8)
    _write_rgb(tmp_path / "normal.png", _blocks(codes))
    stored = 2.0 * codes / 255.0 - 1.0  # the normals as 8 bits hold them (0.4 % off: 3 % of a dim n·l)
    stored /= np.linalg.norm(stored, axis=2, keepdims=True)
    _write_rgb(tmp_path / "white.png", np.full((2 * BLOCK_TEXELS, 3 * BLOCK_TEXELS, 3), 225, np.uint8))
    e_lux, azimuth, elevation = 10000.0, math.radians(45), math.radians(30)
    sun = {"type": "sun", "illuminance_lux": e_lux, "azimuth_deg": 45, "elevation_deg": 30}
    texture = {"type": "file", "base_color_file": "white.png", "normal_file": "normal.png", "tile_m": 6.0}
    scene = _plane(texture, [sun], size_m=(6.0, 4.0))  # one tile: u = x + 3, v = y + 2
    view, pixel = _overhead()
    radiance = renderer.draw(build_scene_graph(scene, tmp_path.joinpath), view, ("radiance",)).radiance
    rho = _srgb_to_linear(np.array(225))
    to_sun = np.array(
        [math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth), math.sin(elevation)]
    )
    for r in range(2):
        for col in range(3):
            x, y = -3.0 + (col + 0.5) * 2.0, 2.0 - (r + 0.5) * 2.0
            v = np.array([-x, -y, 10.0]) / math.hypot(x, y, 10.0)
            expected = _brdf_radiance(stored[r, col], to_sun, v, float(rho), e_lux)
            assert radiance[pixel(x, y)][1] == pytest.approx(expected, rel=0.005), (r, col)
    # Tilted towards the sun (+u and +v: it lies at azimuth 45°) is brighter than flat, away darker.
    flat = radiance[pixel(2.0, 1.0)][1]
    assert radiance[pixel(-2.0, 1.0)][1] > 1.3 * flat > 1.3 * radiance[pixel(0.0, 1.0)][1]


def test_every_box_face_shows_its_texture_unmirrored():
    """(∂p/∂u × ∂p/∂v)·n > 0 on each face: u, v and the outward normal right-handed, so an image reads as
    it does in a viewer and a normal map's +v is the shader's bitangent (normal × tangent)."""
    positions, normals, uv_m, faces = _box_faces((2.0, 3.0, 4.0))
    for face in faces:
        p, uv = positions[face], uv_m[face]
        # Solve p − p0 = J (uv − uv0) for J = [∂p/∂u ∂p/∂v] on this triangle.
        J = (p[1:] - p[0]).T @ np.linalg.inv((uv[1:] - uv[0]).T)
        assert np.cross(J[:, 0], J[:, 1]) @ normals[face[0]] > 0.99


def test_far_ground_and_nir_take_the_files_texels(tmp_path: Path):
    """The ground continued to the horizon takes the image's decoded mean (what the mipmaps average it to
    far away) and the roughness map's; the NIR pass applies its rule to each texel (no type to look up)."""
    from camgen.config.scene import Material
    from camgen.render.nir import material_nir_reflectance
    from camgen.render.scene_graph import far_ground

    _write_rgb(tmp_path / "colour.png", _blocks(CODES))
    cv2.imwrite(str(tmp_path / "rough.png"), np.full((2 * BLOCK_TEXELS, 4 * BLOCK_TEXELS), 153, np.uint8))
    texture = {"type": "file", "base_color_file": "colour.png", "roughness_file": "rough.png", "tile_m": 4.0}
    scene = _plane(texture, [{"type": "ambient", "illuminance_lux": AMBIENT_LUX}], size_m=(20.0, 20.0))
    scene = scene.model_copy(update={"environment": scene.environment.model_copy(update={"ground_to_horizon": True})})
    ground = far_ground(scene, tmp_path.joinpath)
    np.testing.assert_allclose(ground.reflectance_rgb, _srgb_to_linear(CODES).reshape(-1, 3).mean(axis=0), rtol=1e-5)
    assert ground.roughness == pytest.approx(0.6)
    assert material_nir_reflectance(Material.model_validate({"texture": texture})) is None
