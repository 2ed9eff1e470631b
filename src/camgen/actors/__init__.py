"""The world's actors as pure geometry: procedural people (vehicles: `camgen.vehicles`).

`person_rig` turns a scene's person actor into what the renderer draws and the annotations read: a
`PersonModel` (rest mesh, colours, skinning, keypoint markers) and a `Walker` (its pose at any time
along its route); `rider_rig` seats one on a bicycle or motorcycle (`camgen.actors.riding`). Nothing
here touches OpenGL or files other than the MakeHuman data it reads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from camgen.actors.appearance import Appearance, draw_appearance
from camgen.actors.gait import Walker
from camgen.actors.person import KEYPOINT_JOINT_ROWS, PersonModel, build_person
from camgen.actors.riding import Rider
from camgen.actors.skeleton import (
    INDEX,
    JOINTS,
    global_transforms,
    rot_axis,
    skin,
    skinning_matrices,
    weight_matrix,
)
from camgen.annotate.keypoints import COCO_KEYPOINTS
from camgen.config.scene import Actor
from camgen.motion.memo import TimeMemo, frozen
from camgen.motion.trajectory import Route

PERSON_SPAWN_KEY = 0x7065_7273
"""First spawn key of an identity seed derived from the scene's seed (ASCII "pers")."""


def identity_seed(actor: Actor, *, scene_seed: int, actor_index: int) -> int:
    """The actor's identity seed: its own, or one derived from the scene's seed and its index."""
    if actor.appearance is not None and actor.appearance.seed is not None:
        return actor.appearance.seed
    sequence = np.random.SeedSequence(scene_seed, spawn_key=(PERSON_SPAWN_KEY, actor_index))
    return int(sequence.generate_state(1, dtype=np.uint32)[0])


def person_appearance(actor: Actor, *, scene_seed: int, actor_index: int) -> Appearance:
    """The person's look from its identity seed. A rider (`Actor.rides`) drawn as a child is drawn again
    as an adult, everything else as drawn (the two-wheelers are adults' sizes)."""
    block = actor.appearance
    seed = identity_seed(actor, scene_seed=scene_seed, actor_index=actor_index)
    season = block.season if block is not None else "mixed"
    pinned = block.pinned() if block is not None else {}
    appearance = draw_appearance(seed, season=season, pinned=pinned)
    if actor.rides is not None and appearance.age_group == "child" and "age_group" not in pinned:
        appearance = draw_appearance(seed, season=season, pinned={**pinned, "age_group": "adult"})
    return appearance


@lru_cache(maxsize=256)
def _model(appearance: Appearance) -> PersonModel:
    return build_person(appearance)


