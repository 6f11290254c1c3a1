"""A walk you steer while it walks: :class:`SteerableWalk` (``SteerableWalk.make()``).

It is the walk controller (:mod:`.controller`: gyro damping, attitude, heading and line, leg odometry, sag trims, the
servos' stiffness measured while standing, the swing leg's learnt feed-forward) on rows that the rolling planner
(:mod:`.rolling`) writes a phase at a time, from the command of the moment:

* :meth:`SteerableWalk.command` (vx [m/s], vy [m/s], yaw rate [rad/s]) at any tick: kept within the measured
  envelope (:mod:`.envelope`), it takes effect from the next step (one that begins at least
  :data:`~.rolling.PLAN_AHEAD_ROWS` ticks later), the stride changing within the acceleration limits. While the command
  is zero the robot stands (balancing, not stepping); a zero command while walking slows down and closes the feet;
* :meth:`SteerableWalk.stop`: ends within two steps, on both feet; :attr:`done` once the walk has stopped and the body
  has kept still (:mod:`op2motion.motion.stillness`). A command after a stop walks again;
* :meth:`SteerableWalk.kick` (``right`` or ``left``): stop, kick with that foot, walk on (:mod:`.kick`);
* :meth:`SteerableWalk.resume` after the robot was put back on its feet (a fall, :mod:`op2motion.motion.fall`): a fresh
  walk from standing that keeps the command and the clock.

Time: like every controller, ``step`` gets the time since ``start``; the first :data:`LEAD_S` are the lead-in (the
goals ramp from the standing pose to its feed-forward, as a planned walk's do while gravity ramps in physics), then
row 0 of the walk, one row every 8 ms. A :class:`.commands.CommandTimeline` given to :meth:`make` feeds the walk by
itself (its times on the same clock) and makes :attr:`plan`: the whole walk planned ahead of the physics run (a dry
run of the same planner with the same commands, so the judge knows what the walk meant to do).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.formats.action import ActionFile
from op2motion.gait.commands import CommandTimeline
from op2motion.gait.envelope import STEER_ENVELOPE, Envelope
from op2motion.gait.feedback import Feedback
from op2motion.gait.measures import WALK_HOLD_S, WALK_SETTLE_S, walk_measures
from op2motion.gait.params import GaitParams
from op2motion.gait.phases import Intent
from op2motion.gait.presets import load_preset
from op2motion.gait.rolling import RollingPlanner
from op2motion.gait.stabilised import LANDING_ROWS, StabilisedWalk
from op2motion.gait.steer_feedback import RollingCalibration, RollingLearner, RollingOdometry
from op2motion.gait.timeline import ticks
from op2motion.kinematics import small
from op2motion.physics import RAMP_S, Plan, WalkClock
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

LEAD_S = RAMP_S + WALK_SETTLE_S     # before the walk's first row [s] (the physics check ramps gravity in meanwhile)
STEER_PRESET = "steer"              # the preset a steered walk takes by default
STAND_PLAN_S = 5.0                  # the plan of a walk given no commands: standing this long [s]
SETTLE_AFTER_STOP_S = 0.5           # a planned walk ends this long after it stands again after its stop [s]


class SteerableWalk(StabilisedWalk):
    """A walk planned while it walks, from commands (see the module docstring); it stops itself and resumes (the
    hooks of :class:`~op2motion.physics.controller.ControllerHooks`)."""

    stops_itself = True

    def __init__(self, params: GaitParams, spec: Spec, feedback: Feedback = Feedback(),
                 envelope: Envelope = STEER_ENVELOPE, commands: CommandTimeline | None = None,
                 action: ActionFile | None = None):
        self.params, self.spec, self.feedback, self.envelope, self.commands = params, spec, feedback, envelope, commands
        self.action = action
        self._setup_legs(spec, feedback)
        self.lead = int(round(LEAD_S / CONTROL_PERIOD_S))
        self._plan: Plan | None = None
        self.dry: SteerableWalk | None = None
        self.dry_rows = 0
        self._command = (0.0, 0.0, 0.0)
        self._stopping = False
        self._fed: float | None = None
        self._clock_s = 0.0
        self._fresh()

    @classmethod
    def make(cls, spec: Spec | None = None, preset: str | None = None, feedback: Feedback = Feedback(),
             commands: CommandTimeline | None = None, action: ActionFile | None = None) -> "SteerableWalk":
        """The steered walk of a preset (default :data:`STEER_PRESET`) on ``spec`` (default: the shipped one); its
        kicks are the stock pages 12/13 of ``action`` when it has them, op2motion's own otherwise."""
        from op2motion.robot.specfile import default_spec

        return cls(load_preset(preset or STEER_PRESET), spec or default_spec(), feedback, commands=commands,
                   action=action)

    def _fresh(self) -> None:
        """A new walk from standing: the planner, the feedback's memories, row 0 planned."""
        f = self.feedback
        self.planner = RollingPlanner(self.params, self.spec, self.envelope, self.legs, self.action)
        self.rows = self.planner.rows
        per_step = ticks(self.params.single_s) + ticks(self.params.double_s)
        self.learner = RollingLearner.rolling(self.rows, per_step, {s: np.array(leg.index) for s, leg in
                                                                     self.legs.items()}, len(self.spec.joints),
                                              f.learn_gain, f.learn_shift_rows)
        self.calibration = RollingCalibration.rolling(self.rows, self.leg_index, self.planner.state.first_step_row)
        self.odometry = RollingOdometry.rolling(self.rows, self.legs, self.delay_rows + LANDING_ROWS)
        self.planner.tick(0, self._intent)

    # -- what the walk is told ----------------------------------------------------------------------------------

    def command(self, vx_m_s: float, vy_m_s: float, yaw_rate_rad_s: float) -> None:
        """Walk at (vx [m/s] forward, vy [m/s] left, yaw rate [rad/s] left), kept within the envelope; from the next
        step, within the acceleration limits. A command after :meth:`stop` walks again."""
        self._command = self.envelope.clamp(vx_m_s, vy_m_s, yaw_rate_rad_s)
        self._stopping = False

    def stop(self) -> None:
        """End the walk within two steps, on both feet (:attr:`done` once still): a step whose planning had begun is
        planned again with the stop."""
        if not self._stopping:
            self.planner.stop()
        self._stopping = True

    def kick(self, foot: Side) -> None:
        """Stop, kick with the ``right`` or ``left`` foot, walk on with the command in force (:mod:`.kick`)."""
        from op2motion.errors import InputError

        if foot not in ("right", "left"):
            raise InputError(f"expected right or left, got {foot!r}", "foot")
        self.planner.pending_kick = foot
        self.planner.stop()

    @property
    def commanded(self) -> tuple[float, float, float]:
        """The command in force, as clamped (vx [m/s], vy [m/s], yaw rate [rad/s])."""
        return self._command

    @property
    def stopping(self) -> bool:
        """:meth:`stop` was called (and no command since)."""
        return self._stopping

    def _intent(self) -> Intent:
        return Intent(self.envelope.stride(*self._command, self.params.step_s), self._stopping)

    # -- the controller's clock and rows ------------------------------------------------------------------------

    def _row(self, t_s: float) -> int:
        return int(math.floor((t_s - LEAD_S) / CONTROL_PERIOD_S + 1e-9))

    def _planned_goals(self, t_s: float, k: int) -> np.ndarray:
        if k >= 0:
            return self.rows.get("goals", k).copy()
        joints, goals = self.planner.standing_goals, self.rows.get("goals", 0)
        ramped: np.ndarray = joints + min(1.0, max(t_s, 0.0) / RAMP_S) * (goals - joints)
        return ramped

    def _plan_over(self, k: int) -> bool:
        since = self.planner.stand_since
        return self._stopping and since is not None and k >= since

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """A fresh walk from standing; the lead-in's first goals. The command and a stop request are kept, unless a
        timeline drives the walk (it starts over from its beginning)."""
        if self.commands is not None:
            self._command, self._stopping = (0.0, 0.0, 0.0), False
        self._fresh()
        self._fed, self._clock_s = None, 0.0
        return super().start(joint_positions)

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The goals at ``t_s`` [s]: the timeline's entries due fed in, the row planned, the feedback on top."""
        if self.commands is not None:
            self.commands.feed(self, self._fed, self._clock_s + t_s)
            self._fed = self._clock_s + t_s
            if self._fed >= self.commands.duration_s and not self._stopping:
                self.stop()                            # a timeline's walk ends with its last entry
        k = self._row(t_s)
        if k >= 0:
            self.planner.tick(k, self._intent)
        return super().step(t_s, gyro_rad_s, accel_m_s2, joint_positions)

    def resume(self, joint_positions: Mapping[str, float], t_s: float) -> dict[str, float]:
        """Walk again from standing after the robot was put back on its feet at ``t_s`` [s] of an outer clock (a
        supervisor's): a fresh walk with the command in force, whose timeline, if any, goes on from there; the first
        goals."""
        clock, command, stopping = self._clock_s + t_s, self._command, self._stopping
        goals = self.start(joint_positions)
        self._clock_s, self._fed, self._command, self._stopping = clock, clock, command, stopping
        return goals

    def _landed(self, side: Side, k: int) -> tuple[small.Vec3, float] | None:
        """The foot that closed the feet, where it landed; as it swings again, carried to its planned path."""
        held = super()._landed(side, k)
        if held is None:
            return None
        contact = self.rows.obj("contact", k)
        weight = 1.0 - self.rows.value("swing_phase", k) if contact not in ("double", side) else 1.0
        return small.scaled(held[0], weight), held[1] * weight

    # -- the plan a physics check judges against ----------------------------------------------------------------

    @property
    def plan(self) -> Plan:  # type: ignore[override]
        """The whole walk planned ahead (a dry run with the same commands; standing :data:`STAND_PLAN_S` without
        any), for the physics check and its judge."""
        if self._plan is None:
            self._plan = dry_run_plan(self)
        return self._plan


