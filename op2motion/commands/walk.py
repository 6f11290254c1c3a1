"""CLI command ``op2motion walk``: plan a ZMP preview-control gait from a preset, check it in physics, export it."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion.commands.common import (
    add_command,
    engines_of,
    number,
    output_path,
    physics_args,
    png_path,
    progress,
    walk_target,
    whole,
)
from op2motion.errors import InputError
from op2motion.robot.spec import Spec
from op2motion.tasks.walk import OUT_FORMATS


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


def _tables(args: argparse.Namespace) -> tuple[tuple[str, str], ...]:
    """The goal tables ``--out`` names, by role (``out0``, ``out1``), each ending in .csv or .motion."""
    tables: list[tuple[str, str]] = []
    for path in args.out or ():
        suffix = "." + path.rsplit(".", 1)[-1].lower() if "." in path else ""
        if suffix not in OUT_FORMATS:
            raise InputError(f"expected a file ending in .csv or .motion, got {path!r}", "out")
        tables.append((f"out{len(tables)}", path))
    return tuple(tables)


def cmd_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion walk``."""
    from op2motion.commands.deliver import deliver
    from op2motion.fileio import OutputSet
    from op2motion.gait import preset_path, read_preset
    from op2motion.physics import Trials
    from op2motion.tasks.walk import WalkRequest, walk_task

    if not args.validate and (args.push or args.trials or args.robust or args.open_loop):
        raise InputError("expected --validate with --push, --trials, --robust or --open-loop", "validate")
    if args.robust and args.trials:
        raise InputError("expected --robust or --trials, not both", "trials")
    if not args.trials and (args.seed is not None or args.perturb_deg is not None):
        raise InputError("expected --trials N with --seed or --perturb-deg (they set the perturbed starts)",
                         "seed" if args.seed is not None else "perturb_deg")
    target = walk_target(args)
    if args.preset is not None and not args.preset.strip():
        raise InputError("expected a gait preset file or a shipped name, got an empty string", "preset")
    if args.commands is not None or args.action is not None:
        from op2motion.commands.walk_commands import commanded_walk

        return commanded_walk(args, spec)
    tables = _tables(args)
    outputs = OutputSet({**dict(tables), **({"plot": args.plot} if args.plot else {})})
    params = read_preset(preset_path(args.preset)).with_steps(args.steps)
    trials = None
    if args.trials:
        trials = Trials(args.trials, Trials.perturb_deg if args.perturb_deg is None else args.perturb_deg,
                        args.seed or 0)
    request = WalkRequest(params, target, args.retime, args.validate, args.open_loop, args.robust,
                          engines_of(args), args.push, trials, args.plot, tables)
    return deliver(args, walk_task(request, spec, lambda what, unit: progress(args, what, unit)), outputs)
