"""The emulated OP2: what a program on the robot's PC sees on ``/dev/ttyUSB0``, byte for byte.

:class:`Emulator` answers the host's bytes when the wire would (:mod:`.timing`: the request's bytes on the wire, then
the devices of :mod:`.wire` and :mod:`.devices` answering, each after its return delay, and the USB adapter's
packets) and steps the body (:mod:`.body`) in batches of at most :data:`.pty.BATCH_STEPS` physics steps.
:meth:`Emulator.advance` (the body and the wire up to a simulated time) and :meth:`Emulator.receive` (the host's
bytes) serve a lockstep port (:mod:`.lockstep`) and the pseudo-terminal (:mod:`.pty`: made, linked and served in real
time by one thread, no locks).

Faults (:class:`.faults.Faults`) are injected as replies are made and as the body is stepped. :meth:`Emulator.close`
removes the link and closes the pseudo-terminal.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

from op2motion.bus.emulator.body import Drive, EmulatedBody
from op2motion.bus.emulator.faults import Faults
from op2motion.bus.emulator.pty import BATCH_STEPS, PtyServing
from op2motion.bus.emulator.timing import TimedLink, WireTiming, return_delay_s
from op2motion.bus.emulator.wire import BOOT_S, Wire
from op2motion.bus.tables import TORQUE_LIMIT_FULL
from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.physics import EngineName

TRACE_EVERY_S = 0.05               # the ground truth is recorded this often [simulated s]
PUBLISH_EVERY_S = 0.1              # ... and written to the truth file this often
TRUTH_BYTES = 16384                # the truth file's size (its JSON padded with spaces)
REFRESH_S = 0.004                  # the registers follow the body at least this often [simulated s] (and at each
                                   # request answered)


class Emulator(PtyServing):
    """An emulated OP2 (see the module docstring): ``timing`` its wire (default the real one, 1 ms latency timer),
    ``return_delay`` every servo's Return Delay Time register (default 0, as the OP2 ships), ``cold``: the robot just
    switched on (the servos unpowered until a program sets the board's power register; default: powered and holding
    the start pose, as the stock framework leaves them). The board it plays (a CM-730, or a CM-740) is the model
    number the faults give ID 200 (:func:`.faults.with_board`)."""

    def __init__(self, spec: Spec, engine: EngineName = "mujoco", start: str = "standing", faults: Faults | None = None,
                 truth_path: str | Path | None = None, timing: WireTiming | None = None,
                 return_delay: int | None = None, cold: bool = False):
        self.spec = spec
        self.truth_path = None if truth_path is None else Path(truth_path)
        self._truth_map: Any = None
        self.torque_limit_min = TORQUE_LIMIT_FULL
        self.faults = faults or Faults()
        supply = self.faults.supply_v if self.faults.supply_v is not None else spec.servo.supply_voltage_v
        self.body = EmulatedBody(spec, engine, start, supply, self.faults.horn)
        self.engine_name, self.start_kind = engine, start
        self.wire = Wire(spec, self.faults, self._now, self._present_ticks)
        self.timing = timing or WireTiming()
        self.timed_wire = TimedLink(self.timing, self._answer, self._delay_s, self._now())
        self.outbox = bytearray()                  # bytes the wire delivered, for the host to read
        self._next_trace = self._next_publish = 0.0
        self._drive: Drive | None = None            # what the registers ask of the motors, until one is written
        self._stale, self._refreshed_at = False, 0.0
        self.board, self.servos, self.stats = self.wire.board, self.wire.servos, self.wire.stats
        self.master: int | None = None
        self.link: Path | None = None
        self.pty_name = ""
        self.temperature_overrides: dict[int, float] = {}
        self.slipped_s = 0.0
        self.trace: list[dict[str, float]] = []
        self._truth: dict[str, float] = self.body.truth()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._powered_holding()
        if return_delay is not None:
            for servo in self.servos:
                servo.set("return_delay_time", return_delay)
        if cold:                                   # just switched on: the servos unpowered, limp, silent
            self.wire.cold_start()

    # --- setup ---------------------------------------------------------------------------------------------------
    def _powered_holding(self) -> None:
        """The start: servos powered, torque on, holding the start pose (as the stock framework leaves them)."""
        self.board.set("dynamixel_power", 1)
        self.wire.powered_at = -BOOT_S
        ticks = self._present_ticks()
        for servo, tick in zip(self.servos, ticks):
            servo.power_up(tick)
            servo.set("goal_position", int(round(self.body.pose[servo.id - 1] / self.spec.servo.rad_per_tick))
                      + self.spec.servo.center_tick + int(self.body.horn_ticks[servo.id - 1]))
            servo.set("torque_enable", 1)
        self.body.sense(self.servos, self.wire.tables, self.board, self.temperature_overrides)

    def _present_ticks(self) -> list[int]:
        s = self.spec.servo
        return [int(round(q / s.rad_per_tick)) + s.center_tick + int(h)
                for q, h in zip(self.body.joint_angles(), self.body.horn_ticks)]

    def close(self) -> None:
        """Stop serving, remove the link, close the pseudo-terminal, release the engine."""
        self.stop()
        self._refresh()
        self._publish()
        self._close_pty()
        if self._truth_map is not None:
            self._truth_map.close()
            self._truth_map = None
        self.body.close()

    def truth(self) -> dict[str, float]:
        """The simulated torso now: ``t_s``, ``x_m``, ``y_m``, ``z_m``, ``yaw_rad``, ``tilt_rad``."""
        return dict(self._truth)

    def report(self) -> JsonObject:
        """What a program did to the emulated robot, for checking it from outside: the torso now (:meth:`truth`),
        the simulated seconds since the motion started (the first SYNC_WRITE; None before), the lowest torque limit
        any servo has had, each servo's goal [tick], torque enable and torque limit, and the counters."""
        return {"truth": self.truth(), "motion_s": None if self.motion_t0 is None else self._now() - self.motion_t0,
                "torque_limit_min": self.torque_limit_min, "goal_ticks": [s.u16("goal_position") for s in self.servos],
                "torque_enable": [s.get("torque_enable") for s in self.servos],
                "torque_limit": [s.u16("torque_limit") for s in self.servos], "stats": dict(self.stats),
                "slipped_s": round(self.slipped_s, 4)}

    def _publish(self) -> None:
        """Write :meth:`report` into the truth file: JSON padded with spaces to :data:`TRUTH_BYTES`, written into
        the file's memory map (no file-system call that could stall the serving thread; a reader that catches a
        half-written report reads again)."""
        if self.truth_path is None:
            return
        import json
        import mmap

        if self._truth_map is None:
            with open(self.truth_path, "wb") as f:
                f.write(b" " * TRUTH_BYTES)
            with open(self.truth_path, "r+b") as f:
                self._truth_map = mmap.mmap(f.fileno(), TRUTH_BYTES)
        data = json.dumps(self.report()).encode()[:TRUTH_BYTES]
        self._truth_map[:] = data.ljust(TRUTH_BYTES)

    def overheat(self, device: int, celsius: float) -> None:
        """Servo ``device``'s temperature jumps to ``celsius`` now."""
        self.temperature_overrides[device] = float(celsius)
        self._stale = True

    def unplug(self, device: int) -> None:
        """Servo ``device`` goes silent and limp now."""
        self.wire.unplugged.add(device)
        self._drive = None

    @property
    def motion_t0(self) -> float | None:
        """When the motion started (the first SYNC_WRITE) [simulated s]; None before."""
        return self.wire.motion_t0

    # --- time passing ------------------------------------------------------------------------------------------------
    def receive(self, t: float, data: bytes) -> None:
        """The host wrote ``data`` at simulated time ``t`` [s] (the wire model times what follows)."""
        self.advance(t)
        self.timed_wire.send(t, data)
        self.outbox += b"".join(self.timed_wire.run_until(t))       # an instant wire answers at once

    def advance(self, t: float) -> None:
        """Step the body and the wire up to simulated time ``t`` [s]: the requests that reach the devices meanwhile
        are answered from the body as it is then; what the USB adapter sends the host by ``t`` goes to
        :attr:`outbox`."""
        while True:
            event = self.timed_wire.next_event()
            upto = t if event is None or event > t else event
            self._step_to(upto)
            if event is None or event > t:
                break
            self.outbox += b"".join(self.timed_wire.run_until(event))
            if event == t:
                return                  # the wire has run up to t: running it up to t again does nothing
        self.outbox += b"".join(self.timed_wire.run_until(t))

    def _answer(self, t: float, request: bytes) -> list[bytes]:
        """A request reaching the devices at ``t``: their replies, from the registers as the body is now."""
        self._refresh()
        replies = self.wire.feed(request)
        self._drive = None                          # a register may have been written
        return replies

    def _delay_s(self, device: int) -> float:
        """Device ``device``'s return delay [s] (its register 5)."""
        found = self.wire.by_id.get(device)
        return 0.0 if found is None else return_delay_s(found.return_delay)

    def _step_to(self, t: float) -> None:
        """Whole physics steps up to simulated time ``t`` [s] (in batches of :data:`BATCH_STEPS`, the timed faults
        between them); the registers from the body at most every :data:`REFRESH_S` (and whenever a request is
        answered: :meth:`_refresh`)."""
        steps = int((t - self._now()) / self.body.dt + 1e-9)         # int: floor, where it matters (> 0)
        if steps <= 0:
            return
        while steps > 0:
            n = min(steps, BATCH_STEPS)
            self._timed_faults()
            if self._drive is None:
                self._limp_servos()
                self._drive = self.body.drive(self.wire.tables, self.wire.powered())
            self.body.step(n, self.servos, self._drive)
            steps -= n
        self._stale = True
        if self._now() - self._refreshed_at >= REFRESH_S:
            self._refresh()

    def _refresh(self) -> None:
        """The present-state registers, the board's IMU and the ground truth from the body (its alarms may drop a
        servo's torque), when the body has moved since."""
        if not self._stale:
            return
        self._stale, self._refreshed_at = False, self._now()
        self.body.sense(self.servos, self.wire.tables, self.board, self.temperature_overrides)
        self._drive = None
        self._truth = self.body.truth()
        self.torque_limit_min = min(self.torque_limit_min, *self.wire.tables.column("torque_limit").tolist())
        if self._truth["t_s"] >= self._next_trace:
            self.trace.append(self._truth)
            self._next_trace = self._truth["t_s"] + TRACE_EVERY_S
        if self._truth["t_s"] >= self._next_publish:
            self._publish()
            self._next_publish = self._truth["t_s"] + PUBLISH_EVERY_S

    def _limp_servos(self) -> None:
        """The servos as the body sees them: a missing or unplugged servo has no torque."""
        if not (self.faults.missing or self.wire.unplugged):
            return
        for servo in self.servos:
            if self.wire.silent(servo.id):
                servo.set("torque_enable", 0)

    def _now(self) -> float:
        return self.body.steps * self.body.dt

    def sim_time(self) -> float:
        """The simulated time [s] the body has reached."""
        return self._now()

    def _timed_faults(self) -> None:
        if self.motion_t0 is None or not (self.faults.push or self.faults.unplug or self.faults.overheat):
            return
        since = self._now() - self.motion_t0
        self.body.push_n = self.faults.push_at(since)
        for device, at in self.faults.unplug:
            if since >= at and device not in self.wire.unplugged:
                self.unplug(device)
        for device, at, celsius in self.faults.overheat:
            if since >= at and device not in self.temperature_overrides:
                self.overheat(device, celsius)
