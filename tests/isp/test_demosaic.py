"""Demosaicing: CFA layout, colour order of every pattern and method, flat fields, known samples."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.isp.demosaic import DEMOSAIC_METHODS, OPENCV_BAYER_CODES, SQRT_CODE_U8, SQRT_DECODE_U16, demosaic
from camgen.sensor.cfa import CFA_PATTERNS, cfa_channel_index, cfa_phase_channels, tile_phases

R, G, B = 0, 1, 2


def mosaic_of(rgb: np.ndarray, cfa: str) -> np.ndarray:
    """Sample an (H, W, 3) image through a CFA, written out by hand from the pattern's name."""
    mosaic = np.empty(rgb.shape[:2], rgb.dtype)
    for phase, colour in enumerate(cfa):
        py, px = divmod(phase, 2)
        mosaic[py::2, px::2] = rgb[py::2, px::2, "RGB".index(colour)]
    return mosaic


def smooth_rgb(height: int = 64, width: int = 80) -> np.ndarray:
    """Three mutually uncorrelated slow patterns: R a ramp across, B a ramp down, G a bump in the middle."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    red = 2000 + 60000 * x / (width - 1)
    blue = 2000 + 60000 * y / (height - 1)
    green = 2000 + 60000 * np.exp(-(((x - width / 2) / (width / 4)) ** 2 + ((y - height / 2) / (height / 4)) ** 2))
    return np.round(np.stack([red, green, blue], axis=-1)).astype(np.uint16)


def test_phase_channels_read_the_name_row_by_row():
    assert cfa_phase_channels("RGGB") == (R, G, G, B)
    assert cfa_phase_channels("BGGR") == (B, G, G, R)
    assert cfa_phase_channels("GRBG") == (G, R, B, G)
    assert cfa_phase_channels("GBRG") == (G, B, R, G)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
@pytest.mark.parametrize(("height", "width"), [(4, 6), (5, 7), (1, 1)])
def test_channel_index_repeats_the_top_left_block(cfa, height, width):
    index = cfa_channel_index(cfa, height, width)
    assert index.shape == (height, width) and index.dtype == np.uint8 and index.flags.c_contiguous
    phases = cfa_phase_channels(cfa)
    for y in range(height):
        for x in range(width):
            assert index[y, x] == phases[2 * (y % 2) + x % 2]


def test_tile_phases_keeps_dtype_and_rejects_bad_blocks():
    tiled = tile_phases(np.array([[1.5, 2.5], [3.5, 4.5]], np.float32), 3, 3)
    np.testing.assert_array_equal(tiled, [[1.5, 2.5, 1.5], [3.5, 4.5, 3.5], [1.5, 2.5, 1.5]])
    assert tiled.dtype == np.float32
    with pytest.raises(ValueError, match="shape"):
        tile_phases(np.zeros(4), 2, 2)


def test_opencv_codes_agree_with_opencv_5_pattern_aliases():
    # OpenCV ≥ 5 also spells codes by the top-left block (COLOR_BayerRGGB2RGB); ours must match them.
    for (cfa, method), code in OPENCV_BAYER_CODES.items():
        suffix = {"bilinear": "", "edge_aware": "_EA", "vng": "_VNG"}[method]
        alias = getattr(cv2, f"COLOR_Bayer{cfa}2RGB{suffix}", None)
        if alias is not None:
            assert code == alias
    assert OPENCV_BAYER_CODES["RGGB", "bilinear"] == cv2.COLOR_BayerBG2RGB


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_each_output_channel_is_its_own_input_channel(cfa, method):
    rgb = smooth_rgb()
    out = demosaic(mosaic_of(rgb, cfa), cfa, method)
    assert out.shape == rgb.shape and out.dtype == np.uint16
    inner = (slice(3, -3), slice(3, -3))
    for c in range(3):
        for k in range(3):
            r = np.corrcoef(out[inner][..., c].ravel(), rgb[inner][..., k].ravel())[0, 1]
            if k == c:
                assert r > 0.99, (cfa, method, c, r)
            else:
                assert abs(r) < 0.5, (cfa, method, c, k, r)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_a_swapped_opencv_code_would_be_caught(cfa):
    # The "name by the first row" mistake swaps R and B; the correlation test above must fail for it.
    rgb = smooth_rgb()
    naive = getattr(cv2, f"COLOR_Bayer{cfa[:2]}2RGB")
    assert naive != OPENCV_BAYER_CODES[cfa, "bilinear"]
    out = cv2.cvtColor(mosaic_of(rgb, cfa), naive)
    assert np.corrcoef(out[..., R].ravel(), rgb[..., R].ravel())[0, 1] < 0.5


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
@pytest.mark.parametrize("shape", [(16, 20), (9, 11)])
def test_flat_field_is_exact_for_bilinear_and_edge_aware(cfa, shape):
    value = np.array([1000, 30000, 65535], np.uint16)
    mosaic = mosaic_of(np.broadcast_to(value, (*shape, 3)), cfa)
    for method in ("bilinear", "edge_aware"):
        out = demosaic(mosaic, cfa, method)
        np.testing.assert_array_equal(out, np.broadcast_to(value, out.shape), err_msg=method)


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_flat_field_through_vng_is_within_the_companding_step(cfa):
    value = np.array([7, 1000, 50000], np.uint16)
    out = demosaic(mosaic_of(np.broadcast_to(value, (16, 20, 3)), cfa), cfa, "vng").astype(np.float64)
    # Half the square-root coding step at x: √(65535·x)/255, plus the 16-bit rounding of the table.
    half_step = np.sqrt(65535.0 * value) / 255.0 + 0.5
    assert np.all(np.abs(out - value) <= half_step)
    # …and it is exactly the code round trip, since VNG reproduces a flat 8-bit field.
    np.testing.assert_array_equal(out, np.broadcast_to(SQRT_DECODE_U16[SQRT_CODE_U8[value]], out.shape))


def test_companding_tables_are_inverse_at_the_codes_and_monotone():
    assert SQRT_CODE_U8[0] == 0 and SQRT_CODE_U8[65535] == 255
    assert SQRT_DECODE_U16[0] == 0 and SQRT_DECODE_U16[255] == 65535
    np.testing.assert_array_equal(SQRT_CODE_U8[SQRT_DECODE_U16], np.arange(256))
    assert np.all(np.diff(SQRT_CODE_U8.astype(int)) >= 0) and np.all(np.diff(SQRT_DECODE_U16.astype(int)) > 0)
    with pytest.raises(ValueError):
        SQRT_CODE_U8[0] = 1


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_bilinear_keeps_every_known_sample_inside_the_border(cfa):
    mosaic = np.random.default_rng(3).integers(0, 65536, (24, 30), dtype=np.uint16)
    out = demosaic(mosaic, cfa, "bilinear")
    own = np.take_along_axis(out, cfa_channel_index(cfa, *mosaic.shape)[..., None].astype(np.intp), axis=2)[..., 0]
    np.testing.assert_array_equal(own[1:-1, 1:-1], mosaic[1:-1, 1:-1])
    # OpenCV fills the outermost rows and columns from their inner neighbours.
    np.testing.assert_array_equal(out[0], out[1])
    np.testing.assert_array_equal(out[:, -1], out[:, -2])


def test_vng_is_deterministic_and_full_range():
    rgb = smooth_rgb()
    first = demosaic(mosaic_of(rgb, "RGGB"), "RGGB", "vng")
    np.testing.assert_array_equal(first, demosaic(mosaic_of(rgb, "RGGB"), "RGGB", "vng"))
    assert first.max() > 60000


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((np.zeros((8, 8), np.uint8), "RGGB", "bilinear"), "uint16"),
        ((np.zeros((8, 8), np.float32), "RGGB", "bilinear"), "uint16"),
        ((np.zeros((8, 8, 3), np.uint16), "RGGB", "bilinear"), r"\(H, W\)"),
        ((np.zeros((2, 8), np.uint16), "RGGB", "bilinear"), "at least 3"),
        ((np.zeros((8, 8), np.uint16), "RGBG", "bilinear"), "RGGB, BGGR, GRBG, GBRG, mono"),
        ((np.zeros((8, 8), np.uint16), "rggb", "bilinear"), "unknown cfa"),
        ((np.zeros((8, 8), np.uint16), "mono", "bilinear"), "no colour channels"),
        ((np.zeros((8, 8), np.uint16), "RGGB", "ahd"), "bilinear, edge_aware, vng"),
        (([[0, 1], [2, 3]], "RGGB", "bilinear"), "uint16"),
    ],
)
def test_bad_input_is_refused_with_the_alternatives(args, match):
    with pytest.raises(ValueError, match=match):
        demosaic(*args)


def test_cfa_helpers_refuse_mono_unknown_names_and_bad_sizes():
    with pytest.raises(ValueError, match="no colour channels"):
        cfa_phase_channels("mono")
    with pytest.raises(ValueError, match="expected one of"):
        cfa_channel_index("XYZW", 4, 4)
    with pytest.raises(ValueError, match="height_px"):
        cfa_channel_index("RGGB", 0, 4)
    with pytest.raises(ValueError, match="width_px"):
        cfa_channel_index("RGGB", 4, 2.5)
