"""Lens intrinsics and distortion from images of a checkerboard or a ChArUco board.

The board's inner corners are found in each image (sub-pixel), the camera is calibrated by Zhang's
method [1]_ (`cv2.calibrateCameraExtended`, which also gives each view's RMS reprojection error and the
standard deviations of the intrinsics), views that do not fit are rejected one at a time, and the
distortion model is chosen by how well it predicts views it was not fitted to: K-fold
cross-validation over views [2]_. For each fold the candidate model is calibrated on the training
views; each held-out view then gets only its pose from `cv2.solvePnP` (intrinsics and distortion held
at the training values), and its reprojection error measures the model's prediction. The simplest
candidate whose held-out error lies within a small tolerance of the best is chosen, because terms
that do not improve prediction only add correlation (k3 with k1 and k2) and extrapolate badly beyond
the board's reach.

Conventions (DESIGN.md): pixel centres at integer coordinates, the principal point's default at the
sensor centre ((W − 1)/2, (H − 1)/2) (`camgen.optics.intrinsics.camera_matrix_px`), distortion in
OpenCV order (k1, k2, p1, p2, k3, k4, k5, k6) mapping undistorted normalised coordinates to distorted
ones, exactly `cv2.projectPoints`; fx = f / pitch_x, fy = f / pitch_y.

References
----------
.. [1] Z. Zhang, "A flexible new technique for camera calibration", IEEE Trans. PAMI 22(11),
   pp. 1330–1334, 2000.
.. [2] T. Hastie, R. Tibshirani, J. Friedman, *The Elements of Statistical Learning*, 2nd ed.,
   Springer 2009, §7.10 (cross-validation).
.. [3] P. J. Rousseeuw, C. Croux, "Alternatives to the median absolute deviation", JASA 88(424),
   pp. 1273–1283, 1993 (MAD, scaled by 1.4826 to estimate a normal σ).
"""

from __future__ import annotations

import functools
import math
import re
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

from camgen.errors import ConfigError
from camgen.fit.frames import FrameReadError, image_files, listing, mixed_sizes_error, read_gray8
from camgen.optics.distortion import fold_inside
from camgen.optics.intrinsics import corner_radius_normalized

BOARD_EXAMPLES = (
    "'checkerboard:9x6:25mm' (9×6 inner corners, 25 mm squares) or "
    "'charuco:11x8:30mm:22mm:DICT_5X5_100' (11×8 squares of 30 mm, 22 mm ArUco markers from DICT_5X5_100)"
)
"""Valid board specs, quoted in every `parse_board` error."""
LENGTH_UNITS_M = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254}
"""Units a board spec's lengths may carry, in metres."""
MIN_VIEWS = 3
"""Fewest views a calibration accepts: Zhang's method needs three views of a plane for five
intrinsics [1]_ (OpenCV fixes the skew, but distortion needs the redundancy)."""
MIN_CHARUCO_CORNERS = 6
"""Fewest ChArUco corners, spanning two rows and two columns, that make a view: a pose needs four,
and two more leave a residual to judge it by."""
SCREENING_FLAGS = 0
"""The model outliers are screened with: OpenCV's default (k1, k2, p1, p2, k3 free), flexible enough
for ordinary lenses that a bad view stands out from the rest, too stiff to absorb one."""
CALIBRATION_CRITERIA = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
"""Levenberg–Marquardt termination: OpenCV's default 30 iterations can stop the rational model short."""
MAD_TO_SIGMA = 1.4826
"""σ of a normal distribution per median absolute deviation [3]_."""
COVERAGE_MIN = 0.7
"""Fraction of the way to each image corner the board's corners must reach before `fit_lens` stops
warning that distortion there is extrapolated."""
INTRINSIC_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
"""The first twelve entries of `cv2.calibrateCameraExtended`'s stdDeviationsIntrinsics, in its order."""
BOARD_NOT_FOUND = "board not found"
"""The reason given for an image without a usable board."""
DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
"""OpenCV order of the distortion coefficients (`camgen.config.profile.Distortion`)."""
CONSISTENT_RMS_MAX_PX = 1.0
"""Largest overall RMS reprojection error of a fit that is written without --accept-poor-fit, px. Corners
of a flat board are located to 0.05–0.3 px (sharp renders 0.04 px; OpenCV's sample boards and real
wide-angle boards 0.2–0.3 px, BENCHMARKS.md "fit"); an RMS above 1 px after outlier screening means the
views do not come from one camera and lens (a changed zoom or focus, a cropped or rescaled image), the
board is not flat, or corners were misdetected."""
FOCAL_RELATIVE_STD_MAX = 0.02
"""Largest relative 1σ uncertainty of fx or fy of a fit written without --accept-poor-fit. Fifteen views
tilted by 20–45° give 0.05–0.3 %; 2 % means the views hardly constrain the focal length (the board
nearly fronto-parallel in every view, or views that disagree)."""


