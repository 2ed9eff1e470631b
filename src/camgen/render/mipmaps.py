"""Textures whose mip levels camgen computes, averaging what the texels mean.

pyrender uploads a texture's full-size image and lets OpenGL's ``glGenerateMipmap`` make the smaller
levels. Two things go wrong with that, both measured on Mesa's llvmpipe with the 1024² procedural
asphalt (`camgen.world.textures`, mean linear reflectance 0.120, mean sRGB code 97.0):

- each level averages the 8-bit codes and rounds up, about half a code per level: the 1 × 1 level
  held 102, so a distant or grazing view, which samples the small levels, rendered the asphalt up to
  11 % brighter than its reflectance (+5 % over a whole parking lot seen from above);
- sRGB codes averaged as numbers are not the mean reflectance (the code is a concave function of it):
  a texture of 0.7 and 1.3 × a mean rendered 2.5 % too dark once its texels averaged.

`MipmappedTexture` uploads every level itself: level k + 1 is the 2 × 2 box mean of level k in floating
point, of the linear values for colour textures (sRGB decoded, averaged, encoded again: IEC 61966-2-1)
and of the stored values for data textures (roughness, metalness, normals, occlusion), each level
rounded to the nearest code once. Odd sizes take cv2.INTER_AREA's area weights.
"""

from __future__ import annotations

import numpy as np

from camgen.render.gl import pyrender
from camgen.world.textures import decode_srgb8, encode_srgb8


def mip_levels(image: np.ndarray, *, srgb: bool) -> list[np.ndarray]:
    """Every mip level of an (H, W, C) uint8 image, from the image itself down to 1 × 1 (OpenGL's sizes:
    each level ⌊half⌋ of the one above, at least 1). `srgb`: the codes are sRGB-encoded colours, averaged
    as linear values; otherwise the codes are averaged as they are."""
    import cv2

    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim != 3:
        raise ValueError(f"image must be (H, W, C) uint8, got {image.dtype} {image.shape}")
    values = decode_srgb8(image) if srgb else image.astype(np.float64)
    levels = [image]
    while values.shape[0] > 1 or values.shape[1] > 1:
        height, width = max(1, values.shape[0] // 2), max(1, values.shape[1] // 2)
        if values.shape[0] % 2 == 0 and values.shape[1] % 2 == 0 and values.shape[0] > 1 and values.shape[1] > 1:
            values = values.reshape(height, 2, width, 2, -1).mean(axis=(1, 3))
        else:
            resized = cv2.resize(values, (width, height), interpolation=cv2.INTER_AREA)
            values = resized.reshape(height, width, -1)
        levels.append(encode_srgb8(values) if srgb else np.round(values).clip(0, 255).astype(np.uint8))
    return levels


class MipmappedTexture(pyrender.Texture):
    """A pyrender texture whose mip levels are `mip_levels`' rather than ``glGenerateMipmap``'s.

    `srgb`: the image holds sRGB-encoded colour (base colour, emission), averaged as linear values;
    False for data (metallic-roughness, normals, occlusion)."""

    def __init__(self, *, srgb: bool, **kwargs):
        super().__init__(**kwargs)
        self.srgb = srgb

    def _add_to_context(self):
        from OpenGL import GL

        super()._add_to_context()  # the sampler's state and OpenGL's own levels (all replaced here)
        if self.source is None:
            return
        image = np.asarray(self.source)
        if image.ndim == 2:
            image = image[:, :, None]
        formats = {1: GL.GL_RED, 2: GL.GL_RG, 3: GL.GL_RGB, 4: GL.GL_RGBA}
        fmt = formats[image.shape[2]]
        GL.glBindTexture(self.tex_type, self._texid)
        # Rows of 1- and 3-channel levels are not 4-byte multiples, level 0 included: pyrender uploads that one
        # at OpenGL's default alignment of 4, which shears an image whose row is not (a 229 px wide RGB plate
        # came out striped and wrapped wherever level 0 was sampled), so every level is uploaded again here.
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        try:
            for level, data in enumerate(mip_levels(image, srgb=self.srgb)):
                flipped = np.ascontiguousarray(np.flip(data, axis=0))  # pyrender uploads row 0 last
                height, width = flipped.shape[:2]
                GL.glTexImage2D(self.tex_type, level, fmt, width, height, 0, fmt, GL.GL_UNSIGNED_BYTE, flipped)
        finally:
            GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 4)
            GL.glBindTexture(self.tex_type, 0)
