"""Licence plates: a random registration in the UK's current format and the plate's image.

Format (DVLA, "INF104: Vehicle registration numbers and number plates", GOV.UK; the scheme in use
since September 2001): two letters of local memory tag, a two-digit age identifier, a space, three
random letters, e.g. "AB12 CDE". The age identifier is the year's last two digits for a vehicle
registered March–August and the year + 50 for September–February (02–25 and 51–75 for 2001–2025
here). I, Q and Z are not memory-tag letters, and I and Q are not random letters.

The plate (BS AU 145e, as INF104 summarises it): 520 × 111 mm, characters 79 mm high and 50 mm wide
in a 14 mm stroke, 11 mm apart, the two groups 33 mm apart, black on white at the front and on yellow
at the rear. The glyphs here are OpenCV's Hershey simplex font, stroked to the plate's 14 mm and
stretched into each 50 × 79 mm cell (the real plate font is Charles Wright 2001).

A motorcycle carries one plate, at the rear (INF104: motorcycles registered since September 2001 show no
front plate), of two lines, the memory tag and age identifier over the random letters: 229 × 178 mm,
characters 64 mm high and 44 mm wide in a 10 mm stroke, 10 mm apart, the lines 13 mm apart.
"""

from __future__ import annotations

import re

import cv2
import numpy as np

PLATE_SIZE_M = (0.520, 0.111)
"""Width and height of a standard UK plate, m."""
CHARACTER_SIZE_MM = (50.0, 79.0)
STROKE_MM = 14.0
CHARACTER_GAP_MM = 11.0
GROUP_GAP_MM = 33.0
PLATE_PX_PER_MM = 1.0
"""The plate image's resolution (a 520 × 111 px image): finer than any camera here resolves a plate."""

MEMORY_TAG_LETTERS = "ABCDEFGHJKLMNOPRSTUVWXY"
RANDOM_LETTERS = "ABCDEFGHJKLMNOPRSTUVWXYZ"
AGE_IDENTIFIERS = tuple(f"{n:02d}" for n in (*range(2, 26), *range(51, 76)))

UK_PLATE_PATTERN = re.compile(r"^[A-Z]{2}[0-9]{2} [A-Z]{3}$")
"""The current UK format, "AB12 CDE"."""
PLATE_TEXT_PATTERN = r"^[A-Z0-9]{1,4}( [A-Z0-9]{1,4})?$"
"""What a plate can carry here: one or two groups of capital letters and digits (7 or 8 characters at
most fit the plate's width)."""

MOTORCYCLE_PLATE_SIZE_M = (0.229, 0.178)
"""Width and height of a UK motorcycle's two-line rear plate, m."""
MOTORCYCLE_CHARACTER_SIZE_MM = (44.0, 64.0)
MOTORCYCLE_STROKE_MM = 10.0
MOTORCYCLE_CHARACTER_GAP_MM = 10.0
MOTORCYCLE_LINE_GAP_MM = 13.0

# Linear reflectances: retroreflective white and yellow sheeting (about 0.75 in daylight) and the
# black characters.
WHITE_PLATE_RGB = (0.75, 0.75, 0.72)
YELLOW_PLATE_RGB = (0.78, 0.55, 0.02)
CHARACTER_RGB = (0.025, 0.025, 0.025)


def draw_plate_text(*, rng: np.random.Generator) -> str:
    """A random registration in the UK's current format: memory tag, age identifier, random letters."""
    tag = "".join(MEMORY_TAG_LETTERS[i] for i in rng.integers(0, len(MEMORY_TAG_LETTERS), 2))
    age = AGE_IDENTIFIERS[int(rng.integers(0, len(AGE_IDENTIFIERS)))]
    letters = "".join(RANDOM_LETTERS[i] for i in rng.integers(0, len(RANDOM_LETTERS), 3))
    return f"{tag}{age} {letters}"