@dataclass(frozen=True)
class BoardSpec:
    """A calibration board.

    For a checkerboard `inner_corners` is OpenCV's patternSize; a ChArUco board of (c, r) squares has
    (c − 1, r − 1) inner corners, which are its ChArUco corners.
    """

    kind: Literal["checkerboard", "charuco"]
    inner_corners: tuple[int, int]
    """Inner corners along the board's width and height (cols, rows)."""
    square_size_m: float
    """Side of one square, m."""
    marker_size_m: float | None = None
    """Side of a ChArUco board's ArUco markers, m (None for a checkerboard)."""
    dictionary: str | None = None
    """Name of a ChArUco board's predefined ArUco dictionary, e.g. ``DICT_5X5_100``."""

    @property
    def squares(self) -> tuple[int, int]:
        """Squares along the board's width and height."""
        return self.inner_corners[0] + 1, self.inner_corners[1] + 1

    def object_points_m(self) -> np.ndarray:
        """Every inner corner in the board's plane (z = 0), m, (N, 3) float32, in detection order:
        row by row, x fastest (OpenCV's for a checkerboard, ChArUco corner ids for a ChArUco board,
        whose origin is the board's outer corner, so its first inner corner lies at one square)."""
        if self.kind == "charuco":
            return self.charuco_board().getChessboardCorners().astype(np.float32)
        cols, rows = self.inner_corners
        points = np.zeros((cols * rows, 3), np.float32)
        points[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * self.square_size_m
        return points

    def charuco_board(self) -> cv2.aruco.CharucoBoard:
        """The OpenCV ChArUco board (OpenCV ≥ 4.6 pattern; boards printed by older versions with an
        even number of rows need `setLegacyPattern(True)`)."""
        if self.kind != "charuco":
            raise ValueError(f"a {self.kind} is not a ChArUco board")
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        return cv2.aruco.CharucoBoard(self.squares, self.square_size_m, self.marker_size_m, dictionary)


@dataclass(frozen=True)
class Detection:
    """The board's corners found in one image."""

    name: str
    """The image's file name."""
    corners_px: np.ndarray
    """(N, 1, 2) float32, px (pixel centres at integers)."""
    object_points_m: np.ndarray
    """(N, 3) float32, m: the same corners on the board (for ChArUco only those seen)."""


@dataclass(frozen=True)
class BoardImages:
    """What `detect_in_folder` found."""

    detections: tuple[Detection, ...]
    unusable: tuple[tuple[str, str], ...]
    """(file name, reason) of the images without a usable board: "board not found", or why the file
    could not be read."""
    size_px: tuple[int, int]
    """(width, height) shared by every image."""


@dataclass(frozen=True)
class DistortionModel:
    """A candidate distortion model: which coefficients `cv2.calibrateCamera` leaves free."""

    name: str
    coefficients: tuple[str, ...]
    """The free coefficients, in OpenCV order."""
    flags: int

    @property
    def parameters(self) -> int:
        """Free intrinsic parameters: fx, fy, cx, cy and the coefficients."""
        return 4 + len(self.coefficients)


DISTORTION_MODELS = (
    DistortionModel("k1k2", ("k1", "k2"), cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3),
    DistortionModel("k1k2k3", ("k1", "k2", "k3"), cv2.CALIB_ZERO_TANGENT_DIST),
    DistortionModel("k1k2p", ("k1", "k2", "p1", "p2"), cv2.CALIB_FIX_K3),
    DistortionModel("k1k2k3p", ("k1", "k2", "p1", "p2", "k3"), 0),
    DistortionModel("rational", DISTORTION_NAMES, cv2.CALIB_RATIONAL_MODEL),
)
"""The default candidates, simplest first ("k1k2k3p" is OpenCV's default model)."""
OPENCV_DEFAULT_MODEL = "k1k2k3p"
"""The candidate `cv2.calibrateCamera` fits without flags (k1, k2, p1, p2, k3), shown beside the chosen one."""


@dataclass(frozen=True)
class ModelScore:
    """How one candidate model did."""

    name: str
    parameters: int
    """Free intrinsic parameters (fx, fy, cx, cy and the distortion coefficients)."""
    held_out_rms_px: float
    """RMS reprojection error of the views held out of each fold, pooled over every corner, px
    (NaN if a fold's calibration failed)."""
    training_rms_px: float
    """RMS reprojection error of the calibration on every kept view, px."""
    intrinsics_px: tuple[float, float, float, float] = (math.nan,) * 4
    """(fx, fy, cx, cy) of the calibration on every kept view, px (NaN where it failed): how much the
    choice of model moves the intrinsics."""


@dataclass(frozen=True)
class LensFit:
    """Intrinsics and distortion fitted to board views, with their uncertainties and how they were chosen."""

    model: str
    """The selected distortion model (a `DistortionModel` name)."""
    size_px: tuple[int, int]
    """(width, height) of the images."""
    K_px: np.ndarray
    """(3, 3) camera matrix, px."""
    distortion: np.ndarray
    """(8,) OpenCV order (k1, k2, p1, p2, k3, k4, k5, k6); coefficients the model fixes are 0."""
    std: Mapping[str, float]
    """Standard deviation of fx, fy, cx, cy (px) and k1 … k6, p1, p2 (0 where fixed), from
    `cv2.calibrateCameraExtended`."""
    coefficients: tuple[str, ...]
    """The coefficients the selected model fitted, OpenCV order."""
    rms_px: float
    """RMS reprojection error over every corner of every kept view, px."""
    per_view_rms_px: Mapping[str, float]
    """Kept view name → its RMS reprojection error, px."""
    candidates: tuple[ModelScore, ...]
    selection: str
    """Why `model` was chosen among the candidates, in words."""
    rejected: tuple[tuple[str, str], ...]
    """(image name, reason) of every image left out: no board found, or an outlier view."""
    outlier_threshold_px: float
    """The per-view RMS above which the last screening pass would have rejected a view, px."""
    pixel_pitch_um: float | None
    """Horizontal pixel pitch given by the caller, µm."""
    warnings: tuple[str, ...]

    @property
    def principal_point_offset_px(self) -> tuple[float, float]:
        """(cx − (W − 1)/2, cy − (H − 1)/2), px: the sensor's `principal_point_offset_px`."""
        width, height = self.size_px
        return float(self.K_px[0, 2] - (width - 1) / 2), float(self.K_px[1, 2] - (height - 1) / 2)

    @property
    def aspect_is_significant(self) -> bool:
        """fx and fy differ by more than three (conservatively combined) standard deviations."""
        fx, fy = self.K_px[0, 0], self.K_px[1, 1]
        return abs(fx - fy) > 3 * math.hypot(self.std["fx"], self.std["fy"])

    @property
    def focal_length_mm(self) -> float | None:
        """f = fx · pitch_x, mm (None without a pixel pitch)."""
        return None if self.pixel_pitch_um is None else float(self.K_px[0, 0] * self.pixel_pitch_um * 1e-3)

    @property
    def pixel_pitch_y_um(self) -> float | None:
        """Vertical pitch f / fy = pitch_x · fx / fy, µm (None without a pixel pitch)."""
        if self.pixel_pitch_um is None:
            return None
        return float(self.pixel_pitch_um * self.K_px[0, 0] / self.K_px[1, 1])

    @property
    def sensor_size_mm(self) -> tuple[float, float] | None:
        """(W · pitch_x, H · pitch_y), mm, with pitch_y = pitch_x unless fx ≠ fy is significant."""
        if self.pixel_pitch_um is None:
            return None
        pitch_y_um = self.pixel_pitch_y_um if self.aspect_is_significant else self.pixel_pitch_um
        return self.size_px[0] * self.pixel_pitch_um * 1e-3, self.size_px[1] * pitch_y_um * 1e-3

    def profile_fragment(self) -> dict:
        """The fitted values as a partial camera profile (YAML-ready plain types).

        ``sensor``: width_px, height_px, principal_point_offset_px, and with a pixel pitch
        pixel_pitch_um plus pixel_pitch_y_um when fx ≠ fy is significant. ``lens``: focal_length_mm
        (with a pixel pitch) and all eight distortion coefficients (0 for those the model leaves out).

        Values are written at full float precision, not rounded to their uncertainty: the distortion
        coefficients are strongly correlated (k1 with k2 and k3, each with fx), so rounding each to its
        own σ moves the lens far more than σ does (a real wide-angle fit at 0.275 px RMS reprojected at
        1.27 px after rounding k1 1.743 → 1.7 and k4 2.104 → 2.1). The uncertainties go into the
        profile's header comments (`summary_rows`).
        """
        offset_x, offset_y = self.principal_point_offset_px
        sensor: dict = {"width_px": int(self.size_px[0]), "height_px": int(self.size_px[1])}
        lens: dict = {}
        if self.pixel_pitch_um is not None:
            sensor["pixel_pitch_um"] = float(self.pixel_pitch_um)
            # null (square pixels) rather than absent, so a base profile's own value is not inherited.
            sensor["pixel_pitch_y_um"] = None
            if self.aspect_is_significant:
                sensor["pixel_pitch_y_um"] = float(self.pixel_pitch_y_um)
            lens["focal_length_mm"] = float(self.focal_length_mm)
        sensor["principal_point_offset_px"] = [float(offset_x), float(offset_y)]
        values = dict(zip(DISTORTION_NAMES, self.distortion, strict=True))
        # Every coefficient, zeros included: a profile that `extends:` a base must not inherit the base's
        # terms that this model leaves out.
        lens["distortion"] = {
            name: float(values[name]) if name in self.coefficients else 0.0 for name in DISTORTION_NAMES
        }
        return {"sensor": sensor, "lens": lens}

    def summary_rows(self) -> list[tuple[str, float, float, str]]:
        """(name, value, standard deviation, unit) of every fitted quantity; NaN where no σ exists."""
        K = self.K_px
        offset_x, offset_y = self.principal_point_offset_px
        rows = [
            ("fx", float(K[0, 0]), self.std["fx"], "px"),
            ("fy", float(K[1, 1]), self.std["fy"], "px"),
            ("cx", float(K[0, 2]), self.std["cx"], "px"),
            ("cy", float(K[1, 2]), self.std["cy"], "px"),
            ("principal_point_offset_x", offset_x, self.std["cx"], "px"),
            ("principal_point_offset_y", offset_y, self.std["cy"], "px"),
        ]
        values = dict(zip(DISTORTION_NAMES, self.distortion, strict=True))
        rows += [(name, float(values[name]), self.std[name], "") for name in self.coefficients]
        if self.pixel_pitch_um is not None:
            pitch_mm = self.pixel_pitch_um * 1e-3
            rows.append(("focal_length", self.focal_length_mm, self.std["fx"] * pitch_mm, "mm"))
            rows.append(("focal_length_y", float(K[1, 1] * pitch_mm), self.std["fy"] * pitch_mm, "mm"))
            width_mm, height_mm = self.sensor_size_mm
            rows += [("sensor_width", width_mm, math.nan, "mm"), ("sensor_height", height_mm, math.nan, "mm")]
        rows.append(("rms", self.rms_px, math.nan, "px"))
        return rows


def rounded(value: float, std: float, *, std_digits: int = 2, max_digits: int = 8) -> float:
    """`value` rounded to `std_digits` significant digits of its standard deviation `std`.

    At most `max_digits` significant digits, and 6 when `std` is not a positive finite number. The
    rounding error is at most 5 % of σ for two digits.
    """
    value = float(value)
    if value == 0 or not math.isfinite(value):
        return value
    if std > 0 and math.isfinite(std):
        digits = math.floor(math.log10(abs(value))) - math.floor(math.log10(std)) + std_digits
    else:
        digits = 6
    return float(f"{value:.{min(max(digits, 1), max_digits)}g}")


# --- board specs and detection ---------------------------------------------------------------------


def _board_error(spec: str, what: str) -> ConfigError:
    return ConfigError(f"board spec {spec!r}: {what}; a valid one reads {BOARD_EXAMPLES}")


def _grid(spec: str, text: str, what: str) -> tuple[int, int]:
    match = re.fullmatch(r"\s*(\d+)\s*[x×X]\s*(\d+)\s*", text)
    if match is None:
        raise _board_error(spec, f"{what} must read COLSxROWS, e.g. 9x6, got {text!r}")
    return int(match[1]), int(match[2])


def _length_m(spec: str, text: str, what: str) -> float:
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-zA-Z]*)\s*", text)
    units = "|".join(LENGTH_UNITS_M)
    if match is None or not match[2]:
        raise _board_error(spec, f"{what} must be a positive length with a unit ({units}), e.g. 25mm, got {text!r}")
    if match[2].lower() not in LENGTH_UNITS_M:
        raise _board_error(spec, f"{what} has unknown unit {match[2]!r} (use {units}), got {text!r}")
    length_m = float(match[1]) * LENGTH_UNITS_M[match[2].lower()]
    if not length_m > 0:
        raise _board_error(spec, f"{what} must be > 0, got {text!r}")
    return length_m


