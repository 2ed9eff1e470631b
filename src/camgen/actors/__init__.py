"""The world's actors as pure geometry: procedural people (and, later, vehicles).

`person_rig` turns a scene's person actor into what the renderer draws and the annotations read: a
`PersonModel` (rest mesh, colours, skinning, keypoint markers) and a `Walker` (its pose at any time
along its route). Nothing here touches OpenGL or files other than the MakeHuman data it reads.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from camgen.actors.appearance import Appearance, draw_appearance
from camgen.actors.gait import Walker
from camgen.actors.person import COCO_KEYPOINTS, PersonModel, build_person
from camgen.actors.skeleton import INDEX, global_transforms, skin, skinning_matrices
from camgen.config.scene import Actor
from camgen.motion.trajectory import Route

PERSON_SPAWN_KEY = 0x7065_7273
"""First spawn key of an identity seed derived from the scene's seed (ASCII "pers")."""

_KEYPOINT_JOINT_ROWS = [
    INDEX[j]
    for j in (
        "upperarm_l", "upperarm_r", "lowerarm_l", "lowerarm_r", "hand_l", "hand_r",
        "thigh_l", "thigh_r", "calf_l", "calf_r", "foot_l", "foot_r",
    )
]  # fmt: skip


def identity_seed(actor: Actor, *, scene_seed: int, actor_index: int) -> int:
    """The actor's identity seed: its own, or one derived from the scene's seed and its index."""
    if actor.appearance is not None and actor.appearance.seed is not None:
        return actor.appearance.seed
    sequence = np.random.SeedSequence(scene_seed, spawn_key=(PERSON_SPAWN_KEY, actor_index))
    return int(sequence.generate_state(1, dtype=np.uint32)[0])


def person_appearance(actor: Actor, *, scene_seed: int, actor_index: int) -> Appearance:
    block = actor.appearance
    return draw_appearance(
        identity_seed(actor, scene_seed=scene_seed, actor_index=actor_index),
        season=block.season if block is not None else "mixed",
        pinned=block.pinned() if block is not None else None,
    )


@lru_cache(maxsize=256)
def _model(appearance: Appearance) -> PersonModel:
    return build_person(appearance)


@dataclass
class PersonRig:
    """A person's mesh and gait, and its posed state at the last `place` time."""

    model: PersonModel
    walker: Walker
    vertices_m: np.ndarray = field(init=False)
    """(V, 3) float32 posed vertices in the world."""
    normals: np.ndarray = field(init=False)
    joints_m: np.ndarray = field(init=False)
    """(J, 3) posed joint positions in the world."""
    keypoints_m: np.ndarray = field(init=False)
    """(17, 3) COCO keypoints in the world."""

    def __post_init__(self) -> None:
        self.place(0.0)

    def place(self, time_s: float) -> None:
        model = self.model
        pose = self.walker.pose(time_s)
        G = global_transforms(model.joints_m, pose)
        M = skinning_matrices(model.joints_m, G)
        self.vertices_m, self.normals = skin(model.vertices_m, model.normals, model.joint_index, model.joint_weight, M)
        self.joints_m = G[:, :3, 3].copy()
        head = G[INDEX["head"]]
        rest_head = model.joints_m[INDEX["head"]]
        markers = (model.head_markers_m - rest_head) @ head[:3, :3].T + head[:3, 3]
        self.keypoints_m = np.concatenate([markers, self.joints_m[_KEYPOINT_JOINT_ROWS]])


def person_rig(actor: Actor, route: Route, *, scene_seed: int, actor_index: int) -> PersonRig:
    """The procedural person of a person actor (no shape) walking its route."""
    appearance = person_appearance(actor, scene_seed=scene_seed, actor_index=actor_index)
    phase = (identity_seed(actor, scene_seed=scene_seed, actor_index=actor_index) % 1000) / 1000
    return PersonRig(_model(appearance), Walker(_model(appearance), route, phase_seed=phase))


__all__ = ["COCO_KEYPOINTS", "PersonRig", "identity_seed", "person_appearance", "person_rig"]
