"""Standing, and playing from where the robot stands (``op2motion robot stand|play``).

* :func:`close_feet`: feet that stand apart (a walk stopped between its steps: the stop froze it on its next double
  support) are brought side by side by one step (:func:`~op2motion.gait.closing.closing_gait`, the walk's own
  planner and controller), checked in physics first (:data:`~.plans.CHECK_ENGINE`); every motion from such a stance
  starts with it (no move starts there without sliding a sole);
* :func:`stand`: the robot standing on both feet side by side in the walk-ready pose, from wherever it stands;
* :func:`play_on_robot`: a pose, a motion file or an action page, from where the robot is.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from op2motion.bus.loop import run_controller
from op2motion.bus.port import RobotPort
from op2motion.bus.session import RobotStatus, Session
from op2motion.errors import CheckFailed, InputError
from op2motion.onrobot.plans import CHECK_ENGINE, LYING_TILT_RAD, move, page_start, page_trajectory, ready_pose, then
from op2motion.onrobot.tasks import ACTION_FILE_BYTES, MotionResult, Options, checked, run_planned, take_control
from op2motion.robot.spec import Spec

CLOSE_RUN = "close the feet"


def close_feet(session: Session, state: RobotStatus, result: MotionResult, options: Options) -> RobotStatus | None:
    """If the feet stand apart, the step that closes them, checked in physics (refused, exit 1, if it fails there,
    unless ``options.force``) and played as the run :data:`CLOSE_RUN` of ``result``; the robot as read after it
    (``state`` itself when the feet stood side by side; None when the step did not end done: a stop or a fault)."""
    from op2motion.gait import preset_path, read_preset
    from op2motion.gait.closing import closing_gait
    from op2motion.gait.controller import WalkController
    from op2motion.physics import check

    if state.board.tilt_rad > LYING_TILT_RAD:
        return state                                    # lying: the motion's own check refuses it
    gait = closing_gait(state.servo_angles, session.spec, read_preset(preset_path(None)))
    if gait is None:
        return state
    controller = WalkController(gait, session.spec)
    if not options.force:
        problem = check(WalkController(gait, session.spec), session.spec, (CHECK_ENGINE,),
                        on_progress=options.on_progress).problem("does not get through")
        if problem:
            raise CheckFailed(f"refused: the feet stand apart and the step that closes them {problem} in physics "
                              f"({CHECK_ENGINE}, the servo model); --force plays it anyway")
    result.notes.append("the feet stood apart: one step brought them side by side first (checked in physics)"
                        if not options.force else "the feet stood apart: one step brought them side by side first")
    result.planned_s += controller.plan.duration_s
    if options.stopped():
        return None
    if not take_control(session, state, result, CLOSE_RUN):
        return None
    report = run_controller(controller, session.robot, stop=options.stop, on_tick=options.on_tick, until_done=True)
    result.runs.append((CLOSE_RUN, report))
    return session.status() if report.ended == "done" else None


def stand(port: RobotPort, spec: Spec, options: Options = Options()) -> MotionResult:
    """The robot on both feet side by side in the walk-ready pose (:func:`~.plans.ready_pose`): the step that closes
    its feet if they stand apart (:func:`close_feet`), then a planned move, checked in physics; refused lying (get
    up first)."""
    with Session(port, spec) as session:
        state = session.status()
        session.preflight(state)
        if state.board.tilt_rad > LYING_TILT_RAD:
            raise CheckFailed(f"refused: the robot lies (tilted {math.degrees(state.board.tilt_rad):.0f}°): op2motion "
                              f"robot getup first")
        ready = ready_pose(spec)
        result = MotionResult("stand (walk-ready, feet side by side)", 0.0, target=ready.servo,
                              emulator=session.emulated)
        closed = close_feet(session, state, result, options)
        if closed is None:
            return result
        trajectory = move(closed.servo_angles, ready, spec)
        result.planned_s += trajectory.duration_s
        result.notes += list(trajectory.notes)
        result.checked = checked(trajectory, spec, closed, options.force, "the move to walk-ready",
                                 options.on_progress)
        run_planned(session, closed, trajectory, result, "motion", options)
        return result


def load_motion(path: str, page: int | None, spec: Spec) -> tuple[str, Any]:
    """What ``robot play`` was given: ("pose", Pose), ("motion", Motion) or ("page", ActionFile)."""
    from op2motion.formats.action import ActionFile
    from op2motion.formats.motionfile import is_motion_file, read_motion
    from op2motion.formats.posefile import read_pose

    p = Path(path)
    if page is not None:
        return "page", ActionFile.read(path)
    if p.is_file() and p.stat().st_size == ACTION_FILE_BYTES:
        raise InputError(f"{path} is an action file: expected --page N (the page to play)", "page")
    if is_motion_file(path):
        return "motion", read_motion(path, spec)
    return "pose", read_pose(path, spec)


def play_on_robot(port: RobotPort, spec: Spec, path: str, page: int | None = None,
         options: Options = Options()) -> MotionResult:
    """A pose, a motion file or an action page on the robot: a planned move from where it is to the first pose,
    then the motion or the page tick for tick (see the module docstring)."""
    from op2motion.motion.pipeline import plan_motion

    kind, loaded = load_motion(path, page, spec)
    with Session(port, spec) as session:
        state = session.status()
        session.preflight(state)
        result = MotionResult(f"{kind} {Path(path).name}", 0.0, emulator=session.emulated)
        closed = close_feet(session, state, result, options)
        if closed is None:
            return result
        state, current, target = closed, closed.servo_angles, None
        if kind == "pose":
            trajectory = move(current, loaded, spec)
            what, target = f"pose {loaded.name}", loaded.servo
        elif kind == "motion":
            motion = plan_motion(loaded, spec)
            first = loaded.steps[0].pose
            trajectory = then(move(current, first, spec), motion)
            what = f"motion {loaded.name}"
        else:
            if page is None:
                raise InputError(f"{path} is an action file: expected --page N (the page to play)", "page")
            beyond = page_beyond_ranges(loaded, page, spec)
            if beyond and not options.force:
                raise InputError(f"expected page {page}'s angles within the joints' mechanical ranges, got "
                                 f"{beyond[0]}{f' (and {len(beyond) - 1} more)' if len(beyond) > 1 else ''}: "
                                 f"--force plays them clipped to the ranges", "page")
            result.notes += [f"played clipped to its mechanical range: {b}" for b in beyond]
            start = page_start(loaded, page, spec, current)
            trajectory = then(move(current, start, spec), page_trajectory(loaded, page, spec, start))
            what = f"page {page} ({loaded.page(page, spec).name})"
        result.what, result.target = what, target
        result.planned_s += trajectory.duration_s
        result.notes += list(trajectory.notes)
        result.checked = checked(trajectory, spec, state, options.force, what, options.on_progress)
        run_planned(session, state, trajectory, result, "motion", options)
        return result




def page_beyond_ranges(action: Any, page: int, spec: Spec) -> list[str]:
    """Each goal of action page ``page`` beyond its joint's mechanical range, in words (``step 3: r_sho_pitch tick
    4000 (+171.6°), its range ends at +150.0°``): the loop would clip them, so they are refused unless forced."""
    from op2motion.bus.robot import angle_of
    from op2motion.bus.safety import mechanical_bounds

    lower, upper = mechanical_bounds(spec)
    out = []
    for k, step in enumerate(action.page(page, spec).steps, start=1):
        for i, joint in enumerate(spec.joints):
            tick = step.ticks.get(joint.id)
            if tick is None:
                continue
            angle = angle_of(tick, spec)
            if not lower[i] <= angle <= upper[i]:
                end = lower[i] if angle < lower[i] else upper[i]
                out.append(f"step {k}: {joint.name} tick {tick} ({math.degrees(angle):+.1f}°), its range ends at "
                           f"{math.degrees(end):+.1f}°")
    return out