def parse_board(spec: str) -> BoardSpec:
    """A board from its command-line spec.

    ``checkerboard:COLSxROWS:SQUARE`` gives the *inner* corners (OpenCV's patternSize) and the square
    side; ``charuco:COLSxROWS:SQUARE:MARKER:DICT`` gives the *squares*, the square and marker sides and
    the ArUco dictionary name. Lengths take a unit: mm, cm, m or in.

    Raises
    ------
    ConfigError
        Naming the spec, what is wrong with it and a valid example.
    """
    parts = spec.strip().split(":")
    kind = parts[0].strip().lower()
    if kind == "checkerboard":
        if len(parts) != 3:
            raise _board_error(spec, f"a checkerboard takes 3 ':'-separated parts, got {len(parts)}")
        cols, rows = _grid(spec, parts[1], "the inner corner grid")
        if cols < 3 or rows < 3:
            raise _board_error(spec, f"a checkerboard needs at least 3×3 inner corners, got {cols}×{rows}")
        return BoardSpec("checkerboard", (cols, rows), _length_m(spec, parts[2], "the square size"))
    if kind == "charuco":
        if len(parts) != 5:
            raise _board_error(spec, f"a ChArUco board takes 5 ':'-separated parts, got {len(parts)}")
        cols, rows = _grid(spec, parts[1], "the square grid")
        if cols < 3 or rows < 3:
            raise _board_error(spec, f"a ChArUco board needs at least 3×3 squares, got {cols}×{rows}")
        square_m = _length_m(spec, parts[2], "the square size")
        marker_m = _length_m(spec, parts[3], "the marker size")
        if marker_m >= square_m:
            raise _board_error(spec, f"the marker ({parts[3]}) must be smaller than the square ({parts[2]})")
        dictionary = parts[4].strip().upper()
        if not dictionary.startswith("DICT_") or not isinstance(getattr(cv2.aruco, dictionary, None), int):
            known = ", ".join(name for name in dir(cv2.aruco) if re.fullmatch(r"DICT_\dX\d_\d+", name))
            raise _board_error(spec, f"unknown ArUco dictionary {parts[4]!r} (OpenCV has {known})")
        markers_needed = cols * rows // 2
        markers = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)).bytesList.shape[0]
        if markers < markers_needed:
            raise _board_error(
                spec, f"{cols}×{rows} squares need {markers_needed} markers but {dictionary} has only {markers}"
            )
        return BoardSpec("charuco", (cols - 1, rows - 1), square_m, marker_m, dictionary)
    raise _board_error(spec, f"unknown board kind {parts[0]!r} (checkerboard or charuco)")


