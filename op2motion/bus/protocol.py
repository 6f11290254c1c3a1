"""Dynamixel Protocol 1.0, byte for byte: packets, checksums, instructions and status error bits by name.

A packet is ``FF FF ID LEN CODE PARAMS… CHK`` with ``LEN = len(PARAMS) + 2`` and
``CHK = ~(ID + LEN + CODE + ΣPARAMS) & 0xFF``; CODE is the instruction of an instruction packet and the error byte of
a status packet. Broadcast (ID 0xFE) gets no reply. ``SYNC_WRITE`` (0x83) writes ``n`` bytes from one address of
several devices in one packet (``address, n, (id, n bytes)*``); ``BULK_READ`` (0x92, MX series and the CM-730)
reads a different span of each listed device (``0x00, (n, id, address)*``) and every listed device answers with its
own status packet. Both are built here: dynamixel-sdk 3.8 and 4.x cannot bulk-read on Protocol 1.0.

:class:`StreamParser` cuts packets out of a byte stream that may hold noise, late replies of an earlier request,
corrupted or cut-off packets: it resynchronises on the next ``FF FF`` and counts what it threw away.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Iterable, Mapping, Sequence

HEADER = b"\xff\xff"
BROADCAST_ID = 0xFE
MAX_DEVICE_ID = 0xFD               # 253: 0xFE is broadcast, 0xFF cannot follow the header
MAX_PARAMS = 253                   # LEN is one byte and counts CODE and CHK too
MIN_PACKET_BYTES = 6               # FF FF ID LEN CODE CHK


class Instruction(IntEnum):
    """Protocol 1.0 instruction codes."""

    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    RESET = 0x06
    SYNC_WRITE = 0x83
    BULK_READ = 0x92


#: Status error bits (the error byte of a status packet), lowest first.
ERROR_BITS: dict[int, str] = {
    0x01: "input voltage",
    0x02: "angle limit",
    0x04: "overheating",
    0x08: "range",
    0x10: "checksum",
    0x20: "overload",
    0x40: "instruction",
}
INPUT_VOLTAGE, ANGLE_LIMIT, OVERHEATING, RANGE, CHECKSUM, OVERLOAD, INSTRUCTION = ERROR_BITS


def error_names(error: int) -> tuple[str, ...]:
    """The names of the bits set in a status error byte (``()`` for 0); an unknown bit 0x80 is ``bit 7``."""
    names = tuple(name for bit, name in ERROR_BITS.items() if error & bit)
    return names + (("bit 7",) if error & 0x80 else ())


def checksum(body: bytes | bytearray) -> int:
    """The checksum of a packet's ``ID LEN CODE PARAMS…`` bytes."""
    return ~sum(body) & 0xFF


@dataclass(frozen=True)
class Packet:
    """One parsed packet: device ``id``, ``code`` (instruction, or a status packet's error byte), ``params``."""

    id: int
    code: int
    params: bytes

    @property
    def errors(self) -> tuple[str, ...]:
        """A status packet's error bits by name."""
        return error_names(self.code)

    def encode(self) -> bytes:
        """The packet's bytes."""
        return encode(self.id, self.code, self.params)


def encode(device: int, code: int, params: bytes | bytearray | Sequence[int] = b"") -> bytes:
    """``FF FF ID LEN CODE PARAMS CHK``; raises ValueError on an ID, code or parameter count out of range."""
    params = bytes(params)
    if not 0 <= device <= BROADCAST_ID:
        raise ValueError(f"expected a device ID 0..{BROADCAST_ID}, got {device}")
    if not 0 <= code <= 0xFF:
        raise ValueError(f"expected a code 0..255, got {code}")
    if len(params) > MAX_PARAMS:
        raise ValueError(f"expected at most {MAX_PARAMS} parameters, got {len(params)}")
    body = bytes((device, len(params) + 2, code)) + params
    return HEADER + body + bytes((checksum(body),))


def ping(device: int) -> bytes:
    """PING ``device``."""
    return encode(device, Instruction.PING)


def read(device: int, address: int, length: int) -> bytes:
    """READ ``length`` bytes from ``address`` of ``device``."""
    return encode(device, Instruction.READ, bytes((address, length)))


def write(device: int, address: int, data: bytes | Sequence[int]) -> bytes:
    """WRITE ``data`` from ``address`` of ``device``."""
    return encode(device, Instruction.WRITE, bytes((address,)) + bytes(data))


def sync_write(address: int, length: int, data: Mapping[int, bytes | Sequence[int]]) -> bytes:
    """SYNC_WRITE ``length`` bytes from ``address`` of each device: ``data`` {id: bytes} (no reply)."""
    params = bytearray((address, length))
    for device, chunk in data.items():
        chunk = bytes(chunk)
        if len(chunk) != length:
            raise ValueError(f"expected {length} bytes for device {device}, got {len(chunk)}")
        params += bytes((device,)) + chunk
    return encode(BROADCAST_ID, Instruction.SYNC_WRITE, params)


def bulk_read(spans: Iterable[tuple[int, int, int]]) -> bytes:
    """BULK_READ of ``spans`` (id, address, length): each listed device answers with its span."""
    params = bytearray((0x00,))
    for device, address, length in spans:
        params += bytes((length, device, address))
    return encode(BROADCAST_ID, Instruction.BULK_READ, params)


def status(device: int, error: int, params: bytes | Sequence[int] = b"") -> bytes:
    """A status packet (what a device answers)."""
    return encode(device, error, params)


def word(low: int, high: int) -> int:
    """A little-endian 16-bit register value."""
    return low | (high << 8)


def word_bytes(value: int) -> bytes:
    """A 16-bit register value as (low, high) bytes."""
    return bytes((value & 0xFF, (value >> 8) & 0xFF))


class StreamParser:
    """Packets out of a byte stream (see the module docstring). ``discarded`` counts bytes thrown away while
    resynchronising (noise, cut-off packets), ``bad_checksums`` the packets whose checksum did not match."""

    def __init__(self) -> None:
        self.buffer = bytearray()
        self.discarded = 0
        self.bad_checksums = 0

    def feed(self, data: bytes | bytearray) -> list[Packet]:
        """Add ``data``; return every complete, checksum-valid packet now in the buffer, in order."""
        self.buffer += data
        out: list[Packet] = []
        buf = self.buffer
        while True:
            start = buf.find(HEADER)
            if start < 0:
                keep = 1 if buf[-1:] == b"\xff" else 0        # a lone FF may start the next header
                self.discarded += len(buf) - keep
                del buf[:len(buf) - keep]
                break
            if start:
                self.discarded += start
                del buf[:start]
            if len(buf) < 4:
                break
            if buf[2] == 0xFF:                                 # FF FF FF: the header starts one byte later
                self.discarded += 1
                del buf[:1]
                continue
            length = buf[3]
            if length < 2:
                self.discarded += 2
                del buf[:2]
                continue
            end = 4 + length
            if len(buf) < end:
                break
            body = bytes(buf[2:end - 1])
            if checksum(body) != buf[end - 1]:
                self.bad_checksums += 1
                self.discarded += 2
                del buf[:2]                                    # a header may hide inside: rescan after this one
                continue
            out.append(Packet(body[0], body[2], body[3:]))
            del buf[:end]
        return out

    def clear(self) -> None:
        """Forget what is buffered."""
        self.buffer.clear()
