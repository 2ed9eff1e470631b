"""Annotations drawn over 8-bit frames: boxes, track ids, masks, keypoint skeletons, track tails, the camera's
state, and a contact sheet of several frames.

Every function is pure: it takes an (H, W, 3) uint8 RGB image and returns a new one, the input untouched.
Coordinates are pixels in the OpenCV convention of `shared/DESIGN.md` (the centre of the top-left pixel is
(0, 0)). A COCO box ``[x, y, w, h]`` as camgen writes it spans the pixels ``x … x + w − 1`` and
``y … y + h − 1`` (the mask's outermost pixels), so its outline is drawn on exactly those pixels.
Text is OpenCV's Hershey font, which has ASCII only ("deg", "x" for ° and ×).
"""

from __future__ import annotations

import colorsys
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

GOLDEN_RATIO_CONJUGATE = (math.sqrt(5) - 1) / 2
"""Hue step between successive track ids: consecutive ids land far apart on the colour wheel."""
TRACK_SATURATION = 0.85
TRACK_VALUE = 1.0
MASK_ALPHA = 0.4
"""Weight of the track colour inside a mask (0: invisible, 1: opaque)."""
OCCLUDED_KEYPOINT_DIM = 0.5
"""Colour scale of a keypoint COCO marks as labelled but not visible (v = 1)."""
SKELETON_RIM_RGB8 = (20, 20, 20)
CONTACT_SHEET_COLUMNS = 4
CONTACT_SHEET_TILE_WIDTH_PX = 320
"""Width of one tile of the contact sheet (frames narrower than this keep their width)."""
CONTACT_SHEET_GAP_PX = 4
CONTACT_SHEET_BACKGROUND_RGB8 = (24, 24, 24)
FONT = cv2.FONT_HERSHEY_SIMPLEX


@dataclass(frozen=True)
class Style:
    """Line width and text size for one frame height, so that a 240-line and a 1080-line frame look alike."""

    line_px: int
    font_scale: float
    text_px: int

    @classmethod
    def for_height(cls, height_px: int) -> Style:
        """1 px lines and 0.35 text up to 360 lines, growing in proportion above."""
        scale = max(height_px / 360, 1.0)
        return cls(line_px=max(1, round(scale)), font_scale=0.35 * scale, text_px=max(1, round(scale)))


def track_colour_rgb8(track_id: int) -> tuple[int, int, int]:
    """The colour of a track: a function of its id alone, so one object keeps its colour over frames,
    cameras and runs. Hue ``(id · φ⁻¹) mod 1`` (φ the golden ratio), saturation 0.85, value 1."""
    hue = (int(track_id) * GOLDEN_RATIO_CONJUGATE) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, TRACK_SATURATION, TRACK_VALUE)
    return round(255 * r), round(255 * g), round(255 * b)


def box_corners_px(bbox_xywh: Sequence[float]) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1), the first and last pixel column and row of a COCO box ``[x, y, w, h]``."""
    x, y, w, h = (float(v) for v in bbox_xywh)
    return round(x), round(y), round(x + w) - 1, round(y + h) - 1


def draw_box(
    image: np.ndarray, bbox_xywh: Sequence[float], colour_rgb8: Sequence[int], *, line_px: int = 1
) -> np.ndarray:
    """The outline of a COCO box on its outermost pixels (`box_corners_px`), `line_px` wide, centred on them."""
    out = image.copy()
    x0, y0, x1, y1 = box_corners_px(bbox_xywh)
    cv2.rectangle(out, (x0, y0), (x1, y1), tuple(int(c) for c in colour_rgb8), line_px, cv2.LINE_8)
    return out


def blend_mask(
    image: np.ndarray, mask: np.ndarray, colour_rgb8: Sequence[int], *, alpha: float = MASK_ALPHA
) -> np.ndarray:
    """``(1 − alpha) · image + alpha · colour`` inside `mask` (an (H, W) bool array), rounded; outside it the
    pixels stay as they are."""
    out = image.copy()
    inside = np.asarray(mask, dtype=bool)
    mixed = (1 - alpha) * image[inside].astype(np.float32) + alpha * np.asarray(colour_rgb8, np.float32)
    out[inside] = np.clip(np.rint(mixed), 0, 255).astype(np.uint8)
    return out


def draw_skeleton(
    image: np.ndarray,
    keypoints: Sequence[float],
    skeleton: Sequence[Sequence[int]],
    colour_rgb8: Sequence[int],
    *,
    line_px: int = 1,
) -> np.ndarray:
    """A COCO keypoint skeleton: `keypoints` flat ``[x1, y1, v1, x2, …]`` (v = 0 not labelled, 1 labelled but
    hidden, 2 visible), `skeleton` pairs of 1-based keypoint numbers as in a COCO category. Limbs join two
    labelled points; hidden points and the limbs that touch them are drawn at half brightness. Each limb
    and point has a dark rim, so that the skeleton shows over its own mask's colour."""
    out = image.copy()
    points = np.asarray(keypoints, dtype=np.float64).reshape(-1, 3)
    colour = np.asarray(colour_rgb8, dtype=np.float64)
    shade = {1: tuple(int(c) for c in colour * OCCLUDED_KEYPOINT_DIM), 2: tuple(int(c) for c in colour)}
    limbs = [(points[a - 1], points[b - 1]) for a, b in skeleton if points[a - 1][2] > 0 and points[b - 1][2] > 0]
    for width, ink in ((line_px + 2, None), (line_px, shade)):
        for (xa, ya, va), (xb, yb, vb) in limbs:
            tint = SKELETON_RIM_RGB8 if ink is None else ink[int(min(va, vb))]
            cv2.line(out, (round(xa), round(ya)), (round(xb), round(yb)), tint, width, cv2.LINE_AA)
    for x, y, v in points:
        if v > 0:
            cv2.circle(out, (round(x), round(y)), line_px + 2, SKELETON_RIM_RGB8, -1, cv2.LINE_AA)
            cv2.circle(out, (round(x), round(y)), line_px + 1, shade[int(v)], -1, cv2.LINE_AA)
    return out


