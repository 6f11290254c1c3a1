"""What the ``op2motion robot`` commands do, as library functions: :func:`status`, :func:`setup` (the servos' return
delay), :func:`teach` (read a pose) and :func:`play` (a pose, a motion file or an action page); the walks and getting
up: :mod:`.walks`.

Each opens a :class:`~.session.Session` on the port, reads the whole robot, and (for a motion) refuses to start an
unfit robot (:mod:`.safety`), builds the motion from where the robot is (:mod:`.plans`), refuses what fails
op2motion's own checks unless forced, switches the torque on without a jump and runs the 8 ms loop
(:func:`~.loop.run_controller`). A ``stop`` event (the commands set it on Ctrl-C) ends a motion safely: a walk on
its next double support. The result is a :class:`MotionResult`; a fault is in it, not raised: a port that fails once
the motion is under way too (from the torque switched on: the run ends as the fault ``port failed``), while one that
fails before (while the robot is read and checked) raises :class:`~op2motion.errors.PortFailed` (exit 1).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from op2motion.bus.loop import LoopReport, Tick, run_controller
from op2motion.bus.plans import (
    CHECK_ENGINE,
    LYING_TILT_RAD,
    move,
    page_start,
    page_trajectory,
    physics_problem,
    robot_schedule,
    then,
)
from op2motion.bus.port import RobotPort
from op2motion.bus.safety import clip_goals, mechanical_bounds, port_fault
from op2motion.bus.session import RobotStatus, Session
from op2motion.bus.tables import CM730_ID, MX28
from op2motion.errors import CheckFailed, InputError, PortFailed
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

ACTION_FILE_BYTES = 256 * 512      # an action file: 256 pages of 512 bytes
MAX_RETURN_DELAY = 254             # the Return Delay Time register's largest value (2 µs units)
OnTick = Callable[[Tick], None]


@dataclass(frozen=True)
class Options:
    """How a motion runs: ``force`` (play what op2motion's checks refuse), the ``stop`` event (set on Ctrl-C), a
    callback per loop tick (progress), one for the physics check's progress (done, total) and one that hears what
    happens as it happens, in words (a fall, getting up, standing again, resumed)."""

    force: bool = False
    stop: threading.Event | None = None
    on_tick: OnTick | None = None
    on_progress: Any = None
    on_event: Callable[[str], None] | None = None

    def stopped(self) -> bool:
        """Whether a stop was asked for."""
        return self.stop is not None and self.stop.is_set()


@dataclass
class MotionResult:
    """A motion on the robot: what it was, its planned length [s], each run of the loop (the move to the first pose,
    then the motion), the pose it was to end in (20,) [rad] if any, notes, and where the feet took the robot
    (walks: leg odometry)."""

    what: str
    planned_s: float
    runs: list[tuple[str, LoopReport]] = field(default_factory=list)
    target: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    travel: dict[str, float] = field(default_factory=dict)
    checked: str = ""
    emulator: Any = None

    def emulated(self) -> dict[str, Any] | None:
        """What the emulated OP2 the motion ran on did (an in-process one, ``--port lockstep``): its report once the
        robot held its last goals :data:`~.session.HOLD_AFTER_S` more (the torso's position, heading and tilt, the
        servos' goals and torque limits); None on a real robot."""
        return None if self.emulator is None else self.emulator.report()

    @property
    def last(self) -> LoopReport | None:
        """The last run of the loop."""
        return self.runs[-1][1] if self.runs else None

    @property
    def ended(self) -> str:
        """``done``, ``stopped`` (a stop request) or ``fault``."""
        for _, report in self.runs:
            if report.ended != "done":
                return report.ended
        return "done"

    @property
    def fault(self) -> Any:
        """The fault that stopped it (None if none)."""
        return next((r.fault for _, r in self.runs if r.fault is not None), None)

    def target_error_deg(self) -> float | None:
        """The largest difference between the last goals sent and the target pose [deg]."""
        if self.target is None or self.last is None or not len(self.last.goals):
            return None
        return float(np.degrees(np.max(np.abs(self.last.goals - self.target))))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        err = self.target_error_deg()
        return {"what": self.what, "planned_s": round(self.planned_s, 3), "ended": self.ended,
                "fault": None if self.fault is None else self.fault.as_dict(), "checked": self.checked,
                "runs": {name: r.as_dict() for name, r in self.runs}, "notes": list(self.notes),
                "target_error_deg": None if err is None else round(err, 3), "travel": dict(self.travel),
                "emulated": self.emulated()}

    def lines(self) -> list[str]:
        """For people."""
        out = [f"{self.what}: {self.planned_s:.2f} s planned; {self.checked}"]
        out += [f"  {name}: {r.describe()}" for name, r in self.runs]
        out += [f"  note: {n}" for n in self.notes]
        err = self.target_error_deg()
        if err is not None:
            out.append(f"  last goals within {err:.2f}° of the target pose")
        if self.travel:
            out.append("  leg odometry: " + ", ".join(f"{k} {v:+.3f}" for k, v in self.travel.items()))
        emulated = self.emulated()
        if emulated is not None:
            truth = emulated["truth"]
            out.append(f"  emulated OP2 (lockstep): torso at x {truth['x_m']:+.3f} m, y {truth['y_m']:+.3f} m, heading "
                       f"{math.degrees(truth['yaw_rad']):+.1f}°, tilt {math.degrees(truth['tilt_rad']):.1f}°")
        if self.fault is not None:
            out.append(f"  STOPPED: {self.fault.describe()}")
        elif self.ended == "stopped":
            out.append("  stopped on request, standing")
        return out


def status(port: RobotPort, spec: Spec) -> RobotStatus:
    """The board and every servo (switching the servos' power on if it was off)."""
    with Session(port, spec) as session:
        return session.status()


@dataclass(frozen=True)
class SetupResult:
    """What ``robot setup`` changed: the register, the value asked for, the devices written {id: old value}, those
    already right, and those that did not confirm."""

    register: str
    value: int
    written: dict[int, int]
    already: tuple[int, ...]
    failed: tuple[int, ...]


def setup(port: RobotPort, spec: Spec, return_delay: int, confirm: Callable[[str], bool]) -> SetupResult:
    """Set every device's Return Delay Time (register 5, EEPROM: kept over power cycles) to ``return_delay`` (2 µs
    units), writing only where it differs, after ``confirm(question)`` says yes (a no is a refusal: exit 2, nothing
    written); each write confirmed by the device and read back."""
    if not 0 <= return_delay <= MAX_RETURN_DELAY:
        raise InputError(f"expected a return delay of 0 to {MAX_RETURN_DELAY} (2 µs units), got {return_delay}",
                         "return_delay")
    with Session(port, spec) as session:
        state = session.status()
        missing = [f"{s.joint} (ID {s.id})" for s in state.servos if not s.answers]
        if missing:
            raise CheckFailed(f"cannot set every servo: {', '.join(missing)} not answering")
        now = {CM730_ID: state.board.return_delay} | {s.id: s.return_delay for s in state.servos}
        change = {d: v for d, v in now.items() if v != return_delay}
        if change and not confirm(f"write Return Delay Time {return_delay} ({return_delay * 2} µs) into the EEPROM "
                                  f"of {len(change)} device(s) (IDs {', '.join(map(str, sorted(change)))})?"):
            raise InputError("not confirmed: nothing written (--yes confirms)", "yes")
        address = MX28["return_delay_time"].address
        failed = []
        for device in sorted(change):
            reply = session.robot.bus.write(device, address, bytes((return_delay,)))
            back = session.robot.bus.read(device, address, 1)
            if reply is None or back is None or back.params[0] != return_delay:
                failed.append(device)
        return SetupResult("return_delay_time", return_delay, change,
                           tuple(sorted(set(now) - set(change))), tuple(failed))


def teach(port: RobotPort, spec: Spec, name: str, support: Support | SupportName = "double", limp: bool = False,
          wait: Callable[[], None] | None = None) -> tuple[Pose, list[str]]:
    """The robot's present joint angles as a pose. With ``limp`` the torque goes off, ``wait`` lets the user move the
    limbs, the angles are read, and the torque comes back on holding them. Angles beyond a joint's mechanical
    range are clipped to it (a note says so)."""
    with Session(port, spec) as session:
        robot = session.robot
        state = session.status()
        missing = [f"{s.joint} (ID {s.id})" for s in state.servos if not s.answers]
        if missing:
            raise CheckFailed(f"cannot read a whole pose: {', '.join(missing)} not answering")
        if limp:
            robot.torque(False)
            if wait is not None:
                wait()
            state = session.status()
            missing = [f"{s.joint} (ID {s.id})" for s in state.servos if not s.answers]
            if missing:
                raise CheckFailed(f"cannot read a whole pose: {', '.join(missing)} not answering")
        lower, upper = mechanical_bounds(spec)
        angles, clipped = clip_goals(state.servo_angles, lower, upper)
        notes = [f"{spec.joint_names[i]} read {math.degrees(state.servo_angles[i]):.1f}°, beyond its mechanical "
                 f"range: clipped to {math.degrees(angles[i]):.1f}°" for i in np.flatnonzero(clipped)]
        if limp:
            robot.take_control({s.id: q for s, q in zip(state.servos, angles)})
        pose = Pose(name, Support.of(support), angles, {},
                    {"source": "robot", "port": session.path, "limp": limp, "tilt_deg": round(math.degrees(
                        state.board.tilt_rad), 1)})
        return pose.checked(spec), notes


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


def checked(trajectory: Any, spec: Spec, state: RobotStatus, force: bool, what: str,
             on_progress: Any = None) -> str:
    """Refuse (exit 1) what physics says fails, or a start op2motion cannot check (lying), unless ``force``."""
    tilt = state.board.tilt_rad
    if tilt > LYING_TILT_RAD:
        if not force:
            raise CheckFailed(f"refused: the robot lies (tilted {math.degrees(tilt):.0f}°); op2motion cannot check "
                              f"a motion from lying in physics yet: --force plays it unchecked")
        return "not checked (the robot lies; forced)"
    if force:
        return "not checked (forced)"
    problem = physics_problem(trajectory, spec, on_progress)
    if problem:
        raise CheckFailed(f"refused: {what} {problem} in physics ({CHECK_ENGINE}, the servo model, from the robot's "
                          f"present pose); --force plays it anyway")
    return f"checked in physics ({CHECK_ENGINE}, the servo model, from the robot's present pose)"


def play(port: RobotPort, spec: Spec, path: str, page: int | None = None,
         options: Options = Options()) -> MotionResult:
    """A pose, a motion file or an action page on the robot: a planned move from where it is to the first pose,
    then the motion or the page tick for tick (see the module docstring)."""
    from op2motion.motion.pipeline import plan_motion

    kind, loaded = load_motion(path, page, spec)
    with Session(port, spec) as session:
        state = session.status()
        session.preflight(state)
        current = state.servo_angles
        target = None
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
            start = page_start(loaded, page, spec, current)
            trajectory = then(move(current, start, spec), page_trajectory(loaded, page, spec, start))
            what = f"page {page} ({loaded.page(page, spec).name})"
        result = MotionResult(what, trajectory.duration_s, target=target, notes=list(trajectory.notes),
                              emulator=session.emulated)
        result.checked = checked(trajectory, spec, state, options.force, what, options.on_progress)
        run_planned(session, state, trajectory, result, "motion", options)
        return result


def run_planned(session: Session, state: RobotStatus, trajectory: Any, result: MotionResult, name: str,
                options: Options) -> bool:
    """Play a checked trajectory from where the robot is (the torque on without a jump first), as the run ``name``
    of ``result``; whether it ran to its end (not on a stop request before it began, a stop or a fault)."""
    if options.stopped():
        result.runs.append((name, LoopReport(ended="stopped")))
        return False
    if not take_control(session, state, result, name):
        return False
    report = run_controller(robot_schedule(trajectory, session.robot.spec), session.robot, stop=options.stop,
                            on_tick=options.on_tick)
    result.runs.append((name, report))
    return report.ended == "done"


def take_control(session: Session, state: RobotStatus, result: MotionResult, name: str) -> bool:
    """:meth:`~.session.Session.take_control` as the run ``name`` of ``result`` begins; whether it did (a port that
    fails there ends the run as the fault ``port failed``, in ``result``)."""
    try:
        session.take_control(state)
    except PortFailed as exc:
        result.runs.append((name, LoopReport(ended="fault", fault=port_fault(exc))))
        return False
    return True
