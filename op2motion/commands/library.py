"""CLI command of the pose library: library build."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion import book
from op2motion.commands.common import (
    BOUNDARY_RATIO,
    Parser,
    add_command,
    number,
    output_path,
    ticker,
    whole,
)
from op2motion.commands.posture import com_model_arg, solver_args
from op2motion.errors import InputError
from op2motion.library.build import MAX_WORKERS
from op2motion.library.grid import MAX_AXIS
from op2motion.robot.spec import Spec

AXIS_VALUE = number(-1e6, 1e6)   # START, STOP and COUNT of a grid axis; the library checks the real ranges


def register(sub: Any) -> None:
    """Add ``library`` and its subcommand ``build``."""
    lib = sub.add_parser("library", help="the pose library: build a grid of reach poses",
                         description="the pose library: build a grid of reach poses")
    lib_sub = lib.add_subparsers(dest="subcommand", metavar="SUBCOMMAND", required=True, parser_class=Parser,
                                 title="subcommands", help="what to do with the library")
    p = add_command(lib_sub, "build", cmd_library_build,
                    "optimise a grid of reach targets in worker processes (resumable)",
                    "Solve every combination of hands x supports x boundary ratios x target points with the "
                    "posture optimiser, in worker processes. Reached poses go to --out as pose files, every "
                    "target (reached or not, with its reason) to index.json and index.csv. Run it again to "
                    "resume: targets already in the index are skipped. Ctrl-C stops it within seconds with a "
                    "complete index.")
    p.add_argument("--hands", nargs="+", choices=("left", "right"), default=["left", "right"],
                   help="reaching hands (default both)")
    p.add_argument("--supports", nargs="+", choices=("left", "right"), default=["left", "right"],
                   help="support feet (default both)")
    p.add_argument("--br", type=BOUNDARY_RATIO, nargs="+", default=[book.DEFAULT_PROBLEM.br],
                   help=f"boundary ratios (default {book.DEFAULT_PROBLEM.br})")
    for axis, default in (("x", (0.06, 0.14, 3)), ("y", (-0.06, 0.06, 3)), ("z", (0.05, 0.15, 3))):
        p.add_argument(f"--{axis}", type=AXIS_VALUE, nargs=3, default=default, metavar=("START", "STOP", "N"),
                       help=f"N target {axis} values from START to STOP [m], N <= {MAX_AXIS} "
                            f"(default {' '.join(f'{v:g}' for v in default)})")
    p.add_argument("--out", type=output_path, default="poses/library", help="library folder (default poses/library)")
    p.add_argument("--workers", type=whole(0, MAX_WORKERS), default=0,
                   help=f"worker processes, 0 = one per core (default 0, at most {MAX_WORKERS})")
    p.add_argument("--executor", choices=("process", "ray"), default="process",
                   help="process: a pool of worker processes here (default); ray: Ray tasks (pip install "
                        "'.[cluster]'), on this machine or, with --address, on a running cluster")
    p.add_argument("--address", metavar="ADDR", help="with --executor ray: the cluster's head, e.g. 10.0.0.5:6379 "
                                                     "or auto (default: start Ray on this machine)")
    com_model_arg(p)
    solver_args(p)
    p.add_argument("--robust", action="store_true",
                   help="with --validate: also hold each pose that stands on every member of the robustness family "
                        "(the check's engine); the index says how many runs it passed and the worst")


def cmd_library_build(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion library build``."""
    from op2motion.commands.deliver import deliver
    from op2motion.library.build import BuildSettings, Executor, check_workers
    from op2motion.library.grid import axis, grid_jobs
    from op2motion.posture.pso import PSOSettings
    from op2motion.tasks.library import LibraryBuild, build
    from op2motion.workflow import Validate

    check_workers(args.workers)
    executor = Executor(args.executor, args.address)
    if args.robust and not args.validate:
        raise InputError("expected --validate with --robust", "validate")
    x, y, z = (axis(start, stop, count, name) for name, (start, stop, count) in
               (("x", args.x), ("y", args.y), ("z", args.z)))
    jobs = grid_jobs(args.hands, args.supports, args.br, x, y, z, args.com_model)
    settings = BuildSettings(PSOSettings(args.particles, args.iters, seed=args.seed).validated(), args.restarts,
                             Validate(args.seconds, args.engine) if args.validate else None, args.robust)
    request = LibraryBuild(jobs, settings, args.out, executor, args.workers, args.spec)
    with ticker(args, "library", "pose", len(jobs), leave=True) as bar:
        result = build(request, spec, on_done=lambda row: bar.update())
    return deliver(args, result)
