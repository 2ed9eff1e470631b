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

Luminance (`display_luminance_cd_m2`): an LED display is driven from an ambient light sensor, bright enough
to be read in sunshine and dimmed at night so as not to glare. EN 12966 (road variable-message signs; EN
12966-1:2005+A1:2009, EN 12966:2014+A1:2018 §4.4.3) classes the luminance a sign must reach under external
illumination, L1–L3 asking 3,100–12,400 cd/m² of a white sign under the 40,000 lx of direct sun (the
table's figures as camgen cited them before; the table itself was not at hand for this model), but leaves
"the control of the luminance of luminous signs with respect to the ambient light" out of its scope (the
standard's abstract); that curve is the maker's. Hanover Displays' DG3 bus-sign controller states its
exterior displays' brightness limit as a share of their maximum (Installation and Operation Manual
540846-3, 2015: configuration code BL), Microgate's LED boards set 1–100 % from their light sensor (MicroGraph LED
user manual §1.9), and a municipal LED sign dims from 95 % on a sunny day to 5 % at night (appenzell24.ch,
Lutzenberg's entry sign, a 1:19 range); Mobitec's and Luminator's public pages found here give no figures.
At night, Luginbuhl et al. (2010, "Digital LED billboard luminance recommendations", US Naval Observatory
Flagstaff) ask no more than 100 cd/m² of a sign seen by drivers adapted to about 1 cd/m² of lit road.
So, estimates on those figures: `DISPLAY_DAY_CD_M2` (EN 12966's L1 under direct sun) from
`DISPLAY_DAY_LUX` up, `DISPLAY_NIGHT_CD_M2` (half of Luginbuhl's ceiling) at night, and between them
L = L_day·√(E / E_day), the square root spanning the 1:62 range over the 10.4–40,000 lx from a lit street
to direct sun (a sensor's curve is a maker's setting; the square root is an estimate, not a published
law). E is the horizontal illuminance at the display (the renderer's sun, sky and lamps there,
`camgen.render.scene_graph.horizontal_illuminance_lux`).
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
DISPLAY_DAY_CD_M2 = 3_100.0
"""Luminance of the lit dots in sunshine, cd/m²: EN 12966's class L1 under 40,000 lx (an estimate for a bus's
display; see the module's docstring)."""
DISPLAY_DAY_LUX = 40_000.0
"""Horizontal illuminance from which the display shines at `DISPLAY_DAY_CD_M2`, lux (EN 12966's direct sun)."""
DISPLAY_NIGHT_CD_M2 = 50.0
"""Luminance of the lit dots at night, cd/m² (an estimate: half of Luginbuhl et al. 2010's 100 cd/m² ceiling)."""
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


def display_luminance_cd_m2(illuminance_lux: np.ndarray | float) -> np.ndarray:
    """Luminance of the display's lit dots under a horizontal illuminance `illuminance_lux` (any shape), cd/m²:

        L = clip(L_day·√(E / E_day), L_night, L_day)

    with L_day = `DISPLAY_DAY_CD_M2`, E_day = `DISPLAY_DAY_LUX`, L_night = `DISPLAY_NIGHT_CD_M2` (the floor
    holds below E_day·(L_night / L_day)² ≈ 10.4 lx). See the module's docstring for the figures; NaN stays NaN."""
    illuminance = np.maximum(np.asarray(illuminance_lux, dtype=np.float64), 0.0)
    return np.clip(DISPLAY_DAY_CD_M2 * np.sqrt(illuminance / DISPLAY_DAY_LUX), DISPLAY_NIGHT_CD_M2, DISPLAY_DAY_CD_M2)
