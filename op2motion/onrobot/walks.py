"""Walking and getting up on the robot, as library functions (``op2motion robot walk|getup``).

* :func:`walk`: a planned walk (a preset's steps, or to a target) through
  :class:`~op2motion.gait.controller.WalkController`;
* :func:`steered_walk`: a walk steered while it walks (:class:`~op2motion.gait.steer.SteerableWalk`), by a command
  timeline (``--commands``), by keys (``--teleop``, :mod:`.teleop`) or both; optionally inside a
  :class:`~op2motion.motion.fall.Supervisor` (``get_up``): a fall lowers the torque limits, the robot lies still,
  gets up and walks on (the bus's watch leaves that fall to it); otherwise a fall stops the walk
  (:mod:`op2motion.bus.safety`);
* :func:`getup`: :class:`~op2motion.motion.getup.GetUp` from where the robot lies, checked first in physics from the
  same side (:data:`~.plans.CHECK_ENGINE`), until it stands.

Each walk starts standing: a planned move from the present pose to the walk's first, checked in physics, then the
walk in the 8 ms loop (:func:`~op2motion.bus.loop.run_controller`). Ctrl-C stops a walk within two steps, on both feet
side by side (a planned one: :mod:`~op2motion.gait.planned_stop`).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from op2motion.bus.loop import START_JUMP_RAD, LoopReport, run_controller
from op2motion.bus.port import RobotPort
from op2motion.bus.session import Session
from op2motion.errors import CheckFailed
from op2motion.onrobot.plans import CHECK_ENGINE, LYING_TILT_RAD, move
from op2motion.onrobot.stand import close_feet
from op2motion.onrobot.tasks import MotionResult, Options, checked, run_planned, take_control
from op2motion.robot.imu import FALL_TILT_RAD
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import CommandTimeline
    from op2motion.onrobot.teleop import Teleop

MAX_TELEOP_S = 3600.0          # a walk steered by keys ends after this long at the latest [s]


def walk(port: RobotPort, spec: Spec, preset: str | None = None, steps: int | None = None,
         target: tuple[float, float, float] | None = None, options: Options = Options()) -> MotionResult:
    """A walk on the robot: the preset's gait planned within the servos' speed (``steps`` steps, or to ``target``
    (x [m], y [m], heading [rad])), a planned move to its first pose, then :class:`~op2motion.gait.controller.
    WalkController` in the loop with the robot's IMU and joints until it stands at the end."""
    from op2motion.gait import preset_path, read_preset
    from op2motion.gait.controller import WalkController
    from op2motion.gait.speeds import gait_within_speed

    params = read_preset(preset_path(preset)).with_steps(steps)
    gait = gait_within_speed(params, spec, target)
    controller = WalkController(gait, spec)
    result = run_on_robot(port, spec, controller, f"walk '{params.name}' ({gait.params.steps} steps)", options,
                          name="walk")
    walked = dict(result.runs).get("walk")
    if walked is not None:
        result.travel = leg_travel(controller, walked.last_row - controller.lead)
        result.travel["gyro_heading_deg"] = math.degrees(walked.yaw_rad)
    return result


def steered_walk(port: RobotPort, spec: Spec, preset: str | None = None, commands: CommandTimeline | None = None,
                 teleop: Teleop | None = None, action: ActionFile | None = None, get_up: bool = False,
                 options: Options = Options()) -> MotionResult:
    """A steered walk on the robot: ``commands`` (a :class:`~op2motion.gait.commands.CommandTimeline`) feed it on
    its clock, ``teleop`` (a :class:`~.teleop.Teleop`) from the keys between ticks; the kicks are ``action``'s stock
    pages when it has them. It ends standing still after its stop (the timeline's end, the ``x`` key, or Ctrl-C),
    at most :data:`MAX_TELEOP_S` with keys. With ``get_up``, falls are caught (see the module docstring)."""
    from op2motion.gait.steer import SteerableWalk
    from op2motion.motion.fall import Supervisor

    walker = SteerableWalk.make(spec, preset, commands=commands, action=action)
    controller: Any = Supervisor(walker, spec=spec) if get_up else walker
    source = " and ".join(n for n, v in (("a command timeline", commands), ("keys", teleop)) if v is not None)
    what = f"steered walk '{walker.params.name}' ({source or 'standing'}{', getting up after falls' if get_up else ''})"
    duration = MAX_TELEOP_S if teleop is not None else None
    on_tick = announce(controller, options) if get_up else options.on_tick
    if teleop is not None:
        ticked = on_tick

        def on_tick(tick: Any) -> None:            # (the keys, then the caller's progress)
            teleop.apply(walker)
            if ticked is not None:
                ticked(tick)
    result = run_on_robot(port, spec, controller, what, replace(options, on_tick=on_tick), duration, "walk")
    walked = dict(result.runs).get("walk")
    if walked is not None:
        result.travel = {"gyro_heading_deg": math.degrees(walked.yaw_rad)}
        if get_up:
            result.notes += [f"{t_s:.2f} s: {event}" for t_s, event in controller.events]
    return result


