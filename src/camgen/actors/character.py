"""An actor's glTF 2.0 character walking its route (the file is read by `camgen.io.gltf`).

`CharacterRig` plays a clip as the actor walks: the clip's own ground travel is taken out (the route
moves the actor) and the clip is played by distance walked, one loop per ``clip_speed_m_s × duration``
metres, so a foot that the clip plants stays planted whatever the route's speed (the same phase
locking as the procedural gait, `camgen.actors.gait`). Standing, the idle clip plays in time, or the
walk holds its pose. Poses are evaluated by the specification's rules in `camgen.io.gltf`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from camgen.annotate.keypoints import COCO_KEYPOINTS
from camgen.errors import ConfigError
from camgen.io.gltf import (
    CAMGEN_FROM_GLTF,
    IN_PLACE_SPEED_M_S,
    Character,
    Clip,
    clip_ground_speed_m_s,
    clip_ground_travel,
    global_transforms,
    pose_character,
    pose_primitive,
)
from camgen.motion.trajectory import Route


@dataclass
class CharacterRig:
    """A glTF character moved along its route, posed in world coordinates each `place`.

    Same interface as the procedural person's rig where the renderer and the annotations read it:
    `vertices_m`, `normals`, `keypoints_m` (the COCO keypoints the rig's joints give, `coco_joint_nodes`;
    NaN rows for those it lacks; None when it has none), `heading_box()`, `place(time_s)`; and `parts`
    (per primitive slices) for a multi-material mesh.
    """

    character: Character
    route: Route
    T_actor_from_file: np.ndarray
    """The shape's placement and scale, after glTF → camgen axes."""
    walk: Clip | None
    idle: Clip | None
    cycle_m: float
    """Distance walked per loop of the walk clip, m (0 when it does not loop by distance)."""
    travel_per_cycle: np.ndarray
    """The walk clip's own ground travel over one loop (glTF axes), taken out as it plays."""
    keypoints_m: np.ndarray | None = field(default=None, init=False)
    """(17, 3) COCO keypoints in the world at the last `place`, m; NaN where the rig has no such joint."""
    model: None = None
    vertices_m: np.ndarray = field(init=False)
    normals: np.ndarray = field(init=False)
    parts: list[slice] = field(init=False)
    _reach_m: float | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        sizes = [len(p.positions) for p in self.character.primitives]
        ends = np.cumsum(sizes)
        self.parts = [slice(int(e - n), int(e)) for n, e in zip(sizes, ends, strict=True)]
        self._keypoint_nodes = coco_joint_nodes(self.character.names)
        self.place(0.0)

    def clip_time(self, time_s: float) -> tuple[Clip | None, float, float]:
        """(clip, time in it, fraction of the walk's loop taken out as travel) at scene time `time_s`."""
        standing = self.route.standing(time_s)
        if self.walk is None:
            return None, 0.0, 0.0
        duration = self.walk.duration_s
        distance = self.route.distance_at(time_s)
        if standing is not None and self.idle is not None:
            d = self.idle.duration_s
            return self.idle, (time_s % d) if d > 0 else 0.0, 0.0
        if self.cycle_m <= 0 or duration <= 0:  # a clip that does not walk: played in time
            return self.walk, (time_s % duration) if duration > 0 else 0.0, 0.0
        phase = (distance / self.cycle_m) % 1.0
        return self.walk, phase * duration, phase

    def place(self, time_s: float) -> None:
        clip, t, phase = self.clip_time(time_s)
        G = global_transforms(self.character, clip, t)
        shift = -phase * self.travel_per_cycle if clip is self.walk else np.zeros(3)
        xy, heading = self.route.at(time_s)
        T = _actor_pose(float(xy[0]), float(xy[1]), float(heading)) @ self.T_actor_from_file
        positions, normals = [], []
        for primitive in self.character.primitives:
            p, n = pose_primitive(self.character, primitive, G)
            positions.append(p + shift)
            normals.append(n)
        p, n = np.concatenate(positions), np.concatenate(normals)
        self.vertices_m = (p @ T[:3, :3].T + T[:3, 3]).astype(np.float32)
        turned = n @ T[:3, :3].T
        self.normals = (turned / np.maximum(np.linalg.norm(turned, axis=1, keepdims=True), 1e-12)).astype(np.float32)
        self._heading = float(heading)
        if any(node is not None for node in self._keypoint_nodes):
            joints = np.array(
                [G[node][:3, 3] + shift if node is not None else np.full(3, np.nan) for node in self._keypoint_nodes]
            )
            self.keypoints_m = joints @ T[:3, :3].T + T[:3, 3]

    def heading_box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low, high, T_world_from_box): the posed mesh's box in a frame turned with the heading."""
        T = _actor_pose(0.0, 0.0, self._heading)
        centre = self.vertices_m.mean(axis=0)
        T[:2, 3] = centre[:2]
        local = (self.vertices_m - T[:3, 3]) @ T[:3, :3]
        return local.min(axis=0), local.max(axis=0), T

    def envelope_radius_m(self, samples: int = 16) -> float:
        """Farthest reach of the mesh from the actor's origin over its clips, m (for clip ranges)."""
        if self._reach_m is None:
            self._reach_m = self._reach(samples)
        return self._reach_m

    def _reach(self, samples: int) -> float:
        reach = 0.0
        for clip in {id(c): c for c in (self.walk, self.idle) if c is not None}.values() or [None]:
            duration = clip.duration_s if clip is not None else 0.0
            for t in np.linspace(0.0, duration, samples) if duration > 0 else [0.0]:
                posed = pose_character(self.character, clip, float(t))
                p = np.concatenate([q for q, _ in posed])
                local = p @ self.T_actor_from_file[:3, :3].T + self.T_actor_from_file[:3, 3]
                reach = max(reach, float(np.max(np.linalg.norm(local, axis=1))))
        return reach + float(np.linalg.norm(self.travel_per_cycle))


