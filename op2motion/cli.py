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
from typing import Sequence

from op2motion.errors import Interrupted, Op2MotionError, one_line
from op2motion.robot.specfile import load_spec
from op2motion.version import __version__


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand (each command module registers its own)."""
    from op2motion.commands import (
        bench,
        common,
        files,
        kinematics,
        library,
        motion,
        physics,
        posture,
        robot,
        studio,
        tune,
        walk,
    )

    parser = common.Parser(prog="op2motion", description="Whole-body motion for the ROBOTIS OP2, checked in physics.")
    parser.add_argument("--version", action="version", version=f"op2motion {__version__}")
    parser.add_argument("--spec", metavar="FILE", help="robot spec TOML (default: the shipped specs/op2.toml)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=common.Parser,
                                title="commands", help="run 'op2motion COMMAND --help' for its options")
    for module in (kinematics, posture, library, files, physics, motion, walk, tune, robot, studio, bench):
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser: argparse.ArgumentParser | None = None
    try:
        args = build_parser().parse_args(argv)
        parser = args.parser
        from op2motion.commands.common import check_inert, check_paths

        check_inert(parser, args)
        check_paths(parser, args)
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
    Ctrl-C (exit 130 with one line, temp files removed, workers ended)."""
    import signal

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
