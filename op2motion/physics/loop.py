"""The physics loop, engine-independent: place the robot, ramp gravity in if needed, call the controller every
8 ms with simulated sensors, drive the servo model every millisecond, record.

1. The first planned pose is placed on the floor (:func:`.body.placement`), at rest, with its joints where the
   servos' springs hold it still against gravity (:func:`op2motion.model.equilibrium.sagged_angles`) and gravity at
   full strength, so the start is neither an impact nor a transient. A plan with torso poses (a walk), a pose for
   which no such equilibrium exists, and one whose sag would press a foot meant to swing into the floor (it was
   not standing on one leg) start at their goals instead while gravity rises from zero over :data:`.plan.RAMP_S`.
   A run set up to start lying (:attr:`RunSetup.lying`: face down, face up or on a side) lays the plan's first goals
   on the floor that way (:func:`.body.lying_placement`), at rest, gravity at full strength.
2. Every :data:`~op2motion.robot.framework.CONTROL_PERIOD_S` the controller gets the time, the torso's gyro and
   accelerometer (torso frame; the acceleration is the torso origin's velocity change over the last period) and the
   joint angles (:mod:`.controller`), and returns the goals the servos hold until the next call. The first call
   (``start``) comes at time 0; the ticks fall where the plan's rows change (:attr:`.plan.Plan.tick_phase_s`). The
   goals, P gains and torque limits are taken as on the robot (:class:`.controller.GoalMerger`, the controller's
   hooks read after every call).
3. Every physics step (1 kHz) the servo model turns goals and joint angles into motor torques; a push, if any,
   acts on the torso's centre of mass; every :data:`.track.SAMPLE_S` the state is recorded (:class:`.track.Track`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from op2motion.model.equilibrium import sagged_angles
from op2motion.model.servo import ServoModel
from op2motion.physics.body import Body, BodyState, lying_placement, margin_to, placement
from op2motion.physics.controller import Controller, GoalMerger, Goals
from op2motion.physics.engine import Engine
from op2motion.physics.plan import RAMP_S, Plan, PlannedStates, planned_states
from op2motion.physics.sensors import Imu, Reading, Sensors
from op2motion.physics.stopping import FULL, EarlyStop
from op2motion.physics.track import SAMPLE_S, Recorder, Track, foot_loads
from op2motion.robot.framework import CONTROL_PERIOD_S

SAGGED_GAP_TOL_M = 1e-6    # the sagged start may leave a supporting foot this much higher than the rigid one


@dataclass(frozen=True)
class Push:
    """A force (3,) [N] (world frame) at the torso's centre of mass from ``start_s`` for ``duration_s`` [s]."""

    force: np.ndarray
    start_s: float
    duration_s: float


@dataclass(frozen=True)
class RunSetup:
    """What differs between the runs of one check: a push, joint offsets (20,) [rad] at the start (a perturbed
    start: the joints start that far from where the plan puts them), the sensors' latency and noise,
    ``full_length``: run the plan's whole duration even when the verdict is known earlier, and ``lying``: start
    lying on the floor (:data:`.body.LYING`: ``front``, ``back``, ``left``, ``right``; None: on the feet)."""

    push: Push | None = None
    start_offset: np.ndarray | None = None
    sensors: Sensors = Sensors()
    full_length: bool = False
    lying: str | None = None


@dataclass(frozen=True)
class StartFacts:
    """Where a run started: the body state, the planned states (with the start's flat foot and gap), whether
    gravity was ramped in, and why the run ended (:mod:`.stopping`: ``full``, ``settled`` or ``fell``)."""

    state: BodyState
    planned: PlannedStates
    ramped: bool
    ended: str = FULL


@dataclass(frozen=True)
class StartPose:
    """Where a run starts: joint angles ``q`` (20,) [rad], the torso's position ``pos`` [m] and rotation ``rot``
    (world frame), the planned states (with the start's flat foot and gap), and whether gravity must be ramped in."""

    q: np.ndarray
    pos: np.ndarray
    rot: np.ndarray
    planned: PlannedStates
    ramp: bool


def start_pose(body: Body, controller: Controller[Plan], servo: ServoModel, lying: str | None = None) -> StartPose:
    """Where a run starts (see the module docstring)."""
    plan = controller.plan
    planned = planned_states(body, plan)
    if lying is not None:
        pos, rot = lying_placement(body, plan.goals[0], lying)
        return StartPose(plan.goals[0], pos, rot, planned, False)
    if plan.base is None:
        q0 = sagged_angles(plan.goals[0], plan.supports[0], body.spec, servo.kp_of(plan.p_gains[0]),
                           servo.torque_max)
        if q0 is not None:
            placed = placement(body, q0, plan.supports[0])
            if placed.gap <= planned.gap + SAGGED_GAP_TOL_M:
                return StartPose(q0, placed.pos, placed.rot, replace(planned, flat_foot=placed.flat, gap=placed.gap),
                                 False)
    return StartPose(plan.goals[0], planned.start_pos, planned.start_rot, planned, True)


