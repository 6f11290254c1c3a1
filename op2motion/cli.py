"""The ``op2motion`` command line: thin subcommands, each calling library functions.

Every subcommand takes ``--json`` (the result as JSON on stdout, nothing else there). Errors are one line on
stderr, naming the flag the user typed (a newline or another control character a message quotes is printed escaped:
:func:`~op2motion.errors.one_line`); exit code 2 for bad input, 1 for a check that ran and failed, 0 for success, 130
when interrupted. Angles on the command line are degrees, lengths metres.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from typing import Any, Sequence

from op2motion.errors import Interrupted, Op2MotionError, one_line
from op2motion.version import __version__

BLAS_THREADS = "OPENBLAS_NUM_THREADS"

#: Every subcommand in the order ``--help`` lists it: the command module that registers it, its name and its
#: one-line help (the module's own, held equal by tests/test_startup.py). The top-level ``--help`` is drawn from this
#: table, and a command's module is imported only when that command is parsed or its help shown: ``op2motion
#: optimize`` loads nothing of the robot, walk or bench commands, and ``--help`` not even NumPy.
COMMANDS: tuple[tuple[str, str, str], ...] = (
    ("kinematics", "fk", "full-body forward kinematics and balance of one pose"),
    ("kinematics", "convert", "book variables <-> servo angles <-> Dynamixel ticks"),
    ("kinematics", "plot", "stick figure of a pose (front, side, top, 3D) as a PNG"),
    ("kinematics", "arm-ik", "move one hand by a displacement with the Taylor-linearised arm IK"),
    ("posture", "optimize", "PSO posture: reach a target with one hand while the CoM stays over the support foot"),
    ("library", "library", "the pose library: build a grid of reach poses"),
    ("files", "export", "pose files -> ROBOTIS action file, Webots motion or CSV"),
    ("files", "import-action", "list the pages of a ROBOTIS action file, or turn one into a pose"),
    ("physics", "urdf", "the URDF generated from the spec (stdout, or -o FILE)"),
    ("physics", "validate", "physics check: does a pose stand? (exit 0 yes, 1 no)"),
    ("motion", "motion", "play action pages, plan pose-to-pose motions, export them"),
    ("walk", "walk", "plan a walk (ZMP preview control) and check it in physics"),
    ("tune", "tune", "tune a walk for your robot in physics (op2motion's walk, or the stock firmware's config.ini)"),
    ("robot", "robot", "the real OP2 on its bus (status, read, play, walk, stand, getup) and an emulated one"),
    ("studio", "studio", "edit a pose in the browser: joints, balance, physics check, save"),
    ("bench", "bench", "speed figures of the batched models, the PSO and the physics check"),
)


def _top_parser(parser_class: type[argparse.ArgumentParser]) -> tuple[argparse.ArgumentParser, Any]:
    """The program's parser with its global options, and the (empty) action its subcommands are added to, each a
    ``parser_class``."""
    from op2motion.commands import common

    parser = common.Parser(prog="op2motion", description="Whole-body motion for the ROBOTIS OP2, checked in physics.")
    parser.add_argument("--version", action="version", version=f"op2motion {__version__}")
    parser.add_argument("--spec", metavar="FILE", help="robot spec TOML (default: the shipped specs/op2.toml)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=parser_class,
                                title="commands", help="run 'op2motion COMMAND --help' for its options")
    return parser, sub


def build_parser(lazy: bool = False) -> argparse.ArgumentParser:
    """The argument parser of every subcommand (each command module registers its own); ``lazy``: each
    subcommand's module is imported and registered only when that subcommand is parsed or its help shown (what the
    program does; see :data:`COMMANDS`)."""
    import importlib

    from op2motion.commands.common import LazyCommand, Parser

    modules = dict.fromkeys(module for module, _, _ in COMMANDS)
    if not lazy:
        parser, sub = _top_parser(Parser)
        for module in modules:
            importlib.import_module(f"op2motion.commands.{module}").register(sub)
        return parser
    parser, sub = _top_parser(LazyCommand)
    siblings: dict[str, dict[str, LazyCommand]] = {module: {} for module in modules}
    for module, name, help_ in COMMANDS:
        siblings[module][name] = command = sub.add_parser(name, help=help_, description=help_)
        command.defer(module, siblings[module])
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser: argparse.ArgumentParser | None = None
    try:
        args = build_parser(lazy=True).parse_args(argv)
        parser = args.parser
        from op2motion.commands.common import check_inert, check_paths

        check_inert(parser, args)
        check_paths(parser, args)
        # here, not at import: --help needs no spec (nor NumPy)
        from op2motion.robot.specfile import load_spec

        spec = load_spec(args.spec)
        return int(args.func(args, spec))
    except Op2MotionError as exc:
        name_of = parser.flag_of if parser is not None else (lambda p: p)  # type: ignore[attr-defined]
        kind = "interrupted" if isinstance(exc, Interrupted) else "error"
        print(f"op2motion: {kind}: {one_line(exc.render(name_of))}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("op2motion: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except ImportError as exc:
        if _interrupted_within(exc):        # Ctrl-C or SIGTERM while a compiled module initialised
            print("op2motion: interrupted", file=sys.stderr)
            return 130
        return _internal_error(exc)
    except Exception as exc:  # a bug, not bad input: still one line (OP2MOTION_DEBUG=1 shows the traceback)
        return _internal_error(exc)


def _interrupted_within(exc: BaseException) -> bool:
    """Was ``exc`` caused by an interrupt (a compiled module's import turns the KeyboardInterrupt raised inside its
    initialisation into ``ImportError: initialization failed``, the interrupt as its cause or context)?"""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, (KeyboardInterrupt, Interrupted)):
            return True
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return False


def _internal_error(exc: Exception) -> int:
    """A bug, not bad input: one line (``OP2MOTION_DEBUG=1`` re-raises it for the traceback); exit 1."""
    if os.environ.get("OP2MOTION_DEBUG"):
        raise exc
    print(f"op2motion: internal error: {type(exc).__name__}: {one_line(str(exc))} (set OP2MOTION_DEBUG=1 for "
          f"details)", file=sys.stderr)
    return 1


def entry() -> None:
    """The ``op2motion`` program: :func:`main`, then a quick exit. Every file is written, every child joined and
    every ``atexit`` handler run before the process ends; only the interpreter's teardown of its loaded modules is
    skipped (with numba's compiler loaded it took 0.12 s, an eighth of an ``optimize``). SIGTERM is handled as
    Ctrl-C (exit 130 with one line, temp files removed, workers ended).

    The program's maths run on one OpenBLAS thread unless ``OPENBLAS_NUM_THREADS`` says otherwise: its matrices are
    small, and each OpenBLAS that loads (NumPy's, SciPy's) starts a thread per extra core that spins for a while
    (0.2-0.4 s of CPU in an ``optimize``, on the core its figure renderers need)."""
    import signal

    os.environ.setdefault(BLAS_THREADS, "1")        # before NumPy loads: it reads this once
    def terminated(signum: int, frame: object) -> None:
        raise KeyboardInterrupt     # SIGTERM ends a command as Ctrl-C does: files in order, one line, exit 130

    signal.signal(signal.SIGTERM, terminated)
    code = main()
    for sig in (signal.SIGINT, signal.SIGTERM):     # the result is decided: a late signal changes nothing
        signal.signal(sig, signal.SIG_IGN)
    from op2motion.fileio import remove_temps

    remove_temps(final=True)                        # a write cut short in another thread leaves no temp file
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)
