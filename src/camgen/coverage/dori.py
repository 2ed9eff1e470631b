"""IEC 62676-4 DORI classes: the pixel density on a person that each level of detail needs.

IEC 62676-4:2014 (*Video surveillance systems for use in security applications — Part 4: Application
guidelines*), the "DORI" levels: detect 25 px/m, observe 62 px/m, recognise 125 px/m, identify
250 px/m. These are the standard's figures as its users quote them (e.g. Infiniti Optics, "DORI
(Detection, Observation, Recognition, Identification)"; cctv-check.de on DIN EN 62676-4: recognise
= 8 mm per pixel = 125 px/m); the issue's 62.5 px/m for observe is 1 px per 16 mm, which the standard
rounds to 62. The densities are across a person, at the person.
"""

from __future__ import annotations

import numpy as np

DORI_CLASSES = ("detect", "observe", "recognise", "identify")
"""Class names in rising order; class index k + 1 is `DORI_CLASSES[k]`, 0 is below detect (or unseen)."""

DORI_THRESHOLDS_PX_M = (25.0, 62.0, 125.0, 250.0)
"""Least pixel density on the person for each class, px/m (IEC 62676-4:2014)."""

NOT_SEEN = 0
"""Class index of a point no camera sees at detect density or better."""


def dori_class(density_px_m: np.ndarray) -> np.ndarray:
    """Class index (0 = below detect, 1 = detect … 4 = identify) of each density; NaN gives 0.

    Parameters
    ----------
    density_px_m : array of any shape, px/m
        Pixel density on a person at the point.

    Returns
    -------
    int8 array of the same shape: the number of thresholds the density reaches.
    """
    density = np.nan_to_num(np.asarray(density_px_m, dtype=np.float64), nan=0.0)
    return np.searchsorted(np.array(DORI_THRESHOLDS_PX_M), density, side="right").astype(np.int8)


def class_index(name: str) -> int:
    """Class index of a class name (`detect` → 1 … `identify` → 4)."""
    return DORI_CLASSES.index(name) + 1


def class_name(index: int) -> str:
    """`none` for 0, else the class's name."""
    return "none" if index == NOT_SEEN else DORI_CLASSES[index - 1]
