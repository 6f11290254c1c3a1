"""Faults the emulated OP2 can be given, from Python or from ``op2motion robot emulate``'s flags.

* ``missing``: servos not on the bus at all (silent, limp);
* ``unplug``: (id, seconds) a servo that goes silent and limp that long into the motion;
* ``lose``: the share of status packets lost on the way back (seeded);
* ``corrupt``: the share of status packets with one byte changed (the checksum no longer matches);
* ``overheat``: (id, seconds, °C) a servo whose temperature jumps to that much that long into the motion (above
  its limit, 80 °C by default, it reports overheating and its alarm shutdown drops its torque);
* ``supply_v``: the supply voltage [V] (below a servo's lowest voltage limit, 6 V, it reports an input-voltage
  error);
* ``horn``: {id: ticks} a servo whose horn is mounted that many ticks off the joint (a spline off, 1 spline = 4096/25
  ticks on the MX-28's 25-tooth horn): it reads the joint's angle plus that and drives its goal less that;
* ``push``: (newtons, seconds) a push forward (+x of the world, the way the robot first faced) at the torso's centre
  of mass for :data:`PUSH_S`, that long into the motion;
* ``models``: {id: model number} devices that report another model at address 0 (a servo of IDs 1..20: an AX-12
  reports 12; the board, 200: the CM-740's 0x7400 plays the OP2's board, :func:`with_board`, whose table is the
  CM-730's; another number a board of another model); the rest of their tables stays as it was;
* ``errors``: {id: error byte} devices whose every status packet carries these error bits (:data:`ALL_ERRORS`: the
  seven of Protocol 1.0), beside whatever the device reports itself; only the byte reported changes (what the
  firmware would do about them, e.g. an alarm shutdown, does not follow).

Times count from the motion's start: the first SYNC_WRITE the emulator receives (what a client sends every 8 ms
while it drives the robot), so a fault lands at the same point of a motion however long the client took to start.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import NamedTuple

from op2motion.bus.tables import CM730_MODEL_NUMBER, CM740_MODEL_NUMBER, model_name
from op2motion.errors import InputError

MAX_RATE = 0.5                     # more lost or corrupted replies than this is no bus at all
PUSH_S = 0.1                       # a push lasts this long [s]
MAX_PUSH_N = 200                   # a push stronger than this is not a push [N]
_TIMED = re.compile(r"^(\d+)@(\d+(?:\.\d*)?)(?::(\d+(?:\.\d*)?))?$")
_PAIR = re.compile(r"^(\d+):(0x[0-9a-f]+|\d+|all)$", re.IGNORECASE)
ALL_ERRORS = 0x7F                  # every error bit Protocol 1.0 defines (input voltage ... instruction)
BOARD_ID = 200                     # the sub-controller's ID (tables.CM730_ID), a device a fault may name
MAX_MODEL = 0xFFFF                 # a model number is a 16-bit register
#: The boards the emulator plays, by name: the model number each reports (the default: the CM-730).
BOARDS = {"cm730": CM730_MODEL_NUMBER, "cm740": CM740_MODEL_NUMBER}


@dataclass
class Faults:
    """The faults of one emulator run (see the module docstring)."""

    missing: set[int] = field(default_factory=set)
    unplug: list[tuple[int, float]] = field(default_factory=list)
    lose: float = 0.0
    corrupt: float = 0.0
    overheat: list[tuple[int, float, float]] = field(default_factory=list)
    supply_v: float | None = None
    seed: int = 0
    push: list[tuple[float, float]] = field(default_factory=list)
    models: dict[int, int] = field(default_factory=dict)
    errors: dict[int, int] = field(default_factory=dict)
    horn: dict[int, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("lose", "corrupt"):
            value = getattr(self, name)
            if not 0.0 <= value <= MAX_RATE:
                raise InputError(f"expected a share from 0 to {MAX_RATE:g}, got {value!r}", name)
        for device in (set(self.missing) | {d for d, _ in self.unplug} | {d for d, _, _ in self.overheat}
                       | set(self.horn)):
            if not 1 <= device <= 20:
                raise InputError(f"expected a servo ID 1..20, got {device}", "missing")
        for newtons, _ in self.push:
            if not 0.0 < newtons <= MAX_PUSH_N:
                raise InputError(f"expected a push of 1 to {MAX_PUSH_N} N, got {newtons:g}", "push")
        if self.supply_v is not None and not 0.0 <= self.supply_v <= 25.5:
            raise InputError(f"expected a supply of 0 to 25.5 V, got {self.supply_v!r}", "supply")
        self._check_pairs("model", self.models, 0, MAX_MODEL)
        self._check_pairs("errors", self.errors, 1, 0xFF)

    @staticmethod
    def _check_pairs(name: str, pairs: dict[int, int], low: int, high: int) -> None:
        """{id: value} with each ID a servo's (1..20) or the board's (200), each value within ``low..high``."""
        for device, value in pairs.items():
            if not (1 <= device <= 20 or device == BOARD_ID):
                raise InputError(f"expected a servo ID 1..20 or the board's {BOARD_ID}, got {device}", name)
            if not low <= value <= high:
                raise InputError(f"expected a value {low}..{high} for ID {device}, got {value}", name)

    def describe(self) -> list[str]:
        """One phrase per fault."""
        out = [f"servo {d} missing" for d in sorted(self.missing)]
        out += [f"servo {d} unplugged at {t:g} s" for d, t in self.unplug]
        out += [f"servo {d} at {c:g} °C from {t:g} s" for d, t, c in self.overheat]
        if self.lose:
            out.append(f"{self.lose:.1%} of replies lost")
        if self.corrupt:
            out.append(f"{self.corrupt:.1%} of replies corrupted")
        if self.supply_v is not None:
            out.append(f"supply {self.supply_v:g} V")
        out += [f"pushed forward {n:g} N at {t:g} s" for n, t in self.push]
        out += [f"ID {d} reports model {m}" + (f" ({model_name(m)})" if model_name(m) else "")
                for d, m in sorted(self.models.items())]
        out += [f"ID {d} reports error bits {e:#04x}" for d, e in sorted(self.errors.items())]
        out += [f"servo {d}'s horn {t:+d} ticks off" for d, t in sorted(self.horn.items())]
        return out

    def push_at(self, since_s: float) -> float:
        """The forward push [N] at ``since_s`` [s] into the motion (0 when none)."""
        return sum(n for n, t in self.push if t <= since_s < t + PUSH_S)


class Timed(NamedTuple):
    """A fault at a time, as ``ID@SECONDS[:VALUE]`` gives it: the leading ``number`` (a servo's ID, or newtons), the
    time ``at_s`` [s] into the motion and the ``value`` (e.g. °C)."""

    number: int
    at_s: float
    value: float


def parse_timed(text: str, param: str, default_value: float | None = None, first: str = "ID") -> Timed:
    """``ID@SECONDS[:VALUE]`` (e.g. ``13@4:85``; ``first`` names the leading number in messages); bad input names
    ``param``."""
    m = _TIMED.match(text.strip())
    if not m or (m.group(3) is not None and default_value is None):
        form = f"{first}@SECONDS[:CELSIUS]" if default_value is not None else f"{first}@SECONDS"
        example = f"{30 if first == 'N' else 13}@4{':85' if default_value is not None else ''}"
        raise InputError(f"expected {form} (e.g. {example}), got {text!r}", param)
    value = float(m.group(3)) if m.group(3) is not None else float(default_value or 0.0)
    return Timed(int(m.group(1)), float(m.group(2)), value)


def parse_pair(text: str, param: str, all_value: int | None = None) -> tuple[int, int]:
    """``ID:VALUE`` (VALUE decimal or 0x hex; ``all`` is ``all_value`` where one is given), e.g. ``14:12`` or
    ``14:0x7f`` -> (id, value); bad input names ``param``."""
    m = _PAIR.match(text.strip())
    if not m or (m.group(2).lower() == "all" and all_value is None):
        forms = "ID:VALUE (e.g. 14:12 or 14:0x7f" + (", or 14:all" if all_value is not None else "") + ")"
        raise InputError(f"expected {forms}, got {text!r}", param)
    value = m.group(2).lower()
    if value == "all" and all_value is not None:
        return int(m.group(1)), all_value
    return int(m.group(1)), int(value, 16) if value.startswith("0x") else int(value)


def with_board(models: dict[int, int], board: str | None, param: str) -> dict[int, int]:
    """``models`` with the board's model number that of ``board`` (:data:`BOARDS`; None: as ``models`` has it, the
    CM-730's by default); a board named beside a model number given to ID 200 is bad input naming ``param``."""
    if board is None:
        return models
    if board not in BOARDS:
        raise InputError(f"expected a board among {', '.join(BOARDS)}, got {board!r}", param)
    if BOARD_ID in models:
        raise InputError(f"expected a board or a model number for ID {BOARD_ID}, not both", param)
    return {**models, BOARD_ID: BOARDS[board]}