@dataclass
class PersonRig:
    """A person's mesh and gait, and its posed state at the last `place` time (`joints_m`, `keypoints_m` and
    `T_world_from_pelvis` are read-only: the skeleton's pose is kept for its time, `pose_skeleton`)."""

    model: PersonModel
    walker: Walker | Rider
    vertices_m: np.ndarray = field(init=False)
    """(V, 3) float32 posed vertices in the world."""
    normals: np.ndarray = field(init=False)
    joints_m: np.ndarray = field(init=False)
    """(J, 3) posed joint positions in the world."""
    keypoints_m: np.ndarray = field(init=False)
    """(17, 3) COCO keypoints in the world."""

    def __post_init__(self) -> None:
        self.weights = weight_matrix(self.model.joint_index, self.model.joint_weight, len(JOINTS))
        self._skeletons: TimeMemo[tuple[np.ndarray, ...]] = TimeMemo()
        self.place(0.0)

    def pose_skeleton(self, time_s: float) -> np.ndarray:
        """Pose the skeleton at `time_s` (joints and keypoints); its (J, 3, 4) skinning matrices (read-only).
        The pose is a pure function of the time: one already taken is handed out again (`TimeMemo`)."""
        kept = self._skeletons.get(time_s)
        if kept is None:
            kept = self._skeletons.put(time_s, frozen(*self._skeleton_at(time_s)))
        M, self.joints_m, self.keypoints_m, self.T_world_from_pelvis = kept
        return M

    def _skeleton_at(self, time_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(skinning matrices (J, 3, 4), joints (J, 3), keypoints (17, 3), T_world_from_pelvis (4, 4)) at `time_s`."""
        model = self.model
        G = global_transforms(model.joints_m, self.walker.pose(time_s))
        joints_m = G[:, :3, 3].copy()
        head = G[INDEX["head"]]
        markers = (model.head_markers_m - model.joints_m[INDEX["head"]]) @ head[:3, :3].T + head[:3, 3]
        keypoints_m = np.concatenate([markers, joints_m[KEYPOINT_JOINT_ROWS]])
        return skinning_matrices(model.joints_m, G), joints_m, keypoints_m, G[INDEX["pelvis"]].copy()

    def heading_box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low (3,), high (3,), T_world_from_box (4, 4)): the box around the posed mesh in a frame that
        turns with the person's heading (the pelvis's forward axis laid flat), on the ground under
        the pelvis."""
        forward = self.T_world_from_pelvis[:3, 0]
        T = np.eye(4)
        T[:3, :3] = rot_axis("z", math.atan2(forward[1], forward[0]))
        T[:2, 3] = self.T_world_from_pelvis[:2, 3]
        local = (self.vertices_m - T[:3, 3]) @ T[:3, :3]
        # each axis reduced on its own: the same values, ~20× faster than over axis 0 of (N, 3) (50k: 2.7 ms)
        low = np.array([local[:, axis].min() for axis in range(3)])
        high = np.array([local[:, axis].max() for axis in range(3)])
        return low, high, T

    def place(self, time_s: float) -> None:
        """Pose and skin this person alone (`Crowd.place` skins many at once)."""
        M = self.pose_skeleton(time_s)
        self.vertices_m, self.normals = skin(self.model.vertices_m, self.model.normals, self.weights, M)
        self.settle(time_s)

    def settle(self, time_s: float) -> None:
        """A falling or fallen body rests on the ground: the gait tips it about the edge of its feet,
        and it is lifted by what of its posed mesh (a shoulder, a hand, a heel) went below the ground."""
        if not self.walker.falling(time_s):
            return
        below = -float(self.vertices_m[:, 2].min())
        if below > 0:  # lifted copies: the skeleton's arrays are kept for its time (`pose_skeleton`)
            self.vertices_m[:, 2] += below
            self.joints_m = self.joints_m.copy()
            self.keypoints_m = self.keypoints_m.copy()
            self.T_world_from_pelvis = self.T_world_from_pelvis.copy()
            self.joints_m[:, 2] += below
            self.keypoints_m[:, 2] += below
            self.T_world_from_pelvis[2, 3] += below


class Crowd:
    """Many people skinned together: one sparse product for every vertex of every person per frame
    (the per-call overhead of numpy, not arithmetic, dominates a person's few thousand vertices)."""

    def __init__(self, rigs: list[PersonRig]):
        self.rigs = rigs
        J = len(JOINTS)
        self._rest_vertices = np.concatenate([r.model.vertices_m for r in rigs]) if rigs else np.zeros((0, 3))
        self._rest_normals = np.concatenate([r.model.normals for r in rigs]) if rigs else np.zeros((0, 3))
        index = [r.model.joint_index + k * J for k, r in enumerate(rigs)]
        weight = [r.model.joint_weight for r in rigs]
        self._weights = weight_matrix(np.concatenate(index), np.concatenate(weight), J * len(rigs)) if rigs else None
        ends = np.cumsum([len(r.model.vertices_m) for r in rigs])
        self._slices = [slice(int(e - len(r.model.vertices_m)), int(e)) for r, e in zip(rigs, ends, strict=True)]

    def place(self, time_s: float) -> None:
        """Pose every person at `time_s` and skin them all; each rig's vertices and normals are set."""
        if not self.rigs:
            return
        M = np.concatenate([rig.pose_skeleton(time_s) for rig in self.rigs])
        vertices, normals = skin(self._rest_vertices, self._rest_normals, self._weights, M)
        for rig, part in zip(self.rigs, self._slices, strict=True):
            rig.vertices_m, rig.normals = vertices[part], normals[part]
            rig.settle(time_s)


def person_model(actor: Actor, *, scene_seed: int, actor_index: int) -> PersonModel:
    """The procedural person of a person actor (no shape), at rest."""
    return _model(person_appearance(actor, scene_seed=scene_seed, actor_index=actor_index))


def rider_rig(actor: Actor, vehicle, *, scene_seed: int, actor_index: int) -> PersonRig:
    """The procedural person of a rider (`Actor.rides`) on `vehicle`, a `camgen.vehicles.TwoWheelerRig`."""
    model = person_model(actor, scene_seed=scene_seed, actor_index=actor_index)
    return PersonRig(model, Rider(model, vehicle.rider_targets, vehicle.route))


def person_rig(actor: Actor, route: Route, *, scene_seed: int, actor_index: int) -> PersonRig:
    """The procedural person of a person actor (no shape) walking its route."""
    appearance = person_appearance(actor, scene_seed=scene_seed, actor_index=actor_index)
    phase = (identity_seed(actor, scene_seed=scene_seed, actor_index=actor_index) % 1000) / 1000
    walker = Walker(_model(appearance), route, phase_seed=phase, actions=tuple(actor.actions))
    return PersonRig(_model(appearance), walker)


__all__ = [
    "COCO_KEYPOINTS",
    "Crowd",
    "PersonRig",
    "identity_seed",
    "person_appearance",
    "person_model",
    "person_rig",
    "rider_rig",
]
