"""CLI command ``op2motion walk``: plan a ZMP preview-control gait from a preset, check it in physics, export it."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from op2motion.commands.common import (
    add_command,
    emit,
    engines_of,
    number,
    output_path,
    physics_args,
    png_path,
    progress,
    whole,
)
from op2motion.errors import CheckFailed, InputError
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.physics import CheckReport

OUT_FORMATS = {".csv": "csv", ".motion": "webots"}


def register(sub: Any) -> None:
    """Add ``walk``."""
    p = add_command(sub, "walk", cmd_walk, "plan a walk (ZMP preview control) and check it in physics",
                    "Plan a walk from a gait preset: footsteps, ZMP preview control with the multibody "
                    "correction, leg IK, goals every 8 ms; with --validate play them into the servo model in "
                    "physics.")
    p.add_argument("--preset", metavar="TOML", help="gait preset file or shipped name (forward, backward, "
                                                    "sideways, turn_left, turn_right, steer; default forward, "
                                                    "with --commands steer)")
    p.add_argument("--commands", type=str, metavar="FILE",
                   help="walk steered by a command timeline (.csv or .json: times with vx [m/s], vy [m/s], yaw "
                        "rate [deg/s] and events stop, kick_right, kick_left), planned while it walks")
    p.add_argument("--action", type=str, metavar="FILE",
                   help="with --commands: an action file whose kick pages (12 right, 13 left) the kick events play "
                        "(default: op2motion's own kicks)")
    p.add_argument("--steps", type=whole(1, 200), help="number of steps (default: the preset's)")
    p.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "YAW"),
                   help="walk to this pose instead: x [m], y [m], heading [deg] from the start")
    p.add_argument("--validate", action="store_true", help="play the walk in physics")
    physics_args(p, False, "with --validate: also push the torso N newtons for 0.1 s halfway, from each side")
    p.add_argument("--trials", type=whole(0, 100), default=0, metavar="N",
                   help="with --validate: N more runs from randomly perturbed starts (seeded)")
    p.add_argument("--perturb-deg", type=number(0.0, 5.0, "deg"), default=None, metavar="DEG",
                   help="standard deviation of the trials' start offsets per joint (default 0.5°, with --trials)")
    p.add_argument("--seed", type=whole(0, 2 ** 31 - 1), default=None,
                   help="with --trials: seed of the trials' offsets (default 0)")
    p.add_argument("--robust", action="store_true",
                   help="with --validate: walk every member of the robustness family (torso CoM and mass from the "
                        "spec's uncertainty, servo stiffness x0.6-1.6, friction 0.5-1.0, 16 ms IMU latency) and "
                        "print the table; exit 1 unless every run passes")
    p.add_argument("--open-loop", action="store_true",
                   help="with --validate: play the planned goals without the controller's feedback")
    p.add_argument("--retime", action="store_true",
                   help="lengthen the step when a joint would pass 90%% of the servo's no-load speed "
                        "(default: refuse the plan and name the joint)")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="footsteps, ZMP and CoM from above and in time "
                                                              "(with --commands: the commanded, planned and walked "
                                                              "paths and headings)")
    p.add_argument("--out", type=output_path, nargs="+", metavar="FILE",
                   help="write the goals every 8 ms: .csv (CSV) and/or .motion (Webots)")


def _outputs(args: argparse.Namespace) -> dict[str, str | Path]:
    paths: dict[str, str | Path] = {}
    for path in args.out or ():
        suffix = "." + path.rsplit(".", 1)[-1].lower() if "." in path else ""
        if suffix not in OUT_FORMATS:
            raise InputError(f"expected a file ending in .csv or .motion, got {path!r}", "out")
        paths[f"out{len(paths)}"] = path
    if args.plot:
        paths["plot"] = args.plot
    return paths


def _walk_line(engine: str, s: dict[str, Any]) -> str:
    """One engine's walk in words."""
    w = s["worst_torque"]
    line = (f"  {engine}: {'FELL' if s['fell'] else 'walked'}"
            f"{' (' + ', '.join(s['reasons']) + ')' if s['reasons'] else ''}, {s['distance_m']:.3f} m, "
            f"{s['mean_speed_mps']:.3f} m/s steady, drift {s['lateral_drift_m'] * 1000:.0f} mm, heading "
            f"{s['heading_error_deg']:+.1f}°, turn {s['turn_rate_deg_s']:.1f}°/s, CoP inside "
            f"{s['cop_inside_fraction']:.1%}, worst torque {w['torque_nm']:.2f} N·m at {w['joint']} "
            f"({w['ratio']:.0%} of {w['available_nm']:.2f})")
    if s["pushes"]:
        line += "; pushes: " + ", ".join(f"from {p['from']} {'FELL' if p['fell'] else 'ok'}" for p in s["pushes"])
    if "trials" in s:
        line += f"; trials: {s['trials']['walked']}/{s['trials']['runs']} walked"
    return line


