"""The framework's 8 ms loop on the real robot: :func:`run_controller` runs any physics
:class:`~op2motion.physics.Controller` (a :class:`~op2motion.gait.controller.WalkController`, a played page, a
planned motion, a Cartesian line) on the OP2, unchanged.

Every :data:`~op2motion.robot.framework.CONTROL_PERIOD_S`, on an absolute clock:

1. **one bulk read** (:class:`~.link.ReadPlan`, from the link's budget): the board's 30 bytes from register 24
   (power, buttons, gyro, accelerometer, voltage) and each servo's present position, or as many servos as the link
   lets a tick read within :data:`~.link.READ_BUDGET_S` (their return delays, the USB adapter's tail), in turn;
   one servo in turn reads present position to temperature (8 bytes: speed, load, voltage, temperature), so every
   servo's full state comes every 20 ticks at the cost of 6 bytes a tick. Devices that did not answer are asked
   once more in the same tick if the budget still holds that read (after any late reply can have come); a device
   still silent keeps its last values (a missed read);
2. the safety watch (:class:`~.safety.Watch`): missed reads in a row, error bits, temperature, a fall;
3. the controller, as in physics (``start`` at 0, then ``step`` at the plan's ticks with the gyro, accelerometer
   and joint positions); the goals are clipped to the mechanical ranges;
4. **one sync write** from register 26, 6 bytes a servo: D, I, P, 0, goal (the framework's own packet).

All time is the port's clock (:mod:`.clock`): the wall on a real robot, simulated time in lockstep with an emulated
one. The loop measures its period (tick start to tick start: p50, p99, max), counts late ticks and missed reads, and
ends when the plan's duration is over (or the controller is done, when asked to end then), on a fault
(:mod:`.safety`'s policy), on a stop request (Ctrl-C: a controller that can stop itself, a walk, is told to and
ends done, within :data:`~.stopping.SOFT_STOP_MAX_S`, its feet side by side; a walk's plan played open loop first
reaches its next double support, so it stops on both feet, at most a step later), or at once when the port fails
(:class:`~op2motion.errors.PortFailed`: the fault ``port failed``, the report still returned with what the run did
until then). A controller's ``torque_limits`` are written when they change.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from op2motion.bus import safety
from op2motion.bus.link import READ_BUDGET_S, read_plan
from op2motion.bus.port import RobotPort
from op2motion.bus.realtime import LOOP_PRIORITY, realtime, steady
from op2motion.bus.robot import OP2, angle_of
from op2motion.bus.stopping import Stops
from op2motion.bus.tables import (
    BOARD_SPAN,
    CM730_ID,
    MX28,
    SERVO_STATE_SPAN,
    SYNC_SPAN,
    TORQUE_LIMIT_FULL,
)
from op2motion.errors import CheckFailed, InputError, PortFailed
from op2motion.jsonout import JsonObject
from op2motion.robot.controller import Controller, GoalMerger
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.imu import decode_imu
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.spec import Spec

READ_MARGIN_S = 0.0003            # the bulk read's allowance beyond the link's figures (the PC's scheduling)
START_JUMP_RAD = math.radians(8.0)   # a controller's first goals may be this far from where the joints are (a
                                     # servo's sag under load); further needs a planned move first (refused here)
LATE_S = 0.020                     # a period longer than this is a late tick
MAX_P_GAIN = 254


@dataclass(frozen=True)
class Tick:
    """What one tick saw and sent: its index, the controller's time [s], the plan's row, the joint positions (20,)
    [rad], gyro [rad/s] and accelerometer [m/s²] (torso frame), the goals sent (20,) [rad]."""

    index: int
    t_s: float
    row: int
    positions: np.ndarray
    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    goals: np.ndarray


@dataclass
class LoopReport:
    """One run of the loop: ticks, seconds, the period's p50/p99/max [ms], late ticks (period over
    :data:`LATE_S`), missed reads (device reads that held their last values), ticks that needed a second read,
    the longest run of missed reads of one device, clipped goals per joint, how it ended (``done``, ``stopped``,
    ``fault``), the fault, the last goals and positions (20,) [rad], the integrated gyro yaw [rad], the largest
    tilt [rad], the bus's counters, whether the loop ran at real-time priority (:mod:`.realtime`), and the last
    plan row it played (a stop's frozen row)."""

    ticks: int = 0
    seconds: float = 0.0
    period_p50_ms: float = 0.0
    period_p99_ms: float = 0.0
    period_max_ms: float = 0.0
    late_ticks: int = 0
    missed_reads: int = 0
    retried_ticks: int = 0
    max_blind_ticks: int = 0
    clipped: dict[str, int] = field(default_factory=dict)
    ended: str = "done"
    fault: safety.Fault | None = None
    goals: np.ndarray = field(default_factory=lambda: np.zeros(0))
    positions: np.ndarray = field(default_factory=lambda: np.zeros(0))
    yaw_rad: float = 0.0
    tilt_max_rad: float = 0.0
    bus: dict[str, Any] = field(default_factory=dict)
    realtime: bool = False
    plan: dict[str, Any] = field(default_factory=dict)
    last_row: int = -1

    def as_dict(self) -> JsonObject:
        """JSON-ready (angles in degrees)."""
        return {"ticks": self.ticks, "seconds": round(self.seconds, 3),
                "period_ms": {"p50": round(self.period_p50_ms, 3), "p99": round(self.period_p99_ms, 3),
                              "max": round(self.period_max_ms, 3)},
                "late_ticks": self.late_ticks, "missed_reads": self.missed_reads,
                "retried_ticks": self.retried_ticks, "max_blind_ticks": self.max_blind_ticks,
                "clipped": dict(self.clipped), "ended": self.ended,
                "fault": None if self.fault is None else self.fault.as_dict(),
                "yaw_deg": round(math.degrees(self.yaw_rad), 2),
                "tilt_max_deg": round(math.degrees(self.tilt_max_rad), 1),
                "bus": dict(self.bus), "realtime": self.realtime, "read_plan": dict(self.plan)}

    def describe(self) -> str:
        """One line of timing and reads."""
        return (f"{self.ticks} ticks in {self.seconds:.2f} s: period p50 {self.period_p50_ms:.2f} ms, p99 "
                f"{self.period_p99_ms:.2f} ms, max {self.period_max_ms:.2f} ms, {self.late_ticks} late; "
                f"{self.missed_reads} missed reads (longest {self.max_blind_ticks} ticks), "
                f"{self.retried_ticks} ticks read twice")


def controller_time(k: int, phase_s: float) -> float:
    """The controller's time [s] at tick ``k``: 0 at the start, then the plan's ticks (the physics loop's: rows
    change on a tick, ``phase_s`` into each period)."""
    if k == 0:
        return 0.0
    return k * CONTROL_PERIOD_S - (CONTROL_PERIOD_S - phase_s) % CONTROL_PERIOD_S


class _Run:
    """The state of one loop run."""

    def __init__(self, controller: Controller[Any], robot: OP2, watch: bool):
        self.controller, self.robot = controller, robot
        self.spec: Spec = robot.spec
        self.names = self.spec.joint_names
        self.ids = robot.ids
        self.merger = GoalMerger(controller, self.names)
        self.index = self.merger.index
        self.lower, self.upper = safety.mechanical_bounds(self.spec)
        self.watch = safety.Watch(self.spec, robot.imu, CONTROL_PERIOD_S, self.ids, self.names,
                                  falls=not self.merger.hooks.handles_falls) if watch else None
        if self.merger.hooks.takes_foot_forces:
            raise InputError("expected a controller that runs without foot forces (the OP2 does not measure them)",
                             "controller")
        known = robot.positions()                        # a tick reads only some servos: start from all of them
        self.positions = np.array([known.get(d, 0.0) for d in self.ids])
        self.words = {c.register: robot.imu.centre_count for c in (*robot.imu.gyro, *robot.imu.accel)}
        self.gyro, self.accel = np.zeros(3), np.zeros(3)
        self.goals = np.zeros(len(self.names))
        self.report = LoopReport()
        self.answered: set[int] = set()
        self.got: dict[int, Any] = {}
        self.rotating: int | None = self.ids[0]
        self.limits: np.ndarray | None = None          # torque limits a controller set (None: full)
        self.plan = robot.plan or read_plan(robot.bus.link, self.ids)
        self.report.plan = self.plan.as_dict()
        self.asked: set[int] = set()

    def read(self, k: int, started: float) -> set[int]:
        """One bulk read (and one retry for the silent devices if the budget holds it); the devices that
        answered."""
        spans, rotating = self.plan.spans(k, self.ids)
        bus = self.robot.bus
        until = started + READ_BUDGET_S
        got = bus.bulk_read(spans, READ_MARGIN_S, until)
        missing = [s for s in spans if s[0] not in got]
        if missing:
            resend = max(bus.clock.now(), bus.owed_until if bus.owed else 0.0)
            if resend + bus.link.bulk_read_s(missing) + READ_MARGIN_S <= until:
                self.report.retried_ticks += 1
                bus.settle()
                got.update(bus.bulk_read(missing, READ_MARGIN_S, until))
        self.report.missed_reads += len(spans) - len(got)
        self.asked = {s[0] for s in spans}
        board = got.get(CM730_ID)
        board_address = BOARD_SPAN[0]
        if board is not None:
            data = board.params
            self.words = {r: data[r - board_address] | (data[r - board_address + 1] << 8) for r in self.words}
            self.gyro, self.accel = decode_imu(self.robot.imu, self.words, self.robot.gyro_centre)
        for i, d in enumerate(self.ids):
            packet = got.get(d)
            if packet is not None:
                ticks = packet.params[0] | (packet.params[1] << 8)
                self.positions[i] = angle_of(ticks, self.spec)
        self.got = got
        self.rotating = rotating
        return set(got)

    def check(self, answered: set[int]) -> safety.Fault | None:
        """The safety watch on this tick's reads."""
        if self.watch is None:
            return None
        fault = self.watch.reads(answered, self.asked)
        temperature_at = MX28["present_temperature"].address - SERVO_STATE_SPAN[0]
        for d, packet in self.got.items():
            if d == CM730_ID:
                continue
            temperature = packet.params[temperature_at] if d == self.rotating and len(packet.params) > 2 else None
            fault = fault or self.watch.status(d, packet.errors, temperature)
        if CM730_ID in answered:
            fault = fault or self.watch.body(self.accel, self.words)
        self.report.max_blind_ticks = max(self.report.max_blind_ticks, max(self.watch.missed.values()))
        self.report.tilt_max_rad = max(self.report.tilt_max_rad, self.watch.tilt_rad)
        return fault

    def apply(self, goals: Any, row: int) -> np.ndarray:
        """The controller's goals merged into the held ones, clipped; the P gains (20,) to send."""
        self.merger.merge(self.goals, goals)
        clipped, where = safety.clip_goals(self.goals, self.lower, self.upper)
        for i in np.flatnonzero(where):
            self.report.clipped[self.names[i]] = self.report.clipped.get(self.names[i], 0) + 1
        self.goals = clipped
        gains: np.ndarray = np.clip(np.rint(self.merger.p_gains(row)), 0, MAX_P_GAIN).astype(int)
        return gains

    def limit(self) -> None:
        """The controller's torque limits, written when they change (a supervisor lowers them while the robot
        falls)."""
        shares = self.merger.torque_shares()
        if self.limits is None and shares is None:
            return
        values = np.full(len(self.names), TORQUE_LIMIT_FULL) if shares is None else np.rint(
            shares * TORQUE_LIMIT_FULL).astype(int)
        if self.limits is None or not np.array_equal(values, self.limits):
            self.robot.sync("torque_limit", {d: int(values[i]) for i, d in enumerate(self.ids)})
            self.limits = None if shares is None else values

    def send(self, gains: np.ndarray) -> None:
        """The framework's sync write: D, I, P, 0, goal low, goal high for every servo."""
        ticks = servo_to_ticks(self.goals, self.spec)
        address, length = SYNC_SPAN
        self.robot.bus.sync_write(address, length, {
            d: bytes((0, 0, int(gains[i]), 0, int(ticks[i]) & 0xFF, int(ticks[i]) >> 8))
            for i, d in enumerate(self.ids)})


def _percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) * 1000.0 if values else 0.0


