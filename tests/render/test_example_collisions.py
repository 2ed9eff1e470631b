"""No actor of an example scene drives or walks through another: a car through a walker crossing its lane, a
walker through a parked car, a motorcycle inside a bus waiting at its start were each in the examples."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.render.scene_graph import build_scene_graph
from tests.conftest import REPO

STEP_S = 0.25
OVERLAP_M = 0.15
"""Boxes that overlap by more than this on both ground axes (and in height) clash: people's boxes take their
swinging arms, so two walkers passing close, or a walker brushing a wing mirror, may overlap a little."""

VEHICLE_CLASSES = {"car", "truck", "bus", "motorcycle", "bicycle"}


def _scenes_with_vehicles() -> tuple[str, ...]:
    """Every example scene with a vehicle among its actors (read from the YAML: a new example is checked without
    being listed here)."""
    import yaml

    names = []
    for path in sorted((REPO / "scenes").glob("*.yaml")):
        actors = yaml.safe_load(path.read_text(encoding="utf-8")).get("actors") or []
        if any(actor.get("class") in VEHICLE_CLASSES for actor in actors):
            names.append(path.stem)
    return tuple(names)


SCENES_WITH_VEHICLES = _scenes_with_vehicles()


def test_the_scenes_with_vehicles_are_found():
    assert {"parking_lot", "intersection_two_cameras", "night_street", "snowy_street"} <= set(SCENES_WITH_VEHICLES)
    assert "plaza" not in SCENES_WITH_VEHICLES and "corridor" not in SCENES_WITH_VEHICLES


def _world_box(graph, node) -> tuple[np.ndarray, np.ndarray]:
    low, high = node.mesh.bounds
    corners = np.array(
        [[x, y, z, 1.0] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    world = corners @ graph.scene.get_pose(node).T
    return world[:, :3].min(axis=0), world[:, :3].max(axis=0)


def clashes(name: str) -> list[tuple[float, str, str]]:
    """(time, actor, actor) of each first clash between two actors of an example scene, a rider and its
    vehicle apart, and two people apart (a crowd's boxes brush)."""
    loaded = load_scene(REPO / "scenes" / f"{name}.yaml")
    graph = build_scene_graph(loaded.scene, lambda path: loaded.path.parent / path)
    actors = graph.actors
    found = {}
    for time_s in np.arange(0.0, loaded.scene.duration_s, STEP_S):
        graph.place_actors(float(time_s))
        boxes = [_world_box(graph, node) for node in graph.actor_nodes]
        for i in range(len(actors)):
            for j in range(i + 1, len(actors)):
                a, b = actors[i], actors[j]
                if a.rides == b.name or b.rides == a.name or (a.cls == "person" and b.cls == "person"):
                    continue
                overlap = np.minimum(boxes[i][1], boxes[j][1]) - np.maximum(boxes[i][0], boxes[j][0])
                if (overlap[:2] > OVERLAP_M).all() and overlap[2] > 0 and (a.name, b.name) not in found:
                    found[(a.name, b.name)] = float(time_s)
    return [(t, a, b) for (a, b), t in found.items()]


@pytest.mark.parametrize("name", SCENES_WITH_VEHICLES)
def test_no_actor_of_an_example_scene_passes_through_another(name):
    assert clashes(name) == []
