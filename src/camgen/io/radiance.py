"""Write the scene-referred radiance of a camera's frames: 16-bit linear PNG/TIFF with one documented
scale per camera, or float32 OpenEXR.

Samples are the renderer's linear RGB (BT.709 primaries, scaled so that 0.2126 R + 0.7152 G + 0.0722 B
is the luminance in cd/m², `camgen.render.renderer`; with motion blur planned, the mean over the
exposure). 16-bit files store DN = round(radiance / scale),
clipped to 0…65535, with ``scale_cd_m2_per_dn`` in ``radiance.json`` beside them; a reader recovers
radiance = DN · scale within half a step. The scale is a power of two chosen on the camera's first
frame so that its brightest sample uses at most 1 / `HEADROOM` of the range; later, brighter samples
clip at 65535 and ``radiance.json`` counts them per frame.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import MappingProxyType
from typing import Literal

import numpy as np

from camgen.io.files import write_text_atomic
from camgen.io.frames import write_frame

RADIANCE_FORMATS = ("png16", "tiff16", "exr")
RADIANCE_SUFFIX = MappingProxyType({"png16": ".png", "tiff16": ".tif", "exr": ".exr"})
HEADROOM = 4.0
"""The first frame's brightest sample maps to at most 65535 / HEADROOM DN: room for a scene that
brightens (the sun out of a cloud, lights on) before samples clip."""
DN_MAX = 65535
SCALE_MIN_CD_M2_PER_DN = 2.0**-20
"""Smallest scale (a black first frame gets it): 1e-6 cd/m² per DN, below starlight's ~1e-4 cd/m²."""


def radiance_scale_cd_m2_per_dn(radiance: np.ndarray) -> float:
    """The power-of-two scale (cd/m² per DN) at which the brightest finite sample of `radiance`
    takes at most 65535 / `HEADROOM` DN."""
    finite = radiance[np.isfinite(radiance)]
    peak = float(finite.max()) if finite.size else 0.0
    if peak <= 0.0:
        return SCALE_MIN_CD_M2_PER_DN
    return max(SCALE_MIN_CD_M2_PER_DN, 2.0 ** math.ceil(math.log2(peak * HEADROOM / DN_MAX)))


def radiance_u16(radiance: np.ndarray, scale_cd_m2_per_dn: float) -> tuple[np.ndarray, int]:
    """Radiance (…, 3) → uint16 DN = round(radiance / scale) clipped to 0…65535, and how many samples
    clipped at the top. Non-finite samples become 65535 (counted)."""
    dn = np.rint(np.asarray(radiance, dtype=np.float64) / scale_cd_m2_per_dn)
    over = ~(dn <= DN_MAX)  # NaN too
    dn[over] = DN_MAX
    return np.clip(dn, 0, DN_MAX).astype(np.uint16), int(np.count_nonzero(over))


class RadianceWriter:
    """Writes one camera's radiance frames under `directory` and, on `close`, radiance.json."""

    def __init__(self, directory: str | Path, format: Literal["png16", "tiff16", "exr"]):
        if format not in RADIANCE_FORMATS:
            raise ValueError(f"radiance format must be one of {', '.join(RADIANCE_FORMATS)}, got {format!r}")
        self.directory, self.format = Path(directory), format
        self.scale_cd_m2_per_dn: float | None = None
        self.clipped: dict[str, int] = {}

    def write(self, name: str, radiance: np.ndarray) -> Path:
        """Write one frame's (H, W, 3) radiance as `name` plus the format's suffix; returns the path."""
        path = self.directory / f"{name}{RADIANCE_SUFFIX[self.format]}"
        if self.format == "exr":
            write_frame(path, np.ascontiguousarray(radiance, dtype=np.float32), format="exr")
            return path
        if self.scale_cd_m2_per_dn is None:
            self.scale_cd_m2_per_dn = radiance_scale_cd_m2_per_dn(radiance)
        dn, clipped = radiance_u16(radiance, self.scale_cd_m2_per_dn)
        self.clipped[name] = clipped
        write_frame(path, dn, format="png" if self.format == "png16" else "tiff")
        return path

    def close(self) -> Path:
        """Write radiance.json (unit, encoding, scale, clipped samples per frame); returns its path."""
        meta: dict = {
            "unit": "cd/m² per channel: linear RGB, BT.709 primaries, 0.2126 R + 0.7152 G + 0.0722 B = luminance",
            "geometry": "the output frame through the lens's distortion; no lens blur, lateral CA or vignetting",
            "format": self.format,
        }
        if self.format != "exr":
            meta["encoding"] = "radiance_cd_m2 = DN * scale_cd_m2_per_dn"
            meta["scale_cd_m2_per_dn"] = self.scale_cd_m2_per_dn
            meta["clipped_samples"] = self.clipped
        path = self.directory / "radiance.json"
        write_text_atomic(path, json.dumps(meta, indent=1, ensure_ascii=False))
        return path
