"""What a run should do, for the judge: the planned goals, supports and torso, and where the robot starts.

A :class:`Plan` holds rows of planned joint goals [rad] with the servos' P gains and the support each row stands
on. Before ``start_s`` row 0 holds (the pose settles as gravity ramps in), row k from ``start_s + k dt`` on, and
the last row after the motion until ``duration_s``. Three kinds:

* ``pose``: one row held (:meth:`Plan.hold`);
* ``motion``: goals every 8 ms after :data:`RAMP_S` + :data:`MOTION_SETTLE_S` of settling, the last held
  :data:`MOTION_HOLD_S` (:meth:`Plan.motion`);
* ``walk``: a motion whose torso poses are planned too (no foot stays where it started), with a walking clock for
  the walk's measurements (:class:`WalkClock`; built by :mod:`op2motion.gait`).

A plan may carry its own measurements as a hook (:attr:`Plan.measure`): the physics check calls it after every run
and keeps what it returns in the run report's ``walk`` slot. Physics knows no walk: the gait's plans bring
:func:`op2motion.gait.measures.walk_measures`.

:func:`planned_states` says where every row puts the robot with rigid servos: the torso attitude, the centre of mass
and the feet, placed with the fixed foot level on the floor where it started (or at the planned torso poses); the
judge measures tilt and sinking against it, so a planned turn or crouch is not a fall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.physics.body import Body, BodyState, placement, sole_flat
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.support import Side, Support, SupportName, fixed_foot

if TYPE_CHECKING:
    from op2motion.physics.track import Track
    from op2motion.robot.spec import Spec

RAMP_S = 1.0                   # gravity ramps in over this long when a run cannot start sagged; the loading window
STEADY_S = 1.0                 # the last second of a run: the steady window for torques, sag and centre of pressure
MIN_SECONDS, MAX_SECONDS = RAMP_S + STEADY_S + 0.5, 60.0
DEFAULT_SECONDS = 5.0
MOTION_SETTLE_S = 0.5          # a motion starts this long after gravity reached full strength
MOTION_HOLD_S = 1.5            # ... and its last goal is held this long (the last second is the steady window)
MAX_MOTION_S = 120.0
PUSH_SETTLE_S = 1.0            # a held pose is pushed this long after gravity reached full strength
KINDS = ("pose", "motion", "walk")


@dataclass(frozen=True)
class WalkClock:
    """A walk's clock [s]: when the first step's goals start, how long the stepping lasts, and the steady window
    (from the second step's touchdown to the last advancing step's), the last two from the walk's start."""

    start_s: float
    walking_s: float
    steady_from_s: float
    steady_to_s: float


