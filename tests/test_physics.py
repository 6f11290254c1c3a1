"""Physics checks: the calibrated servo model, one verdict with named reasons in two engines that agree, the stock
pages standing and surviving pushes, a test pose for each failure mode, the placement rule, the engines' traps."""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import replace

import numpy as np
import pytest
from helpers import pose_path

from op2motion.errors import InputError
from op2motion.formats.posefile import read_pose
from op2motion.model.dynamics import dynamics_for
from op2motion.model.servo import ServoModel
from op2motion.model.urdf import FRAME_LINK_MASS_KG, link_inertial
from op2motion.physics import ENGINES, MIN_SECONDS, CheckReport, Pushes, Schedule, Setup, check, make_engine
from op2motion.physics.body import Body, placement
from op2motion.physics.pybullet_engine import PyBulletEngine, load_robot, quiet_c_output
from op2motion.physics.sweeps import ARMS_FORWARD, FOLDED_SWING, balanced_pose, servo_pose
from op2motion.robot.framework import p_gain_of_slope
from op2motion.robot.variant import spec_variant

STOCK_STANDING = ["init", "walkready", "sit_down", "stand_up"]
PUSH_N = 2.0
PUSH_RUN_S = 3.0                # 1.5 s after the push
ENGINE_MARGIN_M = 0.002         # the two engines' settled margins agree this well on standing poses
PUSHED_IN_BOTH = "walkready"    # the stock page pushed in both engines (the others: in MuJoCo)
KP_P32_NM_RAD = 0.158 * 32 * 2.5


def _run(servo, support, spec, seconds=3.0, engine="pybullet", p_gains=None, voltage=None, full_length=False):
    """The main run of a held pose in one engine."""
    schedule = Schedule.hold(servo, support, spec, seconds, p_gains)
    return check(schedule, spec, (engine,), setup=Setup(voltage=voltage, full_length=full_length)).run


# --- the servo model -------------------------------------------------------------------------------------------

def test_servo_model_in_physical_units(spec):
    model = ServoModel.of(spec)
    assert model.kp == pytest.approx(np.full(20, KP_P32_NM_RAD))                    # 12.6 N·m/rad at P = 32, 12 V
    assert model.kd_emf == pytest.approx(2.5 / 5.76) and model.torque_max == pytest.approx(0.9625 * 2.5)
    assert model.available(np.array([0.0]))[0] == pytest.approx(model.torque_max)
    assert model.available(np.array([0.9625 * 5.76]))[0] == pytest.approx(0.0, abs=1e-12)  # zero near no-load
    half = model.available(np.array([0.5 * 0.9625 * 5.76]))[0]
    assert half == pytest.approx(0.5 * model.torque_max)                            # linear in between
    speed = np.array([2.0])                                     # [rad/s]: a braking torque gets the back-EMF's help
    assert model.available(speed, np.array([-1.0]))[0] == pytest.approx(model.torque_max + model.kd_emf * 2.0)
    assert model.available(speed, np.array([1.0]))[0] == pytest.approx(model.available(speed)[0])
    goal, q = np.zeros(20), np.full(20, -0.5)
    assert model.active_torque(goal, q) == pytest.approx(np.full(20, model.torque_max))  # clipped
    low = ServoModel.of(spec, voltage=11.1)
    assert low.torque_max == pytest.approx(0.9625 * 2.3) and low.kp[0] == pytest.approx(0.158 * 32 * 2.3)
    with pytest.raises(InputError, match="rated voltages"):
        ServoModel.of(spec, voltage=13.0)


@pytest.mark.parametrize("slope, p", [(0x55, 32), (0x44, 64), (0x66, 16), (0x77, 8), (0x33, 128)])
def test_compliance_byte_sets_the_p_gain(slope, p):
    assert p_gain_of_slope(slope) == p


# --- real poses stand, in both engines, and survive pushes -----------------------------------------------------

