"""Normal maps and file textures' maps (`camgen.world.textures`): the normals of a height field against
its derivative in closed form, the joints' relief of paving and brick, and a file's decoding."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.textures import JOINT_DEPTH_M, file_surface_maps, normal_map_from_height, surface_maps


def test_normals_of_a_sinusoidal_height_follow_its_slope():
    texels, m_per_texel, amplitude_m = 256, 0.002, 0.001
    u = np.arange(texels) * m_per_texel
    omega = 2 * math.pi * 4 / (texels * m_per_texel)  # 4 periods: the tile wraps without a seam
    height = np.tile(amplitude_m * np.sin(omega * u), (texels, 1))  # varies along u (columns) only
    normal = normal_map_from_height(height, m_per_texel)
    slope = amplitude_m * omega * np.cos(omega * u)
    expected_u = -slope / np.sqrt(1 + slope**2)
    np.testing.assert_allclose(normal[0, :, 0], expected_u, atol=2e-3 * np.abs(expected_u).max())
    np.testing.assert_allclose(normal[..., 1], 0.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=2), 1.0, atol=1e-5)
    # Along v (rows) the same field transposed gives the same normals in the v component.
    along_v = normal_map_from_height(height.T, m_per_texel)
    np.testing.assert_allclose(along_v[:, 0, 1], expected_u, atol=2e-3 * np.abs(expected_u).max())


@pytest.mark.parametrize("kind", ["paving", "brick"])
def test_recessed_joints_tilt_their_edges_towards_the_joint(kind):
    maps = surface_maps(kind, 0, texels=512)
    assert maps.normal is not None and maps.normal.shape == (512, 512, 3)
    assert np.all(maps.normal[..., 2] > 0.5)  # 3 mm joints: edges tilted well under 60°
    tilted = np.hypot(maps.normal[..., 0], maps.normal[..., 1]) > 0.05
    assert 0.02 < tilted.mean() < 0.5  # the joints' edges, not the faces
    assert surface_maps("asphalt", 0, texels=64).normal is None
    assert JOINT_DEPTH_M[kind] == pytest.approx(0.003)


def test_a_file_base_colour_is_decoded_and_rescaled():
    codes = np.array([[[0, 128, 255], [64, 192, 32]]], dtype=np.float64) / 255  # 1 × 2 texels
    linear = np.where(codes <= 0.04045, codes / 12.92, ((codes + 0.055) / 1.055) ** 2.4)
    maps = file_surface_maps(codes, 3.0)
    np.testing.assert_allclose(maps.reflectance, linear, rtol=1e-6)
    assert maps.tile_m == (3.0, 1.5) and maps.normal is None and maps.roughness is None
    scaled = file_surface_maps(codes, (3.0, 2.0), mean_rgb=(0.2, 0.1, 0.3))
    np.testing.assert_allclose(scaled.reflectance.reshape(-1, 3).mean(axis=0), (0.2, 0.1, 0.3), rtol=1e-6)
    assert scaled.tile_m == (3.0, 2.0)
    packed = np.full((1, 2, 3), (0.5, 1.0, 0.5))  # +v, at 90° (quantised files never pack exactly this)
    np.testing.assert_allclose(file_surface_maps(codes, 1.0, normal_packed=packed).normal, [[[0, 1, 0]] * 2])
