"""Helpers shared by the command modules: the parser class, output, and the arguments several commands take.

Every command module has ``register(subparsers)``, which adds its subparser(s) with :func:`add_command`; the
handler it names is called with the parsed arguments and the spec, and returns the exit code.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterator, Mapping, Sequence

from op2motion.errors import InputError, OutputError, one_line, ref, render_refs

if TYPE_CHECKING:
    from op2motion.physics import EngineName
    from op2motion.robot.joints import BookAngles
    from op2motion.robot.pose import Pose
    from op2motion.robot.spec import Spec

Handler = Callable[[argparse.Namespace, "Spec"], int]
#: Library parameter names whose flag is spelled differently.
FLAG_ALIASES = {"iterations": "iters", "output": "output"}


class Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one-line :class:`InputError` instead of exiting."""

    def error(self, message: str) -> None:  # type: ignore[override]
        command = self.prog.split(" ", 1)[1] if " " in self.prog else ""     # not the program's name again
        raise InputError(f"{command}: {message}" if command else message)

    def flag_of(self, param: str) -> str:
        """The flag of this (sub)command that sets library parameter ``param`` (the parameter name if none)."""
        dest = FLAG_ALIASES.get(param, re.sub(r"^out\d+$", "out", param))
        for action in self._actions:
            if action.dest == dest and action.option_strings:
                return max(action.option_strings, key=len)
            if action.dest == dest and not action.option_strings:
                return (action.metavar if isinstance(action.metavar, str) else dest).upper()
        return param


class LazyCommand(Parser):
    """A subcommand's parser that is only a name and a help line until it is used: the first parse or help asks
    its command module (``op2motion.commands.MODULE``) to register, which fills in this parser and its
    ``siblings`` (the other subcommands of that module) in place. See :data:`op2motion.cli.COMMANDS`."""

    _module: str | None = None
    _siblings: dict[str, LazyCommand] = {}

    def defer(self, module: str, siblings: dict[str, LazyCommand]) -> None:
        """Register ``module``'s subcommands (``siblings``, by name, this one among them) on first use."""
        self._module, self._siblings = module, siblings

    def _load(self) -> None:
        module = self._module
        if module is None:
            return
        for command in self._siblings.values():
            command._module = None
        import importlib

        importlib.import_module(f"op2motion.commands.{module}").register(_Registered(self._siblings))

    def parse_known_args(self, args: Any = None, namespace: Any = None) -> Any:
        self._load()
        return super().parse_known_args(args, namespace)

    def format_usage(self) -> str:
        self._load()
        return super().format_usage()

    def format_help(self) -> str:
        self._load()
        return super().format_help()


class _Registered:
    """What a command module's ``register`` adds its subcommands to when they exist already as
    :class:`LazyCommand` s: each ``add_parser`` hands back the one of that name with the given settings (its help
    line is the table's)."""

    def __init__(self, commands: dict[str, LazyCommand]):
        self._commands = commands

    def add_parser(self, name: str, **kwargs: Any) -> LazyCommand:
        command = self._commands[name]
        kwargs.pop("help", None)
        for key, value in kwargs.items():       # description, epilog, formatter_class: read when help is drawn
            setattr(command, key, value)
        return command


def add_command(sub: Any, name: str, handler: Handler, help_: str, description: str | None = None) -> Parser:
    """A subcommand with ``--json`` whose parsed arguments call ``handler``."""
    p: Parser = sub.add_parser(name, help=help_, description=description or help_)
    p.add_argument("--json", action="store_true", help="print the result as JSON on stdout (nothing else there)")
    p.set_defaults(func=handler, parser=p)
    return p


