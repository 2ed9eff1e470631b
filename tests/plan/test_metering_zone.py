"""A camera's own exposure zone (`metering_region_frac` in the scene, as an installer sets it): it reaches the
compiled job, it is refused where nothing meters, and it changes what auto-exposure settles at."""

from __future__ import annotations

import json

import pytest

from camgen.cli.main import main
from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.plan import compile_scene
from tests.conftest import FIXED_PROFILE, SCENE, write

ZONE = "    metering_region_frac: [0, 0.5, 1, 1]\n"
SMALL = FIXED_PROFILE.replace("width_px: 640", "width_px: 160").replace("height_px: 480", "height_px: 120")
SKY_SCENE = (
    SCENE.replace("size_m: [20, 20]", "size_m: [200, 200]\n  sky_luminance_cd_m2: 8000")
    .replace("pitch_deg: -20", "pitch_deg: 0")
    .replace("illuminance_lux: 1000", "illuminance_lux: 300")
)
"""The test scene's ground under a bright sky that fills the upper half of a level camera's view."""


def with_zone(scene: str) -> str:
    return scene.replace("      pitch_deg: -20\n", "      pitch_deg: -20\n" + ZONE).replace(
        "      pitch_deg: 0\n", "      pitch_deg: 0\n" + ZONE
    )


def test_the_zone_replaces_the_profiles_metering_window(workspace):
    plain = compile_scene(load_scene(write(workspace, "scenes/plain.yaml", SCENE)))
    zoned = compile_scene(load_scene(write(workspace, "scenes/zoned.yaml", with_zone(SCENE))))
    assert plain.cameras[0].profile.exposure.auto.metering_region_frac == (0.0, 0.0, 1.0, 1.0)
    assert zoned.cameras[0].profile.exposure.auto.metering_region_frac == (0.0, 0.5, 1.0, 1.0)
    assert zoned.job_id != plain.job_id


def test_a_zone_on_a_manually_exposed_camera_is_refused(workspace):
    write(workspace, "profiles/fixed.yaml", FIXED_PROFILE + "exposure: {mode: manual, exposure_time_s: 0.01}\n")
    path = write(workspace, "scenes/zoned.yaml", with_zone(SCENE))
    with pytest.raises(ConfigError) as error:
        compile_scene(load_scene(path))
    (problem,) = error.value.problems
    assert "cameras[0].metering_region_frac" in str(problem) and "exposure.mode: manual" in str(problem)


@pytest.mark.opengl
def test_metering_the_ground_below_a_bright_sky_exposes_it_longer(workspace):
    write(workspace, "profiles/fixed.yaml", SMALL)
    exposures = []
    for name, text in (("sky", SKY_SCENE), ("sky_zoned", with_zone(SKY_SCENE))):
        out = workspace / name
        scene = write(workspace, f"scenes/{name}.yaml", text)
        assert main(["render", str(scene), "-o", str(out), "--frames", "1"]) == 0
        (metadata,) = out.glob("*/cam/camera.jsonl")
        state = json.loads(metadata.read_text().splitlines()[0])
        exposures.append(state["exposure_time_s"] * 10 ** (state["gain_db"] / 20))
    # The sky is far brighter than the ground: averaged over the frame it holds the exposure down.
    assert exposures[1] > 10 * exposures[0], exposures  # measured 84×