def run_on_robot(port: RobotPort, spec: Spec, controller: Any, what: str = "controller",
                 options: Options = Options(), duration_s: float | None = None, name: str = "run") -> MotionResult:
    """Any controller on the robot, the way every robot command starts one: the robot read and preflighted; if the
    controller's first goals are more than :data:`~op2motion.bus.loop.START_JUMP_RAD` from where the joints are, the
    feet closed if they stand apart (:func:`~.stand.close_feet`) and a planned move there first (refused lying), each
    checked in physics (refused if it fails, unless ``options.force``); then the controller in the 8 ms loop (the
    run ``name`` of the result) until its plan is over (or ``duration_s``), or it is done. The Python way to run a
    controller on the robot (docs/robot.md)."""
    with Session(port, spec) as session:
        state = session.status()
        session.preflight(state)
        first = np.asarray(controller.plan.goals[0], dtype=float)
        planned = controller.plan.duration_s if duration_s is None else duration_s
        result = MotionResult(what, planned, emulator=session.emulated, until_stopped_s=duration_s)
        if float(np.max(np.abs(first - state.servo_angles))) <= START_JUMP_RAD:
            result.checked = "no move needed first (the controller starts where the robot is)"
            if options.stopped():
                result.runs.append(("run", LoopReport(ended="stopped")))
                return result
            if not take_control(session, state, result, name):
                return result
        else:
            closed = close_feet(session, state, result, options)
            if closed is None or not _approach(session, closed, first, result, options):
                return result
        report = run_controller(controller, session.robot, duration_s=duration_s, stop=options.stop,
                                on_tick=options.on_tick, until_done=True)
        result.runs.append((name, report))
        return result


def _approach(session: Session, state: Any, first: np.ndarray, result: MotionResult, options: Options) -> bool:
    """The checked, planned move from where the robot is to a controller's first goals; whether it got there."""
    if state.board.tilt_rad > LYING_TILT_RAD:
        raise CheckFailed(f"refused: the robot lies (tilted {math.degrees(state.board.tilt_rad):.0f}°); a walk "
                          f"starts standing (op2motion robot getup first)")
    approach = move(state.servo_angles, Pose("start", Support.DOUBLE, first), session.spec)
    result.planned_s += approach.duration_s
    result.notes += list(approach.notes)
    result.checked = checked(approach, session.spec, state, options.force, "the move to the first pose",
                             options.on_progress)
    return run_planned(session, state, approach, result, "approach", options)


def getup(port: RobotPort, spec: Spec, action: ActionFile | None = None, options: Options = Options()) -> MotionResult:
    """Get the robot up from where it lies (:class:`~op2motion.motion.getup.GetUp`: the stock pages 10/11 when
    ``action`` has them, op2motion's own motions otherwise). Checked first in physics from the side it lies on
    (refused, exit 1, if it does not stand there, unless forced); runs until it stands (or gives up). A robot
    already up is left as it is."""
    from op2motion.motion.getup import GetUp
    from op2motion.motion.lying import lying_side
    from op2motion.physics import Setup, check

    with Session(port, spec) as session:
        state = session.status()
        session.preflight(state)
        tilt = state.board.tilt_rad
        if tilt < FALL_TILT_RAD:
            result = MotionResult("get up", 0.0, notes=[f"the robot is up (tilted {math.degrees(tilt):.0f}°): "
                                                        f"nothing to do"], emulator=session.emulated)
            result.checked = "nothing to check"
            return result
        side = lying_side(state.board.accel_m_s2)
        controller = GetUp(spec, action)
        result = MotionResult(f"get up from lying {side}", controller.plan.duration_s, emulator=session.emulated,
                              until_stopped_s=controller.plan.duration_s, ends_when="it stands")
        if options.force:
            result.checked = "not checked (forced)"
        else:
            trial = GetUp(spec, action)
            check(trial, spec, (CHECK_ENGINE,), setup=Setup(lying=side, full_length=True),
                  on_progress=options.on_progress)
            if not trial.stood:
                raise CheckFailed(f"refused: GetUp does not stand up from lying {side} in physics ({CHECK_ENGINE}, "
                                  f"the servo model); --force plays it anyway")
            result.checked = f"checked in physics ({CHECK_ENGINE}, the servo model, lying {side}): stands"
        if options.stopped():
            result.runs.append(("get up", LoopReport(ended="stopped")))
            return result
        if not take_control(session, state, result, "get up"):
            return result
        report = run_controller(controller, session.robot, stop=options.stop, on_tick=announce(controller, options),
                                until_done=True)
        result.runs.append(("get up", report))
        result.notes += [f"{t_s:.2f} s: {event}" for t_s, event in controller.events]
        if report.ended == "done" and not controller.stood:
            result.notes.append("could not get up")
        return result


def announce(controller: Any, options: Options) -> Callable[[Any], None] | None:
    """``options.on_tick`` that also passes each new entry of ``controller.events`` ((t [s], what) pairs: a
    supervisor's, a get-up's) to ``options.on_event`` as it happens."""
    if options.on_event is None:
        return options.on_tick
    told = 0

    def on_tick(tick: Any) -> None:
        nonlocal told
        events = controller.events
        for t_s, what in events[told:]:
            options.on_event(f"{t_s:.2f} s: {what}")             # type: ignore[misc]
        told = len(events)
        if options.on_tick is not None:
            options.on_tick(tick)
    return on_tick


def leg_travel(controller: Any, row: int = -1) -> dict[str, float]:
    """Where the feet took the robot, by leg odometry: the plan's travel of the feet's midpoint up to gait row
    ``row`` (where the walk ended: its last, or the row a stop froze it at; a walk stopped early: as planned
    again from the stop) plus the placement error the controller
    measured at each landing from the joint angles (plan frame: x forward, y left) [m]."""
    rows = controller.rows                  # (a walk stopped early: its rows planned again from the stop)
    last = rows.end - 1
    at = last if row < 0 else min(max(row, rows.first), last)
    start = np.mean([rows.feet(side, rows.first)[:2] for side in ("left", "right")], axis=0)
    end = np.mean([rows.feet(side, at)[:2] for side in ("left", "right")], axis=0)
    travel = end - start + np.asarray(controller.odometry.error, dtype=float)
    return {"x_m": float(travel[0]), "y_m": float(travel[1]), "distance_m": float(np.hypot(*travel))}
