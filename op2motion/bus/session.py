"""One session with the robot: the port opened (:func:`~.port.open_port`; ``lockstep[:...]``: an emulated OP2 in
this process, :mod:`.emulator.lockstep`), the board found, the link measured and the servos powered
(:meth:`~.robot.OP2.connect`: a board of another model is refused there), the whole robot read (:class:`RobotStatus`:
with the link and each servo's return delay; a servo of another model is refused, naming it: exit 2, nothing
written to it), and before a motion the preflight, the tick's read plan from the link's budget (a link too slow for the
8 ms loop is refused, naming the latency timer: exit 2, nothing moved) and the torque switched on without a jump
(:meth:`Session.ready_for_motion`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from op2motion.bus.client import Bus
from op2motion.bus.link import MIN_SERVOS_PER_TICK, LinkCheck, ReadPlan, read_plan, too_slow, tried_plan
from op2motion.bus.port import PortLike, PortRequest, RobotPort, open_port
from op2motion.bus.robot import OP2, BoardState, ServoState
from op2motion.bus.safety import (
    Fault,
    Refused,
    mechanical_bounds,
    out_of_range,
    preflight,
    preflight_problems,
    refuse_other_models,
)
from op2motion.bus.tables import CM730_ID, model_name
from op2motion.errors import CheckFailed
from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec

HOLD_AFTER_S = 0.5                 # an emulated OP2 of the session's own holds its last goals this long at its end


@dataclass(frozen=True)
class RobotStatus:
    """The board, every servo, and what is wrong (missing or erring servos, hot servos, a low supply)."""

    board: BoardState
    servos: tuple[ServoState, ...]
    problems: tuple[Fault, ...]
    powered_now: bool
    link: LinkCheck | None = None
    plan: ReadPlan | None = None

    @property
    def warnings(self) -> list[str]:
        """What is not a fault but costs the loop: a link too slow for it (the latency timer), servos whose return
        delay keeps a tick from reading them all."""
        if self.plan is None:
            return []
        if self.plan.servos_per_tick == 0:
            timer = self.link.latency_timer_ms if self.link is not None else None
            return [f"the link is too slow for the 8 ms loop (a tick's read of the sub-controller alone takes "
                    f"{self.plan.tick_s * 1000:.1f} ms): motions are refused; the FTDI adapter's latency timer is "
                    f"{'unknown' if timer is None else f'{timer} ms'}: set it to 1 ms (docs/robot.md)"]
        slow = [s.return_delay for s in self.servos if s.answers and s.return_delay > 0]
        if self.plan.servos_per_tick >= self.plan.count or not slow:
            return []
        return [f"{len(slow)} servos have a return delay of up to {max(slow)} ({max(slow) * 2} µs each): the 8 ms "
                f"loop can read only {self.plan.servos_per_tick} of {self.plan.count} servos a tick; set it to 0 with "
                f"'op2motion robot setup --port PORT --return-delay 0'"]

    @property
    def servo_angles(self) -> np.ndarray:
        """The present positions (20,) [rad] in the spec's joint order (a silent servo: 0)."""
        return np.array([s.position_rad for s in self.servos])

    @property
    def ok(self) -> bool:
        """All well: every servo answers, none reports an error, none is hot, the supply is within rating."""
        return not self.problems

    def as_dict(self) -> JsonObject:
        """JSON-ready."""
        return {"ok": self.ok, "board": self.board.as_dict(), "servos": [s.as_dict() for s in self.servos],
                "problems": [p.as_dict() for p in self.problems], "powered_now": self.powered_now,
                "link": None if self.link is None else self.link.as_dict(),
                "read_plan": None if self.plan is None else self.plan.as_dict(), "warnings": self.warnings}

    def lines(self) -> list[str]:
        """For people: the board, one line per servo, the problems."""
        b = self.board
        out = [f"{model_name(b.model_number) or 'sub-controller'} (ID {CM730_ID}): model {b.model_number:#06x}, "
               f"firmware {b.firmware}, servos' power "
               f"{'on' if b.power else 'off'}{' (switched on now)' if self.powered_now else ''}, supply "
               f"{b.voltage_v:.1f} V, return delay {b.return_delay * 2} µs",
               f"  IMU: gyro {', '.join(f'{v:+.3f}' for v in b.gyro_rad_s)} rad/s, accelerometer "
               f"{', '.join(f'{v:+.2f}' for v in b.accel_m_s2)} m/s² (x forward, y left, z up): tilt "
               f"{math.degrees(b.tilt_rad):.1f}° (pitch {math.degrees(b.pitch_rad):+.1f}°, roll "
               f"{math.degrees(b.roll_rad):+.1f}°)"]
        for s in self.servos:
            if not s.answers:
                out.append(f"  {s.id:2d} {s.joint:12s} NOT ANSWERING")
                continue
            model = model_name(s.model_number) or f"model {s.model_number}"
            out.append(f"  {s.id:2d} {s.joint:12s} {model} fw {s.firmware}: {math.degrees(s.position_rad):+7.2f}°, "
                       f"{s.temperature_c:3d} °C, {s.voltage_v:4.1f} V, torque {'on ' if s.torque_on else 'off'}, "
                       f"return delay {s.return_delay * 2} µs{' (SLOW)' if s.return_delay and self.warnings else ''}"
                       f"{', ERRORS: ' + ', '.join(s.errors) if s.errors else ''}")
        if self.link is not None:
            out.insert(1, f"  {self.link.describe()}" + (
                f"; the 8 ms loop's read: {self.plan.servos_per_tick} of {self.plan.count} servos a tick, "
                f"{self.plan.tick_s * 1000:.2f} ms ({self.plan.wire_s * 1000:.2f} ms on the wire)"
                if self.plan is not None else ""))
        out += [f"  problem: {p.describe()}" for p in self.problems]
        out += [f"  warning: {w}" for w in self.warnings]
        return out


