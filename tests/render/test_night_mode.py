"""The camera's IR night mode: it switches below the profile's level and not above, its illuminator's
light returned by a grey target falls as 1/d² (ρ/π · I_eq / d², `camgen.world.night`), the stream is
monochrome, and camera.jsonl records the mode."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.config.profile import Profile
from camgen.plan import PlanSettings, compile_scene
from camgen.world.night import nir_equivalent_intensity_cd
from tests.conftest import FIXED_PROFILE, write

W, H = 160, 120
SWITCH_LUX = 2.0
NIGHT = f"""\
night_mode:
  switch_lux: {SWITCH_LUX}
  ir_illuminator: {{radiant_intensity_mw_sr: 2000, half_angle_deg: 40}}
"""
PROFILE = (
    FIXED_PROFILE.replace("width_px: 640", f"width_px: {W}")
    .replace("height_px: 480", f"height_px: {H}")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
    + NIGHT
)


def _scene(ambient_lux: float, night_mode: str = "auto") -> str:
    return f"""\
duration_s: 0.1
fps: 10
environment:
  meshes:
    - {{type: plane, name: ground, size_m: [60, 60], material: {{color_rgb: [0.1, 0.1, 0.1], nir_reflectance: 0.15}}}}
    - {{type: box, name: hedge, size_m: [3, 0.5, 1.5], position_m: [-1.5, 8, 0.75],
        material: {{color_rgb: [0.05, 0.09, 0.03], nir_reflectance: 0.45}}}}
    - {{type: box, name: car, size_m: [2, 0.5, 1.5], position_m: [1.5, 8, 0.75],
        material: {{color_rgb: [0.6, 0.05, 0.05]}}}}
lights:
  - {{type: ambient, illuminance_lux: {ambient_lux}}}
  - {{type: lamp, position_m: [0, 10, 6], flux_lm: 4000}}
outputs: {{video: false, annotations: [], frames: png}}
cameras:
  - {{name: cam, profile: ir, night_mode: {night_mode}, mount: {{position_m: [0, 0, 2], yaw_deg: 90, pitch_deg: -8}}}}
