"""The whole-body IK's compiled poses and features (op2motion.motion.whole_body_kernel, posture.kernel.body_features)
give the numbers of the NumPy leg IK (kinematics.leg_ik), the D-H points and full-inertia CoM (kinematics.forward)
and the cost model's clearance, on random unknowns around several poses, on one foot and on two."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import POSES, SEED

from op2motion.formats.posefile import read_pose
from op2motion.kinematics import forward
from op2motion.kinematics.leg_ik import leg_ik, within_reach
from op2motion.motion.body_checks import body_cost
from op2motion.motion.whole_body import CLEAR_TASK_M, WholeBodyIk
from op2motion.posture.cost import torso_axes
from op2motion.robot.joints import servo_to_book

SAME_RAD = 1e-6        # a knee near straight: arccos turns a rounding of 1e-16 into 1e-8 rad
SAME_M = 1e-12
CASES = [("walkready", "double", "right"), ("standing", "double", "left"), ("walkready", "left", "right"),
         ("walkready", "right", "left"), ("book_2_44", "left", "left")]


def _rotation(v: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(v, axis=1)
    axis = v / np.maximum(angle, 1e-12)[:, None]
    k = np.zeros((len(v), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    k = k - k.transpose(0, 2, 1)
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * k @ k


def _servo_numpy(ik: WholeBodyIk, x: np.ndarray) -> np.ndarray:
    rot = _rotation(x[:, 3:6]) @ ik.torso_rot
    pos = ik.torso_pos + x[:, :3]
    out = np.repeat(ik.start[None], len(x), axis=0)
    out[:, ik.arm] = x[:, 6:9]
    for leg in ik.legs:
        p, r = ik.soles_world[leg.side]
        local = np.einsum("nji,nj->ni", rot, p - pos)
        out[:, list(leg.index)] = leg_ik(leg, *within_reach(leg, local, rot.transpose(0, 2, 1) @ r,
                                                            ik.reach[leg.side]))
    moved = ik._moved
    out[:, moved] = np.clip(out[:, moved], ik.lower, ik.upper)
    return out


@pytest.mark.parametrize("pose, support, hand", CASES)
def test_compiled_poses_and_features_equal_numpys(spec, pose, support, hand):
    ik = WholeBodyIk(spec, support, hand, read_pose(POSES / f"{pose}.json", spec).servo)
    x = ik.x0 + np.random.default_rng(SEED).normal(0.0, 0.03, (100, 9))
    q = ik.servo(x)
    assert np.abs(q - _servo_numpy(ik, x)).max() < SAME_RAD
    f = ik.features(q)
    angles = servo_to_book(q, ik.frame, spec)
    points = forward(angles, spec, "dh", full_com=True)
    data = points.data
    assert np.abs(f["hand"] - data[ik._hand_row].T).max() < SAME_M
    assert np.abs(f["com"] - points.full()[:2].T).max() < SAME_M
    assert np.abs(f["feet"] - data[ik._foot_rows].transpose(2, 0, 1).reshape(len(q), -1)).max() < SAME_M
    axes = torso_axes(data, spec)
    assert np.abs(f["torso"] - np.concatenate([axes[0].T, axes[2].T], axis=1)).max() < SAME_M
    clearance = body_cost(spec, ik.frame)(angles).clearance
    assert np.abs(f["close"][:, 0] - np.maximum(CLEAR_TASK_M - clearance, 0.0)).max() < SAME_M
