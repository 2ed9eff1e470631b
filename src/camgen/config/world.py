"""How far the world of a scene reaches: the bounds of every position and size in it.

The renderer draws in float32 (pyrender's vertex buffers and matrices), whose 24-bit significand
spaces representable coordinates 2^(e−23) m apart at 2^e m: 1 mm out to 8–16 km from the origin, 8 mm
at 100 km, 1 m at 10 000 km. A camera watching a person 10 m away with a long lens resolves a few
millimetres, so the world keeps to ±10 km; the longest-range surveillance cameras see 2–5 km.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from camgen.config.base import Why

WORLD_EXTENT_M = 10_000.0
"""Largest |x|, |y| or |z| of any point in a scene, m."""

Coordinate = Annotated[
    float,
    Field(ge=-WORLD_EXTENT_M, le=WORLD_EXTENT_M),
    Why(
        f"scenes lie within ±{WORLD_EXTENT_M:g} m of the origin, where the renderer's float32 keeps 1 mm; "
        "move the scene's origin nearer"
    ),
]
"""One coordinate of a point in the world (or in an actor's frame), m."""

Length = Annotated[
    float,
    Field(gt=0, le=2 * WORLD_EXTENT_M),
    Why(f"nothing is larger than the world, which spans ±{WORLD_EXTENT_M:g} m"),
]
"""A size or distance in the world, m."""

Point2 = tuple[Coordinate, Coordinate]
Point3 = tuple[Coordinate, Coordinate, Coordinate]
