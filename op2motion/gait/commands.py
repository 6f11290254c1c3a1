"""Command timelines: what a steered walk is told, and when (``walk --commands FILE``; any loop can feed one).

A timeline is a list of entries in time order, each at ``t_s`` [s] since the controller's start (the time its
``step`` receives), each a command (``vx_m_s`` forward, ``vy_m_s`` to the left [m/s], ``yaw_rate_deg_s`` to the left
[deg/s]: degrees at the edge, radians inside), an event (:data:`EVENTS`: ``stop``; ``kick_right``, ``kick_left``: stop,
kick, walk on), or both. A command holds until the next one; the walk starts standing (a zero command). Two forms:

CSV (a header naming the columns, ``#`` comments and blank lines skipped; an empty cell: no command there)::

    t_s,vx_m_s,vy_m_s,yaw_rate_deg_s,event
    0,0,0,0,
    3,0.15,0,0,
    8,0.15,0,20,
    14,,,,stop

JSON: ``{"schema": "op2motion.commands/1", "commands": [{"t_s": 3, "vx_m_s": 0.15, "vy_m_s": 0, "yaw_rate_deg_s":
0}, {"t_s": 14, "event": "stop"}]}``.

Checked like every input: times finite, from 0 to :data:`MAX_DURATION_S`, strictly increasing; at most
:data:`MAX_ENTRIES` entries; a command gives all three speeds, each finite and within :data:`MAX_SPEED_M_S` /
:data:`MAX_YAW_RATE_DEG_S` (the walk then keeps them within its measured envelope); an unknown event, column or key
is refused. Each error names the file and the line (CSV) or the entry and field (JSON).

:meth:`CommandTimeline.feed` hands a walk what fell due since the last call: ``command()`` when a new command begins,
``stop()`` and ``kick()`` for events.
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.support import Side

SCHEMA = "op2motion.commands/1"
EVENTS = ("stop", "kick_right", "kick_left")
KICKS: dict[str, Side] = {"kick_right": "right", "kick_left": "left"}    # the kick events' feet
MAX_DURATION_S = 600.0
MAX_ENTRIES = 10_000
MAX_SPEED_M_S = 1.0
MAX_YAW_RATE_DEG_S = 180.0
SPEEDS = ("vx_m_s", "vy_m_s", "yaw_rate_deg_s")
COLUMNS = ("t_s", *SPEEDS, "event")


class Steered(Protocol):
    """What a timeline feeds: a steerable walk (:class:`.steer.SteerableWalk`)."""

    def command(self, vx_m_s: float, vy_m_s: float, yaw_rate_rad_s: float) -> None: ...

    def stop(self) -> None: ...

    def kick(self, foot: Side) -> None: ...


@dataclass(frozen=True)
class Entry:
    """One moment of a timeline: its time [s], a command (vx [m/s], vy [m/s], yaw rate [rad/s]) or None, an event
    or None."""

    t_s: float
    command: tuple[float, float, float] | None = None
    event: str | None = None


@dataclass(frozen=True)
class CommandTimeline:
    """Entries in strictly increasing time (see the module docstring)."""

    entries: tuple[Entry, ...]
    source: str = "<commands>"

    @property
    def duration_s(self) -> float:
        """The last entry's time [s]."""
        return self.entries[-1].t_s if self.entries else 0.0

    def due(self, after_s: float | None, until_s: float) -> list[Entry]:
        """The entries later than ``after_s`` (None: from the first) and no later than ``until_s`` [s]."""
        return [e for e in self.entries if (after_s is None or e.t_s > after_s) and e.t_s <= until_s]

    def command_at(self, t_s: float) -> tuple[float, float, float]:
        """The command in force at ``t_s`` [s] (zero before the first and after a stop that no command followed)."""
        out = (0.0, 0.0, 0.0)
        for e in self.entries:
            if e.t_s > t_s:
                break
            if e.command is not None:
                out = e.command
            elif e.event == "stop":
                out = (0.0, 0.0, 0.0)
        return out

    def feed(self, walk: Steered, after_s: float | None, until_s: float) -> None:
        """Hand ``walk`` the entries due between two calls (see :meth:`due`): commands, stops and kicks."""
        for e in self.due(after_s, until_s):
            if e.command is not None:
                walk.command(*e.command)
            if e.event == "stop":
                walk.stop()
            elif e.event is not None:
                walk.kick(KICKS[e.event])


