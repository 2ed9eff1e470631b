"""A file texture (`material.texture: {type: file, …}`): good sets load, and every kind of bad file or
value gets its own located error naming the key, the value and the fix (the pattern of test_bad_input)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import OpenImageIO as oiio  # noqa: N813 — the library's documented alias
import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from tests.conftest import SCENE, assert_located_problem, write

GROUND = "    - type: plane\n      name: ground\n      size_m: [20, 20]\n"


def _scene_with(texture: str) -> str:
    """The test scene whose ground carries `texture` (a flow mapping) on the line marked #<."""
    assert GROUND in SCENE
    return SCENE.replace(GROUND, GROUND + f"      material: {{texture: {texture}}} #<\n", 1)


def _images(directory: Path) -> None:
    """A 64 × 32 set: colour, a flat normal map, grey roughness; and files that are wrong in one way each."""
    colour = np.random.default_rng(0).integers(0, 256, (32, 64, 3), dtype=np.uint8)
    cv2.imwrite(str(directory / "colour.png"), colour)
    cv2.imwrite(str(directory / "normal.png"), np.full((32, 64, 3), (255, 128, 128), np.uint8))  # BGR: +Z
    cv2.imwrite(str(directory / "rough.png"), np.full((32, 64), 200, np.uint8))
    cv2.imwrite(str(directory / "rough16.png"), np.full((32, 64), 40000, np.uint16))
    cv2.imwrite(str(directory / "small_normal.png"), np.full((16, 32, 3), (255, 128, 128), np.uint8))
    cv2.imwrite(str(directory / "grey_normal.png"), np.full((32, 64), 128, np.uint8))
    cv2.imwrite(str(directory / "photo_as_normal.png"), np.full((32, 64, 3), 128, np.uint8))
    cv2.imwrite(str(directory / "colour_rough.png"), colour)
    oiio.ImageBuf(np.ones((32, 64, 3), np.float32)).write(str(directory / "float.exr"))
    (directory / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n not an image")


@pytest.fixture
def scenes(workspace: Path) -> Path:
    _images(workspace / "scenes")
    return workspace / "scenes"


def test_a_full_set_loads(scenes: Path):
    texture = (
        "{type: file, base_color_file: colour.png, normal_file: normal.png, roughness_file: rough16.png, tile_m: 2}"
    )
    loaded = load_scene(write(scenes, "ok.yaml", _scene_with(texture)))
    assert loaded.scene.environment.meshes[0].material.texture.tile_m == 2.0


BAD = [
    (
        "missing_file",
        "{type: file, base_color_file: nowhere.png, tile_m: 2}",
        "base_color_file",
        "refers to 'nowhere.png', but {dir}/nowhere.png does not exist",
    ),
    (
        "unreadable_image",
        "{type: file, base_color_file: broken.png, tile_m: 2}",
        "base_color_file",
        "refers to 'broken.png', which cannot be read as an image",
    ),
    (
        "normal_of_another_size",
        "{type: file, base_color_file: colour.png, normal_file: small_normal.png, tile_m: 2}",
        "normal_file",
        "which is 32×16 px, but base_color_file 'colour.png' is 64×32 px; a texture's maps share one size",
    ),
    (
        "normal_with_one_channel",
        "{type: file, base_color_file: colour.png, normal_file: grey_normal.png, tile_m: 2}",
        "normal_file",
        "has 1 channel(s); a normal map is RGB (X, Y, Z)",
    ),
    (
        "photo_given_as_normal",
        "{type: file, base_color_file: colour.png, normal_file: photo_as_normal.png, tile_m: 2}",
        "normal_file",
        "not a tangent-space normal map",
    ),
    (
        "colour_given_as_roughness",
        "{type: file, base_color_file: colour.png, roughness_file: colour_rough.png, tile_m: 2}",
        "roughness_file",
        "has 3 channels that differ; a roughness map is grey",
    ),
    (
        "tile_not_positive",
        "{type: file, base_color_file: colour.png, tile_m: 0}",
        "tile_m",
        "must be > 0, got 0",
    ),
    (
        "tile_pair_not_positive",
        "{type: file, base_color_file: colour.png, tile_m: [2, -1]}",
        "tile_m[1]",
        "must be > 0, got -1",
    ),
    (
        "no_base_colour",
        "{type: file, normal_file: normal.png, tile_m: 2}",
        "base_color_file",
        "is required",
    ),
    (
        "seed_on_a_file_texture",
        "{type: file, base_color_file: colour.png, tile_m: 2, seed: 3}",
        "seed",
        "is not a known key",
    ),
    (
        "unknown_texture_type",
        "{type: photo, base_color_file: colour.png, tile_m: 2}",
        "type",
        "'file'",
    ),
]


@pytest.mark.parametrize(("texture", "key", "fragment"), [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_bad_file_texture_is_located_and_explained(scenes: Path, texture: str, key: str, fragment: str):
    key_path = f"environment.meshes[0].material.texture.{key}"
    assert_located_problem(scenes.parent, _scene_with(texture), key_path, fragment.format(dir=scenes.resolve()))


def test_a_float_image_is_refused_with_the_format_to_use(scenes: Path):
    path = write(scenes, "exr.yaml", _scene_with("{type: file, base_color_file: float.exr, tile_m: 2}"))
    with pytest.raises(ConfigError, match=r"holds float32 samples; .* convert a float"):
        load_scene(path)
