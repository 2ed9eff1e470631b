"""outputs.raw: the sensor's mosaic per frame as 16-bit PNG/TIFF or float EXR, sample for sample the
raw DN the camera model produced (the same as --save-passes' raw_dn), with raw/raw.json to read it."""

from __future__ import annotations

import json

import numpy as np
import OpenImageIO as oiio  # noqa: N813 - the alias its documentation uses
import pytest

from camgen.cli.main import main
from tests.conftest import SCENE, write

pytestmark = pytest.mark.opengl


@pytest.mark.parametrize(("kind", "suffix"), [("png16", ".png"), ("tiff16", ".tif"), ("exr", ".exr")])
def test_raw_frames_hold_the_adc_samples(workspace, kind, suffix):
    small = (workspace / "profiles/fixed.yaml").read_text().replace("width_px: 640", "width_px: 160")
    write(workspace, "profiles/fixed.yaml", small.replace("height_px: 480", "height_px: 120"))
    outputs = f"outputs: {{video: false, raw: {kind}, annotations: []}}"
    scene = write(workspace, "scenes/raw.yaml", SCENE.replace("duration_s: 1", f"duration_s: 1\n{outputs}"))
    out = workspace / "out"
    assert main(["render", str(scene), "-o", str(out), "--frames", "2", "--save-passes"]) == 0
    (camera,) = out.glob("*/cam")
    meta = json.loads((camera / "raw" / "raw.json").read_text(encoding="utf-8"))
    assert meta["cfa"] == "RGGB" and meta["black_level_dn"] == 64 and meta["bit_depth"] == 12
    for frame in range(2):
        buffer = oiio.ImageBuf(str(camera / "raw" / f"{frame:06d}{suffix}"))
        stored = buffer.get_pixels(oiio.FLOAT if kind == "exr" else oiio.UINT16)[..., 0]
        expected = np.load(camera / "passes" / f"{frame:06d}.npz")["raw_dn"]
        assert stored.shape == expected.shape == (120, 160)
        assert stored.dtype == (np.float32 if kind == "exr" else np.uint16)
        np.testing.assert_array_equal(stored.astype(np.float64), expected.astype(np.float64))
        assert meta["black_level_dn"] - 30 < np.median(expected) < meta["white_level_dn"]