def _step(run: _Run, stops: Stops, k: int, now: float, stop: threading.Event | None) -> tuple[float, int]:
    """One tick after its read: the watch, the controller (or the frozen goals), the sync write; (t, row)."""
    controller, report, plan = run.controller, run.report, run.controller.plan
    fault = run.check(run.answered)
    t = controller_time(k, plan.tick_phase_s)
    row = plan.row(t)
    report.yaw_rad += float(run.gyro[2]) * CONTROL_PERIOD_S if k else 0.0
    if fault is not None and report.fault is None:
        report.fault, report.ended = fault, "fault"
        stops.fault(fault, run.robot, plan, row, k, now)
    if stop is not None and stop.is_set() and stops.frozen_at is None and stops.soft_until is None:
        report.ended = "stopped"
        stops.request(plan, row, k, controller, now)
    stops.soft_over(row, now)
    positions = dict(zip(run.names, run.positions.tolist()))
    goals: Any = {}
    if k == 0:
        goals = controller.start(positions)
        run.goals = run.positions.copy()
        jump(goals, run)
    elif not stops.frozen(row, now):
        goals = controller.step(t, run.gyro.copy(), run.accel.copy(), positions)
    if stops.fall_until is not None and now >= stops.fall_until:     # the fall is over: relax where it lies
        run.goals = run.positions.copy()
        run.robot.torque_limit(TORQUE_LIMIT_FULL)
        stops.fall_until, stops.end_at = None, now
    run.send(run.apply(goals, row))
    run.limit()
    return t, row