def detect_board(gray8: np.ndarray, board: BoardSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """The board's corners in one 8-bit grey image, sub-pixel.

    A checkerboard is found by `cv2.findChessboardCornersSB` with CALIB_CB_ACCURACY (its corners are
    sub-pixel by construction), retried with CALIB_CB_EXHAUSTIVE; all its inner corners must be seen.
    A ChArUco board by `cv2.aruco.CharucoDetector`, which refines its interpolated corners with
    `cv2.cornerSubPix` itself (a second pass with a fixed window measured worse: the markers next to
    each corner pull it); a view needs `MIN_CHARUCO_CORNERS` spanning two rows and two columns.

    Parameters
    ----------
    gray8 : (H, W) uint8
    board : BoardSpec

    Returns
    -------
    (corners_px (N, 1, 2) float32, object_points_m (N, 3) float32), or None where no usable board is found.
    """
    if board.kind == "checkerboard":
        for flags in (cv2.CALIB_CB_ACCURACY, cv2.CALIB_CB_ACCURACY | cv2.CALIB_CB_EXHAUSTIVE):
            found, corners = cv2.findChessboardCornersSB(gray8, board.inner_corners, flags=flags)
            if found:
                return corners.astype(np.float32).reshape(-1, 1, 2), board.object_points_m()
        return None
    corners, ids, _, _ = cv2.aruco.CharucoDetector(board.charuco_board()).detectBoard(gray8)
    if ids is None or len(ids) < MIN_CHARUCO_CORNERS:
        return None
    ids = ids.ravel()
    rows, cols = np.divmod(ids, board.inner_corners[0])
    if len(np.unique(rows)) < 2 or len(np.unique(cols)) < 2:
        return None  # collinear corners give no pose
    return corners.astype(np.float32).reshape(-1, 1, 2), board.object_points_m()[ids]


def detect_in_folder(
    directory: Path, board: BoardSpec, *, on_image: Callable[[Path], None] | None = None
) -> BoardImages:
    """Find the board in every image of `directory` (`camgen.fit.frames.image_files`: images and raw
    files, sorted by name, or a camgen render's frames of every camera; read by
    `camgen.fit.frames.read_gray8`). Each detection is named by its path below `directory`.

    `on_image` is called with each path before it is read (for progress). A file that cannot be read
    is reported in `BoardImages.unusable` with the reason, like an image without a board.

    Raises
    ------
    ConfigError
        When the folder is missing or holds no images, none can be read, or they differ in size (the
        message gives the common size and names the others).
    """
    directory = Path(directory)
    detections, unusable, sizes = [], [], {}
    for path in image_files(directory):
        if on_image is not None:
            on_image(path)
        name = path.relative_to(directory).as_posix()  # a render's frames share names: keep the camera
        try:
            gray8 = read_gray8(path)
        except FrameReadError as error:
            unusable.append((name, str(error)))
            continue
        sizes.setdefault((gray8.shape[1], gray8.shape[0]), []).append(name)
        found = detect_board(gray8, board)
        if found is None:
            unusable.append((name, BOARD_NOT_FOUND))
        else:
            detections.append(Detection(name, *found))
    if not sizes:
        reasons = listing([f"{name} {reason}" for name, reason in unusable])
        raise ConfigError(f"{directory}: none of its images could be read ({reasons})")
    if len(sizes) > 1:
        raise mixed_sizes_error(directory, "images of mixed sizes", sizes, "calibrate one camera mode at a time")
    return BoardImages(tuple(detections), tuple(unusable), next(iter(sizes)))


# --- calibration -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Calibration:
    rms_px: float
    K_px: np.ndarray
    distortion: np.ndarray
    """(8,) OpenCV order."""
    std: np.ndarray
    """(12,) in `INTRINSIC_NAMES` order."""
    per_view_rms_px: np.ndarray


def _calibrate(detections: Sequence[Detection], size_px: tuple[int, int], flags: int) -> _Calibration:
    """`cv2.calibrateCameraExtended` over `detections` (cv2.error becomes a ConfigError naming the views)."""
    try:
        rms, K, dist, _, _, std, _, per_view = cv2.calibrateCameraExtended(
            [d.object_points_m for d in detections],
            [d.corners_px for d in detections],
            size_px,
            None,
            None,
            flags=flags,
            criteria=CALIBRATION_CRITERIA,
        )
    except cv2.error as error:
        raise ConfigError(
            f"calibration failed on {listing([d.name for d in detections])} "
            f"({error.err.strip()}); the views may be too few or too alike: tilt the board more"
        ) from None
    distortion = np.zeros(8)
    coefficients = np.ravel(dist)[:8]
    distortion[: coefficients.size] = coefficients
    return _Calibration(float(rms), K, distortion, np.ravel(std)[:12], np.ravel(per_view))


def reprojection_residuals_px(detection: Detection, K_px: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """Detected − projected corners, (N, 2) px, after fitting only the view's pose (`cv2.solvePnP`,
    Levenberg–Marquardt) with the intrinsics and distortion held fixed."""
    _, rvec, tvec = cv2.solvePnP(detection.object_points_m, detection.corners_px, K_px, distortion)
    projected, _ = cv2.projectPoints(detection.object_points_m, rvec, tvec, K_px, distortion)
    return (detection.corners_px - projected).reshape(-1, 2)


def _outlier_threshold_px(
    per_view_rms_px: np.ndarray, factor: float, mads: float, floor_px: float
) -> tuple[float, str]:
    """The screening threshold, px, and which of its terms set it (for the rejection reason)."""
    median = float(np.median(per_view_rms_px))
    sigma = MAD_TO_SIGMA * float(np.median(np.abs(per_view_rms_px - median)))
    terms = [
        (factor * median, f"{factor:g} × median {median:.3g} px"),
        (median + mads * sigma, f"median {median:.3g} px + {mads:g} × MAD σ {sigma:.3g} px"),
        (floor_px, f"floor {floor_px:g} px"),
    ]
    return max(terms)


def _screen(
    detections: list[Detection], size_px: tuple[int, int], factor: float, mads: float, floor_px: float
) -> tuple[list[Detection], list[tuple[str, str]], float]:
    """Drop the worst view while its RMS exceeds the threshold, recalibrating after each drop (one
    at a time: a bad view inflates its neighbours' errors until it is gone)."""
    rejected = []
    while True:
        rms = _calibrate(detections, size_px, SCREENING_FLAGS).per_view_rms_px
        threshold, why = _outlier_threshold_px(rms, factor, mads, floor_px)
        worst = int(np.argmax(rms))
        if rms[worst] <= threshold:
            return detections, rejected, threshold
        rejected.append((detections[worst].name, f"view RMS {rms[worst]:.3g} px > {threshold:.3g} px ({why})"))
        detections = detections[:worst] + detections[worst + 1 :]
        if len(detections) < MIN_VIEWS:
            dropped = "; ".join(f"{name}: {reason}" for name, reason in rejected)
            raise ConfigError(
                f"only {len(detections)} views remain after rejecting outliers ({dropped}); "
                f"calibration needs at least {MIN_VIEWS}: add sharp views of the board"
            )


def _score(
    detections: list[Detection], size_px: tuple[int, int], model: DistortionModel, folds: int
) -> tuple[ModelScore, _Calibration | None]:
    """Held-out and training error of one model, and its calibration on every view (None, with NaN
    errors, where a calibration fails)."""
    try:
        full = _calibrate(detections, size_px, model.flags)
        fold_calibrations = [
            _calibrate([d for i, d in enumerate(detections) if i % folds != fold], size_px, model.flags)
            for fold in range(folds)
        ]
    except ConfigError:
        return ModelScore(model.name, model.parameters, math.nan, math.nan), None
    K = full.K_px
    intrinsics_px = (float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]))
    residuals = [
        reprojection_residuals_px(detection, calibration.K_px, calibration.distortion)
        for fold, calibration in enumerate(fold_calibrations)
        for detection in detections[fold::folds]
    ]
    held_out = math.sqrt(float(np.mean(np.sum(np.concatenate(residuals) ** 2, axis=1))))
    return ModelScore(model.name, model.parameters, held_out, full.rms_px, intrinsics_px), full


