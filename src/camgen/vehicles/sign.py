"""A bus's front destination display: an LED dot matrix, amber on black, showing a route number and a
destination.

The display sits across the top of the bus's front, above the windscreen (as on the Mercedes-Benz Citaro
and most European and British city buses). Size: a front display area of about 1.6–1.9 m by 0.25–0.30 m is
what the common 16 × 160 to 24 × 200 dot LED signs fill behind a city bus's windscreen (makers' data sheets,
e.g. Hanover Displays' and Mobitec's front signs; an estimate from those), and the UK's Public Service
Vehicles Accessibility Regulations 2000 (Schedule 1, the route number and destination display) ask a front
route number at least 200 mm high and a destination at least 125 mm high, so the matrix here has
`MATRIX_ROWS` rows over `SIGN_SIZE_M`'s 0.28 m: the route number fills the rows, the destination most of
them. Text: route numbers 1–199 and destinations of `DESTINATIONS`, drawn from the vehicle's identity
seed (not from its look's generator, whose draws stay as they were).

The lit dots are the `lit_runs` of `matrix`: each row's runs of lit dots, so that a vehicle part draws one
quad per run.
"""

from __future__ import annotations

import cv2
import numpy as np

SIGN_SIZE_M = (1.70, 0.28)
"""Width and height of the front display's lit area, m."""
MATRIX_ROWS = 16
MATRIX_COLUMNS = 160
DESTINATIONS = (
    "CITY CENTRE",
    "BUS STATION",
    "HOSPITAL",
    "UNIVERSITY",
    "RAILWAY STN",
    "AIRPORT",
    "HARBOUR",
    "PARK & RIDE",
)
SIGN_SPAWN_KEY = 0x7369_676E
"""Spawn key of the display's text from the vehicle's identity seed (ASCII "sign")."""


def destination_text(identity_seed: int) -> tuple[str, str]:
    """(route number, destination) shown by the bus of `identity_seed`."""
    rng = np.random.default_rng(np.random.SeedSequence(identity_seed, spawn_key=(SIGN_SPAWN_KEY,)))
    return str(int(rng.integers(1, 200))), DESTINATIONS[int(rng.integers(len(DESTINATIONS)))]


def matrix(route: str, destination: str) -> np.ndarray:
    """(`MATRIX_ROWS`, `MATRIX_COLUMNS`) bool, row 0 at the top: the lit dots of the route number (left,
    the full height) and the destination (centred in the rest, as tall as fits its width)."""
    dots = np.zeros((MATRIX_ROWS, MATRIX_COLUMNS), np.uint8)
    font = cv2.FONT_HERSHEY_PLAIN
    route_width = _draw(dots, route, font, 0, 0, MATRIX_ROWS, 0.28 * MATRIX_COLUMNS)
    start = route_width + 4
    _draw(dots, destination, font, start, 0, MATRIX_ROWS, MATRIX_COLUMNS - start)
    return dots.astype(bool)


def _draw(dots: np.ndarray, text: str, font: int, x0: int, y0: int, rows: int, most_width: float) -> int:
    """Draw `text` into `dots` from column `x0`, as large as fits `rows` tall and `most_width` wide,
    vertically centred; its width in columns."""
    (width, height), _ = cv2.getTextSize(text, font, 1.0, 1)
    scale = min((rows - 3) / height, most_width / width)  # capitals and digits: no descenders
    thickness = 1 if scale < 1.2 else 2
    (width, height), _ = cv2.getTextSize(text, font, scale, thickness)
    left = x0 + max(0, int((most_width - width) // 2)) if x0 > 0 else x0
    bottom = y0 + (rows + height) // 2
    cv2.putText(dots, text, (left, bottom), font, scale, 1, thickness, cv2.LINE_8)
    return left + width - x0


def lit_runs(dots: np.ndarray) -> np.ndarray:
    """(R, 3) int: (row, first column, last column + 1) of each run of lit dots along a row."""
    padded = np.pad(dots.astype(np.int8), ((0, 0), (1, 1)))
    edges = np.diff(padded, axis=1)
    rows, starts = np.nonzero(edges == 1)
    _, stops = np.nonzero(edges == -1)
    return np.stack([rows, starts, stops], axis=1)