def _number(text: Any, where: str, field: str, low: float, high: float) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{where}: {field}: expected a number, got {text!r}", "commands") from None
    if isinstance(text, bool) or not (math.isfinite(value) and low <= value <= high):
        raise InputError(f"{where}: {field}: expected {low:g} to {high:g}, got {text!r}", "commands")
    return value


def _entry(row: dict[str, Any], where: str) -> Entry:
    """One entry from a row of named fields (empty or missing speeds: no command)."""
    t = _number(row.get("t_s"), where, "t_s", 0.0, MAX_DURATION_S)
    given = [row.get(name) not in (None, "") for name in SPEEDS]
    command = None
    if any(given):
        if not all(given):
            missing = [name for name, g in zip(SPEEDS, given) if not g]
            raise InputError(f"{where}: expected all of {', '.join(SPEEDS)} for a command, got none for "
                             f"{', '.join(missing)}", "commands")
        vx, vy = (_number(row[name], where, name, -MAX_SPEED_M_S, MAX_SPEED_M_S) for name in SPEEDS[:2])
        yaw = _number(row["yaw_rate_deg_s"], where, "yaw_rate_deg_s", -MAX_YAW_RATE_DEG_S, MAX_YAW_RATE_DEG_S)
        command = (vx, vy, math.radians(yaw))
    event = row.get("event")
    event = None if event in (None, "") else str(event).strip()
    if event is not None and event not in EVENTS:
        raise InputError(f"{where}: event: expected one of {', '.join(EVENTS)}, got {event!r}", "commands")
    if command is None and event is None:
        raise InputError(f"{where}: expected a command ({', '.join(SPEEDS)}) or an event, got neither", "commands")
    return Entry(t, command, event)


def _timeline(entries: list[tuple[Entry, str]], source: str) -> CommandTimeline:
    if not entries:
        raise InputError(f"{source}: expected at least one entry, got none", "commands")
    if len(entries) > MAX_ENTRIES:
        raise InputError(f"{source}: expected at most {MAX_ENTRIES} entries, got {len(entries)}", "commands")
    for (before, _), (entry, where) in zip(entries, entries[1:]):
        if entry.t_s <= before.t_s:
            raise InputError(f"{where}: t_s: expected a time after {before.t_s:g} s (strictly increasing), got "
                             f"{entry.t_s:g}", "commands")
    return CommandTimeline(tuple(e for e, _ in entries), source)


def parse_csv(text: str, source: str = "<commands>") -> CommandTimeline:
    """A timeline from CSV text (see the module docstring)."""
    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip() and not line.lstrip()
             .startswith("#")]
    if not lines:
        raise InputError(f"{source}: expected a header line ({','.join(COLUMNS)}), got an empty file", "commands")
    header_line, header = lines[0][0], [c.strip() for c in next(csv.reader([lines[0][1]]))]
    unknown = [c for c in header if c not in COLUMNS]
    if unknown or "t_s" not in header or len(set(header)) != len(header):
        raise InputError(f"{source}, line {header_line}: expected a header of {', '.join(COLUMNS)} (t_s first or "
                         f"anywhere, each once), got {', '.join(header)}", "commands")
    entries = []
    for n, line in lines[1:]:
        where = f"{source}, line {n}"
        cells = next(csv.reader(io.StringIO(line)))
        if len(cells) > len(header):
            raise InputError(f"{where}: expected at most {len(header)} fields, got {len(cells)}", "commands")
        entries.append((_entry({name: cell.strip() for name, cell in zip(header, cells)}, where), where))
        if len(entries) > MAX_ENTRIES:
            break
    return _timeline(entries, source)


