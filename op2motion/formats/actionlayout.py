"""The byte layout of ROBOTIS action files (``motion_4096.bin``): raw pages in, raw pages out.

Layout (ROBOTIS DARwIn-OP framework v1.6.0, ``Framework/include/Action.h`` and
``Framework/src/motion/modules/Action.cpp``; Action Editor ``Linux/project/action_editor/cmd_process.cpp``): 256
pages of 512 bytes; a page is a 64-byte header and 7 steps of 64 bytes. The header holds the name (14 bytes),
``repeat`` (byte 15), ``schedule`` (16: 0x0A time base, 0x00 speed base), the step count (20), ``speed`` (22),
``accel`` (24), ``next`` (25) and ``exit`` (26) pages, the checksum (31) and a compliance byte per Dynamixel ID
(32-62). A step holds 31 little-endian 16-bit goal words indexed by ID (0 and 21-30 unused; bit 0x4000 marks a joint
not specified), then ``pause`` (byte 62) and ``time`` (63), both in 8 ms units at speed 32. A page is valid when its
512 bytes sum to 0xFF modulo 256.

This module knows bytes only: what the words mean (ticks, joints, poses) is :mod:`op2motion.formats.action` and the
player :mod:`op2motion.motion.player`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.framework import DEFAULT_COMPLIANCE as DEFAULT_SLOPE

PAGE_SIZE, NUM_PAGES, HEADER_SIZE, STEP_SIZE, MAX_STEPS, SLOTS = 512, 256, 64, 64, 7, 31
FILE_SIZE = PAGE_SIZE * NUM_PAGES
NAME_LEN = 14                  # 13 characters and a NUL
OFF_REPEAT, OFF_SCHEDULE, OFF_STEPNUM, OFF_SPEED = 15, 16, 20, 22
OFF_ACCEL, OFF_NEXT, OFF_EXIT, OFF_CHECKSUM, OFF_SLOPE = 24, 25, 26, 31, 32
OFF_PAUSE, OFF_TIME = 62, 63   # in a step
OFF_SLOPE_LAST = HEADER_SIZE - 1
TIME_BASE_SCHEDULE = 0x0A
SPEED_BASE_SCHEDULE = 0x00
DEFAULT_SPEED = DEFAULT_ACCEL = 32
MAX_BYTE = 255
# The Action Editor's reset page, as found in every empty page of the stock file: slopes 0x55 for IDs 0-25 and in
# the last header byte, and goal words 0x4200 (not specified) in slots 0-25 of every step.
_RESET_SLOTS = 26
RESET_WORD = 0x4200


@dataclass(frozen=True)
class RawPage:
    """One page as bytes say it: header fields, the compliance byte per ID (31,), and per step the 31 goal words
    (7, 31), pause and time bytes (7,); ``valid`` is the checksum."""

    index: int
    name: str
    valid: bool
    repeat: int
    schedule: int
    stepnum: int
    speed: int
    accel: int
    next: int
    exit: int
    slopes: tuple[int, ...]
    words: np.ndarray
    pause: tuple[int, ...]
    time: tuple[int, ...]

    @property
    def playable(self) -> bool:
        """The framework starts a page only with a valid checksum, repeat > 0 and at least one step."""
        return self.valid and self.repeat > 0 and self.stepnum > 0


def step_offset(step: int) -> int:
    """Byte offset of step ``step`` (0-based) within its page."""
    return HEADER_SIZE + step * STEP_SIZE


def checksum_ok(page: bytes) -> bool:
    """True when the page's bytes sum to 0xFF modulo 256."""
    return sum(page) & 0xFF == 0xFF


def with_checksum(page: bytearray) -> bytearray:
    """Set the checksum byte so the page sums to 0xFF."""
    page[OFF_CHECKSUM] = 0
    page[OFF_CHECKSUM] = (0xFF - sum(page)) & 0xFF
    return page


def reset_page() -> bytes:
    """An empty page as the Action Editor writes it."""
    page = bytearray(PAGE_SIZE)
    page[OFF_REPEAT], page[OFF_SCHEDULE] = 1, TIME_BASE_SCHEDULE
    page[OFF_SPEED], page[OFF_ACCEL] = DEFAULT_SPEED, DEFAULT_ACCEL
    page[OFF_SLOPE:OFF_SLOPE + _RESET_SLOTS] = bytes([DEFAULT_SLOPE]) * _RESET_SLOTS
    page[OFF_SLOPE_LAST] = DEFAULT_SLOPE
    for step in range(MAX_STEPS):
        base = step_offset(step)
        page[base:base + 2 * _RESET_SLOTS] = RESET_WORD.to_bytes(2, "little") * _RESET_SLOTS
    return bytes(with_checksum(page))


def reset_file() -> bytes:
    """A whole file of reset pages (page 0, never played, all zeros as in the stock file)."""
    return bytes(PAGE_SIZE) + reset_page() * (NUM_PAGES - 1)


