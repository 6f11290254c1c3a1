"""CLI command bench."""

from __future__ import annotations

import argparse


from ..cli import emit
from ..errors import InputError
from ..spec import Spec


def cmd_bench(args: argparse.Namespace, spec: Spec) -> int:
    from ..bench import run_bench

    if args.poses < 1 or args.repeat < 1:
        raise InputError("--poses and --repeat: expected positive integers")
    result = run_bench(spec, args.poses, args.repeat)
    lines = [f"{result['poses']} poses, best of {result['repeat']}, scaled to 40 000 full-body evaluations:",
             f"  projection model  {result['fk_pb_40k_ms']:8.2f} ms   (book MATLAB: 780 ms)",
             f"  D-H model         {result['fk_dh_40k_ms']:8.2f} ms   (book MATLAB: 3350 ms)",
             f"  pinocchio loop    {result['pinocchio_com_40k_ms']:8.2f} ms   (centerOfMass per configuration)",
             f"one PyBullet validation (3 s simulated): {result['validate_ms']:.0f} ms",
             f"one PSO posture solve (50 particles x 200 iterations, D-H): {result['pso_solve_ms']:.0f} ms "
             "(target <= 150 ms)"]
    emit(args, result, "\n".join(lines))
    return 0
