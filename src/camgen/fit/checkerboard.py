"""Camera intrinsics from views of a checkerboard, with OpenCV (Zhang's method).

Used to verify rendered geometry (the render tests and `bench`) and, later, to fit lens profiles
from real board images.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from camgen.config.scene import CheckerboardMesh
from camgen.fit.lens import BoardSpec, detect_board, one_opencv_thread

LUMINANCE_WEIGHTS_BT709 = np.array([0.2126, 0.7152, 0.0722], np.float32)
"""Y of linear BT.709 RGB (ITU-R BT.709-6, item 3.2)."""


@dataclass(frozen=True)
class Calibration:
    rms_px: float
    """Reprojection error over every corner of every view, px."""
    K_px: np.ndarray
    distortion: np.ndarray
    """OpenCV order (k1, k2, p1, p2, k3)."""
    views_used: int


def inner_corners(board: CheckerboardMesh) -> tuple[int, int]:
    """Inner corner grid of a board: one fewer than its squares along each axis."""
    return board.squares[0] - 1, board.squares[1] - 1


def board_spec(board: CheckerboardMesh) -> BoardSpec:
    """The calibration board (`camgen.fit.lens`) a scene's checkerboard mesh is."""
    return BoardSpec("checkerboard", inner_corners(board), board.square_size_m)


def board_points_m(board: CheckerboardMesh) -> np.ndarray:
    """Inner corners in the board's own plane (z = 0), m, in OpenCV's detection order: (N, 3) float32."""
    return board_spec(board).object_points_m()


def gray8_from_radiance(radiance_cd_m2: np.ndarray) -> np.ndarray:
    """An 8-bit grey view of linear radiance for corner detection: luminance, white at the 99.5th
    percentile (so the board's light squares do not clip), gamma 1/2.2."""
    luminance = radiance_cd_m2 @ LUMINANCE_WEIGHTS_BT709
    white = max(float(np.percentile(luminance, 99.5)), np.finfo(np.float32).tiny)
    return np.round(255 * np.clip(luminance / white, 0, 1) ** (1 / 2.2)).astype(np.uint8)


def find_corners(gray8: np.ndarray, inner: tuple[int, int]) -> np.ndarray | None:
    """Sub-pixel inner corners (N, 1, 2) of a board in an 8-bit grey image, or None if not found
    (`camgen.fit.lens.detect_board`)."""
    found = detect_board(gray8, BoardSpec("checkerboard", inner, 1.0))
    return None if found is None else found[0]


RECTILINEAR = cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3
"""`calibrate` flags for a lens known to be free of distortion: only the intrinsics are fitted, which
removes their correlation with k1…k3 (it matters at long focal lengths, where perspective is weak)."""


@one_opencv_thread
def calibrate(
    board: CheckerboardMesh, corners: list[np.ndarray], size_px: tuple[int, int], flags: int = 0
) -> Calibration:
    """`cv2.calibrateCamera` over the views whose corners were found (k1, k2, p1, p2, k3 free unless
    `flags` fix them, e.g. `RECTILINEAR`)."""
    if len(corners) < 3:
        raise ValueError(f"calibration needs the board in at least 3 views, found it in {len(corners)}")
    points = board_points_m(board)
    rms, K, dist, _, _ = cv2.calibrateCamera([points] * len(corners), corners, size_px, None, None, flags=flags)
    return Calibration(float(rms), K, dist.ravel(), len(corners))
