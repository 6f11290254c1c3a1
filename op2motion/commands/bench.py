"""CLI command bench."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from op2motion import book
from op2motion.bench import BENCH_POSES
from op2motion.commands.common import add_command, emit, whole
from op2motion.robot.spec import Spec

STOCK_ACTION = Path(__file__).resolve().parents[2] / "tests" / "data" / "motion_4096.bin"


def register(sub: Any) -> None:
    """Add bench."""
    p = add_command(sub, "bench", cmd_bench, "speed figures of the batched models, the PSO and the physics check")
    p.add_argument("--poses", type=whole(100, 1_000_000), default=BENCH_POSES,
                   help=f"batch size; figures are scaled to {BENCH_POSES} (default {BENCH_POSES})")
    p.add_argument("--repeat", type=whole(1, 100), default=9, help="runs per figure; the best is reported (default 9)")
    p.add_argument("--wall-runs", type=whole(0, 20), default=3,
                   help="fresh-process runs of --help, optimize and optimize --validate (median reported), plus one "
                        "library build of the default grid; 0 skips them (default 3)")
    p.add_argument("--action", metavar="FILE", default=str(STOCK_ACTION) if STOCK_ACTION.exists() else None,
                   help="action file for motion_play_ms / motion_validate_ms (default: the stock file in the "
                        "repository's tests/data, when present)")


def cmd_bench(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion bench``."""
    from op2motion.bench import check_bench_action, run_bench
    from op2motion.formats.action import ActionFile

    action = check_bench_action(ActionFile.read(args.action), spec) if args.action else None
    r = run_bench(spec, args.poses, args.repeat, action=action, wall_runs=args.wall_runs)
    lines = [f"{r['poses']} poses, best of {r['repeat']}, scaled to {BENCH_POSES} full-body evaluations:",
             f"  projection model  {r['fk_pb_40k_ms']:8.2f} ms   (book MATLAB: {book.MATLAB_40K_MS['pb']:.0f} ms)",
             f"  D-H model         {r['fk_dh_40k_ms']:8.2f} ms   (book MATLAB: {book.MATLAB_40K_MS['dh']:.0f} ms)",
             f"  D-H + full CoM    {r['fk_dh_full_com_40k_ms']:8.2f} ms   (the spec's link inertials, batched)",
             f"  pinocchio loop    {r['pinocchio_com_40k_ms']:8.2f} ms   (centerOfMass per configuration)",
             f"one physics check of the standing pose ({r['validate_seconds']:g} s planned, "
             f"{r['validate_ended']} after {r['validate_simulated_s']:g} s, 1 kHz): PyBullet "
             f"{r['validate_ms']:.0f} ms, MuJoCo {r['validate_mujoco_ms']:.0f} ms",
             f"one PSO posture solve ({book.PSO_PARTICLES} particles x {book.PSO_ITERATIONS} iterations, D-H, full "
             f"model): {r['pso_solve_ms']:.0f} ms"]
    if r["motion_play_ms"] is not None:
        lines += [f"page {r['motion_page']} played tick for tick ({r['check_motion_ticks']} ticks): "
                  f"{r['motion_play_ms']:.2f} ms; validated in PyBullet: {r['motion_validate_ms']:.0f} ms"]
    lines += [f"walk planned ({r['walk_steps']} steps of the forward preset): {r['walk_plan_ms']:.0f} ms; walked "
              f"({r['walk_simulated_s']:g} s simulated): PyBullet {r['walk_validate_ms']:.0f} ms, MuJoCo "
              f"{r['walk_validate_mujoco_ms']:.0f} ms ({r['check_walk_speed_mps']:.3f} m/s steady)"]
    lines.append(f"pose studio: one joint edit and its readout {r['studio_update_ms']:.2f} ms")
    lines.append(f"robot loop through the emulated OP2 ({r['robot_emulator_engine']}, its own process; "
                 f"{r['robot_loop_ticks']} ticks): period p50 {r['robot_loop_p50_ms']:.2f} ms, p99 "
                 f"{r['robot_loop_p99_ms']:.2f} ms, max {r['robot_loop_max_ms']:.2f} ms, "
                 f"{r['check_robot_loop_missed_reads']} missed reads; robot status (21 reads) "
                 f"{r['robot_status_ms']:.1f} ms")
    if "help_wall_s" in r:
        lines += [f"from the shell (median of {r['wall_runs']}): --help {r['help_wall_s']:.2f} s, optimize "
                  f"{r['optimize_wall_s']:.2f} s, optimize --validate {r['optimize_validate_wall_s']:.2f} s",
                  f"library build --validate --workers 2 (default grid): {r['check_library_standing_poses']} standing "
                  f"poses in {r['library_wall_s']:.1f} s = {r['library_poses_per_min']:.0f} per minute"]
    emit(args, r, "\n".join(lines))
    return 0