def check_file(data: bytes, where: str) -> None:
    """Reject anything that is not exactly 256 pages of 512 bytes."""
    if len(data) != FILE_SIZE:
        kind = "truncated" if len(data) < FILE_SIZE else "too long"
        raise InputError(f"not a ROBOTIS action file ({kind}): expected {FILE_SIZE} bytes, got {len(data)}", where)


def page_bytes(data: bytes, index: int) -> bytes:
    """The 512 bytes of page ``index``."""
    return bytes(data[index * PAGE_SIZE:(index + 1) * PAGE_SIZE])


def parse_page(data: bytes, index: int) -> RawPage:
    """Page ``index`` of a checked file, raw."""
    raw = page_bytes(data, index)
    words = np.empty((MAX_STEPS, SLOTS), dtype=np.int64)
    for s in range(MAX_STEPS):
        base = step_offset(s)
        words[s] = np.frombuffer(raw[base:base + 2 * SLOTS], dtype="<u2")
    return RawPage(index, raw[:NAME_LEN].split(b"\0", 1)[0].decode("latin-1"), checksum_ok(raw), raw[OFF_REPEAT],
                   raw[OFF_SCHEDULE], raw[OFF_STEPNUM], raw[OFF_SPEED], raw[OFF_ACCEL], raw[OFF_NEXT], raw[OFF_EXIT],
                   tuple(raw[OFF_SLOPE:OFF_SLOPE + SLOTS]), words,
                   tuple(raw[step_offset(s) + OFF_PAUSE] for s in range(MAX_STEPS)),
                   tuple(raw[step_offset(s) + OFF_TIME] for s in range(MAX_STEPS)))


def is_empty(data: bytes, index: int) -> bool:
    """A page that holds no action: a bad checksum (the framework replaces it by a reset page) or no steps."""
    raw = page_bytes(data, index)
    return not checksum_ok(raw) or raw[OFF_STEPNUM] == 0


@dataclass(frozen=True)
class StepBytes:
    """One step to write: goal words by Dynamixel ID (IDs left out stay "not specified"), pause and time bytes."""

    words: Mapping[int, int]
    pause: int
    time: int


@dataclass(frozen=True)
class PageHeader:
    """A page's playing fields: ``repeat`` count, the ``next`` page (after the repeats) and the ``exit`` page (after
    a stop), ``speed`` and ``accel`` (32: the framework's), and compliance bytes by Dynamixel ID (None: keep)."""

    repeat: int = 1
    next: int = 0
    exit: int = 0
    speed: int = DEFAULT_SPEED
    accel: int = DEFAULT_ACCEL
    slopes: Mapping[int, int] | None = None


def encode_page(name: str, steps: Sequence[StepBytes], header: PageHeader = PageHeader(),
                base: bytes | None = None) -> bytes:
    """A time-base page with up to 7 steps, the Action Editor's reset defaults elsewhere (or ``base``'s bytes)."""
    if not 1 <= len(steps) <= MAX_STEPS:
        raise InputError(f"expected 1 to {MAX_STEPS} steps in a page, got {len(steps)}", "steps")
    h = header
    for field_name, value in (("repeat", h.repeat), ("next", h.next), ("exit", h.exit), ("speed", h.speed),
                              ("accel", h.accel)):
        if not 0 <= value <= MAX_BYTE:
            raise InputError(f"expected a byte (0..{MAX_BYTE}), got {value}", field_name)
    page = bytearray(base if base is not None else reset_page())
    page[:NAME_LEN] = name.encode("ascii", "replace")[:NAME_LEN - 1].ljust(NAME_LEN, b"\0")
    page[OFF_REPEAT], page[OFF_SCHEDULE], page[OFF_STEPNUM] = h.repeat, TIME_BASE_SCHEDULE, len(steps)
    page[OFF_SPEED], page[OFF_ACCEL], page[OFF_NEXT], page[OFF_EXIT] = h.speed, h.accel, h.next, h.exit
    for ident, slope in (h.slopes or {}).items():
        page[OFF_SLOPE + ident] = slope
    for k, step in enumerate(steps):
        if not (0 <= step.pause <= MAX_BYTE and 0 <= step.time <= MAX_BYTE):
            raise InputError(f"expected pause and time bytes (0..{MAX_BYTE}), got {step.pause}, {step.time}",
                             f"step {k + 1}")
        first = step_offset(k)
        words = np.frombuffer(bytes(page[first:first + 2 * SLOTS]), dtype="<u2").copy()
        for ident, word in step.words.items():
            words[ident] = word
        page[first:first + 2 * SLOTS] = words.astype("<u2").tobytes()
        page[first + OFF_PAUSE], page[first + OFF_TIME] = step.pause, step.time
    return bytes(with_checksum(page))
