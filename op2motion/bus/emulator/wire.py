"""The emulated OP2's bus: the devices on it (:mod:`.devices`: the CM-730 at ID 200 and one MX-28 per joint) and
what each instruction packet makes them do and answer, byte for byte, with the faults of :mod:`.faults`.

* the servos are silent until the board's power register is 1 and :data:`BOOT_S` has passed, and when missing or
  unplugged; switching the power on brings them up with their RAM defaults (torque off, goal where they are);
* a broadcast gets no reply; PING, READ, WRITE, REG_WRITE and ACTION as the e-manual says, each answered per the
  device's status return level; RESET is refused with the instruction error (it would renumber the servo);
* SYNC_WRITE writes each listed device; the first one marks the motion's start (fault times count from it);
* BULK_READ is answered device by device in the order asked, the replies back to back in one write, and a silent
  device silences the ones listed after it (MX firmware waits for the previous device's reply);
* replies are lost or have a byte changed at the faults' rates (seeded).
"""

from __future__ import annotations

import random
from typing import Any, Callable

from op2motion.bus import protocol as p
from op2motion.bus.emulator.devices import Board, Servo
from op2motion.bus.emulator.faults import Faults
from op2motion.bus.tables import CM730_ID
from op2motion.robot.spec import Spec

BOOT_S = 0.1                       # the servos' silence after their power is switched on


class Wire:
    """The devices on the emulated bus (see the module docstring). ``now`` gives the simulated time [s],
    ``present_ticks`` the joints' positions [tick] (a servo powering up takes its goal from them)."""

    def __init__(self, spec: Spec, faults: Faults, now: Callable[[], float],
                 present_ticks: Callable[[], list[int]]):
        self.faults, self.now, self.present_ticks = faults, now, present_ticks
        self.rng = random.Random(faults.seed)
        self.board = Board()
        self.servos = [Servo(j.id) for j in spec.joints]
        self.by_id: dict[int, Any] = {s.id: s for s in self.servos}
        self.by_id[CM730_ID] = self.board
        self.parser = p.StreamParser()
        self.powered_at: float | None = None
        self.motion_t0: float | None = None
        self.unplugged: set[int] = set()
        self.pending: dict[int, tuple[int, bytes]] = {}
        self.stats = {"packets": 0, "replies": 0, "lost": 0, "corrupted": 0, "bad_packets": 0}
        self.out: list[bytes] = []

    def powered(self) -> bool:
        """Whether the servos' supply is on."""
        return self.board.get("dynamixel_power") == 1

    def silent(self, device: int) -> bool:
        """A servo that is not on the bus (missing, or unplugged by now)."""
        return device in self.faults.missing or device in self.unplugged

    def present(self, device: int) -> Any:
        """The device at ``device`` if it would answer now (a powered, booted servo on the bus; the board)."""
        if device == CM730_ID:
            return self.board
        servo = self.by_id.get(device)
        if servo is None or self.silent(device) or not self.powered():
            return None
        if self.powered_at is not None and self.now() - self.powered_at < BOOT_S:
            return None
        return servo

    def feed(self, data: bytes) -> list[bytes]:
        """Bytes from the client in; the bytes to answer with out (one chunk per reply, a bulk read's together)."""
        self.out = []
        bad = self.parser.bad_checksums
        for packet in self.parser.feed(data):
            self.stats["packets"] += 1
            self._handle(packet)
        self.stats["bad_packets"] += self.parser.bad_checksums - bad
        return self.out

    def _reply(self, device: Any, error: int, params: bytes = b"", level: int = 2, out: bytearray | None = None
               ) -> None:
        """A status packet, if the device's status return level allows it; lost or corrupted at the fault rates;
        sent on its own, or added to ``out`` (a bulk read's replies go out back to back)."""
        if device.return_level < level:
            return
        packet = bytearray(p.status(device.id, error, params))
        if self.faults.lose and self.rng.random() < self.faults.lose:
            self.stats["lost"] += 1
            return
        if self.faults.corrupt and self.rng.random() < self.faults.corrupt:
            i = self.rng.randrange(2, len(packet))
            packet[i] ^= 1 << self.rng.randrange(8)
            self.stats["corrupted"] += 1
        self.stats["replies"] += 1
        if out is not None:
            out += packet
        else:
            self.out.append(bytes(packet))

    def write(self, device: Any, address: int, data: bytes) -> int:
        """A write to one device (the board's power switch powers the servos up or down); its error byte."""
        was_powered = self.powered()
        error = device.write(address, data)
        if device is self.board and self.board.power_changed:
            self.board.power_changed = False
            powered = self.powered()
            if powered and not was_powered:
                self.powered_at = self.now()
                for servo, tick in zip(self.servos, self.present_ticks()):
                    servo.power_up(tick)
            elif was_powered and not powered:
                for servo in self.servos:
                    servo.set("torque_enable", 0)
        return error

    def _handle(self, packet: p.Packet) -> None:
        code, params = packet.code, packet.params
        if code == p.Instruction.SYNC_WRITE:
            self._sync_write(params)
            return
        if code == p.Instruction.BULK_READ:
            self._bulk_read(params)
            return
        broadcast = packet.id == p.BROADCAST_ID
        for target in [d for d in self.by_id if self.present(d)] if broadcast else [packet.id]:
            device = self.present(target)
            if device is not None:
                self._one(device, target, code, params, not broadcast)

    def _one(self, device: Any, target: int, code: int, params: bytes, reply: bool) -> None:
        """One instruction to one device."""
        if code == p.Instruction.PING:
            if reply:
                self._reply(device, device.conditions(), level=0)
        elif code == p.Instruction.READ and len(params) == 2:
            error, data = device.read(params[0], params[1])
            if reply:
                self._reply(device, error, data or b"", level=1)
        elif code == p.Instruction.WRITE and len(params) >= 2:
            error = self.write(device, params[0], bytes(params[1:]))
            if reply:
                self._reply(device, error)
        elif code == p.Instruction.REG_WRITE and len(params) >= 2:
            self.pending[target] = (params[0], bytes(params[1:]))
            if reply:
                self._reply(device, device.conditions())
        elif code == p.Instruction.ACTION and not params:
            address, data = self.pending.pop(target, (0, b""))
            error = self.write(device, address, data) if data else device.conditions()
            if reply:
                self._reply(device, error)
        elif reply:                                # RESET is not emulated (it would renumber the servo), nor others
            self._reply(device, device.conditions() | p.INSTRUCTION)

    def _sync_write(self, params: bytes) -> None:
        if len(params) < 2 or params[1] == 0 or (len(params) - 2) % (params[1] + 1):
            self.stats["bad_packets"] += 1
            return
        address, length = params[0], params[1]
        if self.motion_t0 is None:
            self.motion_t0 = self.now()
        for k in range(2, len(params), length + 1):
            device = self.present(params[k])
            if device is not None:
                self.write(device, address, bytes(params[k + 1:k + 1 + length]))

    def _bulk_read(self, params: bytes) -> None:
        if len(params) < 4 or (len(params) - 1) % 3:
            self.stats["bad_packets"] += 1
            return
        out = bytearray()
        for k in range(1, len(params), 3):
            length, target, address = params[k], params[k + 1], params[k + 2]
            device = self.present(target)
            if device is None:
                break                              # the devices listed after it wait for its reply in vain
            error, data = device.read(address, length)
            self._reply(device, error, data or b"", level=0, out=out)
        if out:
            self.out.append(bytes(out))
