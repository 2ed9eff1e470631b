"""Grey-world white balance on the mosaic against its closed form; clipped and black frames."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.isp.white_balance import cfa_gain_image, grey_world_gains
from camgen.sensor.cfa import CFA_PATTERNS, cfa_channel_index

BLACK_DN = 64.0
LIGHT_RGB = np.array([30.0, 20.0, 10.0])
"""A warm light: raw signal per unit reflectance in R, G, B, DN."""


def lit_grey_scene(cfa: str, reflectance: np.ndarray) -> np.ndarray:
    """Raw mosaic of a grey scene whose reflectance is constant over each 2×2 cell, under LIGHT_RGB."""
    cells = np.repeat(np.repeat(reflectance, 2, axis=0), 2, axis=1)
    light = LIGHT_RGB[cfa_channel_index(cfa, *cells.shape)]
    return (BLACK_DN + cells * light).astype(np.uint16)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
@pytest.mark.parametrize("subsample", [1, 4])
def test_gains_equalise_the_channel_means_of_a_lit_grey_scene(cfa, subsample):
    reflectance = np.random.default_rng(0).integers(10, 100, (40, 50)).astype(np.float64)
    mosaic = lit_grey_scene(cfa, reflectance)
    gains = grey_world_gains(mosaic, cfa, BLACK_DN, subsample=subsample)
    assert gains.shape == (3,) and gains.dtype == np.float64
    # Closed form: m_c = L_c · mean(reflectance) over the same cells, so g_c = L_G / L_c.
    np.testing.assert_allclose(gains, LIGHT_RGB[1] / LIGHT_RGB, rtol=1e-12)
    balanced = (mosaic - BLACK_DN) * cfa_gain_image(gains, cfa, *mosaic.shape)
    index = cfa_channel_index(cfa, *mosaic.shape)
    means = [balanced[index == c].mean() for c in range(3)]
    np.testing.assert_allclose(means, means[1], rtol=1e-6)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_saturated_sites_are_left_out(cfa):
    white = 4095
    mosaic = lit_grey_scene(cfa, np.full((40, 50), 50.0))
    red_sites = cfa_channel_index(cfa, *mosaic.shape) == 0
    clipped = red_sites & (np.arange(mosaic.shape[1]) < 30)  # a red highlight over the left part
    mosaic[clipped] = white
    gains = grey_world_gains(mosaic, cfa, BLACK_DN, white_level_dn=white, subsample=1)
    np.testing.assert_allclose(gains, LIGHT_RGB[1] / LIGHT_RGB, rtol=1e-12)
    # Counting the clipped sites as signal would pull the red gain down.
    assert grey_world_gains(mosaic, cfa, BLACK_DN, white_level_dn=white + 1, subsample=1)[0] < 0.75 * gains[0]


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_a_cell_with_one_clipped_channel_is_left_out_whole(cfa):
    """A bright sky whose blue clips while its red and green do not: kept per site, its red and green would
    pull those means up and tint the grey ground below it (the intersection's dusk sky turned it green)."""
    white = 4095
    mosaic = lit_grey_scene(cfa, np.full((40, 50), 50.0))
    index = cfa_channel_index(cfa, *mosaic.shape)
    sky = np.arange(mosaic.shape[0])[:, None] < 20
    mosaic[sky & (index == 2)] = white
    mosaic[sky & (index != 2)] = 3000
    gains = grey_world_gains(mosaic, cfa, BLACK_DN, white_level_dn=white, subsample=1)
    np.testing.assert_allclose(gains, LIGHT_RGB[1] / LIGHT_RGB, rtol=1e-12)


def test_samples_below_black_count_as_negative_signal():
    mosaic = np.full((8, 8), 100, np.uint16)
    mosaic[::2, ::2] = [[60], [140], [60], [140]]  # R averages 100 − 64 = 36 from samples on both sides of black
    np.testing.assert_allclose(grey_world_gains(mosaic, "RGGB", BLACK_DN, subsample=1), [1.0, 1.0, 1.0])


@pytest.mark.parametrize(
    "mosaic",
    [
        np.full((16, 16), int(BLACK_DN), np.uint16),  # black frame: every mean above black is 0
        np.zeros((16, 16), np.uint16),  # below black
        np.full((16, 16), 65535, np.uint16),  # all clipped: no sample left
    ],
)
def test_degenerate_frames_get_unity_gains(mosaic):
    np.testing.assert_array_equal(grey_world_gains(mosaic, "RGGB", BLACK_DN), [1.0, 1.0, 1.0])


def test_one_dark_channel_gets_unity_gains():
    mosaic = lit_grey_scene("RGGB", np.full((8, 8), 50.0))
    mosaic[1::2, 1::2] = int(BLACK_DN)  # no blue signal
    np.testing.assert_array_equal(grey_world_gains(mosaic, "RGGB", BLACK_DN), [1.0, 1.0, 1.0])


@pytest.mark.parametrize(
    ("args", "kwargs", "match"),
    [
        ((np.zeros((8, 8), np.float32), "RGGB", 0.0), {}, "uint16"),
        ((np.zeros((8, 8, 3), np.uint16), "RGGB", 0.0), {}, "2-D"),
        ((np.zeros((8, 8), np.uint16), "mono", 0.0), {}, "no colour channels"),
        ((np.zeros((8, 8), np.uint16), "RBGG", 0.0), {}, "RGGB, BGGR, GRBG, GBRG"),
        ((np.zeros((8, 8), np.uint16), "RGGB", -1.0), {}, "black_level_dn"),
        ((np.zeros((8, 8), np.uint16), "RGGB", float("nan")), {}, "black_level_dn"),
        ((np.zeros((8, 8), np.uint16), "RGGB", 64.0), {"white_level_dn": 64.0}, "white_level_dn"),
        ((np.zeros((8, 8), np.uint16), "RGGB", 64.0), {"subsample": 0}, "subsample"),
        ((np.zeros((8, 8), np.uint16), "RGGB", 64.0), {"subsample": 2.0}, "subsample"),
    ],
)
def test_grey_world_refuses_bad_input(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        grey_world_gains(*args, **kwargs)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_gain_image_puts_each_channel_gain_on_its_sites(cfa):
    gains = np.array([1.9, 1.0, 1.4])
    image = cfa_gain_image(gains, cfa, 7, 10)
    assert image.shape == (7, 10) and image.dtype == np.float32
    np.testing.assert_array_equal(image, gains.astype(np.float32)[cfa_channel_index(cfa, 7, 10)])


@pytest.mark.parametrize("gains", [(1.0, 2.0), (1.0, -1.0, 1.0), (1.0, np.inf, 1.0)])
def test_gain_image_refuses_bad_gains(gains):
    with pytest.raises(ValueError, match="gains_rgb"):
        cfa_gain_image(gains, "RGGB", 4, 4)


def test_gain_image_refuses_mono_and_bad_sizes():
    with pytest.raises(ValueError, match="no colour channels"):
        cfa_gain_image((1, 1, 1), "mono", 4, 4)
    with pytest.raises(ValueError, match="height_px"):
        cfa_gain_image((1, 1, 1), "RGGB", -4, 4)
