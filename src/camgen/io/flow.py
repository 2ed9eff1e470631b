"""Write optical flow as Middlebury ``.flo`` and scene flow as OpenEXR.

``.flo`` (Baker et al. 2011, the Middlebury flow-code's flowIO): the float32 magic 202021.25 (the
bytes "PIEH"), the width and height as int32, then (u, v) float32 pairs row by row, little-endian.
OpenCV reads it with ``cv2.readOpticalFlow``. Unknown flow is stored as 1e10 (readers treat |u| or
|v| > 1e9 as unknown).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camgen.io.files import atomic_path
from camgen.io.frames import write_exr

FLO_MAGIC = 202021.25
"""The float32 tag that opens a .flo file (the bytes "PIEH")."""
SCENE_FLOW_CHANNELS = ("X", "Y", "Z")
"""EXR channel names of a scene-flow file: the world displacement's components, m."""


def write_flo(path: str | Path, flow_px: np.ndarray) -> None:
    """Write a flow field (H, W, 2), px, as a Middlebury .flo file (atomic: complete or absent).

    Raises
    ------
    ValueError
        If `flow_px` is not an (H, W, 2) float array, holds NaN, or `path` does not end in ``.flo``.
    """
    if Path(path).suffix.lower() != ".flo":
        raise ValueError(f"{path}: a Middlebury flow file is named *.flo")
    flow = np.asarray(flow_px)
    if flow.ndim != 3 or flow.shape[2] != 2 or not np.issubdtype(flow.dtype, np.floating) or 0 in flow.shape[:2]:
        raise ValueError(
            f"flow_px must be a float array of shape (H, W, 2) (u, v in px), got {flow.dtype} {flow.shape}"
        )
    if np.isnan(flow).any():
        raise ValueError("flow_px holds NaN; mark unknown flow with camgen.annotate.flow.UNKNOWN_FLOW_PX (1e10)")
    height_px, width_px = flow.shape[:2]
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(np.array([FLO_MAGIC], "<f4").tobytes())
        handle.write(np.array([width_px, height_px], "<i4").tobytes())
        handle.write(np.ascontiguousarray(flow, dtype="<f4").tobytes())


def write_scene_flow(path: str | Path, displacement_m: np.ndarray) -> None:
    """Write a scene-flow field (H, W, 3), m (world x, y, z), as a float EXR with channels X, Y, Z;
    NaN where no surface is seen is kept."""
    write_exr(path, np.ascontiguousarray(displacement_m, dtype=np.float32), channel_names=SCENE_FLOW_CHANNELS)
