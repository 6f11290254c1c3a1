"""ROBOTIS action files (``motion_4096.bin``), read and written byte-exactly.

Layout (ROBOTIS DARwIn-OP framework v1.6.0, ``Framework/include/Action.h`` and
``Framework/src/motion/modules/Action.cpp``; Action Editor ``Linux/project/action_editor/cmd_process.cpp``): 256
pages of 512 bytes; a page is a 64-byte header and 7 steps of 64 bytes. A step holds 31 little-endian uint16 goal
positions indexed by Dynamixel ID (0 and 21-30 unused; bit 0x4000 marks a joint not specified in the step), then
``pause`` and ``time`` (8 ms units at the default page speed 32). A page is valid when its 512 bytes sum to 0xFF
modulo 256.

Writing fills the named pages and keeps every other page byte-for-byte, valid or not. The default base is a file
of reset pages exactly as the Action Editor makes them (the stock file's empty pages).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..fileio import read_bytes
from ..joints import servo_to_ticks, ticks_to_servo
from ..pose import Pose, safe_pose_name
from ..spec import Spec

PAGE_SIZE, NUM_PAGES, HEADER_SIZE, STEP_SIZE, MAX_STEPS, SLOTS = 512, 256, 64, 64, 7, 31
FILE_SIZE = PAGE_SIZE * NUM_PAGES
NAME_LEN = 14                  # 13 characters and a NUL
OFF_REPEAT, OFF_SCHEDULE, OFF_STEPNUM, OFF_SPEED = 15, 16, 20, 22
OFF_ACCEL, OFF_NEXT, OFF_EXIT, OFF_CHECKSUM, OFF_SLOPE = 24, 25, 26, 31, 32
OFF_PAUSE, OFF_TIME = 62, 63   # in a step
OFF_SLOPE_LAST = HEADER_SIZE - 1
TIME_BASE_SCHEDULE = 0x0A
DEFAULT_SPEED = DEFAULT_ACCEL = 32
DEFAULT_SLOPE = 0x55
TIME_UNIT_S = 0.008
# The Action Editor's reset page, as found in every empty page of the stock file: slopes 0x55 for IDs 0-25 and in
# the last header byte, and goal words 0x4200 (not specified) in slots 0-25 of every step.
_RESET_SLOTS = 26
_RESET_WORD = 0x4200


@dataclass(frozen=True)
class Step:
    """One step: goal ticks by Dynamixel ID (None where the joint is not specified), pause and time bytes."""

    ticks: dict[int, int | None]
    pause: int
    time: int


@dataclass(frozen=True)
class Page:
    """One decoded page."""

    index: int
    name: str
    valid: bool
    repeat: int
    speed: int
    next: int
    exit: int
    steps: tuple[Step, ...]


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
        page[base:base + 2 * _RESET_SLOTS] = _RESET_WORD.to_bytes(2, "little") * _RESET_SLOTS
    return bytes(with_checksum(page))


def reset_file() -> bytes:
    """A whole file of reset pages (page 0, never played, all zeros as in the stock file)."""
    return bytes(PAGE_SIZE) + reset_page() * (NUM_PAGES - 1)


def check_file(data: bytes, where: str) -> None:
    """Reject anything that is not exactly 256 pages of 512 bytes."""
    if len(data) != FILE_SIZE:
        kind = "truncated" if len(data) < FILE_SIZE else "too long"
        raise InputError(f"not a ROBOTIS action file ({kind}): expected {FILE_SIZE} bytes, got {len(data)}", where)


def decode_page(data: bytes, index: int, spec: Spec) -> Page:
    """Decode page ``index`` of a checked file."""
    raw = data[index * PAGE_SIZE:(index + 1) * PAGE_SIZE]
    name = raw[:NAME_LEN].split(b"\0", 1)[0].decode("latin-1")
    steps = []
    invalid = spec.servo.invalid_bit
    for s in range(min(raw[OFF_STEPNUM], MAX_STEPS)):
        base = step_offset(s)
        words = np.frombuffer(raw[base:base + 2 * SLOTS], dtype="<u2")
        ticks = {j.id: (None if int(words[j.id]) & invalid else int(words[j.id]) & 0x0FFF) for j in spec.joints}
        steps.append(Step(ticks, raw[base + OFF_PAUSE], raw[base + OFF_TIME]))
    return Page(index, name, checksum_ok(raw), raw[OFF_REPEAT], raw[OFF_SPEED], raw[OFF_NEXT], raw[OFF_EXIT],
                tuple(steps))


def read_action(path: str | Path) -> bytes:
    """Read and size-check an action file."""
    data = read_bytes(path, "action file")
    check_file(data, str(path))
    return data


def list_pages(data: bytes, spec: Spec, where: str = "<action>") -> list[Page]:
    """Every page that holds an action (valid checksum, at least one step), in order."""
    check_file(data, where)
    pages = [decode_page(data, i, spec) for i in range(1, NUM_PAGES)]
    return [p for p in pages if p.valid and p.steps]


def requested_page(data: bytes, index: int, spec: Spec, where: str) -> Page:
    """Page ``index``, which must exist, be valid and hold at least one step."""
    check_file(data, where)
    if not 1 <= index < NUM_PAGES:
        raise InputError(f"expected 1..{NUM_PAGES - 1}, got {index}", "page")
    page = decode_page(data, index, spec)
    if not page.valid:
        raise InputError(f"page {index} fails its checksum", where)
    if not page.steps:
        raise InputError(f"page {index} holds no steps", where)
    return page


def page_to_pose(page: Page, spec: Spec, name: str | None = None) -> Pose:
    """A page's last step as a double-support pose (joints not specified there keep the step before's value)."""
    ticks: dict[int, int] = {}
    for step in page.steps:
        ticks.update({k: v for k, v in step.ticks.items() if v is not None})
    missing = [j.name for j in spec.joints if j.id not in ticks]
    if missing:
        raise InputError(f"no goal position for {', '.join(missing)}", f"page {page.index}")
    servo = ticks_to_servo(np.array([ticks[j.id] for j in spec.joints]), spec)
    return Pose(name or safe_pose_name(page.name, f"page{page.index}"), "double", servo, {},
                {"source": f"action file page {page.index} ({page.name}), last step"})


def encode_pose_page(pose: Pose, spec: Spec, seconds: float, base: bytes | None = None) -> bytes:
    """A one-step page for a pose: name, goal ticks, ``seconds`` of motion, reset defaults elsewhere."""
    if not (math.isfinite(seconds) and TIME_UNIT_S <= seconds <= 255 * TIME_UNIT_S):
        raise InputError(f"expected {TIME_UNIT_S} to {255 * TIME_UNIT_S:.2f} s, got {seconds}", "time")
    name = pose.name.encode("ascii", "replace")[:NAME_LEN - 1]
    page = bytearray(base if base is not None else reset_page())
    page[:NAME_LEN] = name.ljust(NAME_LEN, b"\0")
    page[OFF_REPEAT], page[OFF_SCHEDULE], page[OFF_STEPNUM] = 1, TIME_BASE_SCHEDULE, 1
    page[OFF_SPEED], page[OFF_ACCEL], page[OFF_NEXT], page[OFF_EXIT] = DEFAULT_SPEED, DEFAULT_ACCEL, 0, 0
    first = step_offset(0)
    words = np.frombuffer(bytes(page[first:first + 2 * SLOTS]), dtype="<u2").copy()
    for joint, tick in zip(spec.joints, servo_to_ticks(pose.servo, spec)):
        words[joint.id] = tick
    page[first:first + 2 * SLOTS] = words.astype("<u2").tobytes()
    page[first + OFF_PAUSE], page[first + OFF_TIME] = 0, int(round(seconds / TIME_UNIT_S))
    return bytes(with_checksum(page))


def encode_poses(poses: Sequence[Pose], spec: Spec, first_page: int = 1, seconds: float = 1.0,
                 base: bytes | None = None) -> bytes:
    """A whole action file with each pose in its own page from ``first_page`` on; every other page of ``base``
    (default: reset pages) is kept byte for byte."""
    data = bytearray(base if base is not None else reset_file())
    check_file(bytes(data), "base")
    if poses and not (1 <= first_page and first_page + len(poses) - 1 < NUM_PAGES):
        raise InputError(f"{len(poses)} pose(s) from page {first_page} do not fit in pages 1..{NUM_PAGES - 1}",
                         "page")
    for k, pose in enumerate(poses):
        i = first_page + k
        data[i * PAGE_SIZE:(i + 1) * PAGE_SIZE] = encode_pose_page(pose, spec, seconds)
    return bytes(data)
