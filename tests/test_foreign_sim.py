"""The walk controller in a simulator op2motion did not build (tests/foreign_sim/harness.py: MuJoCo, its own loop,
servo model, IMU, floor, start and fall detection), on a body op2motion's controller does not know.

The world's body is tests/data/op2_official_mesh.toml (the official ROBOTIS link masses with mesh-derived centres of
mass and inertias, 3.107 kg); its URDF, built by op2motion, is the only op2motion-made input to the harness. The
controller is planned on op2motion's shipped spec (``default_spec``), so it walks a body it believes to be another.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Mapping

import numpy as np
import pytest
from foreign_sim.harness import ServoModel, simulate

from op2motion.gait.controller import WalkController
from op2motion.model.urdf import build_urdf
from op2motion.robot.specfile import default_spec, load_spec

pytestmark = pytest.mark.physics

FOREIGN_BODY = Path(__file__).parent / "data" / "op2_official_mesh.toml"
STEPS = 12                      # 12 steps of the forward preset: 0.88 m planned
MIN_DISTANCE_M = 0.7            # forward travel of the torso at least this (80 % of the plan; measured 0.82 m)
MAX_LATERAL_SHARE = 0.10        # sideways drift at most this share of the forward travel
MAX_YAW_DEG = 10.0              # heading at the end within this of the start's
REST_S = 2.0                    # the held start pose is read after this long [s]
GRAVITY_M_S2 = 9.81
ACCEL_TOL_M_S2 = 0.5            # the accelerometer's magnitude and sideways reading at rest within this of g and 0
ACCEL_TILT_TOL_DEG = 0.5        # the tilt the accelerometer sees within this of the torso's true tilt
GYRO_TOL_RAD_S = 0.05           # the gyro at rest within this of zero (each axis)
MAX_REST_TILT_DEG = 10.0        # the held start pose sags (servo compliance, no feedback) but stands


@pytest.fixture(scope="module")
def foreign_urdf() -> str:
    """The URDF of the foreign body."""
    return build_urdf(load_spec(FOREIGN_BODY))


class _Hold:
    """A controller that holds the goals it was made with."""

    def __init__(self, goals: Mapping[str, float]):
        self.goals = dict(goals)

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The held goals."""
        return dict(self.goals)

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The held goals, whatever the sensors say."""
        return dict(self.goals)


def test_walk_controller_walks_in_the_foreign_simulator(foreign_urdf: str) -> None:
    """Twelve forward steps, planned on the shipped spec, walked by the foreign body in the foreign simulator."""
    ctl = WalkController.from_preset("forward", steps=STEPS, spec=default_spec())
    result = simulate(foreign_urdf, ctl, seconds=ctl.plan.duration_s)
    facts = {k: v for k, v in result.items() if k not in ("last_gyro", "last_accel")}
    assert not result["fell"], f"fell at {result['fall_time_s']} s: {facts}"
    assert result["distance_m"] >= MIN_DISTANCE_M, facts
    assert abs(result["lateral_m"]) <= MAX_LATERAL_SHARE * result["distance_m"], facts
    assert abs(result["end_yaw_deg"]) <= MAX_YAW_DEG, facts


#: The foreign world's own uncertainty: its servos softer and stiffer than its model (P of 12.6 N·m/rad), a slippery
#: and a grippy floor, readings two ticks (16 ms) late.
VARIANTS = {"servos x0.6": {"servo": ServoModel(kp_nm_rad=0.6 * ServoModel().kp_nm_rad)},
            "servos x1.6": {"servo": ServoModel(kp_nm_rad=1.6 * ServoModel().kp_nm_rad)},
            "friction 0.5": {"friction": 0.5}, "friction 1.0": {"friction": 1.0},
            "latency 16 ms": {"latency_ticks": 2}}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_walk_controller_walks_the_foreign_worlds_variants(foreign_urdf: str, variant: str) -> None:
    """The same twelve steps with the foreign world's servos, floor or latency changed."""
    ctl = WalkController.from_preset("forward", steps=STEPS, spec=default_spec())
    result = simulate(foreign_urdf, ctl, seconds=ctl.plan.duration_s, **VARIANTS[variant])
    facts = {k: v for k, v in result.items() if k not in ("last_gyro", "last_accel")}
    assert not result["fell"], f"fell at {result['fall_time_s']} s: {facts}"
    assert result["distance_m"] >= MIN_DISTANCE_M, facts
    assert abs(result["lateral_m"]) <= MAX_LATERAL_SHARE * result["distance_m"], facts
    assert abs(result["end_yaw_deg"]) <= MAX_YAW_DEG, facts


def test_harness_at_rest_reads_gravity_and_no_rotation(foreign_urdf: str) -> None:
    """The walk's first goals held: the robot stands, the gyro reads nothing and the accelerometer reads g along
    the torso's true vertical (the pose sags back a few degrees on the servos' compliance)."""
    ctl = WalkController.from_preset("forward", steps=STEPS, spec=default_spec())
    first = ctl.start({name: 0.0 for name in ctl.spec.joint_names})
    result = simulate(foreign_urdf, _Hold(first), seconds=REST_S)
    gyro, accel = result["last_gyro"], result["last_accel"]
    assert not result["fell"]
    assert result["end_tilt_deg"] <= MAX_REST_TILT_DEG
    assert np.all(np.abs(gyro) <= GYRO_TOL_RAD_S), gyro
    assert abs(float(np.linalg.norm(accel)) - GRAVITY_M_S2) <= ACCEL_TOL_M_S2, accel
    assert abs(accel[1]) <= ACCEL_TOL_M_S2 and accel[2] >= GRAVITY_M_S2 - ACCEL_TOL_M_S2, accel
    seen_tilt_deg = math.degrees(math.atan2(math.hypot(accel[0], accel[1]), accel[2]))
    assert abs(seen_tilt_deg - result["end_tilt_deg"]) <= ACCEL_TILT_TOL_DEG, (seen_tilt_deg, result["end_tilt_deg"])
