"""The emulated OP2's bus: the devices on it (:mod:`.devices`: the CM-730 at ID 200 and one MX-28 per joint) and
what each instruction packet makes them do and answer, byte for byte, with the faults of :mod:`.faults`.

Sources: the CM-730 firmware ``CM_DXL_COM.c`` (ROBOTIS 2010, model 0x7300, firmware 0x13: ``ProcessPackets``,
``ProcessInstruction``, ``ReturnPacket``), the Protocol 1.0 and MX-28 e-manual (ROBOTIS-GIT/emanual
``docs/en/dxl/protocol1.md``), the framework's ``CM730.cpp``; ``reference/bus_wire.md``.

* power: the servos are silent until the board's power register (24) is 1 and :data:`BOOT_S` has passed, and when
  missing or unplugged; switching the power on brings each up with its RAM defaults (torque off, goal where it is),
  switching it off drops their torque. :meth:`Wire.cold_start` is the robot just switched on: power 0, servos silent.
* packets are taken as the firmware takes them (:mod:`.parser`): header, ID, length, then that many bytes. One
  whose checksum does not match is not executed; the device it names answers it with the checksum error (16), except
  a PING (the firmware skips it) and a broadcast (its ``ReturnPacket`` never answers a broadcast but a PING, so a
  damaged broadcast gets no reply from anyone). The firmware also drops the rest of what it has buffered; the
  emulator goes on with the bytes after the packet (the servos behind the board still see them).
* replies follow the status return level the device had when the packet arrived (the firmware answers a WRITE before
  writing, so a write that sets level 1 is still answered); a broadcast is not answered, but a PING to it is by the
  CM-730 (its firmware answers every PING; the servos do not answer broadcast). BULK_READ is a READ to each device
  (level 1 or more), answered device by device in the order asked, back to back in one write; a silent device
  silences the ones listed after it (each waits for the previous device's reply).
* PING, READ, WRITE as the e-manual says; REG_WRITE and ACTION on the servos (:mod:`.devices`; the CM-730 answers
  both with the instruction error); RESET: the CM-730 answers it with error 0 and does nothing (its firmware has the
  reset commented out); a servo refuses it with the instruction error (the e-manual's factory reset would renumber it
  to ID 1 at 57600 baud, off this bus: not emulated); other instructions: the instruction error.
* SYNC_WRITE writes each listed device; the first one marks the motion's start (fault times count from it). Written
  to servos only, each listed once, with none missing or unplugged, it goes to their tables at once
  (:meth:`.bank.ServoTables.put`), as the writes one by one would.
* replies are lost or have a byte changed at the faults' rates (seeded); a device given error bits (``errors``)
  reports them in every status packet, one given another model (``models``) reports it at address 0.
"""

from __future__ import annotations

import random
from typing import Any, Callable

import numpy as np

from op2motion.bus import protocol as p
from op2motion.bus.emulator.bank import ServoTables
from op2motion.bus.emulator.devices import Board, EmulatedServo
from op2motion.bus.emulator.faults import Faults
from op2motion.bus.emulator.parser import FirmwareParser
from op2motion.bus.tables import CM730, CM730_ID
from op2motion.robot.spec import Spec

BOOT_S = 0.1                       # the servos' silence after their power is switched on
PING_LEVEL, READ_LEVEL, ALL_LEVEL = 0, 1, 2   # the status return level an answer needs
POWER = CM730["dynamixel_power"].address      # the board's switch of the servos' supply (one byte)