def jump(goals: Any, run: _Run) -> None:
    """Refuse (before anything is sent) a controller whose first goals are more than :data:`START_JUMP_RAD` from
    where the joints are."""
    far = [(abs(float(v) - run.positions[run.index[n]]), n) for n, v in goals.items() if n in run.index]
    worst, joint = max(far, default=(0.0, ""))
    if worst > START_JUMP_RAD:
        raise CheckFailed(f"refused: the controller's first goal for {joint} is {math.degrees(worst):.0f}° from "
                          f"where the joint is (at most {math.degrees(START_JUMP_RAD):.0f}°): nothing was moved; start "
                          f"it with a path or port (run_controller(controller, port), op2motion.onrobot.walks."
                          f"run_on_robot), which moves the robot there first, checked in physics")


def run_controller(controller: Controller[Any], port: RobotPort | OP2, spec: Spec | None = None, *,
                   duration_s: float | None = None, stop: threading.Event | None = None,
                   on_tick: Callable[[Tick], None] | None = None, watch: bool = True,
                   until_done: bool = False) -> LoopReport:
    """Run ``controller`` on ``port``, an :class:`~.robot.OP2` already taken control of (a session's; a controller
    on a path or an open port starts with :func:`~op2motion.onrobot.walks.run_on_robot`, as every robot command starts
    one: read, preflighted, moved to the controller's first goals first by a planned move checked in physics); a
    controller whose first goals are more than :data:`START_JUMP_RAD` from where the joints are is refused
    (:class:`~op2motion.errors.CheckFailed`, exit 1) before a goal is sent. Every 8 ms on the port's clock
    for ``duration_s`` (default: its plan's duration; with ``until_done`` also ending as soon as the controller is
    done, e.g. a steered walk standing still after its stop, a get-up standing), until ``stop`` is set or a fault
    stops it (see the module docstring). ``on_tick`` gets every :class:`Tick`. The servos keep holding the last
    goals afterwards. The controller's hooks (:class:`~op2motion.physics.controller.ControllerHooks`) are honoured."""
    if not isinstance(port, OP2):
        raise InputError(f"expected an OP2 already taken control of, got {type(port).__name__}: a controller on a "
                         f"port starts with op2motion.onrobot.walks.run_on_robot(port, spec, controller), which "
                         f"moves the robot to its first goals first, checked in physics", "port")
    with steady(), realtime(LOOP_PRIORITY) as report_realtime:        # the collection before the priority
        report = _loop(_Run(controller, port, watch), controller.plan.duration_s if duration_s is None else duration_s,
                       stop, on_tick, until_done)
    report.realtime = report_realtime
    return report