@pytest.mark.physics
@pytest.mark.parametrize("name", STOCK_STANDING)
def test_stock_standing_pages_stand_in_both_engines_and_survive_pushes(spec, name):
    """Each page stands in both engines (their margins agree) and survives a push each way: in both engines for the
    page every walk starts from, in MuJoCo for the others (PyBullet costs seven times its CPU per simulated second;
    all four survived in both when measured)."""
    pose = read_pose(pose_path(name), spec)
    pushed = ENGINES if name == PUSHED_IN_BOTH else ("mujoco",)
    hold = Schedule.hold(pose.servo, pose.support, spec, PUSH_RUN_S)
    report = check(hold, spec, pushed, Pushes(PUSH_N))
    if pushed != ENGINES:
        report = CheckReport({**check(hold, spec, ("pybullet",)).engines, **report.engines})
    for engine, e in report.engines.items():
        v = e.run
        assert v.stable, (engine, v.reason)
        if engine in pushed:
            assert [p.direction for p in e.pushes if p.stable] == ["forward", "backward", "left", "right"], engine
        assert v.support_margin_m > 0.01 and v.max_tilt_deg < 10 and v.self_collisions == ()
        assert v.cop_xy is not None
    assert report.agree and report.stable and report.pushes_stood
    runs = {name: e.run for name, e in report.engines.items()}
    assert abs(runs["pybullet"].support_margin_m - runs["mujoco"].support_margin_m) < ENGINE_MARGIN_M


@pytest.mark.physics
def test_same_input_same_verdict(spec):
    servo = servo_pose(spec)
    for engine in ENGINES:
        assert _run(servo, "double", spec, 3.0, engine) == _run(servo, "double", spec, 3.0, engine)


@pytest.mark.physics
def test_a_plans_own_measurements_come_back_in_the_walk_slot(spec):
    """Physics knows no walk: what a plan's hook (``Plan.measure``) returns after a run is kept in the run report's
    ``walk`` slot, and nothing else changes; a plan without one gets nothing there."""
    plain = Schedule.hold(servo_pose(spec), "double", spec, MIN_SECONDS)
    calls = []

    def hook(track, start, plan, spec_):
        calls.append((plan is hooked.plan, spec_ is spec, start.planned.flat_foot))
        return ("measured", len(track.times))

    hooked = Schedule(replace(plain.plan, measure=hook), spec.joint_names)
    assert hooked.plan == plain.plan                  # the hook is no part of the plan's equality
    run = check(hooked, spec, ("pybullet",)).run
    assert calls == [(True, True, run.flat_foot)]    # once, after the run, with that run's start
    assert run.walk[0] == "measured" and run.walk[1] > 0
    without = check(plain, spec, ("pybullet",)).run
    assert without.walk is None and replace(run, walk=None) == without


# --- every failure mode has a pose that fails with exactly that reason -----------------------------------------

def _one_leg(spec, **joints):
    return balanced_pose(spec, servo_pose(spec, "left", **{**ARMS_FORWARD, **joints}), "left", (0.0, 0.011))


@pytest.mark.physics
def test_a_balanced_one_leg_stance_stands_in_both_engines(spec):
    servo = _one_leg(spec, **FOLDED_SWING)
    for engine in ENGINES:
        v = _run(servo, "left", spec, 3.0, engine)
        assert v.stable, (engine, v.reason)


@pytest.mark.physics
@pytest.mark.parametrize("engine", ENGINES)
def test_swing_foot_on_the_floor_is_swing_foot_contact(spec, engine):
    """The standing pose declared as single support: the swing foot carries weight, so it is not a one-leg pose."""
    v = _run(servo_pose(spec), "left", spec, 3.0, engine)
    assert v.reasons == ["swing_foot_contact"]


@pytest.mark.physics
@pytest.mark.parametrize("engine", ENGINES)
def test_thigh_pressed_into_the_torso_is_self_collision(spec, engine):
    v = _run(_one_leg(spec, r_hip_pitch=-105, r_hip_roll=10, r_ank_roll=10), "left", spec, 3.0, engine)
    assert v.reasons == ["self_collision"]
    assert ("body_link", "r_hip_pitch_link") in v.self_collisions