def draw_tail(image: np.ndarray, points_px: np.ndarray, colour_rgb8: Sequence[int], *, line_px: int = 1) -> np.ndarray:
    """A track's recent path, oldest point first: (N, 2) pixels, NaN where it was not imaged (behind the
    camera), which breaks the line. Older segments are thinner."""
    out = image.copy()
    points = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
    colour = tuple(int(c) for c in colour_rgb8)
    count = len(points)
    for k in range(1, count):
        a, b = points[k - 1], points[k]
        if np.isfinite(a).all() and np.isfinite(b).all() and np.abs(np.concatenate([a, b])).max() < 1e6:
            width = max(1, round(line_px * (1 + k / count)))
            cv2.line(out, (round(a[0]), round(a[1])), (round(b[0]), round(b[1])), colour, width, cv2.LINE_AA)
    return out


def draw_label(
    image: np.ndarray, text: str, corner_px: tuple[float, float], colour_rgb8: Sequence[int], *, style: Style
) -> np.ndarray:
    """`text` on a `colour` tag whose bottom-left corner is at `corner_px` (a box's top-left), moved inside
    the image when it would leave it; black or white text, whichever reads better on the colour."""
    out = image.copy()
    (width, height), baseline = cv2.getTextSize(text, FONT, style.font_scale, style.text_px)
    pad = style.line_px + 1
    x = int(np.clip(round(corner_px[0]), 0, max(out.shape[1] - width - 2 * pad, 0)))
    y = int(np.clip(round(corner_px[1]), height + baseline + 2 * pad, out.shape[0]))
    cv2.rectangle(
        out, (x, y - height - baseline - 2 * pad), (x + width + 2 * pad, y), tuple(int(c) for c in colour_rgb8), -1
    )
    luma = 0.2126 * colour_rgb8[0] + 0.7152 * colour_rgb8[1] + 0.0722 * colour_rgb8[2]
    ink = (0, 0, 0) if luma > 128 else (255, 255, 255)
    cv2.putText(out, text, (x + pad, y - baseline - pad), FONT, style.font_scale, ink, style.text_px, cv2.LINE_AA)
    return out


