"""Procedural props as pure geometry: street trees (broadleaf crowns of clumped two-sided leaf cards filling
a lumpy envelope, with branches, `camgen.props.foliage`; or conifers of stacked irregular cones), bushes and
hedges (leaves over a dark core), benches, litter bins, bollards, lamp posts with a bracket and lantern, sign
posts with a plate, and fences or railings.

`placed_props` resolves a scene's `environment.props` and `environment.scatter` (placed props and
scatter rules, `camgen.config.props`) into `PlacedProp`s: a `PropModel` (`camgen.props.types`: closed parts with a
colour and an 850 nm reflectance per vertex, dimensions drawn from the identity seed within cited ranges)
and its pose in the world. Nothing here touches OpenGL or files. Trees and bushes sway in the scene's
wind (`camgen.props.sway`); the other props stand still.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from camgen.config.placement import box_corners
from camgen.config.scene import Environment
from camgen.props.scatter import ScatterSpot, scatter_spots
from camgen.props.shapes import PropPart
from camgen.props.types import PropModel, build_prop

PROP_SPAWN_KEY = 0x7072_6F70
"""First spawn key of a prop's identity seed derived from the scene's seed (ASCII "prop")."""


@dataclass(frozen=True)
class PlacedProp:
    name: str
    model: PropModel
    T_world_from_prop: np.ndarray
    """(4, 4): the prop's frame (x along its heading, z up) on the ground at its foot."""


@lru_cache(maxsize=256)
def _model(kind: str, seed: int, form: str | None, height_m: float | None, length_m: float | None) -> PropModel:
    return build_prop(kind, seed, form=form, height_m=height_m, length_m=length_m)


def _pose(x_m: float, y_m: float, z_m: float, heading_deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:3, 3] = (x_m, y_m, z_m)
    return T


def prop_seed(scene_seed: int, index: int) -> int:
    """A placed prop's identity seed when it gives none: from the scene's seed and its place in the list."""
    sequence = np.random.SeedSequence(scene_seed, spawn_key=(PROP_SPAWN_KEY, index))
    return int(sequence.generate_state(1, dtype=np.uint32)[0])


def prop_names(environment: Environment) -> list[str]:
    """The instance name of every prop `placed_props` places, in its order (no geometry is built)."""
    names = [prop.name or f"{prop.type}_{i}" for i, prop in enumerate(environment.props)]
    for i, rule in enumerate(environment.scatter):
        spots = scatter_spots(rule, where=f"environment.scatter[{i}]")
        names += [f"{rule.type}_scatter{i}.{k}" for k in range(len(spots))]
    return names


def placed_props(environment: Environment, *, scene_seed: int) -> list[PlacedProp]:
    """Every prop of the environment, placed: `environment.props` in order, then each scatter rule's."""
    placed = []
    for i, prop in enumerate(environment.props):
        seed = prop.seed if prop.seed is not None else prop_seed(scene_seed, i)
        model = _model(prop.type, seed, prop.form, prop.height_m, prop.length_m)
        T = _pose(*prop.position_m, prop.elevation_m, prop.heading_deg)
        placed.append(PlacedProp(prop.name or f"{prop.type}_{i}", model, T))
    for i, rule in enumerate(environment.scatter):
        spots: list[ScatterSpot] = scatter_spots(rule, where=f"environment.scatter[{i}]")
        for k, spot in enumerate(spots):
            model = _model(rule.type, spot.seed, rule.form, rule.height_m, None)
            T = _pose(*spot.position_m, rule.elevation_m, spot.heading_deg)
            placed.append(PlacedProp(f"{rule.type}_scatter{i}.{k}", model, T))
    return placed


def prop_box_corners(environment: Environment, *, scene_seed: int) -> list[np.ndarray]:
    """The 8 world corners (8, 3) of each placed prop's box in its own frame (what the plan's depth
    ranges take of the environment's static geometry)."""
    boxes = []
    for prop in placed_props(environment, scene_seed=scene_seed):
        vertices = prop.model.arrays()[0]
        boxes.append(box_corners(vertices.min(axis=0), vertices.max(axis=0), prop.T_world_from_prop))
    return boxes


__all__ = [
    "PlacedProp",
    "PropModel",
    "PropPart",
    "build_prop",
    "placed_props",
    "prop_box_corners",
    "prop_names",
    "prop_seed",
]