def parse_json(doc: Any, source: str = "<commands>") -> CommandTimeline:
    """A timeline from a decoded JSON document (see the module docstring)."""
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        got = doc.get("schema") if isinstance(doc, dict) else type(doc).__name__
        raise InputError(f"{source}: expected an object with schema {SCHEMA!r}, got {got!r}", "commands")
    unknown = sorted(set(doc) - {"schema", "commands", "name"})
    items = doc.get("commands")
    if unknown or not isinstance(items, list):
        raise InputError(f"{source}: expected the keys schema, commands (a list) and optionally name, got "
                         f"{', '.join(sorted(doc))}", "commands")
    entries = []
    for i, item in enumerate(items[:MAX_ENTRIES + 1]):
        where = f"{source}, commands[{i}]"
        if not isinstance(item, dict) or set(item) - set(COLUMNS):
            extra = sorted(set(item) - set(COLUMNS)) if isinstance(item, dict) else type(item).__name__
            raise InputError(f"{where}: expected an object with {', '.join(COLUMNS)}, got {extra}", "commands")
        entries.append((_entry(item, where), where))
    return _timeline(entries, source)


def read_commands(path: str | Path) -> CommandTimeline:
    """The timeline of a ``.csv`` or ``.json`` file (see the module docstring)."""
    from op2motion.fileio import read_text
    from op2motion.formats.posefile import DuplicateKey, _unique_keys

    path = Path(path)
    text = read_text(path, "command file")
    if path.suffix.lower() == ".csv":
        return parse_csv(text, str(path))
    if path.suffix.lower() != ".json":
        raise InputError(f"expected a .csv or .json command file, got {str(path)!r}", "commands")
    try:
        doc = json.loads(text, object_pairs_hook=_unique_keys)
    except DuplicateKey as exc:
        raise InputError(f"{path}: expected each key once in an object, got {exc.key!r} twice", "commands") from None
    except (json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"{path}: not valid JSON: {exc}", "commands") from None
    return parse_json(doc, str(path))


def timeline_of(steps: list[tuple[float, float, float, float] | tuple[float, str]]) -> CommandTimeline:
    """A timeline from code: ``(t_s, vx_m_s, vy_m_s, yaw_rate_rad_s)`` commands and ``(t_s, event)`` events."""
    entries = []
    for i, step in enumerate(steps):
        where = f"step {i}"
        if len(step) == 2:
            entries.append((_entry({"t_s": step[0], "event": step[1]}, where), where))
        else:
            t, vx, vy, yaw = step
            entries.append((_entry({"t_s": t, "vx_m_s": vx, "vy_m_s": vy,
                                    "yaw_rate_deg_s": math.degrees(float(yaw))}, where), where))
    return _timeline(entries, "<code>")


def commanded_path(timeline: CommandTimeline, dt: float = 0.008) -> tuple[np.ndarray, np.ndarray]:
    """The path the commands ask for, from the origin facing +X: times (N,) [s] and poses (N, 3) (x [m], y [m],
    yaw [rad]), the command in force integrated in the body's frame every ``dt`` [s] until the last entry."""
    steps = int(math.ceil(timeline.duration_s / dt)) + 1
    times = np.arange(steps) * dt
    poses = np.zeros((steps, 3))
    for i in range(1, steps):
        vx, vy, yaw_rate = timeline.command_at(times[i - 1])
        x, y, yaw = poses[i - 1]
        c, s = math.cos(yaw), math.sin(yaw)
        poses[i] = (x + (c * vx - s * vy) * dt, y + (s * vx + c * vy) * dt, yaw + yaw_rate * dt)
    return times, poses