def dry_run_plan(walk: SteerableWalk) -> Plan:
    """Plan ``walk``'s commands ahead, with no sensors (the planner alone), into a physics :class:`Plan`: the
    lead-in, every row until the walk stands still again after its stop, the walking clock. The dry run stays on
    ``walk.dry`` (its rows: ``walk.dry.rows``, ``walk.dry_rows`` of them) for summaries and figures."""
    twin, count = dry_run(walk)
    walk.dry, walk.dry_rows = twin, count
    return plan_of_rows(twin, count)


def dry_run(walk: SteerableWalk) -> tuple[SteerableWalk, int]:
    """A twin of ``walk`` fed its commands row by row with no sensors, until it stands still again after its stop
    (or a minute past the last command); the twin and the rows it planned."""
    twin = SteerableWalk(walk.params, walk.spec, walk.feedback, walk.envelope, walk.commands, walk.action)
    twin.planner.keep_all = True
    timeline = walk.commands
    end_s = timeline.duration_s if timeline is not None else STAND_PLAN_S
    fed: float | None = None
    k = 0
    limit = twin._row(end_s) + int(round(60.0 / CONTROL_PERIOD_S))
    while k < limit:
        t = LEAD_S + k * CONTROL_PERIOD_S
        if timeline is not None:
            timeline.feed(twin, fed, t)
            fed = t
        if t >= end_s and not twin.stopping:
            twin.stop()
        twin.planner.tick(k, twin._intent)
        since = twin.planner.stand_since
        if twin.stopping and since is not None and k >= since + ticks(SETTLE_AFTER_STOP_S):
            break
        k += 1
    return twin, k + 1


