"""CLI command ``op2motion tune walk|stock``: faster walks found in physics, robust across the body (thin: the work
is :mod:`op2motion.tune`)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from op2motion.commands.common import add_command, output_path, png_path, progress, whole
from op2motion.robot.spec import Spec

MAX_WORKERS = 64
MAX_VERIFY = 10


def register(sub: Any) -> None:
    """Add ``tune walk`` and ``tune stock``."""
    from op2motion.commands.common import Parser

    top = sub.add_parser("tune", help="tune a walk for your robot in physics (op2motion's walk, or the stock "
                                      "firmware's config.ini)",
                         description="Search gait parameters with Optuna for the fastest walk that holds across the "
                                     "robustness family, verify it in both engines and write it.")
    inner = top.add_subparsers(dest="tune_command", metavar="WHAT", required=True, parser_class=Parser,
                               help="walk or stock")
    p = add_command(inner, "walk", cmd_tune_walk, "op2motion's walk: a gait preset for WalkController")
    p.add_argument("--direction", choices=("forward", "backward", "sideways", "turn"), default="forward",
                   help="the direction to make fast (default forward)")
    p.add_argument("--preset", metavar="TOML", help="the preset tuned from (default: the direction's shipped one)")
    _common(p, "TOML", "the preset to write (e.g. walking/fast.toml)")
    p = add_command(inner, "stock", cmd_tune_stock, "the stock ROBOTIS firmware's Walking module: a config.ini")
    p.add_argument("--config", metavar="INI", help="the config.ini tuned from (default: the Walking module's own "
                                                   "defaults)")
    _common(p, "INI", "the config.ini to write ([Walking Config] and [op2motion])")


def _common(p: argparse.ArgumentParser, kind: str, out_help: str) -> None:
    p.add_argument("--spec", default=argparse.SUPPRESS, metavar="FILE",
                   help="your robot's spec (a variant of specs/op2.toml with what you measured; "
                        "docs/tuning.md, 'Your robot')")
    p.add_argument("--param", nargs=3, action="append", default=[], metavar=("NAME", "LOW", "HIGH"),
                   help="search NAME over LOW..HIGH instead of its default range (repeatable)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="search just these parameters (the others keep the "
                                                             "base values)")
    p.add_argument("--trials", type=whole(1, 10_000), default=60, help="the study's budget of trials (default 60; "
                                                                       "a resumed study counts its earlier ones)")
    p.add_argument("--study", type=output_path, metavar="DB",
                   help="the study's SQLite file (default: OUT with .study.db); the same file and name resume it")
    p.add_argument("--study-name", default=None, metavar="NAME", help="the study's name in its file (default: "
                                                                       "tune-KIND-DIRECTION)")
    p.add_argument("--seed", type=whole(0, 2 ** 31 - 1), default=0, help="the sampler's seed (default 0)")
    p.add_argument("--executor", choices=("process", "ray"), default="process",
                   help="process: worker processes here (default); ray: Ray tasks (pip install '.[cluster]')")
    p.add_argument("--workers", type=whole(0, MAX_WORKERS), default=0, help="trials at a time, 0 = one per core")
    p.add_argument("--address", metavar="ADDR", help="with --executor ray: a running cluster's head")
    p.add_argument("--verify", type=whole(1, MAX_VERIFY), default=3,
                   help="verify at most this many of the best points on the whole family (default 3)")
    p.add_argument("--out", type=output_path, required=True, metavar=kind, help=out_help)
    p.add_argument("--plot", type=png_path, metavar="PNG", help="the study's Pareto figure")


def _tune(args: argparse.Namespace, task: Any, space: Any) -> int:
    """Check the flags and the outputs, run the tuning task, deliver it."""
    from op2motion.commands.deliver import deliver
    from op2motion.fileio import OutputSet
    from op2motion.tasks.tune import TuneRequest, tune

    workers = args.workers or os.cpu_count() or 1
    space = space.narrowed(args.param, args.only)
    outputs = OutputSet({"out": args.out, "out_json": _beside(args.out, ".json"),
                         **({"plot": args.plot} if args.plot else {})})
    study_path = args.study or str(_beside(args.out, ".study.db"))
    paths = {k: str(v) for k, v in outputs.paths.items()}
    request = TuneRequest(task, space, args.trials, args.verify, study_path,
                          args.study_name or f"tune-{task.kind}-{task.direction}", paths["out"], paths["out_json"],
                          args.seed, args.executor, workers, args.address, paths.get("plot"))
    return deliver(args, tune(request, lambda what, unit: progress(args, what, unit)), outputs, "none")


def _beside(out: str, suffix: str) -> Path:
    path = Path(out)
    return path.with_name(path.name + suffix) if suffix == ".study.db" else path.with_suffix(suffix)


def cmd_tune_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion tune walk``."""
    from op2motion.gait import preset_path, read_preset
    from op2motion.tune.spaces import walk_space
    from op2motion.tune.trial import DIRECTIONS, Task
    from op2motion.tune.walkers import PresetWalker

    base = read_preset(preset_path(args.preset or DIRECTIONS[args.direction]))
    return _tune(args, Task(PresetWalker(base), args.direction, getattr(args, "spec", None)),
                 walk_space(args.direction))


def cmd_tune_stock(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion tune stock``."""
    from op2motion.gait.stock_config import StockConfig, read_stock_config
    from op2motion.tune.spaces import stock_space
    from op2motion.tune.trial import Task
    from op2motion.tune.walkers import StockWalker

    base = read_stock_config(args.config) if args.config else StockConfig()
    return _tune(args, Task(StockWalker(base), "forward", getattr(args, "spec", None)), stock_space())
