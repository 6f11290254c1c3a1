"""The robot tasks: the real OP2 on its bus (``robot status``, ``setup``, ``read``, and the motions ``play``,
``walk`` (planned or steered), ``stand`` and ``getup``, run by :mod:`op2motion.onrobot` in the bus's 8 ms loop), and
the emulated OP2's report (``robot emulate``), each as a :class:`~.result.TaskResult`: a missing or faulty servo, a
fault that stopped a motion, is a "no" with its phrase; a stop the user asked for is an interrupted one (exit 130 on
the command line, the robot holding its pose).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.bus.emulator.faults import Faults
    from op2motion.bus.emulator.server import Emulator
    from op2motion.bus.port import RobotPort
    from op2motion.bus.session import RobotStatus
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import CommandTimeline
    from op2motion.onrobot.tasks import Limp, MotionResult, Options, SetupResult
    from op2motion.onrobot.teleop import Teleop
    from op2motion.physics import EngineName
    from op2motion.robot.pose import Pose
    from op2motion.robot.support import Support, SupportName


def robot_status(port: RobotPort, spec: Spec) -> TaskResult[RobotStatus]:
    """``robot status``: the board, the IMU and every servo; a "no" when a servo is missing, reports an error, is hot
    or the supply is low (the first problem named, and how many more)."""
    from op2motion.onrobot.tasks import read_status

    state = read_status(port, spec)
    problem = None if state.ok else state.problems[0].describe() + (
        f" (and {len(state.problems) - 1} more)" if len(state.problems) > 1 else "")
    return TaskResult(problem is None, problem, tuple(state.warnings), {}, state.as_dict(),
                      ("\n".join(state.lines()),), value=state)


def robot_setup(port: RobotPort, spec: Spec, return_delay: int, confirm: Callable[[str], bool]
                ) -> TaskResult[SetupResult]:
    """``robot setup --return-delay N``: every device's Return Delay Time set to N where it differs (EEPROM), after
    ``confirm``; a "no" when a device did not take it."""
    from op2motion.onrobot.tasks import setup

    done = setup(port, spec, return_delay, confirm)
    data: JsonObject = {"register": done.register, "value": done.value,
                        "written": {str(d): v for d, v in done.written.items()}, "already": list(done.already),
                        "failed": list(done.failed)}
    line = (f"return delay {done.value} ({done.value * 2} µs): written to {len(done.written)} device(s)"
            f"{' (IDs ' + ', '.join(map(str, sorted(done.written))) + ')' if done.written else ''}, "
            f"{len(done.already)} already had it")
    problem = (f"IDs {', '.join(map(str, done.failed))} did not take the return delay" if done.failed else None)
    return TaskResult(problem is None, problem, None, {}, data, (line,), value=done)


def robot_read(port: RobotPort, spec: Spec, name: str, output: Path, support: Support | SupportName = "double",
               limp: Limp | None = None, force: bool = False) -> TaskResult[Pose]:
    """``robot read``: the present joint angles as pose ``name`` on ``support``, for ``output`` (``limp``: the chosen
    joints limp after its confirmation while the user moves them, then holding them; a robot found fallen is refused
    unless ``force``: see :func:`~op2motion.onrobot.tasks.teach`)."""
    from op2motion.formats.posefile import pose_to_json
    from op2motion.onrobot.tasks import teach

    pose, notes = teach(port, spec, name, support, limp, force)
    joints = list(pose.provenance["limp_joints"])
    data = {"pose": name, "support": support, "servo_deg": {n: round(math.degrees(q), 3) for n, q in
                                                            zip(spec.joint_names, pose.servo)},
            "notes": notes, "path": str(output), "limp": bool(joints), "limp_joints": joints,
            "tilt_deg": pose.provenance["tilt_deg"], "fallen": pose.provenance["fallen"]}
    lines = "\n".join([f"wrote {output}: pose {name} ({support}){' of a FALLEN robot' if data['fallen'] else ''}"]
                      + [f"  {n}" for n in notes])
    return TaskResult(True, None, None, {"out": Output(str(output), pose_to_json(pose, spec))}, data, (lines,),
                      value=pose)


@dataclass(frozen=True)
class RobotWalk:
    """A walk on the robot: the gait ``preset`` (None: ``forward``), planned for ``steps`` steps (None: the
    preset's) or to ``target`` (x [m], y [m], heading [rad]; None: the steps)."""

    preset: str | None = None
    steps: int | None = None
    target: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class SteeredRobotWalk:
    """A steered walk on the robot: the step's ``preset`` (None: ``steer``), fed by ``commands`` (a command
    timeline) and/or ``teleop`` (keys), kicking with ``action``'s stock pages when it has them, getting back up
    after a fall when ``get_up``."""

    preset: str | None = None
    commands: CommandTimeline | None = None
    teleop: Teleop | None = None
    action: ActionFile | None = None
    get_up: bool = False


def robot_play(port: RobotPort, spec: Spec, path: str, page: int | None, options: Options) -> TaskResult[MotionResult]:
    """``robot play``: a pose, a motion file or an action page on the robot (see
    :func:`~op2motion.onrobot.stand.play_on_robot`)."""
    from op2motion.onrobot.stand import play_on_robot

    return _motion_result(lambda: play_on_robot(port, spec, path, page, options), options)


def robot_walk(port: RobotPort, spec: Spec, request: RobotWalk, options: Options) -> TaskResult[MotionResult]:
    """``robot walk``: a planned walk on the robot (see :func:`~op2motion.onrobot.walks.walk`)."""
    from op2motion.onrobot.walks import walk

    return _motion_result(lambda: walk(port, spec, request.preset, request.steps, request.target, options), options)


def robot_steered_walk(port: RobotPort, spec: Spec, request: SteeredRobotWalk, options: Options
                       ) -> TaskResult[MotionResult]:
    """``robot walk --commands/--teleop``: a steered walk on the robot (see
    :func:`~op2motion.onrobot.walks.steered_walk`)."""
    from op2motion.onrobot.walks import steered_walk

    return _motion_result(lambda: steered_walk(port, spec, request.preset, request.commands, request.teleop,
                                               request.action, request.get_up, options), options)


def robot_stand(port: RobotPort, spec: Spec, options: Options) -> TaskResult[MotionResult]:
    """``robot stand``: the robot on both feet in walk-ready (see :func:`~op2motion.onrobot.stand.stand`)."""
    from op2motion.onrobot.stand import stand

    return _motion_result(lambda: stand(port, spec, options), options)


def robot_getup(port: RobotPort, spec: Spec, action: ActionFile | None, options: Options) -> TaskResult[MotionResult]:
    """``robot getup``: the robot up from where it lies (see :func:`~op2motion.onrobot.walks.getup`)."""
    from op2motion.onrobot.walks import getup

    return _motion_result(lambda: getup(port, spec, action, options), options)


def _motion_result(run: Callable[[], MotionResult], options: Options) -> TaskResult[MotionResult]:
    """A motion on the robot as a result: a fault that stopped it is a "no"; a stop asked for (``options.stop``) an
    interrupted one; a motion refused before it started (a check that ran and failed: the physics check, the
    preflight, a lying robot) a "no" too, its result saying so (``ended``: ``refused``)."""
    from op2motion.errors import CheckFailed, PortFailed

    try:
        result = run()
    except PortFailed:
        raise
    except CheckFailed as exc:
        refused: JsonObject = {"ended": "refused", "refused": exc.message, "runs": {}, "fault": None}
        return TaskResult(False, exc.message, None, {}, refused, (f"refused: {exc.message}",))
    data, lines = result.as_dict(), ("\n".join(result.lines()),)
    if result.fault is not None:
        return TaskResult(False, f"{result.what} stopped: {result.fault.describe()}", None, {}, data, lines,
                          value=result)
    if result.ended == "stopped" or options.stopped():
        return TaskResult(False, f"{result.what} stopped on request; the robot holds its pose", None, {}, data,
                          lines, interrupted=True, value=result)
    return TaskResult(True, None, None, {}, data, lines, value=result)


def emulated(emulator: Emulator, link: str, engine: EngineName, start: str, faults: Faults, interrupted: bool
             ) -> TaskResult[JsonObject]:
    """``robot emulate``'s report once the emulated OP2 stopped: its link, engine, start, faults, traffic and how
    far it fell behind the wall clock; ``interrupted``: it was stopped by Ctrl-C (not by ``--seconds``)."""
    truth = emulator.truth()
    data: JsonObject = {"link": link, "pty": emulator.pty_name, "engine": engine, "start": start,
                        "faults": faults.describe(), "wire": emulator.timing.describe(), "stats": dict(emulator.stats),
                        "slipped_s": emulator.slipped_s, "simulated_s": truth["t_s"], "truth": truth}
    line = (f"emulated OP2 stopped after {truth['t_s']:.1f} s simulated ({emulator.slipped_s:.2f} s behind "
            f"the wall clock), {emulator.stats['packets']} packets, link removed")
    if interrupted:
        return TaskResult(False, "the emulated OP2 stopped; its link is removed", None, {}, data, (line,),
                          interrupted=True, value=data)
    return TaskResult(True, None, None, {}, data, (line,), value=data)