class _Servos:
    """The goals and stiffness the servos hold, updated from the controller every control tick."""

    def __init__(self, controller: Controller[Plan], body: Body, servo: ServoModel):
        self.controller, self.servo = controller, servo
        self.names = body.spec.joint_names
        self.merger = GoalMerger(controller, self.names)
        self.goals = controller.plan.goals[0].copy()
        self.kp = servo.kp_of(controller.plan.p_gains[0])
        self.limit: np.ndarray | None = None          # per joint [N·m], when the controller lowers its servos' limit
        self.foot_links = body.foot_links

    def _apply(self, goals: Goals, row: int) -> None:
        self.merger.merge(self.goals, goals)
        self.kp = self.servo.kp_of(self.merger.p_gains(row))
        shares = self.merger.torque_shares()
        self.limit = None if shares is None else self.servo.torque_max * shares

    def start(self, q: np.ndarray) -> None:
        """Ask the controller for its first goals."""
        self._apply(self.controller.start(dict(zip(self.names, q.tolist()))), 0)

    def tick(self, engine: Engine, t: float, reading: Reading) -> None:
        """One control tick: the sensors to the controller, its goals to the servos."""
        gyro, accel, q = reading
        positions = dict(zip(self.names, q.tolist()))
        if self.merger.hooks.takes_foot_forces:
            ground = [c for c in engine.contacts() if c.other is None and c.normal_force > 0.0]
            loads = {side: load for side, (load, _) in foot_loads(ground, self.foot_links).items()}
            goals = self.controller.step(t, gyro, accel, positions, foot_forces_n=loads)  # type: ignore[call-arg]
        else:
            goals = self.controller.step(t, gyro, accel, positions)
        self._apply(goals, self.controller.plan.row(t))


def simulate(engine: Engine, body: Body, controller: Controller[Plan], servo: ServoModel, setup: RunSetup = RunSetup(),
             on_tick: Callable[[float], object] | None = None) -> tuple[Track, StartFacts]:
    """One run of ``controller`` for its plan's duration, or until its verdict is known (:mod:`.stopping`; not
    with ``setup.full_length``); ``on_tick`` gets the simulated time [s] after every control period. Returns the
    samples and where the run started (with why it ended)."""
    plan = controller.plan
    begin = start_pose(body, controller, servo, setup.lying)
    q0, base_pos, base_rot, planned, ramp = begin.q, begin.pos, begin.rot, begin.planned, begin.ramp
    engine.reset(base_pos, base_rot, q0 + (0.0 if setup.start_offset is None else setup.start_offset))
    dt = engine.time_step
    per_tick, every = max(1, int(round(CONTROL_PERIOD_S / dt))), max(1, int(round(SAMPLE_S / dt)))
    phase = int(round(plan.tick_phase_s / dt))
    steps = int(round(plan.duration_s / dt))
    push = setup.push
    force = None if push is None else push.force
    pushing = range(0) if push is None else range(int(round(push.start_s / dt)),
                                                   int(round((push.start_s + push.duration_s) / dt)))
    stop = EarlyStop(plan, ramp, 0.0 if push is None else push.start_s + push.duration_s, not setup.full_length)
    servos, imu, recorder = _Servos(controller, body, servo), Imu(setup.sensors), Recorder(body, servo)
    gravity = 1.0
    for k in range(steps):
        t = k * dt
        if t <= RAMP_S + dt:
            gravity = min(1.0, t / RAMP_S) if ramp else 1.0
            engine.set_gravity(gravity)
        q, dq = engine.state()
        if k == 0:
            servos.start(imu.read(engine, q, gravity)[2])
        elif (k - phase) % per_tick == 0 and not controller.done:
            servos.tick(engine, t, imu.read(engine, q, gravity))
        engine.step(servo.active_torque(servos.goals, q, servos.kp, servos.limit), force if k in pushing else None)
        last = k == steps - 1
        if (k - phase) % per_tick == per_tick - 1:
            if on_tick is not None:
                on_tick((k + 1) * dt)
            if (k + 1) * dt >= stop.events_s:                   # still after everything the plan does?
                last = last or stop.tick((k + 1) * dt, dq, *engine.base_velocity()[::-1])
        if k % every == every - 1 or last:
            row = plan.row(t)
            recorder.sample(engine, (k + 1) * dt, row, servos.goals, servos.kp, servos.limit)
            state = recorder.lists["states"][-1]
            last = stop.sample((k + 1) * dt, float(state.com[2]), float(planned.states[row].com[2]),
                               functools.partial(margin_to, state, plan.supports[row], state.com[:2])) or last
        if last:
            break
    return recorder.track(), StartFacts(body.state(base_pos, base_rot, q0), planned, ramp, stop.ended)
