"""The per-tick and per-row shortcuts against the array code they stand in for: 3-vector and 3 x 3 helpers, the
one-pose leg IK, the one-point support margin, the batched quaternions (pinocchio's, bit for bit) and the support
points. Each holds to the original's numbers on seeded random inputs."""

from __future__ import annotations

import numpy as np
import pytest

from op2motion.errors import InputError
from op2motion.gait.rows import support_points
from op2motion.kinematics import small
from op2motion.kinematics.frames import eigen_quaternions
from op2motion.kinematics.leg_ik import (
    leg_ik,
    leg_ik_pose,
    leg_of,
    rot_x,
    rot_y,
    rot_z,
    within_reach,
    within_reach_pose,
)
from op2motion.robot.balance import convex_hull, point_margin, polygon_margin
from op2motion.robot.specfile import default_spec
from op2motion.robot.support import Support

SEED = 20261128
ROUNDING = 1e-15        # floats vs NumPy on unit-sized numbers: a few ulps (NumPy's products may fuse)
IK_SAME_RAD = 1e-12     # the one-pose leg IK against the batched one
MARGIN_SAME_M = 1e-15   # the one-point margin against the array one (distances of a few cm)
SAMPLES = 500


@pytest.fixture(scope="module")
def spec():
    return default_spec()


def _rotations(rng: np.random.Generator, n: int, tilt: float = 0.3) -> np.ndarray:
    return (rot_z(rng.uniform(-np.pi, np.pi, n)) @ rot_y(rng.uniform(-tilt, tilt, n))
            @ rot_x(rng.uniform(-tilt, tilt, n)))


def test_the_small_helpers_equal_numpy():
    rng = np.random.default_rng(SEED)
    for _ in range(SAMPLES):
        a, b, angle = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.uniform(-4.0, 4.0)
        u, v = rng.normal(size=3), rng.normal(size=3)
        sa, sb = small.mat(a), small.mat(b)
        pairs = [(small.rot_x(angle), rot_x(angle)), (small.rot_y(angle), rot_y(angle)),
                 (small.rot_z(angle), rot_z(angle)), (small.mul(sa, sb), a @ b), (small.mul_t(sa, sb), a.T @ b),
                 (small.apply(sa, small.vec(u)), a @ u), (small.apply_t(sa, small.vec(u)), a.T @ u),
                 (small.add(u, v), u + v), (small.sub(u, v), u - v), (small.scaled(u, angle), u * angle)]
        for got, want in pairs:
            assert np.allclose(got, want, rtol=0.0, atol=ROUNDING * 10)
        assert small.norm(u) == pytest.approx(float(np.linalg.norm(u)), rel=ROUNDING * 10)


def test_the_one_pose_leg_ik_equals_the_batched_one_within_and_beyond_reach(spec):
    """Soles near the leg's length (some beyond: pulled in by ``within_reach``) at random attitudes."""
    rng = np.random.default_rng(SEED)
    for side in ("left", "right"):
        leg = leg_of(spec, side)
        rot = _rotations(rng, SAMPLES)
        sole = leg.hip + np.column_stack([rng.uniform(-0.05, 0.05, SAMPLES), rng.uniform(-0.03, 0.03, SAMPLES),
                                          -rng.uniform(0.15, 0.24, SAMPLES)])
        pulled, _ = within_reach(leg, sole, rot, 0.999)
        assert np.any(np.abs(pulled - sole) > 0.0)                   # some targets were beyond the leg
        want = leg_ik(leg, pulled, rot)
        for i in range(SAMPLES):
            one = within_reach_pose(leg, sole[i].tolist(), rot[i].tolist(), 0.999)
            assert np.allclose(one, pulled[i], rtol=0.0, atol=ROUNDING)
            assert np.allclose(leg_ik_pose(leg, one, rot[i].tolist()), want[i], rtol=0.0, atol=IK_SAME_RAD)


def test_the_one_pose_leg_ik_refuses_what_the_batched_one_refuses(spec):
    """A sole beyond the leg, and one above the hip: the same error, word for word."""
    leg = leg_of(spec, "left")
    for sole, why in ((leg.hip + [0.0, 0.0, -0.5], "within 0.1860 m"), (leg.hip + [0.0, 0.0, 0.12], "hip above")):
        with pytest.raises(InputError, match=why) as batched:
            leg_ik(leg, sole[None], np.eye(3)[None])
        with pytest.raises(InputError, match=why) as one:
            leg_ik_pose(leg, sole.tolist(), small.IDENTITY)
        assert str(one.value) == str(batched.value)


def test_the_one_point_margin_equals_the_array_one_inside_and_outside():
    rng = np.random.default_rng(SEED)
    signs = set()
    for _ in range(SAMPLES):
        polygon = convex_hull(rng.normal(0.0, 0.05, (8, 2)))
        x, y = rng.normal(0.0, 0.06, 2)
        want = float(polygon_margin(np.array([x, y]), polygon)[0])
        assert point_margin(float(x), float(y), polygon) == pytest.approx(want, abs=MARGIN_SAME_M)
        signs.add(want > 0.0)
    assert signs == {True, False}


def test_the_batched_quaternions_are_pinocchios_bit_for_bit():
    """Both of Eigen's branches: a positive trace, and a half turn or more (the largest diagonal term)."""
    import pinocchio as pin

    rng = np.random.default_rng(SEED)
    rot = _rotations(rng, 4 * SAMPLES, tilt=3.0)
    assert np.any(np.trace(rot, axis1=1, axis2=2) <= 0.0) and np.any(np.trace(rot, axis1=1, axis2=2) > 0.0)
    want = np.array([pin.Quaternion(r).coeffs() for r in rot])
    assert np.array_equal(eigen_quaternions(rot), want)


def test_support_points_are_the_mean_of_the_soles_on_the_floor():
    rng = np.random.default_rng(SEED)
    contact = tuple(rng.choice(["left", "right", "double"], 50))
    feet = {side: rng.normal(size=(50, 4)) for side in ("left", "right")}
    want = np.array([np.mean([feet[s][k, :3] for s in Support.of(c).feet], axis=0) for k, c in enumerate(contact)])
    assert np.array_equal(support_points(feet, contact), want)
