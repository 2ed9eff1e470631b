"""Virtual PTZ (ePTZ): the stream is a window of the sensor image, scaled to the output size.

The window is whole sensor pixels (x0, y0, width, height), as a camera's scaler crops them; the
scaled image maps output pixel u' to sensor position x = x0 + (u' + ½)·w/W' − ½ (OpenCV's resize
convention, pixel centres at integers), so the stream's camera matrix is

    fx' = fx·sx,  cx' = (cx − x0 + ½)·sx − ½,  sx = W'/w   (and likewise in y),

with the lens' distortion coefficients unchanged (they act on normalised coordinates, which a crop
and scale do not change). Annotations projected with K' and the same coefficients land on the
stream's pixels exactly.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from camgen.optics.projection import distort_points

Window = tuple[int, int, int, int]


def full_window_size_px(sensor_size_px: tuple[int, int], output_size_px: tuple[int, int]) -> tuple[float, float]:
    """Width and height of the largest window with the output's aspect ratio that fits the sensor, px."""
    width, height = sensor_size_px
    aspect = output_size_px[0] / output_size_px[1]
    if width / height >= aspect:
        return height * aspect, float(height)
    return float(width), width / aspect


def window_centre_px(pan_deg: float, tilt_deg: float, K_px: np.ndarray, distortion) -> np.ndarray:
    """Where the lens images the direction (pan, tilt) from the mount: the window's centre, px.

    The head frame is x forward, y left, z up (`camgen.motion.pose`); the camera looks along x at
    pan = tilt = 0, so the direction's OpenCV coordinates are (−y, −z, x)."""
    pan, tilt = math.radians(pan_deg), math.radians(tilt_deg)
    forward, left, up = math.cos(tilt) * math.cos(pan), math.cos(tilt) * math.sin(pan), math.sin(tilt)
    if forward <= 1e-9:
        raise ValueError(f"pan {pan_deg:g}°, tilt {tilt_deg:g}° looks behind the camera")
    K = np.asarray(K_px, dtype=np.float64)
    pinhole = np.array([K[0, 0] * (-left / forward) + K[0, 2], K[1, 1] * (-up / forward) + K[1, 2]])
    return distort_points(pinhole, K, distortion)


def eptz_window_px(
    centre_px: np.ndarray, zoom_x: float, sensor_size_px: tuple[int, int], output_size_px: tuple[int, int]
) -> Window:
    """The sensor window (x0, y0, width, height) of a virtual view, in whole pixels.

    Its size is the full window over `zoom_x`, rounded to whole pixels; it is centred on `centre_px`
    as closely as whole pixels allow and stopped at the sensor border."""
    full_w, full_h = full_window_size_px(sensor_size_px, output_size_px)
    width = max(1, min(sensor_size_px[0], round(full_w / zoom_x)))
    height = max(1, min(sensor_size_px[1], round(full_h / zoom_x)))
    x0 = round(float(centre_px[0]) + 0.5 - width / 2)
    y0 = round(float(centre_px[1]) + 0.5 - height / 2)
    x0 = min(max(x0, 0), sensor_size_px[0] - width)
    y0 = min(max(y0, 0), sensor_size_px[1] - height)
    return int(x0), int(y0), int(width), int(height)


def output_camera_matrix(K_px: np.ndarray, window: Window, output_size_px: tuple[int, int]) -> np.ndarray:
    """The camera matrix of the scaled window (see the module docstring)."""
    x0, y0, width, height = window
    sx, sy = output_size_px[0] / width, output_size_px[1] / height
    K = np.asarray(K_px, dtype=np.float64)
    out = K.copy()
    out[0, 0], out[0, 1], out[0, 2] = K[0, 0] * sx, K[0, 1] * sx, (K[0, 2] - x0 + 0.5) * sx - 0.5
    out[1, 1], out[1, 2] = K[1, 1] * sy, (K[1, 2] - y0 + 0.5) * sy - 0.5
    return out


def crop_and_scale(
    image: np.ndarray, window: Window, output_size_px: tuple[int, int], *, nearest: bool = False
) -> np.ndarray:
    """The window of `image` (H, W[, C]) scaled to the output size: area averaging when shrinking,
    bilinear when enlarging, nearest pixel for ids and depth (`nearest`)."""
    x0, y0, width, height = window
    crop = image[y0 : y0 + height, x0 : x0 + width]
    if (width, height) == tuple(output_size_px):
        return np.ascontiguousarray(crop)
    out_w, out_h = (int(n) for n in output_size_px)
    if nearest:  # any dtype (ids are uint32): index the pixel whose centre is nearest, same convention
        cols = np.minimum(np.floor((np.arange(out_w) + 0.5) * width / out_w).astype(np.intp), width - 1)
        rows = np.minimum(np.floor((np.arange(out_h) + 0.5) * height / out_h).astype(np.intp), height - 1)
        return crop[rows[:, None], cols[None, :]]
    flag = cv2.INTER_AREA if width >= out_w and height >= out_h else cv2.INTER_LINEAR
    return cv2.resize(crop, (out_w, out_h), interpolation=flag)
