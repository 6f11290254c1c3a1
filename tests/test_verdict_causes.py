"""A verdict says why, not only what happened: a one-leg squat on servos with a 1 N·m stall torque falls, and the
check names the knee's torque saturation among its reasons in both engines, whether it stops early at the fall or
plays the whole plan; the early run's failures are the full run's up to where it stopped."""

from __future__ import annotations

import dataclasses

import pytest

from op2motion.physics import Schedule, Setup, check
from op2motion.physics.stopping import FELL
from op2motion.physics.sweeps import ARMS_FORWARD, FOLDED_SWING, balanced_pose, servo_pose

pytestmark = pytest.mark.physics
WEAK_STALL_NM = 1.0           # the OP2's knee needs about 2 N·m in this squat
SECONDS = 3.0


def _weak(spec):
    servo = spec.servo
    ratings = tuple(dataclasses.replace(r, stall_torque_nm=WEAK_STALL_NM) for r in servo.ratings)
    return dataclasses.replace(spec, servo=dataclasses.replace(servo, ratings=ratings))


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_a_weak_servo_squat_names_its_saturation(spec, engine):
    squat = dict(l_knee=-100, l_hip_pitch=50, l_ank_pitch=-50, **FOLDED_SWING)
    servo = balanced_pose(spec, servo_pose(spec, "left", **{**ARMS_FORWARD, **squat}), "left", (-0.02, 0.011))
    weak = _weak(spec)
    early, full = (check(Schedule.hold(servo, "left", weak, SECONDS), weak, (engine,),
                         setup=Setup(full_length=length)).run for length in (False, True))
    assert early.ended == FELL and early.seconds < SECONDS
    for run in (early, full):
        assert {"tilt", "com_drop", "torque_saturation"} <= set(run.reasons), run.reasons
        saturated = next(f for f in run.failures if f.reason == "torque_saturation")
        assert "l_knee" in saturated.detail
        assert saturated.time_s < next(f.time_s for f in run.failures if f.reason == "tilt")   # before the fall
    assert [(f.reason, f.time_s) for f in early.failures] == [
        (f.reason, f.time_s) for f in full.failures if f.time_s <= early.seconds + 1e-9]
