"""Reading a file texture's images (`camgen.config.scene.FileTexture`): base colour, normal and roughness.

Each image is read through OpenImageIO in its stored integer type and scaled by its format's full scale
(2^bits − 1: PNG, JPEG and TIFF store codes of 0…full scale for 0…1), nothing decoded yet: the base
colour's sRGB decoding and the normal map's unpacking are `camgen.world.textures.file_surface_maps`'.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camgen.io.files import input_file_problem

MAX_TEXELS_PER_SIDE = 8192
"""The largest image side read (an 8K set; OpenGL 3.3 guarantees only 1024, Mesa's llvmpipe and desktop
GPUs take 8192 or more)."""

MIN_NORMAL_Z = 0.3
"""The least mean +Z (out of the surface) of a tangent-space normal map: real ones average 0.8–1 (their
texels are bluish); a colour photo given as a normal map averages about 0 (a grey 0.5 blue)."""


class TextureFileError(ValueError):
    """A texture image that cannot be used: `key` is the texture's key that names it, `message` continues
    the key path (``refers to 'a.png', but … does not exist``)."""

    def __init__(self, key: str, message: str):
        super().__init__(f"{key} {message}")
        self.key, self.message = key, message


@dataclass(frozen=True)
class TextureImages:
    """A file texture's images as stored, scaled to 0…1 (float32, row 0 the image's top): `base_color`
    (H, W, 3) sRGB-encoded; `normal` (H, W, 3) packed as n / 2 + 0.5; `roughness` (H, W)."""

    base_color: np.ndarray
    normal: np.ndarray | None
    roughness: np.ndarray | None


def read_image_01(path: Path) -> np.ndarray:
    """(H, W, C) float32: the image's samples over its format's full scale; ValueError with a reason."""
    import OpenImageIO as oiio  # noqa: N813 — the library's documented alias

    image_input = oiio.ImageInput.open(str(path))
    if image_input is None:
        raise ValueError(f"cannot be read as an image ({oiio.geterror().strip() or 'unknown format'})")
    try:
        spec = image_input.spec()
        if max(spec.width, spec.height) > MAX_TEXELS_PER_SIDE:
            raise ValueError(
                f"is {spec.width}×{spec.height} px, more than {MAX_TEXELS_PER_SIDE} px a side; give a smaller "
                "version of the set (4K or 2K)"
            )
        pixels = image_input.read_image(spec.format)  # native type: scaled below by its own full scale
    finally:
        image_input.close()
    if pixels is None:
        raise ValueError(f"holds no pixels ({oiio.geterror().strip() or 'truncated?'}); export it again")
    if pixels.dtype not in (np.uint8, np.uint16):
        raise ValueError(
            f"holds {pixels.dtype} samples; a texture image stores 8- or 16-bit codes (PNG, JPEG, TIFF): "
            "convert a float (EXR, HDR) map to a 16-bit PNG"
        )
    pixels = pixels.reshape(spec.height, spec.width, spec.nchannels)
    return (pixels.astype(np.float32) / np.float32(np.iinfo(pixels.dtype).max)).astype(np.float32)


def _readable(directory: Path, reference: str, key: str) -> Path:
    path = directory / reference
    problem = input_file_problem(path)
    if problem == "no such file":
        raise TextureFileError(
            key,
            f"refers to {reference!r}, but {path.resolve()} does not exist; give its path relative to the scene file",
        )
    if problem:
        raise TextureFileError(key, f"refers to {reference!r}, but {path.resolve()} {problem}")
    return path


def _image(directory: Path, reference: str, key: str) -> np.ndarray:
    path = _readable(directory, reference, key)
    try:
        return read_image_01(path)
    except ValueError as exc:
        raise TextureFileError(key, f"refers to {reference!r}, which {exc}; give a PNG, JPEG or TIFF") from None


def read_texture_images(
    directory: Path, base_color_file: str, normal_file: str | None = None, roughness_file: str | None = None
) -> TextureImages:
    """The images of a file texture whose paths are relative to `directory`, checked: readable, the
    channels each map needs, one size for all, a normal map that points out of the surface.
    TextureFileError names the first key at fault."""
    base = _image(directory, base_color_file, "base_color_file")
    if base.shape[2] not in (1, 3, 4):
        raise TextureFileError(
            "base_color_file",
            f"refers to {base_color_file!r}, which has {base.shape[2]} channels; give an RGB, RGBA or grey image",
        )
    base = np.repeat(base, 3, axis=2) if base.shape[2] == 1 else base[..., :3]
    height, width = base.shape[:2]
    normal = roughness = None
    if normal_file is not None:
        normal = _image(directory, normal_file, "normal_file")
        _same_size(normal, normal_file, "normal_file", base_color_file, width, height)
        if normal.shape[2] not in (3, 4):
            raise TextureFileError(
                "normal_file",
                f"refers to {normal_file!r}, which has {normal.shape[2]} channel(s); a normal map is RGB (X, Y, Z)",
            )
        normal = normal[..., :3]
        mean_z = float(np.mean(2.0 * normal[..., 2] - 1.0))
        if mean_z < MIN_NORMAL_Z:
            raise TextureFileError(
                "normal_file",
                f"refers to {normal_file!r}, whose mean Z (blue, out of the surface) is {mean_z:.2f}, under "
                f"{MIN_NORMAL_Z}: not a tangent-space normal map (those are bluish, about (0.5, 0.5, 1)); give "
                "the set's normal map",
            )
    if roughness_file is not None:
        image = _image(directory, roughness_file, "roughness_file")
        _same_size(image, roughness_file, "roughness_file", base_color_file, width, height)
        if image.shape[2] == 2 or (image.shape[2] > 1 and np.ptp(image[..., :3], axis=2).max() > 1.5 / 255):
            raise TextureFileError(
                "roughness_file",
                f"refers to {roughness_file!r}, which has {image.shape[2]} channels that differ; a roughness map "
                "is grey (one channel, or equal R, G and B): give the set's roughness map, not a colour or "
                "packed metallic-roughness image",
            )
        roughness = image[..., 0]
    return TextureImages(base, normal, roughness)


def _same_size(image: np.ndarray, reference: str, key: str, base_reference: str, width: int, height: int) -> None:
    if image.shape[:2] != (height, width):
        raise TextureFileError(
            key,
            f"refers to {reference!r}, which is {image.shape[1]}×{image.shape[0]} px, but base_color_file "
            f"{base_reference!r} is {width}×{height} px; a texture's maps share one size: give maps of one "
            "resolution of the set",
        )
