"""CLI command ``op2motion tune walk|stock``: faster walks found in physics, robust across the body (thin: the work
is :mod:`op2motion.tune`)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from op2motion.commands.common import add_command, emit, output_path, png_path, progress, whole
from op2motion.errors import CheckFailed, InputError
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


def _run(args: argparse.Namespace, task: Any, space: Any, unit: str) -> Any:
    """Open the study, search, verify; the result."""
    from op2motion.fileio import OutputSet
    from op2motion.tune.executor import trials_on
    from op2motion.tune.run import Effort, search_and_verify
    from op2motion.tune.study import check_budget, open_study

    if args.address is not None and args.executor != "ray":
        raise InputError("expected --address only with --executor ray", "address")
    workers = args.workers or os.cpu_count() or 1
    space = space.narrowed(args.param, args.only)
    outputs = OutputSet({"out": args.out, "out_json": _beside(args.out, ".json"),
                         **({"plot": args.plot} if args.plot else {})})
    study_path = args.study or str(_beside(args.out, ".study.db"))
    study = open_study(study_path, args.study_name or f"tune-{task.kind}-{task.direction}", space, args.seed)
    with trials_on(args.executor, workers, args.address) as trials, \
            progress(args, "trials", "trial") as on_trial, progress(args, "verify", "body") as on_run:
        result = search_and_verify(study, space, task, Effort(check_budget(args.trials), args.verify), trials,
                                   on_trial, on_run)
    result.executor = args.executor
    return result, outputs, study_path


def _beside(out: str, suffix: str) -> Path:
    path = Path(out)
    return path.with_name(path.name + suffix) if suffix == ".study.db" else path.with_suffix(suffix)


def _finish(args: argparse.Namespace, result: Any, outputs: Any, text: str, unit: str, study_path: str) -> int:
    """Write (when a point held everywhere) and report."""
    import json

    from op2motion.figures.tune import render_pareto
    from op2motion.tune.run import result_json
    from op2motion.tune.study import MIN_MARGIN, pareto

    data = result_json(result)
    data["study"] = study_path
    if args.plot:
        outputs.put("plot", render_pareto(result, pareto(result.table), MIN_MARGIN, unit))
    if result.settings is not None:
        outputs.put("out", text)
        outputs.put("out_json", json.dumps(data, indent=2) + "\n")
    written = outputs.commit()
    data["files"] = {k: str(v) for k, v in written.items()}
    speed = result.verified_speed
    lines = [f"tune {result.kind} {result.direction}: {data['trials']['finished']} trials "
             f"({data['trials']['pruned']} pruned, {result.ran} this run), {data['cost']['study_wall_s']:.0f} s on "
             f"{result.workers} {result.executor} worker(s)"]
    lines += [f"  rejected in verification: trial {n}: {p}" for n, p in result.rejected]
    if result.settings is None:
        emit(args, data, "\n".join(lines))
        raise CheckFailed(f"no point held on every body of the family in both engines (verified "
                          f"{len(result.rejected)}); nothing written: more --trials resume the study")
    lines.append(f"  chosen trial {result.chosen.number}: nominal {speed:.3f} {unit} in both engines, every body "
                 f"held; wrote {', '.join(str(p) for p in written.values())}")
    emit(args, data, "\n".join(lines))
    return 0


def cmd_tune_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion tune walk``."""
    from op2motion.gait import preset_path, read_preset
    from op2motion.tune.run import header_lines, preset_text
    from op2motion.tune.spaces import walk_space
    from op2motion.tune.trial import DIRECTIONS, Task

    base = read_preset(preset_path(args.preset or DIRECTIONS[args.direction]))
    task = Task("walk", args.direction, base, getattr(args, "spec", None))
    unit = "rad/s" if args.direction == "turn" else "m/s"
    result, outputs, study_path = _run(args, task, walk_space(args.direction), unit)
    text = ""
    if result.settings is not None:
        name = Path(args.out).stem
        params = result.settings.__class__(**{**result.settings.__dict__, "name": name})
        text = preset_text(params, header_lines(result, unit))
    return _finish(args, result, outputs, text, unit, study_path)


def cmd_tune_stock(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion tune stock``."""
    from op2motion.gait.stock_config import StockConfig, read_stock_config, stock_config_text
    from op2motion.tune.run import header_lines
    from op2motion.tune.spaces import stock_space
    from op2motion.tune.trial import Task

    base = read_stock_config(args.config) if args.config else StockConfig()
    task = Task("stock", "forward", base, getattr(args, "spec", None))
    result, outputs, study_path = _run(args, task, stock_space(), "m/s")
    text = ""
    if result.settings is not None:
        text = stock_config_text(result.settings, "\n".join(header_lines(result, "m/s")))
    return _finish(args, result, outputs, text, "m/s", study_path)