class Session:
    """The robot on ``port`` (a path, a :class:`~.port.PortRequest`: a path and how to open it, or an open port) for
    the length of a ``with`` block (see the module docstring)."""

    def __init__(self, port: RobotPort, spec: Spec):
        self.spec = spec
        self.request = PortRequest(port) if isinstance(port, str) else port if isinstance(port, PortRequest) else None
        self.given: PortLike | None = None if isinstance(port, (str, PortRequest)) else port
        self.path = port if isinstance(port, str) else port.path
        self.port: PortLike | None = None
        self.robot: OP2 = None  # type: ignore[assignment]
        self.powered_now = False
        self.emulated: Any = None                       # an emulator this session made (``lockstep:``), or None

    def _open(self) -> PortLike:
        if self.given is not None:
            return self.given
        from op2motion.bus.emulator.lockstep import is_lockstep, lockstep_robot

        if is_lockstep(self.path):               # nothing else can hold an emulator in this process: shared or not
            port = lockstep_robot(self.path, self.spec)
            self.emulated = port.emulator
            return port
        return open_port(self.path, shared=self.request is not None and self.request.shared)

    def __enter__(self) -> "Session":
        self.port = self._open()
        try:
            self.robot = OP2(Bus(self.port), self.spec)
            self.robot.connect(power=False)
            self.powered_now = self.robot.power_on()
        except BaseException:
            self.port.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self.emulated is not None and self.port is not None:
            self.port.clock.sleep_until(self.port.clock.now() + HOLD_AFTER_S)
        if self.port is not None and self.given is None:
            self.port.close()
        if self.emulated is not None:
            self.emulated.close()

    def status(self) -> RobotStatus:
        """The board and every servo read in full, with the problems; a device of another model is refused
        (:class:`~.safety.WrongModel`, exit 2) before anything is written to it."""
        board = self.robot.board()
        if board is None:
            raise CheckFailed("the sub-controller (ID 200) stopped answering")
        servos = tuple(self.robot.servos())
        refuse_other_models(board, servos)
        return RobotStatus(board, servos, tuple(preflight_problems(board, servos, self.spec)), self.powered_now,
                           self.robot.link, read_plan(self.robot.bus.link, self.robot.ids))

    def preflight(self, status: RobotStatus) -> None:
        """Refuse (exit 2) a link too slow for the 8 ms loop: a tick's read holds fewer than
        :data:`~.link.MIN_SERVOS_PER_TICK` servos beside the board (the latency timer, the servos' return delay), as
        planned from the link's figures and as tried on it (:func:`~.link.tried_plan`, whose plan the loop then
        reads by); and (exit 1) a robot unfit for a motion (:func:`~.safety.preflight`)."""
        plan = status.plan or read_plan(self.robot.bus.link, self.robot.ids)
        if plan.servos_per_tick:
            plan = tried_plan(self.robot.bus, self.robot.ids, plan)
        if plan.servos_per_tick < min(MIN_SERVOS_PER_TICK, plan.count):
            board = read_plan(self.robot.bus.link, ()).tick_s
            raise too_slow(self.robot.link or LinkCheck(None, "", (), self.robot.bus.link.tail_s), board, self.path,
                           plan.servos_per_tick, max((s.return_delay for s in status.servos), default=0))
        self.robot.plan = plan
        preflight(status.board, status.servos, self.spec)

    def take_control(self, status: RobotStatus, p_gains: dict[int, int] | None = None) -> None:
        """The gyro's zero-rate counts measured while the robot is still (as the framework does before it moves
        anything), then every torque on with the goals where the joints are (as ``status`` read them), never outside
        the mechanical ranges: a reading beyond one is refused (exit 1, naming the joint) unless within
        :data:`~.safety.RANGE_SLACK_RAD`, where its goal is the range's end."""
        beyond = [Fault("out of range", s.joint, s.id, why) for s in status.servos
                  if (why := out_of_range(s.joint, s.position_rad, self.spec))]
        if beyond:
            raise Refused("refused to switch the torque on: " + beyond[0].describe())
        lower, upper = mechanical_bounds(self.spec)
        index = {n: i for i, n in enumerate(self.spec.joint_names)}
        goals = {s.id: float(np.clip(s.position_rad, lower[index[s.joint]], upper[index[s.joint]]))
                 if s.joint in index else s.position_rad for s in status.servos}
        self.robot.calibrate_gyro()
        failed = self.robot.take_control(goals, p_gains)
        if failed:
            names = ", ".join(f"{self.robot.joint_of[d]} (ID {d})" for d in failed)
            raise CheckFailed(f"the torque could not be switched on: {names} did not confirm")

    def ready_for_motion(self, p_gains: dict[int, int] | None = None) -> RobotStatus:
        """:meth:`status`, :meth:`preflight` and :meth:`take_control` in one."""
        status = self.status()
        self.preflight(status)
        self.take_control(status, p_gains)
        return status