def emit(args: argparse.Namespace, result: Mapping[str, object], text: str) -> None:
    """Print ``result`` as JSON with ``--json`` (through the one encoder, :func:`op2motion.jsonout.to_json`), else
    ``text`` for people."""
    if args.json:
        from op2motion.jsonout import to_json

        json.dump(to_json(result), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    elif text:
        print(text)


def warn(args: argparse.Namespace, result: dict[str, Any], warnings: Sequence[str]) -> None:
    """Record ``warnings`` in the JSON result and print each as one line on stderr (stdout stays the result); a
    parameter a warning refers to is shown as the flag of the command that set it."""
    warnings = [render_refs(w, args.parser.flag_of) for w in warnings]
    result["warnings"] = warnings
    for w in warnings:
        print(f"op2motion: warning: {one_line(w)}", file=sys.stderr)


PLAIN_EVERY_S = 10.0      # where stderr is not a terminal (a log, CI), progress is a plain line this often at most


def progress_enabled(args: argparse.Namespace) -> bool:
    """Progress bars go to stderr when it is a terminal and the output is not JSON (elsewhere: plain lines, see
    :func:`ticker`)."""
    return sys.stderr.isatty() and not getattr(args, "json", False)


class PlainTicker:
    """Progress for a log: one line ``op2motion: DESC: N/TOTAL UNIT (S s)`` on stderr at most every
    :data:`PLAIN_EVERY_S` seconds (a run shorter than that prints nothing); the tqdm calls the commands use."""

    def __init__(self, desc: str, unit: str, total: float | None = None):
        import time

        self.desc, self.unit, self.total, self.n = desc, unit, total, 0.0
        self._clock = time.monotonic
        self._start = self._last = self._clock()
        self._postfix = ""

    def update(self, k: float = 1.0) -> None:
        """``k`` more done; a line if the last was long enough ago."""
        self.n += k
        now = self._clock()
        if now - self._last >= PLAIN_EVERY_S:
            self._last = now
            total = f"/{self.total:g}" if self.total else ""
            print(f"op2motion: {self.desc}: {self.n:g}{total} {self.unit} ({now - self._start:.0f} s){self._postfix}",
                  file=sys.stderr, flush=True)

    def set_postfix(self, **values: Any) -> None:
        """Shown after the count (e.g. the best cost)."""
        self._postfix = "; " + ", ".join(f"{k} {v}" for k, v in values.items())

    def close(self) -> None:
        """Nothing to clear (as tqdm's ``close``)."""

    def __enter__(self) -> "PlainTicker":
        return self

    def __exit__(self, *exc: object) -> None:
        return None


def ticker(args: argparse.Namespace, desc: str, unit: str, total: float | None = None, leave: bool = False,
           bar_format: str | None = None) -> Any:
    """A tqdm bar on a terminal (``bar_format``: tqdm's, e.g. for a count that is not whole), else a
    :class:`PlainTicker` (JSON output keeps stdout clean either way)."""
    if progress_enabled(args):
        from tqdm import tqdm

        return tqdm(total=total, desc=desc, unit=unit, leave=leave, bar_format=bar_format)
    return PlainTicker(desc, unit, total)


def say(args: argparse.Namespace, line: str) -> None:
    """``op2motion: LINE`` on stderr while a command runs (from any thread): on a terminal through tqdm, which clears
    its bars, prints the line and draws them again below it, so that neither overwrites the other."""
    if progress_enabled(args):
        from tqdm import tqdm

        tqdm.write(f"op2motion: {line}", file=sys.stderr)
    else:
        print(f"op2motion: {line}", file=sys.stderr, flush=True)


@contextlib.contextmanager
def progress(args: argparse.Namespace, desc: str, unit: str) -> Iterator[Callable[[float, float], None]]:
    """Progress on stderr (:func:`ticker`) fed with (done, total), e.g. the simulated seconds of a physics check."""
    with ticker(args, desc, unit) as bar:
        def update(done: float, total: float) -> None:
            if bar.total != total:
                bar.total = total
            bar.update(done - bar.n)

        yield update


def physics_args(p: argparse.ArgumentParser, flag: bool, push_help: str) -> None:
    """``--validate`` (when ``flag``), ``--engine pybullet|mujoco|both`` and ``--push N``."""
    from op2motion.physics import ENGINES, MAX_PUSH_N

    if flag:
        p.add_argument("--validate", action="store_true", help="check it in physics")
    p.add_argument("--engine", choices=(*ENGINES, "both"), default="pybullet",
                   help="physics engine (default pybullet); both: run both and say where they disagree")
    p.add_argument("--push", type=number(0.0, MAX_PUSH_N, "N"), default=0.0, metavar="N", help=push_help)


def engines_of(args: argparse.Namespace) -> tuple[EngineName, ...]:
    """The engines ``--engine`` names (argparse has checked it is one of them, or ``both``)."""
    from op2motion.physics import ENGINES

    return tuple(ENGINES) if args.engine == "both" else tuple(e for e in ENGINES if e == args.engine)


def book_args(p: argparse.ArgumentParser, pose_flag: bool = True) -> None:
    """``--support``, ``--th``, ``--phi``, ``--psi`` (and ``--pose FILE``)."""
    p.add_argument("--support", choices=("left", "right"), default="left", help="support foot (default left)")
    p.add_argument("--th", type=BOOK_ANGLE_DEG, nargs="+", metavar="DEG", help="11 sagittal angles th1..th11 [deg]")
    p.add_argument("--phi", type=BOOK_ANGLE_DEG, nargs="+", metavar="DEG", help="6 coronal angles phi1..phi6 [deg]")
    p.add_argument("--psi", type=BOOK_ANGLE_DEG, nargs="+", metavar="DEG",
                   help="3 transverse angles psi1..psi3 [deg] (default 0)")
    if pose_flag:
        p.add_argument("--pose", metavar="FILE", help="a pose file instead of --th/--phi")


@dataclass(frozen=True)
class NamedAngles:
    """A pose as the command line gave it: its book ``angles``, its ``name``, and the ``pose`` file's pose (None when
    it came from ``--th``/``--phi``)."""

    angles: BookAngles
    name: str
    pose: Pose | None


def angles_from(args: argparse.Namespace, spec: Spec, pose_path: str | None = None, default_standing: bool = False
                ) -> NamedAngles:
    """Book angles and a name from a pose file, or ``--th``/``--phi``[/``--psi``] ``--support``, or (when
    ``default_standing``) the book's standing pose."""
    from op2motion.formats.posefile import read_pose
    from op2motion.robot.joints import BookAngles

    pose_path = pose_path if pose_path is not None else getattr(args, "pose", None)
    if pose_path:
        if args.th is not None or args.phi is not None:
            raise InputError("give either a pose file or --th/--phi, not both")
        pose = read_pose(pose_path, spec)
        return NamedAngles(pose.book(spec), pose.name, pose)
    if args.th is None and args.phi is None:
        if default_standing:
            return NamedAngles(BookAngles.standing(args.support), "standing", None)
        raise InputError("expected --th (11 angles) and --phi (6 angles) in degrees, or --pose FILE")
    if args.th is None or args.phi is None:
        raise InputError("expected both --th (11 angles) and --phi (6 angles)")
    return NamedAngles(BookAngles.from_deg(args.th, args.phi, args.psi, args.support), "pose", None)


def vec3(values: Sequence[float] | None, name: str) -> tuple[float, float, float] | None:
    """Three finite numbers, or ``None`` when not given."""
    if values is None:
        return None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"expected 3 finite numbers, got {list(values)}", name)
    return (float(values[0]), float(values[1]), float(values[2]))