def _coverage_warnings(detections: Sequence[Detection], K_px: np.ndarray, size_px: tuple[int, int]) -> list[str]:
    """Image quadrants the board's corners do not reach `COVERAGE_MIN` of the way into."""
    width, height = size_px
    corners = np.concatenate([d.corners_px.reshape(-1, 2) for d in detections]) - K_px[:2, 2]
    warnings = []
    for sx, sy, where in ((-1, -1, "top-left"), (1, -1, "top-right"), (-1, 1, "bottom-left"), (1, 1, "bottom-right")):
        image_corner = np.array([-0.5 if sx < 0 else width - 0.5, -0.5 if sy < 0 else height - 0.5]) - K_px[:2, 2]
        inside = np.all(np.sign(corners) == (sx, sy), axis=1)
        reach = float(np.hypot(*corners[inside].T).max()) / float(np.hypot(*image_corner)) if inside.any() else 0.0
        if reach < COVERAGE_MIN:
            warnings.append(
                f"the board reaches only {reach:.0%} of the way to the {where} image corner; distortion there "
                "is extrapolated: add views with the board in that corner"
            )
    return warnings


def _inconsistency(calibration: _Calibration) -> list[str]:
    """What in a calibration shows that its views disagree, or that they do not determine the lens."""
    doubts = []
    if calibration.rms_px > CONSISTENT_RMS_MAX_PX:
        doubts.append(
            f"the corners miss their fitted positions by {calibration.rms_px:.3g} px RMS, more than the "
            f"{CONSISTENT_RMS_MAX_PX:g} px views of one flat board through one lens leave"
        )
    K = calibration.K_px
    for name, value, std in (("fx", K[0, 0], calibration.std[0]), ("fy", K[1, 1], calibration.std[1])):
        if not std <= FOCAL_RELATIVE_STD_MAX * abs(value):
            doubts.append(
                f"{name} is {value:.4g} ± {std:.2g} px (±{std / abs(value):.1%}), more uncertain than "
                f"±{FOCAL_RELATIVE_STD_MAX:.0%}"
            )
    return doubts


