"""One controller contract in both loops: a controller offering no hooks runs in the physics loop and in the robot's
8 ms loop (an emulated OP2 in lockstep) with the plan's P gains and full torque; one offering each hook
(:class:`~op2motion.physics.controller.ControllerHooks`) has it honoured in both, and through the fall supervisor;
the one goal merger both loops use (named goals, the unknown-name error, the P gains over the plan's, the
torque-limit shares)."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from bus_support import lockstep

from op2motion.bus.tables import TORQUE_LIMIT_FULL
from op2motion.errors import InputError
from op2motion.motion import Supervisor
from op2motion.physics import Plan, Setup, check
from op2motion.physics.controller import NO_HOOKS, ControllerHooks, GoalMerger, hooks_of
from op2motion.physics.sweeps import servo_pose
from op2motion.robot.support import Support

PLAN_P = 40.0                  # the plan's P gain (not the MX-28's default 32, so that the plan's is seen)
HOOK_P = 8.0                   # the hook's P gain for JOINT
JOINT = "l_sho_pitch"
SHARE = 0.02                   # the hook's torque-limit share for LIMITED: 0.05 N·m, a third of what holds the arm
                               # level (it sinks, as fast as the servo's damping lets it: 0.2 rad/s)
LIMITED = "r_sho_pitch"
ARM_OUT_RAD = math.pi / 2      # both arms held out level: gravity pulls them from their goals
HOLD_S = 1.0                   # a physics run [s]
ROBOT_S = 0.2                  # a run on the emulated robot [s]
STOP_AT_TICK = 5               # a stop request (Ctrl-C) at this tick
STEPS_AFTER_STOP = 10          # a controller that stops itself is done this many steps after its stop
DROP_FACTOR = 10.0             # on SHARE of its torque the level arm sinks at least this many times further
SOFTER_FACTOR = 2.0            # P 8 instead of 40 lets the level arm sag at least this many times further


class Hold:
    """Holds ``goals`` (20,) [rad] and offers no hooks (duck typed, as a controller of one's own)."""

    def __init__(self, spec, goals: np.ndarray, seconds: float):
        self.names = spec.joint_names
        self.plan = Plan("pose", np.asarray(goals, dtype=float)[None], np.full((1, len(self.names)), PLAN_P),
                         (Support.DOUBLE,), 1.0, 0.0, seconds)
        self.steps, self.stopped_at, self.resumed_at = 0, None, None

    def start(self, joint_positions):
        return dict(zip(self.names, self.plan.goals[0].tolist()))

    def step(self, t_s, gyro_rad_s, accel_m_s2, joint_positions):
        self.steps += 1
        return self.start(joint_positions)

    @property
    def done(self):
        return False


class Hooked(Hold, ControllerHooks):
    """Holds, and offers every hook."""

    handles_falls = True
    stops_itself = True
    p_gains = {JOINT: HOOK_P}
    torque_limits = {LIMITED: SHARE}

    def stop(self):
        self.stopped_at = self.steps

    def resume(self, joint_positions, t_s):
        self.resumed_at = t_s
        return self.start(joint_positions)

    @property
    def done(self):
        return self.stopped_at is not None and self.steps >= self.stopped_at + STEPS_AFTER_STOP


class Feet(Hold, ControllerHooks):
    """Holds, and wants the soles' loads."""

    takes_foot_forces = True


# -- the merger and the hooks' defaults ---------------------------------------------------------------------------


def test_a_controller_offers_no_hooks_unless_it_declares_them(spec):
    plain, hooked = Hold(spec, servo_pose(spec), HOLD_S), Hooked(spec, servo_pose(spec), HOLD_S)
    assert hooks_of(plain) is NO_HOOKS and hooks_of(hooked) is hooked
    assert not (NO_HOOKS.handles_falls or NO_HOOKS.takes_foot_forces or NO_HOOKS.stops_itself)
    assert NO_HOOKS.p_gains is None and NO_HOOKS.torque_limits is None
    assert NO_HOOKS.resume({}, 1.0) is None


def test_the_merger_names_goals_gains_and_shares(spec):
    j, k = spec.joint_names.index(JOINT), spec.joint_names.index(LIMITED)
    held = np.zeros(len(spec.joint_names))
    plain = GoalMerger(Hold(spec, servo_pose(spec), HOLD_S), spec.joint_names)
    plain.merge(held, {JOINT: 0.5})
    assert held[j] == 0.5 and np.count_nonzero(held) == 1                   # a joint left out keeps its goal
    with pytest.raises(InputError, match="official joint name"):
        plain.merge(held, {"left_knee": 0.0})
    assert np.array_equal(plain.p_gains(0), np.full(len(held), PLAN_P)) and plain.torque_shares() is None
    hooked = Hooked(spec, servo_pose(spec), HOLD_S)
    merger = GoalMerger(hooked, spec.joint_names)
    gains, shares = merger.p_gains(0), merger.torque_shares()
    assert gains[j] == HOOK_P and np.all(np.delete(gains, j) == PLAN_P)
    assert shares[k] == SHARE and np.all(np.delete(shares, k) == 1.0)
    hooked.torque_limits = {LIMITED: -1.0, "r_knee": 2.0, "no_such_joint": 0.5}   # clamped to 0..1, unknown ignored
    assert np.array_equal(merger.torque_shares(), np.where(np.arange(len(held)) == k, 0.0, 1.0))


def test_the_supervisor_passes_the_wrapped_controllers_hooks_on(spec):
    hooked = Hooked(spec, servo_pose(spec), HOLD_S)
    supervised, plain = Supervisor(hooked, spec=spec), Supervisor(Hold(spec, servo_pose(spec), HOLD_S), spec=spec)
    assert supervised.handles_falls and plain.handles_falls
    assert supervised.p_gains == hooked.p_gains and supervised.torque_limits == hooked.torque_limits
    assert plain.p_gains is None and plain.torque_limits is None
    assert supervised.stops_itself and not plain.stops_itself
    supervised.stop()
    assert hooked.stopped_at == 0


@pytest.mark.parametrize("offers", [True, False])
def test_the_supervisor_resumes_by_the_hook_or_starts_again(spec, offers):
    """Up again after a fall, the supervisor goes on with the wrapped controller's ``resume`` at its clock when it
    offers one, else with ``start``."""
    inner = (Hooked if offers else Hold)(spec, servo_pose(spec), HOLD_S)
    supervisor = Supervisor(inner, spec=spec)
    supervisor.getup.phase = "standing"                          # as GetUp ends when it stood up
    supervisor.paused_at, supervisor.fell_at = 1.5, 2.0
    q = servo_pose(spec)
    supervisor._got_up(6.0, dict(zip(spec.joint_names, q.tolist())), q)
    assert supervisor.phase == "blend"
    assert inner.resumed_at == (1.5 if offers else None)
    assert (supervisor.paused is not None) is offers


# -- the physics loop ---------------------------------------------------------------------------------------------


def _arms_out(spec) -> np.ndarray:
    q = servo_pose(spec)
    for name in (JOINT, LIMITED):
        q[spec.joint_names.index(name)] = ARM_OUT_RAD
    return q


@pytest.mark.physics
def test_both_controllers_run_in_physics_and_the_hooks_are_honoured(spec):
    """Without hooks the servos hold both level arms on the plan's P gains and all their torque; with them, JOINT's
    servo is softer (its arm sags further) and LIMITED's has SHARE of its torque (too little: its arm drops)."""
    j, k = spec.joint_names.index(JOINT), spec.joint_names.index(LIMITED)
    setup = Setup(keep_track=True, full_length=True)
    plain = check(Hold(spec, _arms_out(spec), HOLD_S), spec, ("mujoco",), setup=setup).run.track
    hooked = check(Hooked(spec, _arms_out(spec), HOLD_S), spec, ("mujoco",), setup=setup).run.track
    (sag_plain, drop_plain), (sag_hooked, drop_hooked) = (np.abs(t.q[-1] - t.goals[-1])[[j, k]]
                                                          for t in (plain, hooked))
    assert sag_hooked > SOFTER_FACTOR * sag_plain, (sag_hooked, sag_plain)
    assert drop_hooked > DROP_FACTOR * drop_plain, (drop_hooked, drop_plain)


# -- the robot's loop ---------------------------------------------------------------------------------------------


def _on_robot(spec, make, stop_at: int | None = None):
    """``make(start (20,) [rad])``'s controller run on an emulated OP2 in lockstep, a stop requested (Ctrl-C) at tick
    ``stop_at``: (controller, report, the servos' P gains, their torque limits, whether the safety watch stops the
    run for a fall)."""
    from op2motion.bus.loop import _Run, run_controller
    from op2motion.bus.session import Session

    stop = threading.Event()

    def on_tick(tick) -> None:
        if tick.index == stop_at:
            stop.set()

    with lockstep(spec) as (emulator, port), Session(port, spec) as session:
        controller = make(np.asarray(session.ready_for_motion().servo_angles))
        report = run_controller(controller, session.robot, stop=stop, on_tick=on_tick)
        gains = [s.get("p_gain") for s in emulator.servos]
        falls = _Run(controller, session.robot, True).watch.falls
        return controller, report, gains, emulator.report()["torque_limit"], falls


@pytest.mark.physics
def test_a_controller_offering_no_hooks_runs_on_the_robot(spec):
    controller, report, gains, limits, falls = _on_robot(spec, lambda q: Hold(spec, q, ROBOT_S))
    assert report.ended == "done" and report.fault is None and controller.steps == report.ticks - 1
    assert gains == [PLAN_P] * len(gains) and limits == [TORQUE_LIMIT_FULL] * len(limits)
    assert falls                                                # the safety watch stops the run on a fall
    controller, stopped, *_ = _on_robot(spec, lambda q: Hold(spec, q, 5.0), STOP_AT_TICK)
    assert stopped.ended == "stopped" and controller.steps == STOP_AT_TICK      # a stop freezes the goals at once


@pytest.mark.physics
def test_a_controller_offering_every_hook_has_them_honoured_on_the_robot(spec):
    j, k = spec.joint_names.index(JOINT), spec.joint_names.index(LIMITED)
    controller, report, gains, limits, falls = _on_robot(spec, lambda q: Hooked(spec, q, 5.0), STOP_AT_TICK)
    assert gains[j] == HOOK_P and set(np.delete(gains, j)) == {PLAN_P}
    assert limits[k] == round(SHARE * TORQUE_LIMIT_FULL) and set(np.delete(limits, k)) == {TORQUE_LIMIT_FULL}
    assert not falls                                            # it deals with falls itself
    assert report.ended == "stopped" and report.fault is None
    assert controller.stopped_at == STOP_AT_TICK                 # told to stop, it ran on until it was done
    assert controller.steps == STOP_AT_TICK + STEPS_AFTER_STOP and report.ticks == controller.steps + 1


@pytest.mark.physics
def test_a_controller_that_needs_the_soles_loads_is_refused_on_the_robot(spec):
    """The OP2 does not measure them: refused before a goal is sent."""
    from op2motion.bus.loop import run_controller
    from op2motion.bus.session import Session

    with lockstep(spec) as (emulator, port), Session(port, spec) as session:
        feet = Feet(spec, np.asarray(session.ready_for_motion().servo_angles), ROBOT_S)
        held = emulator.report()["goal_ticks"]
        with pytest.raises(InputError, match="without foot forces"):
            run_controller(feet, session.robot)
        assert emulator.report()["goal_ticks"] == held
