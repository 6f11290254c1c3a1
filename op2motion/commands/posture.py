"""CLI commands of the posture optimiser: optimize, library build."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..cli import emit, vec3
from ..errors import InputError
from ..spec import Spec


def cmd_optimize(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from ..errors import CheckFailed
    from ..export.library import pose_to_json, write_pose
    from ..plot import PoseFigure, plot_cost_curve, plot_poses
    from ..posture.cost import PostureProblem
    from ..posture.pso import PSOSettings
    from ..posture.solve import optimize_posture

    target = vec3(args.target, "--target")
    problem = PostureProblem(args.support, args.hand, target, args.br, args.model).validated()
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    name = args.name or problem.name
    out = Path(args.out) if args.out else Path("poses") / f"{name}.json"
    png = Path(args.plot) if args.plot else out.with_suffix(".png")
    cost_png = out.with_name(out.stem + "_cost.png")
    interactive = sys.stderr.isatty() and not args.json
    validations: dict[int, Any] = {}

    def physics_check(res: Any) -> tuple[bool, str]:
        from ..physics import validate_servo

        v = validate_servo(res.pose(name, spec).servo, args.support, spec, args.seconds)
        validations[res.settings.seed] = v
        return v.stable, f"does not stand in physics ({v.reason})"

    with tqdm(total=settings.iterations * (1 + args.restarts), desc="PSO", unit="it", disable=not interactive,
              leave=False) as bar:
        res = optimize_posture(problem, spec, settings, not args.no_refine,
                               on_iteration=lambda best: (bar.update(), bar.set_postfix(cost=f"{best:.4f}")),
                               restarts=args.restarts, check=physics_check if args.validate else None)
    command = "op2motion optimize " + " ".join(sys.argv[2:]) if len(sys.argv) > 1 else "op2motion optimize"
    pose = res.pose(name, spec, {"command": command})
    m = res.metrics
    result: dict[str, Any] = {
        "pose": json.loads(pose_to_json(pose, spec)), "reached": res.reached, "message": res.message,
        "cost": m["cost"], "hand_error_m": m["hand_error_m"], "com": m["com"],
        "stability_margin_m": m["stability_margin_m"], "com_full": m["com_full"],
        "stability_margin_full_m": m["stability_margin_full_m"], "swing_foot_min_z": m["swing_foot_min_z"],
        "iterations": int(len(res.pso.history)), "attempts": m["attempts"], "refinement": res.method,
        "seconds": round(res.seconds, 3),
    }
    lines = [f"{args.hand} hand to ({', '.join(f'{v:.3f}' for v in target)}) m on the {args.support} foot, "
             f"br {args.br}: {res.message}",
             f"  CoM ({m['com'][0]:+.3f}, {m['com'][1]:+.3f}, {m['com'][2]:.3f}) m [lumped], stability margin "
             f"{m['stability_margin_m'] * 1000:.1f} mm (full-inertia CoM: {m['stability_margin_full_m'] * 1000:.1f} mm)"
             f", swing foot {m['swing_foot_min_z'] * 1000:.1f} mm above the floor, torso tilt {m['torso_tilt_deg']:.0f}°",
             f"  PSO {settings.particles} particles x {settings.iterations} iterations (seed {res.settings.seed}, "
             f"attempt {m['attempts']}), refinement: {res.method}, {res.seconds:.2f} s"]
    if res.settings.seed in validations:
        v = validations[res.settings.seed]
        result["validation"] = v.as_dict()
        lines.append(f"  physics ({args.seconds:g} s): {'STABLE' if v.stable else 'NOT STABLE'} ({v.reason}), "
                     f"tilt {v.max_tilt_deg:.1f}°, torque {v.max_torque_nm:.2f} N·m at {v.worst_joint}")
    if not res.reached:
        emit(args, result, "\n".join(lines))
        raise CheckFailed(f"{res.message}; nothing written")
    write_pose(pose, out, spec)
    fig = PoseFigure(forward_points(res, spec), np.array(m["com"]), name, args.br, target)
    plot_poses([fig], spec, png, title=f"{name}: {res.message}")
    plot_cost_curve(res.pso.history, cost_png, f"PSO cost, {name}")
    result["files"] = {"pose": str(out), "png": str(png), "cost_png": str(cost_png)}
    lines.append(f"  wrote {out}, {png}, {cost_png}")
    emit(args, result, "\n".join(lines))
    return 0


def forward_points(res: Any, spec: Spec) -> Any:
    """D-H body points of a posture result (for its figure)."""
    from ..kinematics import forward

    return forward(res.angles, spec, "dh")


def cmd_library_build(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from ..posture.library_build import axis, build_library, grid_jobs
    from ..posture.pso import PSOSettings

    jobs = grid_jobs(args.hands, args.supports, args.br, axis(*args.x, "--x"), axis(*args.y, "--y"),
                     axis(*args.z, "--z"))
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    if args.workers < 0:
        raise InputError(f"--workers: expected 0 (all cores) or more, got {args.workers}")
    with tqdm(total=len(jobs), desc="library", unit="pose", disable=not sys.stderr.isatty() or args.json) as bar:
        summary = build_library(jobs, spec, args.out, settings, args.workers, args.validate, args.spec,
                                on_done=lambda row: bar.update())
    text = (f"{summary['targets']} targets: {summary['solved']} reached, {summary['failed']} not, "
            f"{summary['skipped']} already done; {summary['seconds']:.1f} s; index {summary['index']}")
    emit(args, summary, text)
    return 0
