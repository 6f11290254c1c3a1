"""The robot tasks: the real OP2 on its bus (``robot status``, ``read``, and the motions ``play``, ``walk``,
``getup`` run by :mod:`op2motion.bus`), and the emulated OP2's report (``robot emulate``), each as a
:class:`~.result.TaskResult`: a missing or faulty servo, a fault that stopped a motion, is a "no" with its phrase; a
stop the user asked for is an interrupted one (exit 130 on the command line, the robot holding its pose).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.bus.port import RobotPort
    from op2motion.onrobot.tasks import Limp, MotionResult, Options
    from op2motion.physics import EngineName
    from op2motion.robot.support import Support, SupportName


def robot_status(port: RobotPort, spec: Spec) -> TaskResult:
    """``robot status``: the board, the IMU and every servo; a "no" when a servo is missing, reports an error, is hot
    or the supply is low (the first problem named, and how many more)."""
    from op2motion.onrobot.tasks import read_status

    state = read_status(port, spec)
    problem = None if state.ok else state.problems[0].describe() + (
        f" (and {len(state.problems) - 1} more)" if len(state.problems) > 1 else "")
    return TaskResult(problem is None, problem, tuple(state.warnings), {}, state.as_dict(), ("\n".join(state.lines()),))


def robot_setup(port: RobotPort, spec: Spec, return_delay: int, confirm: Callable[[str], bool]) -> TaskResult:
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
    return TaskResult(problem is None, problem, None, {}, data, (line,))


def robot_read(port: RobotPort, spec: Spec, name: str, output: Path, support: Support | SupportName = "double",
               limp: Limp | None = None, force: bool = False) -> TaskResult:
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
    return TaskResult(True, None, None, {"out": Output(str(output), pose_to_json(pose, spec))}, data, (lines,))


def robot_motion(run: Callable[[Options], MotionResult], options: Options) -> TaskResult:
    """A motion on the robot (``run``: a :mod:`op2motion.bus` motion, e.g. ``lambda o: play_on_robot(port, spec, file,
    page, o)``) with ``options``: a fault that stopped it is a "no"; a stop asked for (``options.stop``) an
    interrupted one; a motion refused before it started (a check that ran and failed: the physics check, the
    preflight, a lying robot) a "no" too, its result saying so (``ended``: ``refused``)."""
    from op2motion.errors import CheckFailed, PortFailed

    try:
        result = run(options)
    except PortFailed:
        raise
    except CheckFailed as exc:
        refused: dict[str, Any] = {"ended": "refused", "refused": exc.message, "runs": {}, "fault": None}
        return TaskResult(False, exc.message, None, {}, refused, (f"refused: {exc.message}",))
    data, lines = result.as_dict(), ("\n".join(result.lines()),)
    if result.fault is not None:
        return TaskResult(False, f"{result.what} stopped: {result.fault.describe()}", None, {}, data, lines)
    if result.ended == "stopped" or options.stopped():
        return TaskResult(False, f"{result.what} stopped on request; the robot holds its pose", None, {}, data,
                          lines, interrupted=True)
    return TaskResult(True, None, None, {}, data, lines)


def emulated(emulator: Any, link: str, engine: EngineName, start: str, faults: Any, interrupted: bool) -> TaskResult:
    """``robot emulate``'s report once the emulated OP2 stopped: its link, engine, start, faults, traffic and how
    far it fell behind the wall clock; ``interrupted``: it was stopped by Ctrl-C (not by ``--seconds``)."""
    data = {"link": link, "pty": emulator.pty_name, "engine": engine, "start": start, "faults": faults.describe(),
            "wire": emulator.timing.describe(),
            "stats": dict(emulator.stats), "slipped_s": round(emulator.slipped_s, 3),
            "simulated_s": round(emulator.truth()["t_s"], 3), "truth": emulator.truth()}
    line = (f"emulated OP2 stopped after {data['simulated_s']:.1f} s simulated ({emulator.slipped_s:.2f} s behind "
            f"the wall clock), {emulator.stats['packets']} packets, link removed")
    if interrupted:
        return TaskResult(False, "the emulated OP2 stopped; its link is removed", None, {}, data, (line,),
                          interrupted=True)
    return TaskResult(True, None, None, {}, data, (line,))