def walk_target(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """A walk's ``--target X Y YAW_DEG`` as (x [m], y [m], yaw [rad]), or None; refused with ``--steps`` (a target
    sets the number of steps) or when not finite. The one rule of ``walk`` and ``robot walk``."""
    if args.target is not None and args.steps is not None:
        raise InputError("expected --steps or --target, not both (a target sets the number of steps)", "steps")
    target = vec3(args.target, "target")
    return None if target is None else (target[0], target[1], math.radians(target[2]))


def _parse_float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def number(lo: float, hi: float, unit: str = "", open_low: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in [lo, hi] (or (lo, hi] with ``open_low``); the range is in the message."""
    span = f"{'(' if open_low else '['}{lo:g}, {hi:g}]{' ' + unit if unit else ''}"

    def parse(text: str) -> float:
        value = _parse_float(text)
        if not (math.isfinite(value) and (lo < value if open_low else lo <= value) and value <= hi):
            raise argparse.ArgumentTypeError(f"expected a finite number in {span}, got {text}")
        return value

    parse.__name__ = "number"
    return parse


def whole(lo: int, hi: int) -> Callable[[str], int]:
    """An argparse type: a whole number in [lo, hi]; the range is in the message."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number from {lo} to {hi}, got {text!r}") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"expected a whole number from {lo} to {hi}, got {value}")
        return value

    parse.__name__ = "whole number"
    return parse