# COCO keypoints from a rig's joint names. A joint node's origin is the joint (a bone's head in Blender,
# a joint in Mixamo, SMPL and Rigify exports); names are compared lower-cased, without a namespace
# ("mixamorig:"), a "mixamorig" prefix, or any character other than letters and digits, with the side as
# "left"/"l" before or after the part ("LeftArm", "arm_l", "upper_arm.L", "L_Elbow"). The shoulder is
# the upper arm's origin ("Arm" in Mixamo, whose "LeftShoulder" is the collarbone, as Rigify's
# "shoulder.L" is); a joint named "shoulder" counts only in a rig that also has a collarbone ("collar",
# "clavicle"), as SMPL's L_Shoulder beside L_Collar. Face points come only from joints named for them
# (eyes, ears, nose), which most body rigs lack.
KEYPOINT_PARTS = {
    "nose": ("nose", "nosetip"),
    "eye": ("eye",),
    "ear": ("ear",),
    "shoulder": ("arm", "upperarm", "uparm"),
    "elbow": ("elbow", "forearm", "lowerarm", "loarm"),
    "wrist": ("wrist", "hand"),
    "hip": ("hip", "upleg", "upperleg", "thigh"),
    "knee": ("knee", "leg", "lowerleg", "loleg", "shin", "calf"),
    "ankle": ("ankle", "foot"),
}
"""COCO part → joint names, the joint's own name first (SMPL's L_Wrist before its L_Hand, the knuckles),
then the bone that starts there (Mixamo's LeftHand starts at the wrist, LeftFoot at the ankle)."""
COLLARBONE_PARTS = ("collar", "clavicle")


def _normalised_name(name: str) -> str:
    name = name.rsplit(":", 1)[-1].lower()
    name = "".join(c for c in name if c.isalnum())
    return name.removeprefix("mixamorig")


def coco_joint_nodes(names) -> tuple[int | None, ...]:
    """For each of the 17 COCO keypoints (`COCO_KEYPOINTS` order), the node whose origin is that joint,
    found by name (`KEYPOINT_PARTS`), or None where the rig has no such joint."""
    index = {}
    for node, name in enumerate(names):
        index.setdefault(_normalised_name(name), node)
    has_collarbone = any(part in key for key in index for part in COLLARBONE_PARTS)
    nodes = []
    for keypoint in COCO_KEYPOINTS:
        side, _, part = keypoint.rpartition("_")
        bases = KEYPOINT_PARTS[part] + (("shoulder",) if part == "shoulder" and has_collarbone else ())
        sides = ("",) if not side else (side, side[0])
        candidates = [
            f"{s}{base}" if first else f"{base}{s}" for base in bases for s in sides for first in (True, False)
        ]
        nodes.append(next((index[c] for c in candidates if c in index), None))
    return tuple(nodes)


def _actor_pose(x: float, y: float, heading_rad: float) -> np.ndarray:
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[0, 3], T[1, 3] = x, y
    return T


def character_rig(
    character: Character,
    route: Route,
    *,
    T_actor_from_mesh: np.ndarray,
    scale: float,
    clip: str | None,
    idle_clip: str | None,
    clip_speed_m_s: float | None,
) -> CharacterRig:
    """A rig playing `clip` (None: the file's first) by distance walked and `idle_clip` (None: hold the
    walk) while standing. The walk loop's length is `clip_speed_m_s` × its duration, or, when not
    given, the ground the clip itself covers (refused when it walks in place)."""
    walk = character.clip(clip)
    idle = character.clip(idle_clip) if idle_clip is not None else None
    S = np.diag([scale, scale, scale, 1.0])
    T_actor_from_file = T_actor_from_mesh @ S @ CAMGEN_FROM_GLTF
    cycle_m, travel = 0.0, np.zeros(3)
    if walk is not None and walk.duration_s > 0:
        travel, duration = clip_ground_travel(character, walk)
        own_speed = clip_ground_speed_m_s(character, walk, scale)
        if clip_speed_m_s is not None:
            cycle_m = clip_speed_m_s * duration
        elif own_speed >= IN_PLACE_SPEED_M_S:
            cycle_m = own_speed * duration
        elif route_moves(route):
            raise ConfigError(
                f"{character.path}: its animation {walk.name!r} walks in place (its body travels "
                f"{own_speed:.3f} m/s), so camgen cannot tell how far one loop carries the character; give "
                "shape.animation.clip_speed_m_s, the walking speed the clip was animated for (about 1.3 m/s for "
                "an adult's walk)"
            )
    return CharacterRig(character, route, T_actor_from_file, walk, idle, cycle_m, travel)


def route_moves(route: Route) -> bool:
    return bool(len(route.points_m) > 1 and np.ptp(route.points_m, axis=0).max() > 0)