def plan_of_rows(twin: SteerableWalk, count: int) -> Plan:
    """A :class:`Plan` of the first ``count`` rows a (dry-run) walk planned, after its lead-in."""
    rows, lead, dt = twin.rows, twin.lead, CONTROL_PERIOD_S
    n = min(count, rows.end)
    numeric = {name: rows.numeric[name][:n] for name in ("joints", "goals", "p_gains", "torso_pos", "torso_rot")}
    joints0, goals0 = twin.planner.standing_goals, numeric["goals"][0]
    ramp = np.minimum(1.0, np.arange(lead) * dt / RAMP_S)[:, None]
    goals = np.vstack([joints0 + ramp * (goals0 - joints0), numeric["goals"]])

    def led(values: np.ndarray) -> np.ndarray:
        return np.concatenate([np.repeat(values[:1], lead, axis=0), values])

    supports = tuple(Support.of(s) for s in rows.objects["support"][:n])
    contact = tuple(Support.of(s) for s in rows.objects["contact"][:n])
    steps = [(first, phase) for first, phase in twin.planner.phases if phase.kind == "step" and first < n]
    walk_from = steps[0][0] if steps else 0
    walk_to = steps[-1][0] + steps[-1][1].rows if steps else 0
    steady = [first + phase.rows for first, phase in steps]
    steady_from = steady[1] if len(steady) > 3 else walk_from
    steady_to = steady[-2] if len(steady) > 3 else walk_to
    clock = WalkClock(lead * dt, (walk_to - walk_from) * dt, steady_from * dt, steady_to * dt)
    return Plan("walk", goals, led(numeric["p_gains"]), (supports[0],) * lead + supports, dt, 0.0,
                (len(goals) - 1) * dt + WALK_HOLD_S, (led(numeric["torso_pos"]), led(numeric["torso_rot"])),
                (contact[0],) * lead + contact, clock, measure=walk_measures)