def draw_text_panel(image: np.ndarray, lines: Sequence[str], *, style: Style) -> np.ndarray:
    """`lines` in white on a half-transparent dark panel in the top-left corner (the camera's state)."""
    if not lines:
        return image.copy()
    sizes = [cv2.getTextSize(line, FONT, style.font_scale, style.text_px) for line in lines]
    line_height = max(h + b for (_, h), b in sizes) + 2 * style.line_px
    pad = 2 * style.line_px + 2
    width = min(max(w for (w, _), _ in sizes) + 2 * pad, image.shape[1])
    height = min(line_height * len(lines) + 2 * pad, image.shape[0])
    out = image.copy()
    out[:height, :width] = (out[:height, :width].astype(np.uint16) * 2 // 5).astype(np.uint8)
    for k, line in enumerate(lines):
        baseline_y = pad + (k + 1) * line_height - sizes[k][1] - style.line_px
        cv2.putText(out, line, (pad, baseline_y), FONT, style.font_scale, (255, 255, 255), style.text_px, cv2.LINE_AA)
    return out


def camera_state_lines(state: dict) -> list[str]:
    """A camera.jsonl record as the few lines `draw_text_panel` shows: frame and time, pan/tilt/zoom and
    focal length, exposure and gain, and the PTZ mode with its target. Fields a record lacks are left out."""

    def have(*keys: str) -> bool:
        return all(isinstance(state.get(key), int | float) for key in keys)

    lines = (
        [f"frame {state['frame']}" + (f"  t {state['time_s']:.2f} s" if have("time_s") else "")]
        if "frame" in state
        else []
    )
    ptz = []
    if have("pan_deg", "tilt_deg"):
        ptz.append(f"pan {state['pan_deg']:.1f} deg  tilt {state['tilt_deg']:.1f} deg")
    if have("zoom_x"):
        ptz.append(f"zoom {state['zoom_x']:.2f}x")
    if have("focal_length_mm"):
        ptz.append(f"f {state['focal_length_mm']:.1f} mm")
    if ptz:
        lines.append("  ".join(ptz))
    exposure = []
    if have("exposure_time_s"):
        exposure.append(f"exposure {1e3 * state['exposure_time_s']:.3g} ms")
    if have("gain_db"):
        exposure.append(f"gain {state['gain_db']:.1f} dB")
    if have("f_number"):
        exposure.append(f"f/{state['f_number']:.1f}")
    if exposure:
        lines.append("  ".join(exposure))
    if isinstance(state.get("ptz_mode"), str):
        target = state.get("follow_target")
        lines.append(f"ptz {state['ptz_mode']}" + (f" -> {target}" if isinstance(target, str) else ""))
    return lines


def contact_sheet(
    tiles: Sequence[np.ndarray], captions: Sequence[str], *, columns: int = CONTACT_SHEET_COLUMNS
) -> np.ndarray:
    """Frames side by side in a grid, each with its caption in the bottom-left corner.

    The grid has ``min(columns, n)`` columns and ``ceil(n / columns)`` rows of tiles (the last row filled
    from the left), `CONTACT_SHEET_GAP_PX` between tiles and around them. Each tile is its frame scaled to
    ``w = min(CONTACT_SHEET_TILE_WIDTH_PX, frame width)`` and ``h = round(frame height · w / frame width)``,
    so the sheet is ``rows · h + (rows + 1) · gap`` by ``cols · w + (cols + 1) · gap`` pixels.

    Parameters
    ----------
    tiles : sequence of (H, W, 3) uint8 arrays, all of one size
    captions : one string per tile
    columns : most tiles in a row, ≥ 1
    """
    if not tiles or len(tiles) != len(captions):
        raise ValueError(
            f"contact_sheet needs one caption per tile and at least one tile, got {len(tiles)} tiles "
            f"and {len(captions)} captions"
        )
    height_px, width_px = tiles[0].shape[:2]
    tile_w = min(CONTACT_SHEET_TILE_WIDTH_PX, width_px)
    tile_h = round(height_px * tile_w / width_px)
    cols = min(columns, len(tiles))
    rows = math.ceil(len(tiles) / cols)
    gap = CONTACT_SHEET_GAP_PX
    sheet = np.empty((rows * tile_h + (rows + 1) * gap, cols * tile_w + (cols + 1) * gap, 3), np.uint8)
    sheet[:] = CONTACT_SHEET_BACKGROUND_RGB8
    style = Style.for_height(tile_h)
    for k, (tile, caption) in enumerate(zip(tiles, captions, strict=True)):
        small = cv2.resize(tile, (tile_w, tile_h), interpolation=cv2.INTER_AREA) if tile_w != width_px else tile
        small = draw_label(small, caption, (0, tile_h), (255, 255, 255), style=style)
        row, col = divmod(k, cols)
        y, x = gap + row * (tile_h + gap), gap + col * (tile_w + gap)
        sheet[y : y + tile_h, x : x + tile_w] = small
    return sheet


@dataclass(frozen=True)
class DrawnObject:
    """One annotated object of a frame, in the drawn image's pixels.

    track_id: picks the colour (`track_colour_rgb8`). label: the tag over its box ("3 person").
    bbox_xywh: COCO box. mask: (H, W) bool or None. keypoints: flat COCO ``[x, y, v, …]`` or None;
    skeleton: its category's 1-based limb pairs.
    """

    track_id: int
    label: str
    bbox_xywh: tuple[float, float, float, float]
    mask: np.ndarray | None = None
    keypoints: tuple[float, ...] | None = None
    skeleton: tuple[tuple[int, int], ...] = ()


def annotate_frame(
    image: np.ndarray,
    objects: Sequence[DrawnObject],
    *,
    tails_px: dict[int, np.ndarray] | None = None,
    panel_lines: Sequence[str] = (),
) -> np.ndarray:
    """A frame with everything drawn on it, in this order so that nothing hides what matters more: masks,
    track tails (`tails_px`: track id → (N, 2) pixels, oldest first), boxes, skeletons, id tags, and the
    camera's state in the top-left corner (`panel_lines`)."""
    style = Style.for_height(image.shape[0])
    out = image
    for obj in objects:
        if obj.mask is not None:
            out = blend_mask(out, obj.mask, track_colour_rgb8(obj.track_id))
    for track_id, points in (tails_px or {}).items():
        out = draw_tail(out, points, track_colour_rgb8(track_id), line_px=style.line_px)
    for obj in objects:
        colour = track_colour_rgb8(obj.track_id)
        out = draw_box(out, obj.bbox_xywh, colour, line_px=style.line_px)
        if obj.keypoints is not None:
            out = draw_skeleton(out, obj.keypoints, obj.skeleton, colour, line_px=style.line_px)
    for obj in objects:
        x0, y0, _, _ = box_corners_px(obj.bbox_xywh)
        out = draw_label(out, obj.label, (x0, y0), track_colour_rgb8(obj.track_id), style=style)
    out = draw_text_panel(out, panel_lines, style=style)
    return out.copy() if out is image else out
