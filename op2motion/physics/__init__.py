"""Physics checks of poses: one verdict, two engines (PyBullet, the default, and MuJoCo), one servo model.

:func:`validate` places a pose on the floor at rest where its servos hold it against gravity (statically sagged,
:mod:`op2motion.model.equilibrium`; else at its goals with gravity ramped in), holds the pose with the MX-28 model
(:mod:`op2motion.model.servo`) at 1 kHz and judges it with named reasons (:mod:`.verdict`); ``push_n`` adds separate
runs with a push in four directions after settling; ``engine="both"`` runs PyBullet and MuJoCo and compares them.
:func:`validate_motion` does the same for a motion: the goals played every 8 ms with the P gains they were sent
with, judged against the plan, with the tracking error per joint.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.model.servo import ServoModel
from op2motion.physics.run import RAMP_S, STEADY_S, Push, judge, simulate
from op2motion.physics.scene import ENGINES, TIME_STEP_S
from op2motion.physics.schedule import Schedule
from op2motion.physics.verdict import PUSH_DIRECTIONS, REASONS, PushResult, Validation
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

__all__ = ["DEFAULT_SECONDS", "ENGINES", "MAX_SECONDS", "MIN_SECONDS", "MOTION_HOLD_S", "MOTION_SETTLE_S", "RAMP_S",
           "REASONS", "TIME_STEP_S", "Validation", "make_engine", "steps_for", "validate", "validate_motion"]

MIN_SECONDS, MAX_SECONDS = RAMP_S + STEADY_S + 0.5, 60.0
DEFAULT_SECONDS = 5.0
PUSH_DURATION_S = 0.1
PUSH_SETTLE_S = 1.0            # a push starts this long after gravity reached full strength
MAX_PUSH_N = 100.0
MOTION_SETTLE_S = 0.5          # a motion starts this long after gravity reached full strength
MOTION_HOLD_S = 1.5            # ... and its last goal is held this long (the last second is the steady window)
MAX_MOTION_S = 120.0


def steps_for(seconds: float) -> int:
    """Simulation steps in ``seconds`` (see :data:`MIN_SECONDS`, :data:`MAX_SECONDS`)."""
    if not (math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
        raise InputError(f"expected {MIN_SECONDS:g} to {MAX_SECONDS:g} s, got {seconds!r}", "seconds")
    return int(round(seconds / TIME_STEP_S))


def make_engine(name: str, spec: Spec, servo: ServoModel) -> Any:
    """A fresh world of engine ``name`` (``pybullet`` or ``mujoco``) with the robot and the floor."""
    if name == "pybullet":
        from op2motion.physics.pybullet_engine import PyBulletEngine

        return PyBulletEngine(spec, servo, TIME_STEP_S)
    if name == "mujoco":
        from op2motion.physics.mujoco_engine import MuJoCoEngine

        return MuJoCoEngine(spec, servo, TIME_STEP_S)
    raise InputError(f"expected one of {', '.join(ENGINES)}, got {name!r}", "engine")


def judged_run(engine_name: str, schedule: Schedule, spec: Spec, model: ServoModel, seconds: float,
               push: Push | None, on_step: Callable[[], Any] | None = None, start_offset: np.ndarray | None = None,
               finish: Callable[[Validation, Any], Validation] | None = None) -> tuple[Validation, Any, dict[str, Any]]:
    """One run in a fresh world of ``engine_name``: the verdict (passed through ``finish`` with the live engine
    when given), the recorded samples and the start facts (:func:`.run.simulate`)."""
    engine = make_engine(engine_name, spec, model)
    try:
        track, facts = simulate(engine, spec, model, schedule, seconds, push, on_step, start_offset)
        verdict = judge(track, facts, spec, model, schedule, engine_name, engine.time_step, seconds)
        return (verdict if finish is None else finish(verdict, engine)), track, facts
    finally:
        engine.close()


def _run(engine_name: str, schedule: Schedule, spec: Spec, model: ServoModel, seconds: float,
         push: Push | None, snapshot: bool, on_step: Callable[[], Any] | None) -> Validation:
    finish = (lambda verdict, engine: _with_snapshot(verdict, engine, spec, model)) if snapshot else None
    return judged_run(engine_name, schedule, spec, model, seconds, push, on_step, finish=finish)[0]


def _with_snapshot(verdict: Validation, engine: Any, spec: Spec, model: ServoModel) -> Validation:
    """The verdict with a TinyRenderer picture of the final state (PyBullet renders for both engines)."""
    from dataclasses import replace

    from op2motion.physics.pybullet_engine import PyBulletEngine

    if isinstance(engine, PyBulletEngine):
        return replace(verdict, snapshot_png=engine.snapshot())
    q, _ = engine.state()
    pos, rot = engine.base()
    painter = PyBulletEngine(spec, model, TIME_STEP_S)
    try:
        painter.reset(pos, rot, q)
        return replace(verdict, snapshot_png=painter.snapshot())
    finally:
        painter.close()


def validate(servo_angles: np.ndarray, support: str, spec: Spec, seconds: float = DEFAULT_SECONDS,
             engine: str = "pybullet", push_n: float = 0.0, stiffness: float = 1.0,
             p_gains: np.ndarray | None = None, snapshot: bool = False,
             on_step: Callable[[], Any] | None = None, voltage: float | None = None) -> Validation:
    """Does a pose (servo angles (20,) [rad], support left/right/double) stand on ``engine``? See the package
    docstring; ``stiffness`` scales the servos' Kp, ``p_gains`` sets each servo's P gain (default 32),
    ``voltage`` [V] picks the servo's rating (default: the spec's supply voltage)."""
    Support.of(support)
    servo_angles = np.asarray(servo_angles, dtype=float)
    if servo_angles.shape != (len(spec.joints),) or not np.all(np.isfinite(servo_angles)):
        raise InputError(f"expected {len(spec.joints)} finite servo angles", "servo angles")
    steps_for(seconds)
    _check_push(push_n)
    model = ServoModel.of(spec, p_gains, stiffness, voltage)
    schedule = Schedule.hold(servo_angles, support, model)
    verdict = _run(engine, schedule, spec, model, seconds, None, snapshot, on_step)
    return _pushed(verdict, engine, schedule, spec, model, seconds, push_n, RAMP_S + PUSH_SETTLE_S)


def _check_push(push_n: float) -> None:
    if not (math.isfinite(push_n) and 0.0 <= push_n <= MAX_PUSH_N):
        raise InputError(f"expected a force from 0 to {MAX_PUSH_N:g} N, got {push_n!r}", "push")


def _pushed(verdict: Validation, engine: str, schedule: Schedule, spec: Spec, model: ServoModel, seconds: float,
            push_n: float, start: float) -> Validation:
    """The verdict with a push of ``push_n`` newtons at ``start`` [s] in each of four directions (separate runs)."""
    if push_n <= 0.0:
        return verdict
    results = []
    for direction, (dx, dy) in PUSH_DIRECTIONS.items():
        push = Push(np.array([dx * push_n, dy * push_n, 0.0]), start, PUSH_DURATION_S)
        pushed = _run(engine, schedule, spec, model, seconds, push, False, None)
        results.append(PushResult(direction, push_n, start, PUSH_DURATION_S, pushed.stable, pushed.reasons))
    from dataclasses import replace

    return replace(verdict, pushes=results)


def validate_motion(goals: np.ndarray, p_gains: np.ndarray, supports: tuple[str, ...], spec: Spec,
                    dt: float = 0.008, engine: str = "pybullet", push_n: float = 0.0, push_at_s: float | None = None,
                    stiffness: float = 1.0, voltage: float | None = None,
                    on_step: Callable[[], Any] | None = None) -> Validation:
    """Does the robot get through a motion? ``goals`` (K, 20) [rad] are sent every ``dt`` [s] with the servos' P
    gains (K, 20) and stand on ``supports`` (K,). The first goal settles as gravity ramps in (:data:`RAMP_S` +
    :data:`MOTION_SETTLE_S`), the motion plays, the last goal is held :data:`MOTION_HOLD_S`. ``push_n`` pushes the
    torso during the motion, ``push_at_s`` [s] into it (default: halfway), in four directions (separate runs)."""
    model = ServoModel.of(spec, None, stiffness, voltage)
    start = RAMP_S + MOTION_SETTLE_S
    schedule = Schedule.motion(goals, p_gains, tuple(supports), dt, start, model, spec)
    seconds = schedule.end_s + MOTION_HOLD_S
    if not (math.isfinite(dt) and 0 < dt <= 1.0) or schedule.end_s - start > MAX_MOTION_S:
        raise InputError(f"expected goals at most {MAX_MOTION_S:g} s long, one every 0 to 1 s, got "
                         f"{len(goals)} goals every {dt!r} s", "motion")
    _check_push(push_n)
    verdict = _run(engine, schedule, spec, model, seconds, None, False, on_step)
    at = start + (0.5 * (schedule.end_s - start) if push_at_s is None else push_at_s)
    return _pushed(verdict, engine, schedule, spec, model, seconds, push_n, at)

