"""What the ``op2motion robot`` commands do, as library functions: :func:`read_status`, :func:`setup` (the servos'
return delay), :func:`teach` (read a pose; chosen joints limp first, after a confirmation), and what every motion shares
(:class:`MotionResult`, :class:`Options`, :func:`checked`, :func:`run_planned`); playing a pose, a motion file or an
action page and standing: :mod:`.stand`; the walks and getting up: :mod:`.walks`.

Each opens a :class:`~op2motion.bus.session.Session` on the port, reads the whole robot, and (for a motion) refuses to
start an unfit robot (:mod:`op2motion.bus.safety`), builds the motion from where the robot is (:mod:`.plans`), refuses
what fails op2motion's own checks unless forced, switches the torque on without a jump and runs the 8 ms loop
(:func:`~op2motion.bus.loop.run_controller`). A ``stop`` event (the commands set it on Ctrl-C) ends a motion safely: a
walk on its next double support. The result is a :class:`MotionResult`; a fault is in it, not raised: a port that fails
once the motion is under way too (from the torque switched on: the run ends as the fault ``port failed``), while one
that fails before (while the robot is read and checked) raises :class:`~op2motion.errors.PortFailed` (exit 1).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from op2motion.bus.clock import sleep
from op2motion.bus.loop import LoopReport, Tick, run_controller
from op2motion.bus.port import RobotPort
from op2motion.bus.safety import clip_goals, mechanical_bounds, port_fault
from op2motion.bus.session import RobotStatus, Session
from op2motion.bus.tables import CM730_ID, MX28
from op2motion.errors import CheckFailed, InputError, PortFailed
from op2motion.jsonout import JsonObject
from op2motion.onrobot.plans import (
    CHECK_ENGINE,
    LYING_TILT_RAD,
    physics_problem,
    robot_schedule,
)
from op2motion.onrobot.teleop import signed_text
from op2motion.robot.imu import FALL_TILT_RAD
from op2motion.robot.limbs import describe_joints, limb_groups
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
    (walks: leg odometry). A motion that runs until it is stopped (a walk steered by keys), or until something
    happens (``ends_when``: a get-up until it stands), has ``until_stopped_s``, the most it may run after its move
    to the first pose [s] (then ``planned_s`` is the longest it may last)."""

    what: str
    planned_s: float
    runs: list[tuple[str, LoopReport]] = field(default_factory=list)
    target: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    travel: dict[str, float] = field(default_factory=dict)
    checked: str = ""
    emulator: Any = None
    until_stopped_s: float | None = None
    ends_when: str = "stopped"

    def emulated(self) -> JsonObject | None:
        """What the emulated OP2 the motion ran on did (an in-process one, ``--port lockstep``): its report once the
        robot held its last goals :data:`~op2motion.bus.session.HOLD_AFTER_S` more (the torso's position, heading and
        tilt, the servos' goals and torque limits); None on a real robot."""
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

    def as_dict(self) -> JsonObject:
        """JSON-ready."""
        err = self.target_error_deg()
        return {"what": self.what, "planned_s": round(self.planned_s, 3), "ended": self.ended,
                "fault": None if self.fault is None else self.fault.as_dict(), "checked": self.checked,
                "runs": {name: r.as_dict() for name, r in self.runs}, "notes": list(self.notes),
                "target_error_deg": None if err is None else round(err, 3), "travel": dict(self.travel),
                "until_stopped_s": self.until_stopped_s, "emulated": self.emulated()}

    def lines(self) -> list[str]:
        """For people."""
        if self.until_stopped_s is None:
            plan = f"{self.planned_s:.2f} s planned"
        else:
            most = (f"{self.until_stopped_s / 60:g} min" if self.until_stopped_s >= 60.0 else
                    f"{self.until_stopped_s:g} s")
            first = self.planned_s - self.until_stopped_s
            plan = (f"{f'{first:.2f} s to its first pose, then ' if first > 0.0 else ''}until {self.ends_when} "
                    f"(at most {most})")
        out = [f"{self.what}: {plan}; {self.checked}"]
        out += [f"  {name}: {r.describe()}" for name, r in self.runs]
        out += [f"  note: {n}" for n in self.notes]
        err = self.target_error_deg()
        if err is not None:
            out.append(f"  last goals within {err:.2f}° of the target pose")
        out += self._travel_lines()
        if self.emulator is not None:
            truth: dict[str, float] = self.emulator.truth()
            heading = signed_text(math.degrees(truth["yaw_rad"]), 1)
            out.append(f"  emulated OP2 (lockstep): torso at x {signed_text(truth['x_m'], 3)} m, y "
                       f"{signed_text(truth['y_m'], 3)} m, heading {heading}°, tilt "
                       f"{math.degrees(truth['tilt_rad']):.1f}°")
        if self.fault is not None:
            out.append(f"  STOPPED: {self.fault.describe()}")
        elif self.ended == "stopped":
            out.append("  stopped on request, standing")
        return out

    def _travel_lines(self) -> list[str]:
        """Where the feet took it (leg odometry, planned walks) and the gyro's heading, for people."""
        t, out = self.travel, []
        if "distance_m" in t:
            out.append(f"  leg odometry: x {t['x_m']:+.3f} m, y {t['y_m']:+.3f} m, {t['distance_m']:.3f} m in all")
        if "gyro_heading_deg" in t:
            out.append(f"  heading by the gyro: {signed_text(t['gyro_heading_deg'], 1)}°")
        return out