@dataclass(frozen=True)
class Plan:
    """Planned goals (K, 20) [rad] with P gains (K, 20) and supports (K,), one row per ``dt`` [s] from ``start_s``
    [s], for ``duration_s`` [s]; optionally the planned torso poses ((K, 3) [m], (K, 3, 3)), the planned contact of
    each row (walks: the sole(s) meant to be on the floor) and a walk's clock.

    ``measure``: the plan's own measurements of a run of it, a wing's hook (a walk's:
    :func:`op2motion.gait.measures.walk_measures`): called as ``measure(track, start, plan, spec)`` after each run
    (:class:`.track.Track`, :class:`.loop.StartFacts`, this plan, the :class:`~op2motion.robot.spec.Spec`), what it
    returns is stored in the run report's ``walk`` slot (:attr:`.report.RunReport.walk`); None: nothing more is
    measured. Left out of the plan's equality and repr."""

    kind: str
    goals: np.ndarray
    p_gains: np.ndarray
    supports: tuple[Support, ...]
    dt: float
    start_s: float
    duration_s: float
    base: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    contact: tuple[Support, ...] | None = None
    walk: WalkClock | None = None
    # the start is a .loop.StartFacts, not named here: the loop imports this module
    measure: Callable[[Track, Any, Plan, Spec], Any] | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        goals, gains = np.asarray(self.goals, dtype=float), np.asarray(self.p_gains, dtype=float)
        if self.kind not in KINDS:
            raise InputError(f"expected one of {', '.join(KINDS)}, got {self.kind!r}", "kind")
        if goals.ndim != 2 or gains.shape != goals.shape or len(self.supports) != len(goals) or not len(goals):
            raise InputError(f"expected goals, P gains and supports of one length, got {goals.shape}, {gains.shape} "
                             f"and {len(self.supports)}", self.kind)
        if not np.all(np.isfinite(goals)) or np.any(gains < 0) or np.any(gains > 1024):
            raise InputError("expected finite goals and P gains 0..1024", self.kind)
        object.__setattr__(self, "goals", goals)
        object.__setattr__(self, "p_gains", gains)
        object.__setattr__(self, "supports", tuple(Support.of(s) for s in self.supports))
        if self.contact is not None:
            if len(self.contact) != len(goals):
                raise InputError(f"expected one planned contact per row ({len(goals)}), got {len(self.contact)}",
                                 self.kind)
            object.__setattr__(self, "contact", tuple(Support.of(s) for s in self.contact))

    @classmethod
    def hold(cls, servo: np.ndarray, support: Support | SupportName, seconds: float, p_gains: np.ndarray) -> "Plan":
        """One pose (servo angles (20,) [rad]) held for ``seconds`` (:data:`MIN_SECONDS` to :data:`MAX_SECONDS`)
        with servo P gains (20,)."""
        if not (isinstance(seconds, (int, float)) and math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
            raise InputError(f"expected {MIN_SECONDS:g} to {MAX_SECONDS:g} s, got {seconds!r}", "seconds")
        servo = np.asarray(servo, dtype=float)
        if servo.ndim != 1 or not np.all(np.isfinite(servo)):
            raise InputError(f"expected one row of finite servo angles, got shape {servo.shape}", "servo angles")
        return cls("pose", servo[None], np.asarray(p_gains, dtype=float)[None], (Support.of(support),), 1.0, 0.0,
                   float(seconds))

    @classmethod
    def motion(cls, goals: np.ndarray, p_gains: np.ndarray, supports: tuple[Support | SupportName, ...],
               dt: float = CONTROL_PERIOD_S) -> "Plan":
        """Goals (K, 20) [rad] sent every ``dt`` [s] with P gains (K, 20), each row on its support, after
        settling; the last goal held :data:`MOTION_HOLD_S`."""
        goals = np.asarray(goals, dtype=float)
        if not (math.isfinite(dt) and 0 < dt <= 1.0) or (len(goals) - 1) * dt > MAX_MOTION_S:
            raise InputError(f"expected goals at most {MAX_MOTION_S:g} s long, one every 0 to 1 s, got "
                             f"{len(goals)} goals every {dt!r} s", "motion")
        start = RAMP_S + MOTION_SETTLE_S
        end = start + (len(goals) - 1) * dt
        return cls("motion", goals, p_gains, tuple(Support.of(s) for s in supports), float(dt), start,
                   end + MOTION_HOLD_S)

    @property
    def is_motion(self) -> bool:
        """More than one row."""
        return len(self.goals) > 1

    @property
    def end_s(self) -> float:
        """When the last row is first sent [s]."""
        return self.start_s + (len(self.goals) - 1) * self.dt

    @property
    def tick_phase_s(self) -> float:
        """Where the control ticks fall in each period [s]: the plan's rows change on a tick."""
        return self.start_s % CONTROL_PERIOD_S

    @property
    def contacts(self) -> tuple[Support, ...]:
        """The planned contact of each row (the supports where none was planned apart)."""
        return self.contact if self.contact is not None else self.supports

    def row(self, t: float) -> int:
        """The row the servos hold at time ``t`` [s]."""
        if t < self.start_s:
            return 0
        return min(int((t - self.start_s) / self.dt + 1e-9), len(self.goals) - 1)

    def default_push_s(self) -> float:
        """When a push comes by default [s]: a held pose :data:`PUSH_SETTLE_S` after loading, a motion or a walk
        halfway through."""
        if not self.is_motion:
            return RAMP_S + PUSH_SETTLE_S
        start = self.walk.start_s if self.walk is not None else self.start_s
        return start + 0.5 * (self.end_s - start)


@dataclass(frozen=True)
class PlannedStates:
    """Where each row of a plan puts the robot with rigid servos: torso rotation (K, 3, 3) and body state (K,);
    the start's flat foot and settling gap [m] (see :func:`.body.placement`)."""

    rot: np.ndarray
    states: tuple[BodyState, ...]
    flat_foot: Side
    gap: float
    start_pos: np.ndarray
    start_rot: np.ndarray


def planned_states(body: Body, plan: Plan) -> PlannedStates:
    """The start placement and every row's planned state. The start follows :func:`.body.placement` (nothing
    below the floor, the lower more level sole flat); a motion's rows keep its fixed foot where it started; a plan
    with torso poses (a walk) starts at, and plans, those."""
    if plan.base is not None:
        positions, rotations = plan.base
        along = tuple(body.state(p, r, g) for p, r, g in zip(positions, rotations, plan.goals))
        gap = max(0.0, max(float(along[0].corners[s][:, 2].min()) for s in plan.supports[0].feet))
        return PlannedStates(rotations, along, "left", gap, positions[0], rotations[0])
    placed = placement(body, plan.goals[0], plan.supports[0])
    pos0, rot0, flat, gap = placed.pos, placed.rot, placed.flat, placed.gap
    if not plan.is_motion:
        return PlannedStates(rot0[None], (body.state(pos0, rot0, plan.goals[0]),), flat, gap, pos0, rot0)
    side = fixed_foot(plan.supports) if len(set(plan.supports)) > 1 else flat
    start = body.state(pos0, rot0, plan.goals[0]).soles[side]
    rots: list[np.ndarray] = []
    states: list[BodyState] = []
    for goal in plan.goals:
        pos, rot = sole_flat(body, goal, side)
        sole_pos, sole_rot = body.state(pos, rot, goal).soles[side]
        turn = start[1] @ sole_rot.T          # the fixed sole where it started: rotate and move the body onto it
        rot = turn @ rot
        pos = turn @ (pos - sole_pos) + start[0]
        rots.append(rot)
        states.append(body.state(pos, rot, goal))
    return PlannedStates(np.array(rots), tuple(states), flat, gap, pos0, rot0)