@dataclass(frozen=True)
class EndPose:
    """Where a walk ends: the torso at ``x_m``, ``y_m`` [m] (world: the start's support-foot frame) turned by
    ``yaw_deg`` [deg]."""

    x_m: float
    y_m: float
    yaw_deg: float


@dataclass(frozen=True)
class PlannedWalk:
    """A steered walk's plan in figures (:func:`planned_summary`): its rows, duration [s], steps and kicks, the
    torso's path length [m] and end pose, the planned ZMP's least margin to the soles [m], when [s] (the
    controller's time) and in which kind of phase."""

    rows: int
    duration_s: float
    steps: int
    kicks: int
    path_m: float
    end_pose: EndPose
    zmp_margin_min_m: float
    zmp_margin_min_at_s: float
    zmp_margin_min_during: str


def planned_summary(walk: SteerableWalk) -> PlannedWalk:
    """The figures of ``walk``'s planned commands (its dry run): steps, kicks, length, the torso's path and end pose,
    the planned ZMP's least margin to the soles on the floor, when (the controller's time [s]) and in which kind of
    phase (a step, a kick, ...)."""
    from op2motion.gait.rows import planned_zmp_margins

    walk.plan                                                     # the dry run, once
    twin, n = walk.dry, walk.dry_rows
    if twin is None:
        raise Op2MotionError("the steered walk's dry run left no plan")
    rows = twin.rows
    kinds = [phase.kind for first, phase in twin.planner.phases if first < n]
    pos = rows.numeric["torso_pos"][:n:25, :2]
    yaw = float(rows.numeric["plan_yaw"][n - 1])
    margin = planned_zmp_margins(rows, walk.spec, n)
    worst = int(np.argmin(margin))
    during = next((phase.kind for first, phase in reversed(twin.planner.phases) if first <= rows.first + worst), "")
    end = EndPose(float(rows.numeric["torso_pos"][n - 1, 0]), float(rows.numeric["torso_pos"][n - 1, 1]),
                  math.degrees(yaw))
    return PlannedWalk(n, walk.plan.duration_s, kinds.count("step"), kinds.count("kick"),
                       float(np.sum(np.hypot(*np.diff(pos, axis=0).T))), end, float(margin.min()),
                       LEAD_S + worst * CONTROL_PERIOD_S, during)



__all__ = ["LEAD_S", "STEER_PRESET", "EndPose", "PlannedWalk", "SteerableWalk", "dry_run", "dry_run_plan",
           "planned_summary"]
