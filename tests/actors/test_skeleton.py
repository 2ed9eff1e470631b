"""Forward kinematics gives, bit for bit, what the textbook product along each joint's chain gives, for every
joint (`global_transforms`) and for a few (`joint_transforms`); the time memo keeps what it is given."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from camgen.actors.skeleton import INDEX, JOINTS, PARENT_INDEX, Pose, global_transforms, joint_transforms
from camgen.motion.memo import TimeMemo


def _textbook(rest_joints_m: np.ndarray, pose: Pose) -> np.ndarray:
    """G_j = G_parent(j) · Tr(r_j − r_parent(j)) · R_j, one joint at a time from a fresh identity."""
    G = np.empty((len(JOINTS), 4, 4))
    G[0] = pose.T_world_from_pelvis
    for j in range(1, len(JOINTS)):
        p = PARENT_INDEX[j]
        local = np.eye(4)
        local[:3, :3] = pose.local_rotations[j]
        local[:3, 3] = rest_joints_m[j] - rest_joints_m[p]
        G[j] = G[p] @ local
    return G


def _poses(count: int):
    rng = np.random.default_rng(5)
    for k in range(count):
        rest = rng.normal(scale=0.4, size=(len(JOINTS), 3))
        rotations = Rotation.random(len(JOINTS), random_state=k).as_matrix()
        rotations[rng.integers(0, len(JOINTS), 6)] = np.eye(3)  # joints at rest, as most of a gait's are
        T = np.eye(4)
        T[:3, :3] = Rotation.random(random_state=10_000 + k).as_matrix()
        T[:3, 3] = rng.normal(scale=20.0, size=3)
        yield rest, Pose(T, rotations)


def test_global_transforms_are_the_textbook_products_bit_for_bit():
    for rest, pose in _poses(200):
        np.testing.assert_array_equal(global_transforms(rest, pose), _textbook(rest, pose))


@pytest.mark.parametrize(
    "names",
    [("upperarm_l", "upperarm_r"), ("hand_r",), ("ball_l", "head", "spine_01"), ("pelvis", "calf_r"), JOINTS],
)
def test_joint_transforms_are_those_joints_rows_bit_for_bit(names):
    joints = tuple(INDEX[name] for name in names)
    for rest, pose in _poses(50):
        np.testing.assert_array_equal(joint_transforms(rest, pose, joints), _textbook(rest, pose)[list(joints)])


def test_a_time_memo_keeps_its_latest_times_and_forgets_the_oldest_first():
    memo = TimeMemo(limit=3)
    for time_s in (0.1, 0.2, 0.3):
        memo.put(time_s, f"pose at {time_s}")
    memo.put(0.2, "pose at 0.2 again")  # a time it holds: nothing forgotten
    assert len(memo) == 3 and memo.get(0.2) == "pose at 0.2 again"
    memo.put(0.4, "pose at 0.4")
    assert memo.get(0.1) is None and [memo.get(t) for t in (0.3, 0.4)] == ["pose at 0.3", "pose at 0.4"]
    assert memo.get(0.30000000000000004) is None  # exact times only: a time computed another way is another time
    with pytest.raises(ValueError, match="at least one"):
        TimeMemo(limit=0)
