"""A person's skeleton: forward kinematics and linear blend skinning, in numpy.

Joints have rest frames aligned with the actor frame (x forward, y left, z up) at their rest
positions, so a joint's local rotation is expressed in body axes: a rotation about y flexes a hip or a
shoulder forward. The global transform of joint j is G_j = G_parent(j) · Tr(r_j − r_parent(j)) · R_j,
and a vertex skinned to joints with weights w_j moves by Σ_j w_j · G_j · Tr(−r_j) (linear blend
skinning; Magnenat-Thalmann et al. 1988, the glTF 2.0 skin definition).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import sparse

JOINTS = (
    "pelvis",
    "spine_01",
    "spine_02",
    "spine_03",
    "neck_01",
    "head",
    "clavicle_l",
    "upperarm_l",
    "lowerarm_l",
    "hand_l",
    "clavicle_r",
    "upperarm_r",
    "lowerarm_r",
    "hand_r",
    "thigh_l",
    "calf_l",
    "foot_l",
    "ball_l",
    "thigh_r",
    "calf_r",
    "foot_r",
    "ball_r",
)
"""Joint names (MakeHuman's game-engine rig without fingers), parents before children."""

PARENTS = {
    "pelvis": None,
    "spine_01": "pelvis",
    "spine_02": "spine_01",
    "spine_03": "spine_02",
    "neck_01": "spine_03",
    "head": "neck_01",
    "clavicle_l": "spine_03",
    "upperarm_l": "clavicle_l",
    "lowerarm_l": "upperarm_l",
    "hand_l": "lowerarm_l",
    "clavicle_r": "spine_03",
    "upperarm_r": "clavicle_r",
    "lowerarm_r": "upperarm_r",
    "hand_r": "lowerarm_r",
    "thigh_l": "pelvis",
    "calf_l": "thigh_l",
    "foot_l": "calf_l",
    "ball_l": "foot_l",
    "thigh_r": "pelvis",
    "calf_r": "thigh_r",
    "foot_r": "calf_r",
    "ball_r": "foot_r",
}
INDEX = {name: i for i, name in enumerate(JOINTS)}
PARENT_INDEX = np.array([-1 if PARENTS[n] is None else INDEX[PARENTS[n]] for n in JOINTS], dtype=np.int64)


def rot_axis(axis: str, angle_rad: float | np.ndarray) -> np.ndarray:
    """Rotation matrix (…, 3, 3) by `angle_rad` about the x, y or z axis (right-handed)."""
    if isinstance(angle_rad, float | int):  # one angle: no array machinery (the gait calls this a lot)
        c, s = math.cos(angle_rad), math.sin(angle_rad)
        if axis == "x":
            return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        if axis == "y":
            return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    a = np.asarray(angle_rad, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((*a.shape, 3, 3))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    k = 3 - i - j
    R[..., k, k] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b of two 3-vectors (numpy's cross costs ten times more on single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (3, 3) taking direction `a` onto direction `b` (Rodrigues)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a = a / math.sqrt(a @ a)
    b = b / math.sqrt(b @ b)
    v = cross(a, b)
    c = float(np.dot(a, b))
    if c < -1 + 1e-12:  # opposite: turn half-way round any perpendicular axis
        axis = cross(a, np.array([1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0]))
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


@dataclass(frozen=True)
class Pose:
    """A skeleton pose: where the pelvis is and how every joint turns."""

    T_world_from_pelvis: np.ndarray
    """(4, 4) the pelvis joint's global transform (rotation and position in the world)."""
    local_rotations: np.ndarray
    """(J, 3, 3) each joint's rotation relative to its parent, in rest-aligned axes (pelvis: unused)."""


def _local_transforms(rest_joints_m: np.ndarray, pose: Pose) -> np.ndarray:
    """(J, 4, 4) each joint's transform from its parent's frame, Tr(r_j − r_parent(j)) · R_j (the pelvis's
    row unused)."""
    local = np.zeros((len(JOINTS), 4, 4))
    local[:, :3, :3] = pose.local_rotations
    local[1:, :3, 3] = rest_joints_m[1:] - rest_joints_m[PARENT_INDEX[1:]]
    local[:, 3, 3] = 1.0
    return local


def global_transforms(rest_joints_m: np.ndarray, pose: Pose) -> np.ndarray:
    """(J, 4, 4) global transform of every joint for `pose` (forward kinematics).

    One 4 × 4 product per joint, its parent's global transform times its local one; the local transforms
    are built in one go (one identity built per joint cost more than the products)."""
    G = np.empty((len(JOINTS), 4, 4))
    G[0] = pose.T_world_from_pelvis
    local = _local_transforms(rest_joints_m, pose)
    for j, p in _CHAIN:
        G[j] = G[p] @ local[j]
    return G


_CHAIN = tuple((j, int(PARENT_INDEX[j])) for j in range(1, len(JOINTS)))


@lru_cache(maxsize=16)
def _chain_to(joints: tuple[int, ...]) -> tuple[tuple[int, int], ...]:
    """(joint, parent) of `joints` and their ancestors but the pelvis, parents first."""
    needed = set()
    for j in joints:
        while j > 0:
            needed.add(j)
            j = int(PARENT_INDEX[j])
    return tuple((j, p) for j, p in _CHAIN if j in needed)


def joint_transforms(rest_joints_m: np.ndarray, pose: Pose, joints: tuple[int, ...]) -> np.ndarray:
    """(len(joints), 4, 4) the global transforms of `joints` alone (`global_transforms`' rows, bit for bit:
    the same products along their chains from the pelvis, the other joints' left out)."""
    G = np.empty((len(JOINTS), 4, 4))
    G[0] = pose.T_world_from_pelvis
    local = _local_transforms(rest_joints_m, pose)
    for j, p in _chain_to(tuple(joints)):
        G[j] = G[p] @ local[j]
    return G[list(joints)]


def skinning_matrices(rest_joints_m: np.ndarray, G: np.ndarray) -> np.ndarray:
    """(J, 3, 4) G_j · Tr(−r_j): the affine map each joint applies to a rest vertex."""
    M = G[:, :3, :].copy()
    M[:, :, 3] -= np.einsum("jab,jb->ja", G[:, :3, :3], rest_joints_m)
    return M


def weight_matrix(joint_index: np.ndarray, joint_weight: np.ndarray, joint_count: int) -> sparse.csr_matrix:
    """The (V, joint_count) sparse matrix of skinning weights (`joint_index` may address joints of
    several skeletons stacked: skeleton k's joint j is column k·J + j)."""
    rows = np.repeat(np.arange(len(joint_index)), joint_index.shape[1])
    return sparse.csr_matrix(
        (joint_weight.ravel().astype(np.float32), (rows, joint_index.ravel())), shape=(len(joint_index), joint_count)
    )


def skin(
    rest_vertices_m: np.ndarray, rest_normals: np.ndarray, weights: sparse.csr_matrix, M: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Linear blend skinning of vertices and normals.

    Parameters
    ----------
    rest_vertices_m, rest_normals : ndarray, shape (V, 3), float32
    weights : scipy.sparse matrix, shape (V, J)
        `weight_matrix`: each vertex's weights over the joints (rows sum to 1).
    M : ndarray, shape (J, 3, 4)
        `skinning_matrices` (of one skeleton, or of several stacked).

    Returns
    -------
    vertices_m, normals : ndarray, shape (V, 3), float32
        Posed vertices; normals turned by the blended rotation (renormalised).

    The blended matrices are one sparse product, W·M (V × 12), and applying them is twelve
    multiply-adds per vertex on whole columns: no per-vertex 3×4 matrices are gathered.
    """
    B = weights @ M.reshape(len(M), 12).astype(np.float32)
    v, n = rest_vertices_m, rest_normals
    vertices = np.empty((len(v), 3), dtype=np.float32)
    normals = np.empty((len(v), 3), dtype=np.float32)
    for row in range(3):
        r = 4 * row
        vertices[:, row] = B[:, r] * v[:, 0] + B[:, r + 1] * v[:, 1] + B[:, r + 2] * v[:, 2] + B[:, r + 3]
        normals[:, row] = B[:, r] * n[:, 0] + B[:, r + 1] * n[:, 1] + B[:, r + 2] * n[:, 2]
    normals /= np.maximum(np.sqrt(np.einsum("ij,ij->i", normals, normals))[:, None], 1e-12)
    return vertices, normals
