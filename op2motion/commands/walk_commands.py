"""``op2motion walk --commands FILE``: a walk steered by a command timeline, planned as it would be while walking,
checked in physics, drawn against the commanded path."""

from __future__ import annotations

import argparse

from op2motion.commands.common import engines_of, progress
from op2motion.errors import InputError
from op2motion.robot.spec import Spec

#: Flags of ``walk`` that mean nothing with ``--commands`` (the commands set the steps and where they go).
NOT_WITH_COMMANDS = {"steps": "--steps", "target": "--target", "retime": "--retime", "trials": "--trials",
                     "open_loop": "--open-loop", "out": "--out"}


def _refuse_others(args: argparse.Namespace) -> None:
    for dest, flag in NOT_WITH_COMMANDS.items():
        if getattr(args, dest, None):
            raise InputError(f"expected --commands or {flag}, not both (the commands set the steps)", dest)
    if args.action and not args.commands:
        raise InputError("expected --commands with --action (its pages 12/13 are the kicks of a commanded walk)",
                         "action")


def commanded_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``walk --commands FILE`` (see the module docstring)."""
    from op2motion.commands.deliver import deliver
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import read_commands
    from op2motion.tasks.steered import SteeredRequest, steered_walk_task

    _refuse_others(args)
    outputs = OutputSet({"plot": args.plot} if args.plot else {})
    timeline = read_commands(args.commands)
    action = ActionFile.read(args.action) if args.action else None
    request = SteeredRequest(timeline, action, args.preset, args.validate, args.robust, engines_of(args), args.push,
                             args.plot)
    return deliver(args, steered_walk_task(request, spec, lambda what, unit: progress(args, what, unit)), outputs)