def read_status(port: RobotPort, spec: Spec) -> RobotStatus:
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


@dataclass(frozen=True)
class Limp:
    """What :func:`teach` lets go limp: ``joints`` (official names, e.g. from
    :func:`~op2motion.robot.limbs.select_joints`); ``confirm(question)``, which must say yes before any torque goes off
    (the question names the joints and, for a standing robot's legs, that it will sag and fall); and the time to
    move them by hand: once they are limp, ``wait()`` (e.g. until Enter), then ``wait_s`` seconds on the robot's clock
    (simulated time on an emulated robot in lockstep)."""

    joints: tuple[str, ...]
    confirm: Callable[[str], bool]
    wait: Callable[[], None] | None = None
    wait_s: float | None = None


def limp_question(spec: Spec, joints: tuple[str, ...], tilt_rad: float) -> str:
    """What :func:`teach` asks before ``joints`` go limp on a robot tilted ``tilt_rad``: a standing robot (tilted
    less than :data:`~op2motion.robot.imu.FALL_TILT_RAD`) whose legs are among them is told it will sag and fall."""
    what = describe_joints(joints, spec.joint_names)
    if set(joints) & set(limb_groups(spec.joint_names)["legs"]) and tilt_rad < FALL_TILT_RAD:
        return (f"switch the torque off in {what}, though the robot stands (tilted {math.degrees(tilt_rad):.0f}°): "
                f"its legs give way and it will sag and fall unless you hold it up?")
    return f"switch the torque off in {what} (they go limp: hold them)?"