"""


def _job(root, ambient_lux: float, night_mode: str = "auto"):
    write(root, "profiles/ir.yaml", PROFILE)
    name = f"scenes/s{ambient_lux:g}_{night_mode}.yaml"
    return compile_scene(load_scene(write(root, name, _scene(ambient_lux, night_mode))), PlanSettings(supersampling=1))


@pytest.mark.parametrize(
    ("ambient_lux", "night_mode", "expected"),
    [
        (0.95 * SWITCH_LUX, "auto", True),
        (1.05 * SWITCH_LUX, "auto", False),
        (0.05, "auto", True),
        (1000.0, "auto", False),
        (1000.0, "on", True),
        (0.05, "off", False),
    ],
)
def test_the_camera_switches_below_its_level_and_not_above(tmp_path, ambient_lux, night_mode, expected):
    job = _job(tmp_path, ambient_lux, night_mode)
    (camera,) = job.cameras
    assert all(state.night_mode is expected for state in camera.states)
    (decision,) = [d for d in camera.decisions if d.stage == "camera.night_mode"]
    assert decision.included is expected and decision.effect == pytest.approx(ambient_lux)


def test_a_camera_without_night_mode_cannot_be_forced_into_it(tmp_path):
    from camgen.errors import ConfigError

    write(tmp_path, "profiles/ir.yaml", FIXED_PROFILE)
    with pytest.raises(ConfigError, match="no night mode with a removable IR-cut filter"):
        compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", _scene(0.05, "on"))))


@pytest.mark.opengl
def test_the_illuminators_light_falls_as_the_inverse_square_of_distance(renderer):
    """A grey board (ρ₈₅₀ = 0.5, roughness 1) facing the camera on its axis at 4, 8 and 16 m returns
    L = ρ/π · I_eq / d² with I_eq = 2 W/sr · 1045.7 lm/W · 0.35 = 732 cd-equivalent: within 3 % at each
    distance (measured +1.99 % at each: the BRDF's specular lobe at roughness 1), and L·d² constant within 0.1 %."""
    from camgen.render.nir import aim_illuminator, build_nir_graph
    from camgen.render.renderer import View
    from tests.render.conftest import camera_matrix, look_at, scene_from

    profile = Profile.model_validate(
        {**_profile_dict(), "night_mode": {"ir_illuminator": {"radiant_intensity_mw_sr": 2000, "half_angle_deg": 40}}}
    )
    equivalent_cd = nir_equivalent_intensity_cd(2000, profile.sensor.qe_850nm_rel)
    assert equivalent_cd == pytest.approx(2.0 * 1045.71 * 0.35, rel=1e-5)
    values = []
    for distance_m in (4.0, 8.0, 16.0):
        scene = scene_from(
            environment={
                "meshes": [
                    {
                        "type": "box",
                        "name": "board",
                        "size_m": [0.05, 4.0, 4.0],
                        "position_m": [distance_m, 0, 2.0],
                        "material": {"color_rgb": [0.1, 0.1, 0.1], "nir_reflectance": 0.5, "roughness": 1.0},
                    }
                ]
            },
            lights=[{"type": "ambient", "illuminance_lux": 100.0}],
        )
        graph = build_nir_graph(scene, profile)
        T = look_at((0.0, 0.0, 2.0), (distance_m, 0.0, 2.0))
        aim_illuminator(graph, T)
        view = View(camera_matrix(200.0, 200.0, 79.5, 59.5), T, W, H)
        radiance = renderer.draw(graph, view, ("radiance",)).radiance
        centre = radiance[58:62, 78:82]
        assert np.ptp(centre) < 1e-3 * centre.mean()  # grey: equal in R, G and B
        near_face_m = distance_m - 0.025
        expected = 0.5 / math.pi * equivalent_cd / near_face_m**2
        assert float(centre.mean()) == pytest.approx(expected, rel=0.03)
        values.append(float(centre.mean()) * near_face_m**2)
    assert max(values) / min(values) - 1 < 1e-3


def _profile_dict() -> dict:
    import yaml

    return yaml.safe_load(PROFILE.replace(NIGHT, ""))


@pytest.fixture(scope="module")
def night_frames(renderer, tmp_path_factory):
    """The scene at 0.05 lx (night mode) and at 1000 lx (colour), executed at 160 × 120."""
    from camgen.plan.execute import execute

    root = tmp_path_factory.mktemp("night")
    out = {}
    for lux in (0.05, 1000.0):
        (result,) = execute(_job(root, lux), root / f"out{lux:g}", renderer=renderer)
        out[lux] = result.directory
    return out


@pytest.mark.opengl
def test_the_night_stream_is_monochrome_and_the_day_stream_is_not(night_frames):
    import cv2

    night = cv2.imread(str(next((night_frames[0.05] / "frames").iterdir())))
    day = cv2.imread(str(next((night_frames[1000.0] / "frames").iterdir())))
    assert (night[..., 0] == night[..., 1]).all() and (night[..., 1] == night[..., 2]).all()
    assert night.mean() > 10  # the illuminator lights the scene
    assert np.abs(day[..., 2].astype(int) - day[..., 1]).max() > 20  # the red car in colour


@pytest.mark.opengl
def test_camera_jsonl_records_the_mode(night_frames):
    for lux, expected in ((0.05, True), (1000.0, False)):
        records = [json.loads(line) for line in (night_frames[lux] / "camera.jsonl").read_text().splitlines()]
        assert [r["night_mode"] for r in records] == [expected]


def test_textured_surfaces_and_people_take_their_nir_reflectance():
    """In the NIR graph a grass texture's mean linear albedo is its 850 nm reflectance, 0.45, and an
    asphalt one's 0.14, within 2 % (the texture's own variation is kept; their visible means are 0.06
    and 0.11), grey in R, G and B; a procedural person's vertex colours turn grey by the red-reflectance
    rule; emission is off."""
    from camgen.render.nir import build_nir_graph
    from camgen.world.night import NIR_REFLECTANCE_BY_TEXTURE
    from camgen.world.textures import decode_srgb8
    from tests.render.conftest import scene_from

    profile = Profile.model_validate({**_profile_dict(), "night_mode": {}})
    scene = scene_from(
        environment={
            "meshes": [
                {"type": "plane", "name": "grass", "size_m": [4, 8], "material": {"texture": {"type": "grass"}}},
                {"type": "plane", "name": "asphalt", "size_m": [4, 8], "material": {"texture": {"type": "asphalt"}}},
                {"type": "box", "name": "sign", "size_m": [1, 1, 1], "material": {"emission_cd_m2": 500}},
            ]
        },
        lights=[{"type": "ambient", "illuminance_lux": 100.0}],
        actors=[{"name": "walker", "class": "person", "path": {"waypoints_m": [[0, 5]]}}],
    )
    graph = build_nir_graph(scene, profile)
    for node, name in zip(graph.environment_nodes[:2], ("grass", "asphalt"), strict=True):
        texture = decode_srgb8(node.mesh.primitives[0].material.baseColorTexture.source)
        assert np.allclose(texture[..., 0], texture[..., 1]) and np.allclose(texture[..., 1], texture[..., 2])
        assert float(texture.mean()) == pytest.approx(NIR_REFLECTANCE_BY_TEXTURE[name], rel=0.02)
    assert tuple(graph.environment_nodes[2].mesh.primitives[0].material.emissiveFactor) == (0.0, 0.0, 0.0)
    person = graph.actor_nodes[0].mesh.primitives[0].color_0
    assert np.allclose(person[:, 0], person[:, 1]) and np.allclose(person[:, 1], person[:, 2])
    assert 0.02 < float(person[:, 0].mean()) < 0.9
