"""The bus's speed figures for ``op2motion bench``: the 8 ms loop and a full status read through the emulated OP2,
which runs beside them in its own process (``op2motion robot emulate``, the real wire: 1 Mbps, return delays, the
FTDI's packets and a 1 ms latency timer), as it would on a robot's two cores; and the same loop in lockstep.

* ``robot_loop_p99_ms`` (with p50 and max): the loop's period, tick start to tick start, holding the standing pose
  for :data:`LOOP_S` (one bulk read and one sync write a tick); the check: its missed reads;
* ``robot_bulk_read_wire_ms`` and ``robot_bulk_read_ms``: a tick's bulk read as planned, its bytes and return delays
  on the wire alone, and with the link's measured tail; ``robot_servos_per_tick`` and ``robot_ping_ms`` (the
  board's round trip, median);
* ``robot_status_ms``: the board and all 20 servos read in full (21 reads), best of :data:`STATUS_REPEAT`; the
  check: every servo answered;
* ``robot_lockstep_speedup``: simulated seconds of the same loop in lockstep per wall second.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.physics import EngineName

LOOP_S = 3.0                       # the loop runs this long
STATUS_REPEAT = 5
START_TIMEOUT_S = 60.0             # the emulator must serve within this long


def robot_figures(spec: Spec, engine: EngineName = "mujoco") -> JsonObject:
    """The figures (see the module docstring), the emulator (``engine``) in a process of its own."""
    from op2motion.bus.loop import run_controller
    from op2motion.bus.session import Session
    from op2motion.physics import Schedule
    from op2motion.robot.joints import BookAngles, book_to_servo

    with tempfile.TemporaryDirectory(prefix="op2-bench-") as folder:
        link = Path(folder) / "op2"
        emulator = subprocess.Popen([sys.executable, "-m", "op2motion", "robot", "emulate", "--link", str(link),
                                     "--engine", engine], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + START_TIMEOUT_S
            while not os.path.lexists(link):
                if emulator.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError("the emulated OP2 did not start")
                time.sleep(0.05)
            best, answered = float("inf"), 0
            with Session(str(link), spec) as session:
                for _ in range(STATUS_REPEAT):
                    t0 = time.perf_counter()
                    status = session.status()
                    best = min(best, time.perf_counter() - t0)
                    answered = sum(s.answers for s in status.servos)
                session.ready_for_motion()
                stand = book_to_servo(BookAngles.standing("left"), spec)[0]
                report = run_controller(Schedule.hold(stand, "double", spec, LOOP_S + 1.0), session.robot,
                                        duration_s=LOOP_S)
        finally:
            emulator.send_signal(signal.SIGTERM)
            try:
                emulator.wait(timeout=10)
            except subprocess.TimeoutExpired:
                emulator.kill()
    median = status.link.median_round_trip_s if status.link is not None else None
    lockstep_s, lockstep_speedup = _lockstep_speedup(spec, engine)
    return {"robot_loop_p50_ms": round(report.period_p50_ms, 3), "robot_loop_p99_ms": round(report.period_p99_ms, 3),
            "robot_loop_max_ms": round(report.period_max_ms, 3), "robot_loop_ticks": report.ticks,
            "robot_emulator_engine": engine, "robot_status_ms": round(best * 1000.0, 2),
            "robot_bulk_read_wire_ms": report.plan.get("bulk_read_wire_ms"),
            "robot_bulk_read_ms": report.plan.get("bulk_read_ms"),
            "robot_servos_per_tick": report.plan.get("servos_per_tick"),
            "robot_ping_ms": None if median is None else median * 1000.0,
            "robot_lockstep_speedup": lockstep_speedup, "check_robot_lockstep_s": round(lockstep_s, 3),
            "check_robot_loop_missed_reads": report.missed_reads, "check_robot_status_servos": answered}


def _lockstep_speedup(spec: Spec, engine: EngineName) -> tuple[float, float]:
    """How long the loop ran [simulated s] and its simulated seconds per wall second: :data:`LOOP_S` of the standing
    hold in lockstep behind the real wire (run for its duration, as :func:`robot_figures` runs it: a hold is done at
    once, so until done it would end after a tick)."""
    from op2motion.bus.emulator.lockstep import LockstepPort
    from op2motion.bus.emulator.server import Emulator
    from op2motion.bus.loop import run_controller
    from op2motion.bus.session import Session
    from op2motion.physics import Schedule
    from op2motion.robot.joints import BookAngles, book_to_servo

    emulator = Emulator(spec, engine)
    try:
        stand = book_to_servo(BookAngles.standing("left"), spec)[0]
        with Session(LockstepPort(emulator), spec) as session:
            session.ready_for_motion()
            t0 = time.perf_counter()
            report = run_controller(Schedule.hold(stand, "double", spec, LOOP_S + 1.0), session.robot,
                                    duration_s=LOOP_S)
            wall = time.perf_counter() - t0
        return report.seconds, round(report.seconds / wall, 2)
    finally:
        emulator.close()