def _controller(args: argparse.Namespace, gait: Any, spec: Spec) -> Any:
    """The walk's controller: the closed loop, or with ``--open-loop`` the planned goals as they are."""
    from op2motion.gait import gait_schedule
    from op2motion.gait.controller import WalkController

    return gait_schedule(gait, spec) if args.open_loop else WalkController(gait, spec)


def _walk_physics(args: argparse.Namespace, gait: Any, spec: Spec, result: dict[str, Any]) -> CheckReport:
    """``--validate``: the walk in physics; its results go into ``result``."""
    from op2motion.gait import side_pushes, walk_summary
    from op2motion.physics import Trials, check

    controller = _controller(args, gait, spec)
    trials = None
    if args.trials:
        trials = Trials(args.trials, Trials.perturb_deg if args.perturb_deg is None else args.perturb_deg,
                        args.seed or 0)
    with progress(args, "physics", "s") as on_progress:
        report = check(controller, spec, engines_of(args), side_pushes(args.push) if args.push else None, trials,
                       on_progress=on_progress)
    physics = walk_summary(report, controller.plan.walk.start_s if controller.plan.walk else 0.0)
    main = physics["engines"][next(iter(report.engines))]
    result["physics"] = physics
    result["controller"] = "open loop" if args.open_loop else "WalkController"
    result.update({key: main[key] for key in ("reasons", "lateral_drift_m", "heading_error_deg", "turn_rate_deg_s",
                                              "cop_inside_fraction", "worst_torque")})
    result["mean_speed_mps"] = min(s["mean_speed_mps"] for s in physics["engines"].values())
    result["fell"] = physics["fell"]
    return report


def _walk_robust(args: argparse.Namespace, gait: Any, spec: Spec, result: dict[str, Any]) -> Any:
    """``--validate --robust``: the walk over the robustness family; the table goes into ``result``."""
    from op2motion.gait import side_pushes
    from op2motion.gait.robust import robust_table, walk_badness, walk_judge
    from op2motion.physics import robust_check, robust_summary

    with progress(args, "robust", "run") as on_progress:
        report = robust_check(lambda: _controller(args, gait, spec), spec, engines_of(args), walk_judge,
                              side_pushes(args.push) if args.push else None, on_progress=on_progress)
    result["robust"] = robust_summary(report)
    result["robust"]["worst"] = report.worst(walk_badness).member.name
    return report, robust_table(report)


def _walk_files(args: argparse.Namespace, outputs: Any, gait: Any, spec: Spec, report: CheckReport | None) -> None:
    """Stage the plot and the goal tables asked for."""
    from op2motion.figures.gait import render_gait
    from op2motion.gait import gait_csv, gait_webots
    from op2motion.physics import RAMP_S, WALK_SETTLE_S

    for key, path in outputs.paths.items():
        if key == "plot":
            verdict = "not checked in physics" if report is None else " | ".join(
                f"{e}: {'fell' if r.run.fell else 'walked'} {r.run.walk.mean_speed_mps if r.run.walk else 0.0:.3f} "
                f"m/s" for e, r in report.engines.items())
            cop = report.run.motion.cop_track if report is not None and report.run.motion else None
            outputs.put(key, render_gait(gait, spec, f"walk '{gait.params.name}'", cop, RAMP_S + WALK_SETTLE_S,
                                         verdict))
        else:
            fmt = OUT_FORMATS[path.suffix.lower()]
            outputs.put(key, gait_csv(gait, spec) if fmt == "csv" else gait_webots(gait, spec))