def _glyph(character: str, width_px: int, height_px: int, stroke_px: int) -> np.ndarray:
    """A (height, width) float mask of one character filling its cell."""
    font, scale = cv2.FONT_HERSHEY_SIMPLEX, 4.0
    (w, h), _ = cv2.getTextSize(character, font, scale, stroke_px)
    pad = stroke_px
    canvas = np.zeros((h + 2 * pad + stroke_px, w + 2 * pad), np.uint8)
    cv2.putText(canvas, character, (pad, h + pad), font, scale, 255, stroke_px, cv2.LINE_AA)
    rows, cols = np.nonzero(canvas)
    crop = canvas[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    # Narrow glyphs (1) keep their aspect; the others fill the cell's width.
    target_w = width_px if crop.shape[1] > 0.5 * crop.shape[0] else round(crop.shape[1] * height_px / crop.shape[0])
    glyph = cv2.resize(crop, (max(1, target_w), height_px), interpolation=cv2.INTER_AREA).astype(np.float32) / 255
    cell = np.zeros((height_px, width_px), np.float32)
    x0 = (width_px - glyph.shape[1]) // 2
    cell[:, x0 : x0 + glyph.shape[1]] = glyph
    return cell


def _ink_line(
    ink: np.ndarray, text: str, y0: int, cell_px: tuple[int, int], stroke_px: int, gap_px: float, group_gap_px: float
) -> None:
    """Draw one line of characters centred across `ink`, its cells' tops at row `y0`."""
    cw, ch = cell_px
    width_px = ink.shape[1]
    groups = text.split(" ")
    total = sum(len(g) for g in groups) * cw + sum(len(g) - 1 for g in groups) * gap_px
    total += (len(groups) - 1) * group_gap_px
    x = (width_px - total) / 2
    for g, group in enumerate(groups):
        if g:
            x += group_gap_px - gap_px
        for character in group:
            x0 = round(x)
            cell = _glyph(character, cw, ch, stroke_px)
            x1 = min(width_px, x0 + cw)
            ink[y0 : y0 + ch, max(0, x0) : x1] = np.maximum(
                ink[y0 : y0 + ch, max(0, x0) : x1], cell[:, max(0, -x0) : x1 - x0]
            )
            x += cw + gap_px


def motorcycle_plate_image(text: str) -> np.ndarray:
    """A motorcycle's rear plate carrying `text` as a linear albedo image, (178, 229, 3) float32 at 1 px
    per mm: the text's first group over its second (one line when it has one group), black on yellow."""
    s = PLATE_PX_PER_MM
    height_px, width_px = round(MOTORCYCLE_PLATE_SIZE_M[1] * 1000 * s), round(MOTORCYCLE_PLATE_SIZE_M[0] * 1000 * s)
    cw, ch = round(MOTORCYCLE_CHARACTER_SIZE_MM[0] * s), round(MOTORCYCLE_CHARACTER_SIZE_MM[1] * s)
    stroke = max(1, round(MOTORCYCLE_STROKE_MM * s * 0.5))  # the stroke scales with the glyph's stretch (≈ 2×)
    ink = np.zeros((height_px, width_px), np.float32)
    lines = text.split(" ")
    block = len(lines) * ch + (len(lines) - 1) * MOTORCYCLE_LINE_GAP_MM * s
    top = (height_px - block) / 2
    for k, line in enumerate(lines):
        y0 = round(top + k * (ch + MOTORCYCLE_LINE_GAP_MM * s))
        _ink_line(ink, line, y0, (cw, ch), stroke, MOTORCYCLE_CHARACTER_GAP_MM * s, 0.0)
    background = np.array(YELLOW_PLATE_RGB, np.float32)
    return background + ink[..., None] * (np.array(CHARACTER_RGB, np.float32) - background)


def plate_image(text: str, *, rear: bool) -> np.ndarray:
    """The plate carrying `text` as a linear albedo image, (111, 520, 3) float32 at 1 px per mm:
    black characters centred on white (front) or yellow (rear)."""
    s = PLATE_PX_PER_MM
    height_px, width_px = round(PLATE_SIZE_M[1] * 1000 * s), round(PLATE_SIZE_M[0] * 1000 * s)
    cw, ch = round(CHARACTER_SIZE_MM[0] * s), round(CHARACTER_SIZE_MM[1] * s)
    stroke = max(1, round(STROKE_MM * s * 0.5))  # the stroke scales with the glyph's stretch (≈ 2×)
    ink = np.zeros((height_px, width_px), np.float32)
    _ink_line(ink, text, (height_px - ch) // 2, (cw, ch), stroke, CHARACTER_GAP_MM * s, GROUP_GAP_MM * s)
    background = np.array(YELLOW_PLATE_RGB if rear else WHITE_PLATE_RGB, np.float32)
    characters = np.array(CHARACTER_RGB, np.float32)
    return background + ink[..., None] * (characters - background)
