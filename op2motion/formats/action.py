"""ROBOTIS action files as poses: pages decoded into goal ticks, poses written as pages (the bytes are
:mod:`op2motion.formats.actionlayout`).

Writing fills the named pages and keeps every other page byte-for-byte, valid or not. The default base is a file
of reset pages exactly as the Action Editor makes them (the stock file's empty pages).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from op2motion.errors import InputError, ref
from op2motion.fileio import read_bytes
from op2motion.formats.actionlayout import (
    MAX_BYTE,
    MAX_STEPS,
    NUM_PAGES,
    PAGE_SIZE,
    RawPage,
    StepBytes,
    check_file,
    encode_page,
    is_empty,
    parse_page,
    reset_file,
)
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.joints import servo_to_ticks, ticks_to_servo
from op2motion.robot.pose import Pose, safe_pose_name
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

MIN_STEP_UNITS = 3             # the framework moves a step only when time x speed / 32 >= 3 ticks (24 ms)


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


def decode_page(raw: RawPage, spec: Spec) -> Page:
    """A raw page decoded: goal ticks by ID (None where not specified)."""
    invalid = spec.servo.invalid_bit
    steps = tuple(Step({j.id: (None if int(raw.words[s, j.id]) & invalid else int(raw.words[s, j.id]) & 0x0FFF)
                        for j in spec.joints}, raw.pause[s], raw.time[s])
                  for s in range(min(raw.stepnum, len(raw.words))))
    return Page(raw.index, raw.name, raw.valid, raw.repeat, raw.speed, raw.next, raw.exit, steps)


def page_to_pose(page: Page, spec: Spec, name: str | None = None) -> Pose:
    """A page's last step as a double-support pose (joints not specified there keep the step before's value)."""
    ticks: dict[int, int] = {}
    for step in page.steps:
        ticks.update({k: v for k, v in step.ticks.items() if v is not None})
    missing = [j.name for j in spec.joints if j.id not in ticks]
    if missing:
        raise InputError(f"no goal position for {', '.join(missing)}", f"page {page.index}")
    servo = ticks_to_servo(np.array([ticks[j.id] for j in spec.joints]), spec)
    return Pose(name or safe_pose_name(page.name, f"page{page.index}"), Support.DOUBLE, servo, {},
                {"source": f"action file page {page.index} ({page.name}), last step"})


@dataclass(frozen=True)
class ActionFile:
    """A whole action file (256 pages of 512 bytes, checked when made), parsed once: pages by index, the poses
    they end in, the empty pages, and new files with pages written in. ``where`` names it in messages."""

    data: bytes
    where: str = "<action file>"
    _raw: dict[int, RawPage] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_file(self.data, self.where)

    @classmethod
    def read(cls, path: str | Path) -> "ActionFile":
        """Read and size-check an action file."""
        return cls(read_bytes(path, "action file"), str(path))

    @classmethod
    def blank(cls) -> "ActionFile":
        """A file of reset pages, as the Action Editor makes them (the stock file's empty pages)."""
        return cls(reset_file(), "<reset pages>")

    def raw(self, index: int) -> RawPage:
        """Page ``index`` as bytes say it (parsed once)."""
        if index not in self._raw:
            raw = parse_page(self.data, index)
            if raw.valid and raw.stepnum > MAX_STEPS:      # the framework would read past the page's 7 steps
                raise InputError(f"page {index} ({raw.name!r}) says it has {raw.stepnum} steps; expected at most "
                                 f"{MAX_STEPS}", self.where)
            self._raw[index] = raw
        return self._raw[index]

    def is_empty(self, index: int) -> bool:
        """Page ``index`` holds no action (a bad checksum, or no steps)."""
        return is_empty(self.data, index)

    def page(self, index: int, spec: Spec) -> Page:
        """Page ``index`` decoded; it must exist, be valid and hold at least one step."""
        if isinstance(index, bool) or not isinstance(index, int) or not 1 <= index < NUM_PAGES:
            raise InputError(f"expected 1..{NUM_PAGES - 1}, got {index!r}", "page")
        page = decode_page(self.raw(index), spec)
        if not page.valid:
            raise InputError(f"page {index} fails its checksum", self.where)
        if not page.steps:
            raise InputError(f"page {index} holds no steps", self.where)
        return page

    def pages(self, spec: Spec) -> list[Page]:
        """Every page that holds an action (valid checksum, at least one step), in order."""
        pages = [decode_page(self.raw(i), spec) for i in range(1, NUM_PAGES)]
        return [p for p in pages if p.valid and p.steps]

    def pose(self, index: int, spec: Spec, name: str | None = None) -> Pose:
        """Page ``index``'s last step as a double-support pose (:func:`page_to_pose`)."""
        return page_to_pose(self.page(index, spec), spec, name)

    def first_empty_run(self, count: int, start: int = 1) -> int:
        """The first page from ``start`` on that begins ``count`` consecutive empty pages."""
        for first in range(start, NUM_PAGES - count + 1):
            if all(self.is_empty(i) for i in range(first, first + count)):
                return first
        raise InputError(f"no {count} consecutive empty pages in the file", "page")

    def check_free(self, first: int, count: int, force: bool) -> None:
        """Refuse to overwrite pages that hold an action (unless ``force``), or to run past the last page."""
        if not (1 <= first and first + count - 1 < NUM_PAGES):
            raise InputError(f"{count} page(s) from page {first} do not fit in pages 1..{NUM_PAGES - 1}", "page")
        taken = [i for i in range(first, first + count) if not self.is_empty(i)]
        if taken and not force:
            raise InputError(f"page(s) {', '.join(map(str, taken))} of the base hold actions; choose empty pages or "
                             f"give {ref('force')} to overwrite them", "page")

    def with_pages(self, pages: Sequence[bytes], first: int | None = None, force: bool = False) -> "PagesWritten":
        """A new file with ``pages`` (512 bytes each) written from ``first`` on (default: the first run of empty
        pages; occupied pages refused unless ``force``), every other page kept byte for byte; and that first page."""
        if not pages:
            return PagesWritten(self, 0)
        first = self.first_empty_run(len(pages)) if first is None else first
        self.check_free(first, len(pages), force)
        data = bytearray(self.data)
        for k, page in enumerate(pages):
            data[(first + k) * PAGE_SIZE:(first + k + 1) * PAGE_SIZE] = page
        return PagesWritten(ActionFile(bytes(data), self.where), first)

    def with_poses(self, poses: Sequence[Pose], spec: Spec, first: int | None = None, seconds: float = 1.0,
                   force: bool = False) -> "PagesWritten":
        """A new file with each pose in its own one-step page of ``seconds`` (see :meth:`with_pages`)."""
        if not poses:
            return PagesWritten(self, 0)
        units = step_units(seconds)
        pages = [encode_page(pose.name, [StepBytes(pose_words(pose, spec), 0, units)]) for pose in poses]
        return self.with_pages(pages, first, force)


@dataclass(frozen=True)
class PagesWritten:
    """An action file with pages written into it: the new ``action`` file and the ``first`` page written (0 when
    none was)."""

    action: ActionFile
    first: int


def step_units(seconds: float, what: str = "time") -> int:
    """A step time [s] in 8 ms units at speed 32: at least 3 (24 ms, the shortest step the framework moves) and at
    most 255 (2.04 s)."""
    lo, hi = MIN_STEP_UNITS * CONTROL_PERIOD_S, MAX_BYTE * CONTROL_PERIOD_S
    if not (math.isfinite(seconds) and lo - 1e-9 <= seconds <= hi + 1e-9):
        raise InputError(f"expected {lo:.3f} to {hi:.2f} s (the robot does not move a step shorter than 24 ms), "
                         f"got {seconds}", what)
    return int(round(seconds / CONTROL_PERIOD_S))


def pose_words(pose: Pose, spec: Spec) -> dict[int, int]:
    """Goal words by Dynamixel ID of a pose."""
    return {j.id: int(t) for j, t in zip(spec.joints, servo_to_ticks(pose.servo, spec))}