def cmd_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion walk``."""
    from op2motion.fileio import OutputSet
    from op2motion.gait import gait_summary, preset_path, read_preset
    from op2motion.gait.speeds import plan_within_speed

    if not args.validate and (args.push or args.trials or args.robust or args.open_loop):
        raise InputError("expected --validate with --push, --trials, --robust or --open-loop", "validate")
    if args.robust and args.trials:
        raise InputError("expected --robust or --trials, not both", "trials")
    if not args.trials and (args.seed is not None or args.perturb_deg is not None):
        raise InputError("expected --trials N with --seed or --perturb-deg (they set the perturbed starts)",
                         "seed" if args.seed is not None else "perturb_deg")
    if args.target is not None and args.steps is not None:
        raise InputError("expected --steps or --target, not both (a target sets the number of steps)", "steps")
    if args.preset is not None and not args.preset.strip():
        raise InputError("expected a gait preset file or a shipped name, got an empty string", "preset")
    if args.commands is not None or args.action is not None:
        from op2motion.commands.walk_commands import commanded_walk

        return commanded_walk(args, spec, _walk_line)
    outputs = OutputSet(_outputs(args))
    params = read_preset(preset_path(args.preset)).with_steps(args.steps)
    target = None if args.target is None else (args.target[0], args.target[1], math.radians(args.target[2]))
    with progress(args, "plan", "pass") as on_progress:
        gait = plan_within_speed(params, spec, target, args.retime, on_progress)
    result: dict[str, Any] = gait_summary(gait)
    lines = [f"walk '{params.name}': {result['steps']} steps in {result['walking_s']:.2f} s, "
             f"{result['distance_m']:.3f} m planned ({result['planned_speed_mps']:.3f} m/s steady), ZMP margin >= "
             f"{result['zmp_margin_min_m'] * 1000:.1f} mm, CoM height {result['com_height_m']:.3f} m"]
    if gait.params.step_s != params.step_s:
        lines.append(f"  re-timed: step {params.step_s:.3f} s -> {gait.params.step_s:.3f} s (joint speeds)")
    result["step_s"] = gait.params.step_s
    robust = _walk_robust(args, gait, spec, result) if args.validate and args.robust else None
    report = _walk_physics(args, gait, spec, result) if args.validate and robust is None else None
    if report is not None:
        lines += [_walk_line(e, s) for e, s in result["physics"]["engines"].items()]
    if robust is not None:
        lines.append(robust[1])
    failed = (robust is not None and not robust[0].passed) or (report is not None and (
        report.fell or not report.pushes_survived))
    _walk_files(args, outputs, gait, spec, report)
    written = {} if failed else outputs.commit()        # a walk that failed its check writes nothing
    result["files"] = {k: str(v) for k, v in written.items()}
    lines += [f"  wrote {p}" for p in written.values()]
    emit(args, result, "\n".join(lines))
    if robust is not None and not robust[0].passed:
        raise CheckFailed(f"walk '{params.name}' failed in {sum(not r.passed for r in robust[0].runs)} of "
                          f"{len(robust[0].runs)} runs of the robustness family")
    if report is not None and report.fell:
        raise CheckFailed(f"walk '{params.name}' fell in physics: " + "; ".join(
            f"{e}: {', '.join(r.run.reasons)}" for e, r in report.engines.items() if r.run.fell))
    if report is not None and not report.pushes_survived:
        raise CheckFailed(f"walk '{params.name}' " + (report.problem("does not get through", fall_only=True)
                                                      or "fell when pushed"))
    return 0