def output_path(text: str) -> str:
    """An argparse type: a path to write; an empty string is refused before any work."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file path, got an empty string")
    return text


#: Arguments that name files a command reads (their dests), so that no output may land on one of them.
INPUT_DESTS = ("spec", "pose", "poses", "pose_positional", "file", "motion", "base", "start", "action")


def _values(value: Any) -> list[str]:
    if value is None:
        return []
    return [str(v) for v in value] if isinstance(value, (list, tuple)) else [str(value)]


#: Flags that only act on a physics check: typed without ``--validate`` they would do nothing.
VALIDATE_ONLY = ("push", "engine", "seconds", "trials", "robust", "open_loop", "perturb_deg")


def check_inert(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse (bad input, naming the flag) a flag given a value that cannot act: a physics option without
    ``--validate``, a planner seed with ``--planner none``."""
    if getattr(args, "validate", None) is False:
        for dest in VALIDATE_ONLY:
            if hasattr(args, dest) and getattr(args, dest) != parser.get_default(dest):
                raise InputError(f"expected --validate with {ref(dest)} (it sets the physics check)", dest)
    if getattr(args, "planner", None) == "none" and getattr(args, "seed", 0) != parser.get_default("seed"):
        raise InputError(f"expected {ref('planner')} rrt with {ref('seed')} (the seed drives the path planner)",
                         "seed")


def check_paths(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse (bad input, naming the flag) an output file that is also an input file or another output of the same
    command: writing it would destroy the input or one of the two results."""
    seen: dict[str, str] = {}
    for dest in INPUT_DESTS:
        for value in _values(getattr(args, dest, None)):
            seen.setdefault(os.path.realpath(value), dest)
    for action in parser._actions:
        if action.type not in (output_path, png_path):
            continue
        for value in _values(getattr(args, action.dest, None)):
            where = os.path.realpath(value)
            if where in seen:
                other = seen[where]
                what = "an input file" if other in INPUT_DESTS else "another output"
                raise OutputError(f"expected a file other than {what} ({ref(other)}), got {value}", action.dest)
            seen[where] = action.dest


def png_path(text: str) -> str:
    """An argparse type: a PNG file to write (the name must end in .png: the bytes written are PNG)."""
    path = output_path(text)
    if not path.lower().endswith(".png"):
        raise argparse.ArgumentTypeError(f"expected a file name ending in .png, got {text}")
    return path


def pose_name(text: str) -> str:
    """An argparse type: a pose name (see :func:`op2motion.robot.pose.check_pose_name`)."""
    from op2motion.robot.pose import NAME_RULE, check_pose_name

    try:
        return check_pose_name(text)
    except InputError:
        raise argparse.ArgumentTypeError(f"expected a pose name ({NAME_RULE}), got {text!r}") from None


#: Ranges of the numbers users type, shared by every command (angles [deg], lengths [m]).
BOOK_ANGLE_DEG = number(-360.0, 360.0, "deg")
HEADING_DEG = number(-360.0, 360.0, "deg")
POSITION_M = number(-10.0, 10.0, "m")
TARGET_M = number(-1.0, 1.0, "m")
DELTA_M = number(-0.5, 0.5, "m")
BOUNDARY_RATIO = number(0.0, 1.0, open_low=True)