def teach(port: RobotPort, spec: Spec, name: str, support: Support | SupportName = "double",
          limp: Limp | None = None, force: bool = False) -> tuple[Pose, list[str]]:
    """The robot's present joint angles as a pose. With ``limp`` (:class:`Limp`), once it confirms, its joints'
    torque goes off while every other joint holds, the user moves them, the angles are read, and the limp joints hold
    where they were left (:func:`_read_limp`). A robot found fallen (tilted beyond
    :data:`~op2motion.robot.imu.FALL_TILT_RAD`), before going limp or at the read, is refused (exit 1, before
    anything moved or with nothing to write) unless ``force``: then its pose says ``fallen`` in its provenance and a
    note says so. Angles beyond a joint's mechanical range are clipped to it (a note says so)."""
    with Session(port, spec) as session:
        state = _whole(session)
        start_rad = state.board.tilt_rad
        if start_rad > FALL_TILT_RAD and not force:
            raise CheckFailed(f"refused: the robot lies (tilted {math.degrees(start_rad):.0f}°): a pose read from it "
                              f"is a fallen robot's; --force reads it, marked fallen")
        joints = limp.joints if limp is not None else ()
        if limp is not None and joints:
            state = _read_limp(session, state, limp)
        tilt_rad = state.board.tilt_rad
        fallen = tilt_rad > FALL_TILT_RAD
        if fallen and not force:
            raise CheckFailed(f"refused: the robot fell while limp (tilted {math.degrees(tilt_rad):.0f}°, from "
                              f"{math.degrees(start_rad):.0f}°): nothing written; its joints hold where it lies; "
                              f"--force writes a fallen robot's pose, marked fallen")
        lower, upper = mechanical_bounds(spec)
        angles, clipped = clip_goals(state.servo_angles, lower, upper)
        notes = [f"{spec.joint_names[i]} read {math.degrees(state.servo_angles[i]):.1f}°, beyond its mechanical "
                 f"range: clipped to {math.degrees(angles[i]):.1f}°" for i in np.flatnonzero(clipped)]
        if fallen:
            notes.insert(0, f"the robot lies (tilted {math.degrees(tilt_rad):.0f}°): a fallen robot's pose, marked "
                            f"fallen in the file (--force)")
        pose = Pose(name, Support.of(support), angles, {},
                    {"source": "robot", "port": session.path, "limp": bool(joints), "limp_joints": list(joints),
                     "tilt_deg": round(math.degrees(tilt_rad), 1), "fallen": fallen})
        return pose.checked(spec), notes


def _whole(session: Session) -> RobotStatus:
    """The whole robot read; a servo that does not answer is refused (exit 1): a pose needs every joint."""
    state = session.status()
    missing = [f"{s.joint} (ID {s.id})" for s in state.servos if not s.answers]
    if missing:
        raise CheckFailed(f"cannot read a whole pose: {', '.join(missing)} not answering")
    return state


def _read_limp(session: Session, state: RobotStatus, limp: Limp) -> RobotStatus:
    """Ask ``limp.confirm`` (a no: exit 2, nothing done); hold every other joint (a servo whose torque is off, as on
    a robot just powered, switched on where it is); switch the torque off in ``limp.joints``; wait; read the whole
    robot; and, however the wait ends (Ctrl-C too), switch those joints on again where they are, so nothing jumps."""
    robot, spec = session.robot, session.spec
    if not limp.confirm(limp_question(spec, limp.joints, state.board.tilt_rad)):
        raise InputError("not confirmed: nothing done (--yes confirms)", "yes")
    others = {s.id: s.position_rad for s in state.servos if s.joint not in limp.joints and not s.torque_on}
    if others:
        robot.take_control(others)
    devices = [s.id for s in state.servos if s.joint in limp.joints]
    robot.torque(False, devices)
    held: dict[int, float] | None = None
    try:
        if limp.wait is not None:
            limp.wait()
        if limp.wait_s is not None and session.port is not None:
            sleep(session.port.clock, limp.wait_s)      # the robot's clock: simulated time moves on in lockstep
        after = _whole(session)
        held = {s.id: s.position_rad for s in after.servos if s.id in devices}     # held as read: as in the pose
        return after
    finally:
        held = robot.positions(devices) if held is None else held
        if held:
            robot.take_control(held)


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
    """:meth:`~op2motion.bus.session.Session.take_control` as the run ``name`` of ``result`` begins; whether it did (a
    port that fails there ends the run as the fault ``port failed``, in ``result``)."""
    try:
        session.take_control(state)
    except PortFailed as exc:
        result.runs.append((name, LoopReport(ended="fault", fault=port_fault(exc))))
        return False
    return True
