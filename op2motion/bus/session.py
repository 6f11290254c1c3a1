"""One session with the robot: the port opened (:func:`~.port.open_port`), the board found and the servos powered
(:meth:`~.robot.OP2.connect`), the whole robot read (:class:`RobotStatus`), and before a motion the preflight and
the torque switched on without a jump (:meth:`Session.ready_for_motion`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from op2motion.bus.client import Bus
from op2motion.bus.port import Port, open_port
from op2motion.bus.robot import OP2, BoardState, ServoState
from op2motion.bus.safety import Fault, preflight, preflight_problems
from op2motion.errors import CheckFailed
from op2motion.robot.spec import Spec


@dataclass(frozen=True)
class RobotStatus:
    """The board, every servo, and what is wrong (missing or erring servos, hot servos, a low supply)."""

    board: BoardState
    servos: tuple[ServoState, ...]
    problems: tuple[Fault, ...]
    powered_now: bool

    @property
    def servo_angles(self) -> np.ndarray:
        """The present positions (20,) [rad] in the spec's joint order (a silent servo: 0)."""
        return np.array([s.position_rad for s in self.servos])

    @property
    def ok(self) -> bool:
        """All well: every servo answers, none reports an error, none is hot, the supply is within rating."""
        return not self.problems

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"ok": self.ok, "board": self.board.as_dict(), "servos": [s.as_dict() for s in self.servos],
                "problems": [p.as_dict() for p in self.problems], "powered_now": self.powered_now}

    def lines(self) -> list[str]:
        """For people: the board, one line per servo, the problems."""
        b = self.board
        out = [f"CM-730 (ID 200): model {b.model_number:#06x}, firmware {b.firmware}, servos' power "
               f"{'on' if b.power else 'off'}{' (switched on now)' if self.powered_now else ''}, supply "
               f"{b.voltage_v:.1f} V",
               f"  IMU: gyro {', '.join(f'{v:+.3f}' for v in b.gyro_rad_s)} rad/s, accelerometer "
               f"{', '.join(f'{v:+.2f}' for v in b.accel_m_s2)} m/s² (x forward, y left, z up): tilt "
               f"{math.degrees(b.tilt_rad):.1f}° (pitch {math.degrees(b.pitch_rad):+.1f}°, roll "
               f"{math.degrees(b.roll_rad):+.1f}°)"]
        for s in self.servos:
            if not s.answers:
                out.append(f"  {s.id:2d} {s.joint:12s} NOT ANSWERING")
                continue
            model = "MX-28" if s.model_number == 29 else f"model {s.model_number}"
            out.append(f"  {s.id:2d} {s.joint:12s} {model} fw {s.firmware}: {math.degrees(s.position_rad):+7.2f}°, "
                       f"{s.temperature_c:3d} °C, {s.voltage_v:4.1f} V, torque {'on ' if s.torque_on else 'off'}"
                       f"{', ERRORS: ' + ', '.join(s.errors) if s.errors else ''}")
        out += [f"  problem: {p.describe()}" for p in self.problems]
        return out


class Session:
    """The robot on ``port`` for the length of a ``with`` block (see the module docstring)."""

    def __init__(self, port: str, spec: Spec):
        self.path, self.spec = port, spec
        self.port: Port | None = None
        self.robot: OP2 = None  # type: ignore[assignment]
        self.powered_now = False

    def __enter__(self) -> "Session":
        self.port = open_port(self.path)
        try:
            self.robot = OP2(Bus(self.port), self.spec)
            self.robot.connect(power=False)
            self.powered_now = self.robot.power_on()
        except BaseException:
            self.port.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self.port is not None:
            self.port.close()

    def status(self) -> RobotStatus:
        """The board and every servo read in full, with the problems."""
        board = self.robot.board()
        if board is None:
            raise CheckFailed("the sub-controller (ID 200) stopped answering")
        servos = tuple(self.robot.servos())
        return RobotStatus(board, servos, tuple(preflight_problems(board, servos, self.spec)), self.powered_now)

    def preflight(self, status: RobotStatus) -> None:
        """Refuse (exit 1) a robot unfit for a motion (:func:`~.safety.preflight`)."""
        preflight(status.board, status.servos, self.spec)

    def take_control(self, status: RobotStatus, p_gains: dict[int, int] | None = None) -> None:
        """The gyro's zero-rate counts measured while the robot is still (as the framework does before it moves
        anything), then every torque on with the goals where the joints are (as ``status`` read them)."""
        self.robot.calibrate_gyro()
        failed = self.robot.take_control({s.id: s.position_rad for s in status.servos}, p_gains)
        if failed:
            names = ", ".join(f"{self.robot.joint_of[d]} (ID {d})" for d in failed)
            raise CheckFailed(f"the torque could not be switched on: {names} did not confirm")

    def ready_for_motion(self, p_gains: dict[int, int] | None = None) -> RobotStatus:
        """:meth:`status`, :meth:`preflight` and :meth:`take_control` in one."""
        status = self.status()
        self.preflight(status)
        self.take_control(status, p_gains)
        return status
