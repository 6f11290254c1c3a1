"""The statically sagged start (op2motion.model.equilibrium): torque balance, symmetry, and agreement with physics."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from op2motion.formats.posefile import read_pose
from op2motion.model.dynamics import dynamics_for
from op2motion.model.equilibrium import CHORD_REUSE_RAD, Chord, _right_from_left, loaded_foot_margin, sagged_angles
from op2motion.model.servo import ServoModel
from op2motion.physics import Schedule, Setup, check
from op2motion.physics.sweeps import sweep_base
from op2motion.robot.specfile import default_spec

POSES_DIR = Path(__file__).resolve().parents[1] / "poses"

BALANCE_TOL_NM = 1e-5          # torque imbalance left at a solution [N·m]
MIRROR_TOL_RAD = 1e-4          # left and right sags of a symmetric pose differ by less
SETTLED_TOL_DEG = 0.5          # physics started at the sagged angles moves them less than this (friction band
                               # 0.03 N·m / 12.6 N·m/rad = 0.14°, and the contacts give; a ramped start overshoots
                               # by degrees)
HOLD_S = 2.5                   # the shortest check [s]
SOLE_TOL_M = 1e-6              # the right sole stays where it was put down, seen from the left one
FOOT_COP_TOL_M = 0.002         # the solved split's per-foot CoP margin against both engines' measured ones
CHORD_SAME_M = 1e-6            # a margin solved with a lent Jacobian against a fresh solve's [m]


@pytest.fixture(scope="module")
def spec():
    return default_spec()


def test_one_leg_sag_balances_gravity(spec):
    servo = ServoModel.of(spec)
    goal = sweep_base(spec, "left")
    q = sagged_angles(goal, "left", spec, servo.kp, servo.torque_max)
    assert q is not None
    held = dynamics_for(spec).static_torques(q, "left").torques
    assert np.max(np.abs(servo.kp * (goal - q) - held)) < BALANCE_TOL_NM
    assert np.max(np.abs(np.degrees(q - goal))) > 1.0           # an OP2 on one leg at P = 32 sags by degrees


def test_two_leg_sag_is_mirror_symmetric_and_keeps_the_soles(spec):
    servo = ServoModel.of(spec)
    goal = sweep_base(spec, "double")
    q = sagged_angles(goal, "double", spec, servo.kp, servo.torque_max)
    assert q is not None
    sag = q - goal
    names = spec.joint_names
    for name in names:
        if name.startswith("l_"):
            left, right = sag[names.index(name)], sag[names.index("r_" + name[2:])]
            assert abs(abs(left) - abs(right)) < MIRROR_TOL_RAD, name
    before, _ = _right_from_left(dynamics_for(spec), goal)
    after, _ = _right_from_left(dynamics_for(spec), q)
    assert np.linalg.norm(before.translation - after.translation) < SOLE_TOL_M


def test_too_soft_servos_have_no_equilibrium(spec):
    servo = ServoModel.of(spec, stiffness_scale=0.1)
    assert sagged_angles(sweep_base(spec, "left"), "left", spec, servo.kp, servo.torque_max) is None


@pytest.mark.physics
@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_physics_holds_the_sagged_angles(spec, engine):
    servo = ServoModel.of(spec)
    goal = sweep_base(spec, "left")
    q = sagged_angles(goal, "left", spec, servo.kp, servo.torque_max)
    verdict = check(Schedule.hold(goal, "left", spec, HOLD_S), spec, (engine,), setup=Setup(keep_track=True)).run
    assert verdict.stable, verdict.reasons
    moved = np.degrees(np.max(np.abs(verdict.track.q - q), axis=0))
    assert moved.max() < SETTLED_TOL_DEG, dict(zip(spec.joint_names, np.round(moved, 2)))


def test_a_lean_that_rolls_the_lighter_foot_loads_the_other_one_towards_its_edge(spec):
    # walk-ready with the torso shifted sideways by the hip and ankle rolls: at first the load moves onto one foot
    # (its own CoP margin grows); once the split would press the lighter foot outside itself (no equilibrium with
    # both soles flat), that foot rolls onto its edge and the loaded one takes over the moment: its margin falls
    servo = ServoModel.of(spec)
    goal = read_pose(POSES_DIR / "walkready.json", spec).servo

    def lean(roll_deg: float) -> np.ndarray:
        out = goal.copy()
        for joint, sign in (("l_hip_roll", 1), ("r_hip_roll", 1), ("l_ank_roll", -1), ("r_ank_roll", -1)):
            out[spec.joint_names.index(joint)] += sign * np.radians(roll_deg)
        return out

    margins = {deg: loaded_foot_margin(lean(deg), spec, servo.kp, servo.torque_max) for deg in (0.0, 4.0, 8.0, 12.0)}
    assert margins[4.0] > margins[0.0] > 0.015
    assert sagged_angles(lean(4.0), "double", spec, servo.kp, servo.torque_max) is not None
    assert sagged_angles(lean(12.0), "double", spec, servo.kp, servo.torque_max) is None
    assert margins[4.0] > margins[8.0] > margins[12.0] > 0.0

    # a run of nearby leans sharing one Jacobian (as a line's rows do) finds the fresh solves' margins
    chord = Chord()
    for deg in np.arange(0.0, 12.5, 0.5):
        lent = loaded_foot_margin(lean(deg), spec, servo.kp, servo.torque_max, chord)
        fresh = loaded_foot_margin(lean(deg), spec, servo.kp, servo.torque_max)
        assert lent == pytest.approx(fresh, abs=CHORD_SAME_M), deg
    assert np.max(np.abs(chord.goal - lean(12.0))) <= CHORD_REUSE_RAD    # taken afresh on the way, not at 0°


@pytest.mark.physics
def test_per_foot_margin_of_a_standing_pose_agrees_with_both_engines(spec):
    servo = ServoModel.of(spec)
    goal = read_pose(POSES_DIR / "standing.json", spec).servo
    ours = loaded_foot_margin(goal, spec, servo.kp, servo.torque_max)
    report = check(Schedule.hold(goal, "double", spec, HOLD_S), spec, ("pybullet", "mujoco"))
    for name, engine in report.engines.items():
        measured = min(f.cop_margin_m for f in engine.run.feet.values())
        assert abs(measured - ours) < FOOT_COP_TOL_M, (name, measured, ours)
