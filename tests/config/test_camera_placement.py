"""A camera behind a one-sided plane is refused; a camera inside a closed solid is warned about."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from camgen.cli.main import main
from camgen.config import load_scene
from camgen.config.placement import cameras_behind_planes, cameras_inside_solids
from camgen.errors import ConfigError, ConfigWarning
from tests.conftest import SCENE, write

HUT = "      size_m: [20, 20]\n    - {type: box, name: hut, size_m: [4, 4, 6], position_m: [0, -5, 3]}\n"


def scene_text(position: str, extra: str = "") -> str:
    text = SCENE.replace("position_m: [0, -5, 3]", f"position_m: {position}")
    return text.replace("      size_m: [20, 20]\n", extra) if extra else text


def test_a_camera_under_the_ground_is_refused_with_its_place(workspace: Path, capsys):
    path = write(workspace, "scenes/under.yaml", scene_text("[0, -5, -1]"))
    assert main(["validate", str(path)]) == 1
    err = capsys.readouterr().err
    assert f"{path}:" in err
    assert "cameras[0].mount.position_m puts camera 'cam' 1 m behind the plane 'ground'" in err
    assert "z > 0" in err


def test_a_camera_under_the_ground_beside_it_is_accepted(workspace: Path):
    # the 20 m ground ends at y = -10: a camera below z = 0 outside its outline is not behind it
    load_scene(write(workspace, "scenes/beside.yaml", scene_text("[0, -12, -1]")))


@pytest.mark.parametrize(
    ("mesh", "behind"),
    [
        ("{type: plane, name: wall, size_m: [6, 4], position_m: [0, -4, 2], rotation_deg: [-90, 0, 0]}", True),
        ("{type: plane, name: wall, size_m: [6, 4], position_m: [0, -4, 2], rotation_deg: [90, 0, 0]}", False),
        ("{type: plane, name: wall, size_m: [6, 4], position_m: [0, -6, 2], rotation_deg: [90, 0, 0]}", True),
        (
            "{type: checkerboard, name: board, squares: [8, 6], square_size_m: 0.5, position_m: [0, -4, 3], "
            "rotation_deg: [-90, 0, 0]}",
            True,
        ),
    ],
)
def test_a_turned_plane_is_judged_in_its_own_frame(mesh: str, behind: bool, workspace: Path):
    # rotation_deg [-90, 0, 0] turns the plane's front (local +Z) to world +Y: a plane at y = −4 then faces
    # away from the camera at y = −5; [90, 0, 0] turns it to −Y, towards the camera, unless the plane
    # stands beyond the camera (y = −6)
    text = scene_text("[0, -5, 3]", f"      size_m: [20, 20]\n    - {mesh}\n")
    path = write(workspace, "scenes/wall.yaml", text)
    if behind:
        with pytest.raises(ConfigError, match="behind the"):
            load_scene(path)
    else:
        scene = load_scene(path).scene
        assert cameras_behind_planes(scene) == [] and cameras_inside_solids(scene) == []


def test_a_camera_inside_a_box_is_a_located_warning(workspace: Path, capsys):
    path = write(workspace, "scenes/hut.yaml", scene_text("[0, -5, 3]", HUT))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scene(path)
    assert [type(w.message) for w in caught] == [ConfigWarning]
    assert "inside the closed box 'hut'" in str(caught[0].message) and "sees through it" in str(caught[0].message)
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    assert err.startswith("warning ") and f"{path}:" in err


@pytest.mark.parametrize(
    ("mesh", "inside"),
    [
        ("{type: cylinder, name: pole, radius_m: 0.2, height_m: 6, position_m: [0.1, -5, 3]}", True),
        ("{type: cylinder, name: pole, radius_m: 0.2, height_m: 6, position_m: [0.3, -5, 3]}", False),
        ("{type: sphere, name: dome, radius_m: 0.5, position_m: [0, -5, 3.4]}", True),
        ("{type: sphere, name: dome, radius_m: 0.5, position_m: [0, -5, 3.6]}", False),
        # turned 90° about Z, the box's 4 m side runs along Y and reaches the camera 1.6 m away; unturned, not
        ("{type: box, name: hut, size_m: [4, 1, 6], position_m: [0, -6.6, 3], rotation_deg: [0, 0, 90]}", True),
        ("{type: box, name: hut, size_m: [4, 1, 6], position_m: [0, -6.6, 3]}", False),
    ],
)
def test_inside_a_solid(mesh: str, inside: bool, workspace: Path):
    text = scene_text("[0, -5, 3]", f"      size_m: [20, 20]\n    - {mesh}\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scene(write(workspace, "scenes/solid.yaml", text))
    assert len(caught) == int(inside)


def test_the_example_scenes_place_every_camera_well():
    repo = Path(__file__).resolve().parents[2]
    for path in sorted((repo / "scenes").glob("*.yaml")):
        with warnings.catch_warnings():
            warnings.simplefilter("error", ConfigWarning)
            load_scene(path)


SKY = "  sky: clear\n  sky_luminance_cd_m2: {zenith}\n"
LOW_SUN = "  - {type: sun, illuminance_lux: 6370, azimuth_deg: 270, elevation_deg: 4}\n"


@pytest.mark.parametrize(
    ("zenith", "ambient", "warned"),
    [
        (300, 40, "sheds 2,132 lx on the ground, 53× as much"),  # the intersection's old dusk
        (689, 4890, None),  # the IES clear-sky model's own at 4°
        (689, 1700, None),  # within a factor of 3 (buildings hide some sky)
        (689, 1500, "sheds 4,89"),
    ],
)
def test_a_sky_far_brighter_or_darker_than_its_light_is_a_located_warning(workspace: Path, zenith, ambient, warned):
    """The sky the frames show sheds L_z·∫ℓ cos Z dω on the ground (4,890 lx for a clear sky of zenith 689 cd/m²
    with the sun at 4°, `camgen.world.daylight`); an ambient light far from it is warned about where it is set."""
    text = SCENE.replace("environment:\n", "environment:\n" + SKY.format(zenith=zenith), 1)
    text = text.replace("{type: ambient, illuminance_lux: 1000}", f"{{type: ambient, illuminance_lux: {ambient}}}")
    text = text.replace("lights:\n", "lights:\n" + LOW_SUN, 1)
    path = write(workspace, "scenes/sky.yaml", text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scene(path)
    messages = [str(w.message) for w in caught if isinstance(w.message, ConfigWarning)]
    assert bool(messages) == (warned is not None), messages
    if warned:
        (message,) = messages
        assert f"{path}:" in message and "lights[1].illuminance_lux" in message
        assert warned in message and "silhouettes" in message and "environment.site" in message