@pytest.mark.physics
@pytest.mark.parametrize("engine", ENGINES)
def test_one_leg_squat_beyond_stall_is_torque_saturation(spec, engine):
    """A one-leg squat on the OP2's 11.1 V battery (2.21 N·m available): the OP2 needs 1.98 N·m at the knee and
    stands; the same robot with a torso 40 % heavier (a 0.39 kg payload) needs 2.30 N·m, beyond stall, and the
    check names the knee's torque saturation. Stiff servos (compliance 0x33, P = 128) keep the sag small."""
    squat = dict(l_knee=-100, l_hip_pitch=50, l_ank_pitch=-50, **FOLDED_SWING)
    stiff = np.full(20, p_gain_of_slope(0x33))
    available = ServoModel.of(spec, voltage=11.1).torque_max
    for body, stands in ((spec, True), (spec_variant(spec, torso_mass_scale=1.4), False)):
        servo = balanced_pose(body, servo_pose(body, "left", **{**ARMS_FORWARD, **squat}), "left", (-0.02, 0.011))
        needed = abs(dynamics_for(body).static_torques(servo, "left").torques[body.joint_names.index("l_knee")])
        assert (needed < available) == stands, (needed, available)
        v = _run(servo, "left", body, 3.0, engine, p_gains=stiff, voltage=11.1)
        if stands:
            assert v.stable, v.reasons
        else:
            assert "torque_saturation" in v.reasons and v.worst_joint == "l_knee" and not v.torque_ok


@pytest.mark.physics
@pytest.mark.parametrize("engine", ENGINES)
def test_lean_past_the_edge_tilts(spec, engine):
    pose = servo_pose(spec, l_ank_pitch=35, r_ank_pitch=-35)
    v = _run(pose, "double", spec, 3.0, engine, full_length=True)
    assert v.reasons[0] == "tilt" and v.max_tilt_deg > 30 and "ground_contact" in v.reasons
    early = _run(pose, "double", spec, 3.0, engine)            # ends once its CoM has sunk: it fell
    assert early.reasons == ["tilt", "com_drop"] and early.ended == "fell" and early.seconds < 1.0


@pytest.mark.physics
def test_arm_through_the_torso_is_reported(spec):
    v = _run(servo_pose(spec, l_sho_roll=75), "double", spec, 3.0)   # upper arm swung 30° inwards
    assert v.reasons[0] == "self_collision"
    assert {"body_link"} < set(v.self_collisions[0]) and set(v.self_collisions[0]) & {"l_sho_roll_link", "l_el_link"}


def test_bad_input(spec):
    with pytest.raises(InputError, match="support"):
        Schedule.hold(servo_pose(spec), "both", spec)
    with pytest.raises(InputError, match="seconds"):
        Schedule.hold(servo_pose(spec), "left", spec, seconds=float("nan"))
    with pytest.raises(InputError, match="engine"):
        check(Schedule.hold(servo_pose(spec), "left", spec), spec, ("ode",))
    with pytest.raises(InputError, match="push"):
        Pushes(-1.0)
    with pytest.raises(InputError, match="servo angles"):
        Schedule.hold(servo_pose(spec)[:19], "left", spec)


# --- placement -------------------------------------------------------------------------------------------------

FLOOR_M = 1e-9


@pytest.mark.physics
@pytest.mark.parametrize("splay", [-6.0, 6.0])
def test_non_parallel_feet_start_on_the_floor_not_in_it(spec, splay):
    """Double support with the feet rolled apart by ``splay`` degrees: the lower sole lies flat, the other touches
    at its lowest corner, no corner below the floor."""
    servo = servo_pose(spec, r_ank_roll=splay)
    body = Body(spec)
    placed = placement(body, servo, "double")
    pos, rot, flat, gap = placed.pos, placed.rot, placed.flat, placed.gap
    state = body.state(pos, rot, servo)
    lowest = min(c[:, 2].min() for c in state.corners.values())
    assert lowest == pytest.approx(0.0, abs=FLOOR_M)                                      # touching, not below
    assert np.ptp(state.corners[flat][:, 2]) < 1e-9                                        # the level sole
    other = "left" if flat == "right" else "right"
    assert state.corners[other][:, 2].min() == pytest.approx(0.0, abs=FLOOR_M)            # touches at a corner
    assert state.corners[flat][:, 2].min() == pytest.approx(gap, abs=1e-9) and gap < 0.005
    for engine in ENGINES:
        v = _run(servo, "double", spec, 3.0, engine)
        assert v.stable and v.start_gap_m == pytest.approx(gap, abs=1e-5), engine


