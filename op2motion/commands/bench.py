"""CLI command bench."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from op2motion.book import TIMED_POSES as BENCH_POSES
from op2motion.commands.common import add_command, whole
from op2motion.robot.spec import Spec

STOCK_ACTION = Path(__file__).resolve().parents[2] / "tests" / "data" / "motion_4096.bin"


def register(sub: Any) -> None:
    """Add bench."""
    p = add_command(sub, "bench", cmd_bench, "speed figures of the batched models, the PSO and the physics check")
    p.add_argument("--poses", type=whole(100, 1_000_000), default=BENCH_POSES,
                   help=f"batch size; figures are scaled to {BENCH_POSES} (default {BENCH_POSES})")
    p.add_argument("--repeat", type=whole(1, 100), default=9,
                   help="runs per figure (at most 3 for the physics checks, the PSO and the planners); the best is "
                        "reported (default 9)")
    p.add_argument("--wall-runs", type=whole(0, 20), default=3,
                   help="fresh runs of the op2motion program: --help, optimize and optimize --validate, each timed "
                        "to its exit (the best and the median reported), plus one library build of the default grid; "
                        "0 skips them (default 3)")
    p.add_argument("--action", metavar="FILE", default=str(STOCK_ACTION) if STOCK_ACTION.exists() else None,
                   help="action file for motion_play_ms / motion_validate_ms (default: the stock file in the "
                        "repository's tests/data, when present)")


def cmd_bench(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion bench``."""
    from op2motion.commands.deliver import deliver
    from op2motion.formats.action import ActionFile
    from op2motion.tasks.bench import bench

    action = ActionFile.read(args.action) if args.action else None
    return deliver(args, bench(spec, args.poses, args.repeat, action, args.wall_runs))