class Wire:
    """The devices on the emulated bus (see the module docstring). ``now`` gives the simulated time [s],
    ``present_ticks`` the joints' positions [tick] (a servo powering up takes its goal from them). The board is a
    CM-730 unless the faults give ID 200 another model (the CM-740's: :func:`.faults.with_board`)."""

    def __init__(self, spec: Spec, faults: Faults, now: Callable[[], float],
                 present_ticks: Callable[[], list[int]]):
        self.faults, self.now, self.present_ticks = faults, now, present_ticks
        self.rng = random.Random(faults.seed)
        self.board = Board()
        self.tables = ServoTables(len(spec.joints))              # the servos' tables, a row each
        self.servos = [EmulatedServo(j.id, self.tables.row(i)) for i, j in enumerate(spec.joints)]
        self._row_of_id = np.full(256, -1, dtype=np.intp)           # a servo's row by its ID (-1: no servo)
        for i, servo in enumerate(self.servos):
            self._row_of_id[servo.id] = i
        self.by_id: dict[int, Any] = {s.id: s for s in self.servos}
        self.by_id[CM730_ID] = self.board
        for device, model in faults.models.items():            # kept over power cycles: address 0 is EEPROM
            if device in self.by_id:
                self.by_id[device].set("model_number", model)
        self.parser = FirmwareParser()
        self.powered_at: float | None = None
        self._booted_since: float | None = None                 # the powered_at found booted (see _booted)
        self.motion_t0: float | None = None
        self.unplugged: set[int] = set()
        self.stats = {"packets": 0, "replies": 0, "lost": 0, "corrupted": 0, "bad_packets": 0}
        self.out: list[bytes] = []

    def cold_start(self) -> None:
        """The robot just switched on: the board up with its power-on registers (the servos' power register 24 at
        0, the LEDs as its firmware sets them), the servos unpowered and silent, nothing buffered. Writing 1 to
        register 24 then powers them up, each with its torque off and its goal where its joint is (:meth:`write`).
        The board's sensor registers keep what the body last put there; the fault clock (:attr:`motion_t0`) is
        left alone."""
        self.board.cold_start()
        for servo in self.servos:
            servo.power_off()
        self.powered_at = None
        self.parser.clear()

    def powered(self) -> bool:
        """Whether the servos' supply is on."""
        return self.board.table[POWER] == 1

    def silent(self, device: int) -> bool:
        """A servo that is not on the bus (missing, or unplugged by now)."""
        return device in self.faults.missing or device in self.unplugged

    def present(self, device: int, servos_up: bool | None = None) -> Any:
        """The device at ``device`` if it would answer now (a powered, booted servo on the bus; the board);
        ``servos_up``: :meth:`servos_up` if the caller knows it."""
        if device == CM730_ID:
            return self.board
        servo = self.by_id.get(device)
        if servo is None or self.silent(device) or not (self.servos_up() if servos_up is None else servos_up):
            return None
        return servo

    def servos_up(self) -> bool:
        """Whether the servos on the bus answer now: powered, and booted."""
        return self.board.table[POWER] == 1 and self._booted()

    def _booted(self) -> bool:
        """Whether the servos have had :data:`BOOT_S` since their power came on (kept once so, until it next
        comes on: time only moves on)."""
        if self.powered_at is None or self.powered_at == self._booted_since:
            return True
        if self.now() - self.powered_at < BOOT_S:
            return False
        self._booted_since = self.powered_at
        return True

    def feed(self, data: bytes) -> list[bytes]:
        """Bytes from the client in; the bytes to answer with out (one chunk per reply, a bulk read's together)."""
        self.out = []
        for packet, intact in self.parser.feed(data):
            if intact:
                self.stats["packets"] += 1
                self._handle(packet)
            else:
                self.stats["bad_packets"] += 1
                self._damaged(packet)
        return self.out

    def _reply(self, device: Any, error: int, params: bytes = b"", need: int = ALL_LEVEL, level: int | None = None,
               out: bytearray | None = None) -> None:
        """A status packet, if the device's status return level (``level`` if given: the one it had as the packet
        arrived) is ``need`` or more; lost or corrupted at the fault rates; sent on its own, or added to ``out`` (a
        bulk read's replies go out back to back)."""
        if (device.return_level if level is None else level) < need:
            return
        packet = p.status(device.id, error | self.faults.errors.get(device.id, 0), params)
        if self.faults.lose and self.rng.random() < self.faults.lose:
            self.stats["lost"] += 1
            return
        if self.faults.corrupt and self.rng.random() < self.faults.corrupt:
            damaged = bytearray(packet)
            i = self.rng.randrange(2, len(damaged))
            damaged[i] ^= 1 << self.rng.randrange(8)
            packet = bytes(damaged)
            self.stats["corrupted"] += 1
        self.stats["replies"] += 1
        if out is not None:
            out += packet
        else:
            self.out.append(packet)

    def write(self, device: Any, address: int, data: bytes) -> int:
        """A write to one device (the board's power switch powers the servos up or down); its error byte."""
        was_powered = self.powered()
        error: int = device.write(address, data)
        if device is self.board and self.board.power_changed:
            self.board.power_changed = False
            powered = self.powered()
            if powered and not was_powered:
                self.powered_at = self.now()
                for servo, tick in zip(self.servos, self.present_ticks()):
                    servo.power_up(tick)
            elif was_powered and not powered:
                for servo in self.servos:
                    servo.power_off()
        return error

    def _damaged(self, packet: p.Packet) -> None:
        """A packet whose checksum does not match: the checksum error from the device it names (see the module
        docstring)."""
        if packet.id == p.BROADCAST_ID or packet.code == p.Instruction.PING:
            return
        device = self.present(packet.id)
        if device is not None:
            self._reply(device, device.conditions() | p.CHECKSUM)

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
                self._one(device, code, params, broadcast)

    def _one(self, device: Any, code: int, params: bytes, broadcast: bool) -> None:
        """One instruction to one device, answered unless broadcast (a PING to the board always)."""
        level = device.return_level                        # the answer is made before a write is applied
        error, data, need = self._execute(device, code, params)
        if not broadcast or (code == p.Instruction.PING and device is self.board):
            self._reply(device, error, data, need, level)

    def _execute(self, device: Any, code: int, params: bytes) -> tuple[int, bytes, int]:
        """Carry out one instruction on one device: (its error byte, the data to answer with, the status return
        level the answer needs)."""
        if code == p.Instruction.PING:
            return device.conditions(), b"", PING_LEVEL
        if code == p.Instruction.READ and len(params) == 2:
            error, data = device.read(params[0], params[1])
            return error, data or b"", READ_LEVEL
        if code == p.Instruction.WRITE and len(params) >= 2:
            return self.write(device, params[0], bytes(params[1:])), b"", ALL_LEVEL
        if isinstance(device, EmulatedServo):
            if code == p.Instruction.REG_WRITE and len(params) >= 2:
                return device.reg_write(params[0], bytes(params[1:])), b"", ALL_LEVEL
            if code == p.Instruction.ACTION and not params:
                return device.action(), b"", ALL_LEVEL
        elif code == p.Instruction.RESET:                  # the CM-730: error 0, nothing done
            return device.conditions(), b"", ALL_LEVEL
        return device.conditions() | p.INSTRUCTION, b"", ALL_LEVEL

    def _sync_write(self, params: bytes) -> None:
        if len(params) < 2 or params[1] == 0 or (len(params) - 2) % (params[1] + 1):
            self.stats["bad_packets"] += 1
            return
        address, length = params[0], params[1]
        if self.motion_t0 is None:
            self.motion_t0 = self.now()
        ids = params[2::length + 1]
        plan = self.servos[0].plan(address, length)
        if (plan.reactions or CM730_ID in ids or len(set(ids)) < len(ids) or self.faults.missing
                or self.unplugged):
            self._write_each(params)                     # a write may change who answers, or what a write does
            return
        if not self.servos_up():
            return                                       # no servo takes it (and the board is not listed)
        chunks = np.frombuffer(params, dtype=np.uint8, offset=2).reshape(-1, length + 1)
        rows = self._row_of_id[chunks[:, 0]]
        here = rows >= 0                                 # the IDs of servos on the bus (no other device is)
        self.tables.put(rows[here], address, chunks[here, 1:], plan)   # nobody answers: no standing conditions

    def _write_each(self, params: bytes) -> None:
        """A sync write's writes one by one, in order."""
        address, length = params[0], params[1]
        for k in range(2, len(params), length + 1):
            device = self.present(params[k])
            if device is self.board:                    # its power switch: see write
                self.write(device, address, bytes(params[k + 1:k + 1 + length]))
            elif device is not None:                    # nobody answers: the standing conditions are not asked
                device.put(address, bytes(params[k + 1:k + 1 + length]))

    def _bulk_read(self, params: bytes) -> None:
        if len(params) < 4 or (len(params) - 1) % 3:
            self.stats["bad_packets"] += 1
            return
        out = bytearray()
        up = self.servos_up()                      # reads change nothing of it
        for k in range(1, len(params), 3):
            length, target, address = params[k], params[k + 1], params[k + 2]
            device = self.present(target, up)
            level = None if device is None else device.return_level
            if level is None or level < READ_LEVEL:
                break                              # the devices listed after it wait for its reply in vain
            error, data = device.read(address, length)
            self._reply(device, error, data or b"", READ_LEVEL, level, out)
        if out:
            self.out.append(bytes(out))