def _loop(run: _Run, duration: float, stop: threading.Event | None, on_tick: Callable[[Tick], None] | None,
          until_done: bool = False) -> LoopReport:
    """The ticks of one run (see :func:`run_controller`)."""
    stops, report = Stops(), run.report
    time = run.robot.bus.clock
    periods: list[float] = []
    time.sleep_until(run.robot.bus.tx_free)             # what an earlier run wrote is out: the reads have the budget
    start = time.now()
    clock, last, k = start, None, 0
    while True:
        now = time.now()
        if now < clock:
            time.sleep_until(clock)
            now = time.now()
        elif now - clock > CONTROL_PERIOD_S:            # far behind (a pause): resync, do not burst
            clock = now
        if last is not None:
            periods.append(now - last)
            report.late_ticks += (now - last) > LATE_S
        last = now
        try:
            run.answered = run.read(k, now)
            t, row = _step(run, stops, k, now, stop)
        except PortFailed as exc:                       # nothing reaches the robot any more: end the run, report it
            report.fault, report.ended = safety.port_fault(exc), "fault"
            break
        if on_tick is not None:
            on_tick(Tick(k, t, row, run.positions.copy(), run.gyro.copy(), run.accel.copy(), run.goals.copy()))
        k += 1
        clock += CONTROL_PERIOD_S
        if stops.over(now, t, duration, lambda: k > 1 and bool(run.controller.done), until_done):
            break
    report.ticks, report.seconds = k, time.now() - start
    report.last_row = stops.frozen_at if stops.frozen_at is not None else row
    report.period_p50_ms, report.period_p99_ms = _percentile(periods, 50), _percentile(periods, 99)
    report.period_max_ms = max(periods) * 1000.0 if periods else 0.0
    report.goals, report.positions = run.goals.copy(), run.positions.copy()
    report.bus = run.robot.bus.stats.as_dict()
    return report
