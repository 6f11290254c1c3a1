"""CLI command of the posture optimiser: optimize."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from op2motion import book
from op2motion.commands.common import (
    BOUNDARY_RATIO,
    TARGET_M,
    add_command,
    number,
    output_path,
    png_path,
    pose_name,
    ticker,
    vec3,
    whole,
)
from op2motion.physics import DEFAULT_SECONDS, ENGINES, MAX_SECONDS, MIN_SECONDS
from op2motion.posture.pso import MAX_ITERATIONS, MAX_PARTICLES, MAX_SEED, PSOSettings
from op2motion.robot.balance import COM_MODEL_FULL, COM_MODELS
from op2motion.robot.spec import Spec
from op2motion.workflow import DEFAULT_RESTARTS, MAX_RESTARTS

SECONDS = number(MIN_SECONDS, MAX_SECONDS, "s")


def com_model_arg(p: argparse.ArgumentParser) -> None:
    """``--com-model full|book``: the centre of mass the optimiser balances."""
    p.add_argument("--com-model", choices=COM_MODELS, default=COM_MODEL_FULL,
                   help="centre of mass to balance: full (the spec's link inertials, as physics has them; default) "
                        "or book (the book's lumped masses, to reproduce its scenarios)")


def solver_args(p: argparse.ArgumentParser) -> None:
    """The PSO, restart and validation options shared by ``optimize`` and ``library build``."""
    d = PSOSettings()
    p.add_argument("--particles", type=whole(2, MAX_PARTICLES), default=d.particles,
                   help=f"swarm size (default {d.particles})")
    p.add_argument("--iters", type=whole(1, MAX_ITERATIONS), default=d.iterations,
                   help=f"PSO iterations (default {d.iterations})")
    p.add_argument("--seed", type=whole(0, MAX_SEED), default=d.seed,
                   help="random seed of the first attempt (default 0)")
    p.add_argument("--restarts", type=whole(0, MAX_RESTARTS), default=DEFAULT_RESTARTS,
                   help=f"extra solves with the next seeds when one fails (default {DEFAULT_RESTARTS})")
    p.add_argument("--validate", action="store_true",
                   help="check each reached pose in physics; a pose that falls counts as failed and is not written")
    p.add_argument("--seconds", type=SECONDS, default=DEFAULT_SECONDS,
                   help=f"simulated time of --validate [s] (default {DEFAULT_SECONDS:g})")
    p.add_argument("--engine", choices=ENGINES, default="pybullet",
                   help="physics engine of --validate (default pybullet)")


def register(sub: Any) -> None:
    """Add optimize."""
    d = book.DEFAULT_PROBLEM
    p = add_command(sub, "optimize", cmd_optimize,
                    "PSO posture: reach a target with one hand while the CoM stays over the support foot")
    p.add_argument("--support", choices=("left", "right"), default=d.support,
                   help=f"support foot (default {d.support})")
    p.add_argument("--hand", choices=("left", "right"), default=d.hand, help=f"reaching hand (default {d.hand})")
    p.add_argument("--target", type=TARGET_M, nargs=3, default=d.target, metavar=("X", "Y", "Z"),
                   help="target in the support-foot frame [m] (default %s)" % " ".join(f"{v:g}" for v in d.target))
    p.add_argument("--br", type=BOUNDARY_RATIO, default=d.br,
                   help=f"boundary ratio of the support rectangle (default {d.br})")
    p.add_argument("--model", choices=("dh", "pb"), default="dh", help="kinematic model of the PSO (default dh)")
    com_model_arg(p)
    solver_args(p)
    p.add_argument("--no-refine", action="store_true", help="skip the local refinement (hand within 5 mm)")
    p.add_argument("--name", type=pose_name, help="pose name (default from hand, support, target and br)")
    p.add_argument("--out", type=output_path, metavar="FILE", help="pose file (default poses/NAME.json)")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="pose figure (default beside the pose file)")


def cmd_optimize(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion optimize``: solve, optionally validate, then write pose, figure and cost curve together."""
    from op2motion.commands.deliver import deliver
    from op2motion.figures.background import Renderers
    from op2motion.fileio import OutputSet
    from op2motion.posture.cost import PostureProblem
    from op2motion.tasks.posture import Reach, reach
    from op2motion.workflow import Validate

    target = vec3(args.target, "target") or book.DEFAULT_PROBLEM.target
    problem = PostureProblem(args.support, args.hand, target, args.br, args.model, args.com_model).validated()
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    name = args.name or problem.name
    out = Path(args.out) if args.out else Path("poses") / f"{name}.json"
    png = Path(args.plot) if args.plot else out.with_suffix(".png")
    cost = out.with_name(out.stem + "_cost.png")
    outputs = OutputSet({"out": out, "plot": png, "cost curve": cost})
    command = "op2motion " + " ".join(sys.argv[1:]) if len(sys.argv) > 1 else "op2motion optimize"
    request = Reach(problem, settings, name, str(out), str(png), str(cost), args.restarts, not args.no_refine,
                    Validate(args.seconds, args.engine) if args.validate else None, command)
    shown: list[bool] = []
    with Renderers(2, ("op2motion.figures.pose",)) as renderers:    # they load matplotlib while the swarm searches
        with ticker(args, "PSO", "it", settings.iterations) as bar:
            def seen(best: float) -> None:
                if bar.n >= bar.total:              # a restart on the next seed (only when the hand missed): more
                    bar.total += settings.iterations
                bar.update()
                bar.set_postfix(cost=f"{best:.4f}")

            early = all(p.parent.is_dir() for p in outputs.paths.values())

            def answer(lines: tuple[str, ...]) -> None:
                """The result for a person as soon as it is known; the figures are drawn meanwhile, and the files
                (all of them, or none) are named once written. Only where the outputs' folders exist: a folder
                that cannot be made fails the command with nothing printed, as before."""
                if not args.json and early:
                    bar.close()
                    print("\n".join(lines), flush=True)
                    shown.append(True)

            result = reach(request, spec, renderers, seen, answer)
    return deliver(args, result, outputs, "one", lines_shown=bool(shown))
