"""CLI command of the posture optimiser: optimize."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from op2motion import book
from op2motion.commands.common import (
    BOUNDARY_RATIO,
    TARGET_M,
    add_command,
    emit,
    number,
    output_path,
    png_path,
    pose_name,
    ticker,
    vec3,
    warn,
    whole,
)
from op2motion.physics import DEFAULT_SECONDS, ENGINES, MAX_SECONDS, MIN_SECONDS
from op2motion.posture.pso import MAX_ITERATIONS, MAX_PARTICLES, MAX_SEED, PSOSettings
from op2motion.robot.balance import COM_MODEL_FULL, COM_MODELS
from op2motion.robot.spec import Spec
from op2motion.workflow import DEFAULT_RESTARTS, MAX_RESTARTS

if TYPE_CHECKING:
    from op2motion.figures.background import Renderers
    from op2motion.fileio import OutputSet
    from op2motion.posture.cost import PostureProblem

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
    from op2motion.figures.background import Renderers
    from op2motion.fileio import OutputSet
    from op2motion.posture.cost import PostureProblem

    target = vec3(args.target, "target") or book.DEFAULT_PROBLEM.target
    problem = PostureProblem(args.support, args.hand, target, args.br, args.model, args.com_model).validated()
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    name = args.name or problem.name
    out = Path(args.out) if args.out else Path("poses") / f"{name}.json"
    png = Path(args.plot) if args.plot else out.with_suffix(".png")
    outputs = OutputSet({"out": out, "plot": png, "cost curve": out.with_name(out.stem + "_cost.png")})
    with Renderers(2) as renderers:          # they load matplotlib while the swarm searches
        return _optimize(args, spec, problem, settings, name, outputs, renderers)


def _optimize(args: argparse.Namespace, spec: Spec, problem: PostureProblem, settings: PSOSettings, name: str,
              outputs: OutputSet, renderers: Renderers) -> int:
    """The work of :func:`cmd_optimize`, its figures drawn by ``renderers``."""
    from op2motion.errors import CheckFailed
    from op2motion.figures.pose import outcome_cost_curve, outcome_pose_figure
    from op2motion.formats.posefile import pose_to_json
    from op2motion.workflow import Validate, solve

    target = problem.target
    with ticker(args, "PSO", "it", settings.iterations * (1 + args.restarts)) as bar:
        outcome = solve(problem, spec, settings, restarts=args.restarts, refine=not args.no_refine,
                        validate=Validate(args.seconds, args.engine) if args.validate else None,
                        on_iteration=lambda best: (bar.update(), bar.set_postfix(cost=f"{best:.4f}")))
    command = "op2motion " + " ".join(sys.argv[1:]) if len(sys.argv) > 1 else "op2motion optimize"
    pose = outcome.pose(name, spec, {"command": command})
    r = outcome.result
    result: dict[str, Any] = {"pose": json.loads(pose_to_json(pose, spec)), **outcome.as_dict()}
    lines = [f"{args.hand} hand to ({', '.join(f'{v:.3f}' for v in target)}) m on the {args.support} foot, "
             f"br {args.br}: {r.message}",
             f"  CoM full inertia ({r.com_full[0]:+.3f}, {r.com_full[1]:+.3f}, {r.com_full[2]:.3f}) m, margin "
             f"{r.margin_full_m * 1000:.1f} mm to the sole shrunk by br; lumped (book) margin "
             f"{r.margin_lumped_m * 1000:.1f} mm [balanced: {args.com_model}]; "
             f"swing foot {r.swing_foot_min_z * 1000:.1f} mm above the floor, torso "
             f"tilt {result['torso_tilt_deg']:.0f}°",
             f"  PSO {settings.particles} particles x {settings.iterations} iterations (seed {r.settings.seed}, "
             f"attempt {r.attempts}), refinement: {r.method}, {r.seconds:.2f} s"]
    v = outcome.validation
    if v is not None:
        lines.append(f"  physics: {v.summary()}")
    warn(args, result, outcome.warnings())
    if not outcome.ok:
        emit(args, result, "\n".join(lines))
        raise CheckFailed(f"{r.message}; nothing written")
    jobs = renderers.submit(outcome_pose_figure, outcome, name, spec), renderers.submit(outcome_cost_curve, outcome,
                                                                                          name)
    (figure, drawn), cost_curve = renderers.result(jobs[0]), renderers.result(jobs[1])
    outputs.put("out", pose_to_json(pose, spec))
    outputs.put("plot", figure)
    outputs.put("cost curve", cost_curve)
    files = outputs.commit()
    result["files"] = {"pose": str(files["out"]), "png": str(files["plot"]), "cost_png": str(files["cost curve"])}
    result["figure"] = drawn
    lines.append(f"  wrote {files['out']}, {files['plot']}, {files['cost curve']}")
    emit(args, result, "\n".join(lines))
    return 0