def _fold(calibration: _Calibration, size_px: tuple[int, int]) -> str | None:
    """Why the fitted distortion folds over inside the image, or None: a profile cannot hold such a lens
    (`camgen.config.profile.Profile` refuses it, by the same test)."""
    K = calibration.K_px
    corner_radius = corner_radius_normalized(K, *size_px)
    if not np.any(calibration.distortion) or not math.isfinite(corner_radius):
        return None
    reach = fold_inside(calibration.distortion, corner_radius)
    if reach is None:
        return None
    coefficients = ", ".join(
        f"{n} {v:.3g}" for n, v in zip(DISTORTION_NAMES, calibration.distortion, strict=False) if v
    )
    return (
        f"the fitted distortion ({coefficients}) folds over inside the image: its radial mapping turns back at "
        f"normalised radius {reach:.3f}, the image corner lies at {corner_radius:.3f}"
    )


def one_opencv_thread(function):
    """Run `function` with OpenCV on one thread, then restore its thread count.

    `cv2.calibrateCamera` is not deterministic on several threads: its parallel reductions sum in an order
    that depends on scheduling, and Levenberg–Marquardt carries the last-digit differences into different
    paths. Measured on this machine with 15 views: the rational model's coefficients differed by up to 79
    between identical calls on 2 threads, and agreed to the last bit on one (which cost 1.3× the time).
    Fitted profiles are written at full precision, so the same images must give the same bytes.

    OpenCV's thread count is process-wide: while any such call runs, all OpenCV work in the process runs
    on one thread. Calls from several threads share one count of those running (under a lock), and the
    last to finish restores the count the first found."""

    @functools.wraps(function)
    def on_one_thread(*args, **kwargs):
        with _ONE_THREAD:
            return function(*args, **kwargs)

    return on_one_thread


