"""outputs.radiance: the scene-referred radiance per frame, as 16-bit linear PNG/TIFF with the scale in
radiance/radiance.json or as float EXR; read back with OpenCV and OpenImageIO, it is the renderer's
radiance within half a quantisation step."""

from __future__ import annotations

import json

import cv2
import numpy as np
import OpenImageIO as oiio  # noqa: N813 - the alias its documentation uses
import pytest

from camgen.config import load_scene
from camgen.io.radiance import HEADROOM, RadianceWriter, radiance_scale_cd_m2_per_dn, radiance_u16
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.execute import execute
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer, crop_to_output
from tests.conftest import FIXED_PROFILE, SCENE, write


def test_the_scale_is_a_power_of_two_that_leaves_the_headroom():
    radiance = np.array([[[0.0, 1.0, 1234.5]]], np.float32)
    scale = radiance_scale_cd_m2_per_dn(radiance)
    assert np.log2(scale) == round(np.log2(scale))
    assert 65535 / (2 * HEADROOM) < 1234.5 / scale <= 65535 / HEADROOM
    dn, clipped = radiance_u16(radiance * np.float32(2 * HEADROOM), scale)  # brighter than the range
    assert clipped == 1 and dn[0, 0, 2] == 65535 and dn[0, 0, 0] == 0


@pytest.mark.parametrize(("kind", "suffix"), [("png16", ".png"), ("tiff16", ".tif")])
def test_sixteen_bit_files_read_back_with_opencv_within_half_a_step(tmp_path, kind, suffix):
    rng = np.random.default_rng(2)
    radiance = rng.lognormal(3.0, 1.5, (24, 32, 3)).astype(np.float32)  # ~1–2000 cd/m²
    writer = RadianceWriter(tmp_path, kind)
    writer.write("000000", radiance)
    meta = json.loads(writer.close().read_text(encoding="utf-8"))
    stored = cv2.imread(str(tmp_path / f"000000{suffix}"), cv2.IMREAD_UNCHANGED)[..., ::-1]  # BGR → RGB
    assert stored.dtype == np.uint16 and meta["clipped_samples"] == {"000000": 0}
    scale = meta["scale_cd_m2_per_dn"]
    assert np.abs(stored * scale - radiance).max() <= scale / 2 * (1 + 1e-6)


@pytest.mark.opengl
@pytest.mark.parametrize("kind", ["png16", "exr"])
def test_rendered_radiance_files_hold_the_renderers_radiance(workspace, renderer, kind):
    profile = FIXED_PROFILE.replace("width_px: 640", "width_px: 160").replace("height_px: 480", "height_px: 120")
    profile = profile.replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
    vignetting = "  vignetting: {relative_illumination_corner: 0.5}\n"  # the lens darkens, the scene does not
    write(workspace, "profiles/fixed.yaml", profile + vignetting)
    outputs = f"outputs: {{video: false, radiance: {kind}, annotations: []}}"
    scene = write(workspace, "scenes/r.yaml", SCENE.replace("duration_s: 1", f"duration_s: 0.2\n{outputs}"))
    job = compile_scene(load_scene(scene), PlanSettings(supersampling=1))
    (camera,) = job.cameras
    stages = {s.name for s in camera.stages}
    assert "optics.remap" not in stages and "optics.vignetting" in stages  # no distortion: a crop
    (result,) = execute(job, workspace / "out", renderer=renderer)
    # The frames as drawn at the exposures auto-exposure set (camera.jsonl): the walker's motion blur spans them.
    used = [json.loads(line) for line in (result.directory / "camera.jsonl").read_text().splitlines()]
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    try:
        expected = [
            crop_to_output(
                drawer.frame(
                    index, state.model_copy(update={"exposure_time_s": record["exposure_time_s"]})
                ).passes.radiance,
                camera.render,
            )
            for index, (state, record) in enumerate(zip(camera.states, used, strict=True))
        ]
    finally:
        drawer.close()
    meta = json.loads((result.directory / "radiance" / "radiance.json").read_text(encoding="utf-8"))
    assert meta["unit"].startswith("cd/m²") and len(expected) == 2
    for index, radiance in enumerate(expected):
        path = result.directory / "radiance" / f"{index:06d}{'.png' if kind == 'png16' else '.exr'}"
        if kind == "exr":
            stored = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)
            np.testing.assert_array_equal(stored, radiance)
        else:
            stored = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[..., ::-1].astype(np.float64)
            scale = meta["scale_cd_m2_per_dn"]
            assert np.abs(stored * scale - radiance).max() <= scale / 2 * (1 + 1e-6)
            assert meta["clipped_samples"][f"{index:06d}"] == 0
        assert stored.shape == (120, 160, 3) and 1.0 < float(np.median(radiance)) < 1e4