# --- engine traps and models ----------------------------------------------------------------------------------

@pytest.mark.physics
def test_mujoco_compiles_the_same_robot(spec):
    engine = make_engine("mujoco", spec, ServoModel.of(spec))
    assert engine.total_mass() == pytest.approx(sum(i.mass for i in spec.inertials), abs=1e-4)
    m = engine.model
    assert list(m.dof_armature[engine.dadr]) == pytest.approx([spec.servo.armature_kg_m2] * 20)
    for name in spec.joint_names:
        lower, upper = spec.joint(name).mechanical
        assert list(m.jnt_range[m.joint(name).id]) == pytest.approx([lower, upper])


@pytest.mark.physics
def test_trap_inertia_is_taken_from_the_file_only_when_told(spec):
    expected = np.linalg.eigvalsh(link_inertial(next(i for i in spec.inertials if i.link == "l_knee_link")).tensor)
    for from_file in (True, False):
        engine = PyBulletEngine(spec, ServoModel.of(spec), 0.001, use_inertia_from_file=from_file)
        diag = np.sort(engine.client.getDynamicsInfo(engine.robot, engine.link_index["l_knee_link"])[2])
        engine.close()
        if from_file:
            assert diag == pytest.approx(expected, rel=1e-6)
        else:  # recomputed from the collision box: a different tensor
            assert not np.allclose(diag, expected, rtol=0.05)


@pytest.mark.physics
def test_trap_a_link_without_inertial_weighs_one_kilogram(spec):
    bare = ('<robot name="t"><link name="a"><inertial><mass value="0.5"/><inertia ixx="1e-3" iyy="1e-3" '
            'izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"/>'
            '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint></robot>')
    engine = PyBulletEngine(spec, ServoModel.of(spec), 0.001)
    other = load_robot(engine.client, bare, engine.pb.URDF_USE_INERTIA_FROM_FILE)
    assert engine.client.getDynamicsInfo(other, 0)[0] == pytest.approx(1.0)     # PyBullet's default
    masses = engine.masses()                                                   # ours: every link as specified
    engine.close()
    webots = {i.link: i.mass for i in spec.inertials}
    for link, mass in masses.items():
        assert mass == pytest.approx(webots.get(link, FRAME_LINK_MASS_KG))


@pytest.mark.physics
def test_trap_loadurdf_needs_a_file_and_the_temp_file_is_removed(spec, tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))      # a private temp folder: other tests make URDFs too
    PyBulletEngine(spec, ServoModel.of(spec), 0.001).close()
    assert [f for f in os.listdir(tmp_path) if f.endswith(".urdf")] == []


@pytest.mark.physics
@pytest.mark.parametrize("engine_name", ENGINES)
def test_trap_the_torso_frame_is_not_its_centre_of_mass(spec, engine_name):
    """PyBullet reports the base's centre of mass; both engines must put and report the torso link frame."""
    engine = make_engine(engine_name, spec, ServoModel.of(spec))
    body = Body(spec)
    servo = servo_pose(spec)
    placed = placement(body, servo, "double")
    pos, rot = placed.pos, placed.rot
    engine.reset(pos, rot, servo)
    got_pos, got_rot = engine.base()
    engine.close()
    assert got_pos == pytest.approx(pos, abs=1e-6) and got_rot == pytest.approx(rot, abs=1e-6)


def test_pybullet_banner_is_silenced(capfd):
    with quiet_c_output():
        os.write(1, b"noise")
        os.write(2, b"noise")
    out, err = capfd.readouterr()
    assert "noise" not in out and "noise" not in err


@pytest.mark.physics
def test_servo_sag_matches_the_stiffness(spec):
    """Standing double support: every loaded joint sags by about its static torque / Kp."""
    pose = read_pose(pose_path("walkready"), spec)
    v = _run(pose.servo, pose.support, spec, 3.0, "mujoco")
    from op2motion.model.dynamics import dynamics_for

    static = dynamics_for(spec).static_torques(pose.servo, "double").torques
    knee = spec.joint_names.index("l_knee")
    assert abs(v.sag_deg["l_knee"]) == pytest.approx(math.degrees(abs(static[knee]) / KP_P32_NM_RAD), rel=0.35)