class _OneOpenCVThread:
    """OpenCV on one thread while any user is inside; the first in saves the thread count, the last out
    restores it."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._users = 0
        self._saved_threads = 0

    def __enter__(self) -> None:
        with self._lock:
            if self._users == 0:
                self._saved_threads = cv2.getNumThreads()
                cv2.setNumThreads(1)
            self._users += 1

    def __exit__(self, *exc) -> None:
        with self._lock:
            self._users -= 1
            if self._users == 0:
                cv2.setNumThreads(self._saved_threads)


_ONE_THREAD = _OneOpenCVThread()


@one_opencv_thread
def fit_lens(
    detections: Sequence[Detection],
    size_px: tuple[int, int],
    *,
    unusable: Sequence[tuple[str, str]] = (),
    pixel_pitch_um: float | None = None,
    models: Sequence[DistortionModel] = DISTORTION_MODELS,
    folds: int = 5,
    outlier_factor: float = 3.0,
    outlier_mads: float = 5.0,
    outlier_floor_px: float = 0.2,
    selection_tolerance: float = 0.02,
    selection_tolerance_px: float = 0.002,
    accept_poor_fit: bool = False,
) -> LensFit:
    """Intrinsics and distortion from board detections, with outlier views rejected and the distortion
    model chosen by held-out reprojection error.

    1. Screening: calibrate (`SCREENING_FLAGS`); while the worst view's RMS exceeds
       ``max(outlier_factor · median, median + outlier_mads · 1.4826 · MAD, outlier_floor_px)``, reject
       it and calibrate again. The relative terms adapt to the detector's noise (0.04 px on sharp
       renders, typically 0.1–0.3 px on real images); the floor keeps views whose error is within a
       few times a sharp image's detection noise, which carry no evidence of being wrong.
    2. Selection: for each candidate, K-fold cross-validation over views (``min(folds, views)`` folds;
       view i in fold i mod K): calibrate on the other folds, fit each held-out view's pose alone
       (`reprojection_residuals_px`) and pool its squared errors. The chosen model is the one with
       the fewest parameters whose held-out RMS is within
       ``max(selection_tolerance · best, selection_tolerance_px)`` of the best: 2 % (or 0.002 px on
       near-perfect data) is an improvement no application can see, and smaller differences between
       nested models are within the fold-to-fold scatter.
    3. The chosen model's calibration on every kept view is the result.

    Parameters
    ----------
    detections : the views where the board was found (`detect_in_folder`, `detect_board`).
    size_px : (width, height) of the images.
    unusable : (name, reason) of images left out before fitting (`BoardImages.unusable`), reported
        as rejected.
    pixel_pitch_um : horizontal pixel pitch, µm, for the focal length and sensor size in mm.
    models : candidate distortion models; ties in parameter count go to the earlier one.
    folds : folds of the cross-validation (leave-one-out with fewer views).
    outlier_factor, outlier_mads, outlier_floor_px : the screening threshold's terms (px for the floor).
    selection_tolerance, selection_tolerance_px : the selection tolerance, relative and px.
    accept_poor_fit : return a fit that `_inconsistency` doubts (its doubts become warnings) instead of
        raising.

    Raises
    ------
    ConfigError
        Fewer than `MIN_VIEWS` views show the board, or remain after rejecting outliers (the message
        names the files and why each was dropped), or the calibration fails, or (unless
        `accept_poor_fit`) the fit shows the views disagree: RMS above `CONSISTENT_RMS_MAX_PX` or fx or fy
        more uncertain than `FOCAL_RELATIVE_STD_MAX`; and whatever `accept_poor_fit` says, when the fitted
        distortion folds over inside the image (no profile can hold it).
    """
    total = len(detections) + len(unusable)
    rejected = [(name, reason) for name, reason in unusable]
    left_out = listing([f"{name} ({reason})" for name, reason in unusable])
    if len(detections) < MIN_VIEWS:
        raise ConfigError(
            f"the board was found in {len(detections)} of {total} images"
            + (f" ({listing([d.name for d in detections])})" if detections else "")
            + f"; calibration needs at least {MIN_VIEWS}"
            + (f"; left out: {left_out}" if unusable else "")
            + ": check the board spec against the printed board and that the whole board is in view"
        )
    warnings = []
    if len(detections) < total / 2:
        warnings.append(
            f"the board was found in only {len(detections)} of {total} images (left out: {left_out}); "
            "check the board spec and the lighting"
        )
    kept, outliers, threshold_px = _screen(list(detections), size_px, outlier_factor, outlier_mads, outlier_floor_px)
    rejected += outliers
    fold_count = min(folds, len(kept))
    scored = [_score(kept, size_px, model, fold_count) for model in models]
    candidates = tuple(score for score, _ in scored)
    finite = [s.held_out_rms_px for s in candidates if math.isfinite(s.held_out_rms_px)]
    if not finite:
        raise ConfigError(
            f"no distortion model could be cross-validated on {listing([d.name for d in kept])}: "
            "the calibration of a training fold failed; add more views, with the board tilted more"
        )
    best = min(finite)
    tolerance = max(selection_tolerance * best, selection_tolerance_px)
    order = sorted(range(len(models)), key=lambda i: models[i].parameters)
    chosen = next(i for i in order if candidates[i].held_out_rms_px <= best + tolerance)
    model, calibration = models[chosen], scored[chosen][1]
    best_name = next(s.name for s in candidates if s.held_out_rms_px == best)
    selection = (
        f"{model.name} ({model.parameters} parameters) predicts held-out views to "
        f"{candidates[chosen].held_out_rms_px:.4g} px RMS"
        + (
            " (the best)"
            if best_name == model.name
            else f", within {tolerance:.2g} px of the best, {best_name} at {best:.4g} px: more terms would add "
            "correlation without predicting better"
        )
    )
    for score in candidates:
        if not math.isfinite(score.held_out_rms_px):
            warnings.append(f"model {score.name} could not be calibrated on these views, so it was not a candidate")
    warnings += _coverage_warnings(kept, calibration.K_px, size_px)
    doubts = _inconsistency(calibration)
    fold = _fold(calibration, size_px)
    worst = sorted(zip(kept, calibration.per_view_rms_px, strict=True), key=lambda item: -item[1])[:5]
    worst_views = listing([f"{d.name} ({rms:.2g} px)" for d, rms in worst])
    advice = (
        "check that every image comes from one camera at one zoom and focus, uncropped and unscaled, that the "
        "board is flat and that the board spec matches it, and add views with the board tilted 20–45° towards "
        "each side; a fisheye lens is beyond the Brown–Conrady models fitted here"
    )
    if fold is not None:
        raise ConfigError(
            f"{'; '.join([fold, *doubts])}; no profile can hold such a lens (views with the worst RMS: "
            f"{worst_views}): {advice}"
        )
    if doubts and not accept_poor_fit:
        raise ConfigError(
            f"the fit is not trustworthy: {'; '.join(doubts)} (views with the worst RMS: {worst_views}); a "
            f"profile from it would be wrong: {advice} (or pass --accept-poor-fit to write it anyway)"
        )
    warnings += doubts
    return LensFit(
        model=model.name,
        size_px=(int(size_px[0]), int(size_px[1])),
        K_px=calibration.K_px,
        distortion=calibration.distortion,
        std=dict(zip(INTRINSIC_NAMES, (float(s) for s in calibration.std), strict=True)),
        coefficients=model.coefficients,
        rms_px=calibration.rms_px,
        per_view_rms_px={d.name: float(r) for d, r in zip(kept, calibration.per_view_rms_px, strict=True)},
        candidates=candidates,
        selection=selection,
        rejected=tuple(rejected),
        outlier_threshold_px=threshold_px,
        pixel_pitch_um=pixel_pitch_um,
        warnings=tuple(warnings),
    )
