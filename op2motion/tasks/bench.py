"""The bench task (``bench``): speed figures of the batched models, the PSO, the physics check, motions, walks, the
studio and the robot loop through the emulated OP2, each with a check of the timed work
(:func:`op2motion.bench.run_bench`), returned as a :class:`~.result.TaskResult` (the figures and their lines).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from op2motion import book
from op2motion.robot.spec import Spec
from op2motion.tasks.result import TaskResult

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.jsonout import JsonObject


def _lines(r: dict[str, Any]) -> list[str]:
    """The figures for a person."""
    from op2motion.bench import BENCH_POSES

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
    lines.append(f"  the wire (1 Mbps, 1 ms FTDI latency timer): a tick reads {r['robot_servos_per_tick']} servos, "
                 f"{r['robot_bulk_read_wire_ms']} ms on the wire, {r['robot_bulk_read_ms']} ms with the link's tail; "
                 f"ping {r['robot_ping_ms']} ms; in lockstep the loop runs {r['robot_lockstep_speedup']} x real time")
    if "main_job_s" in r:
        lines += [f"from the shell ({r['wall_program']}, best of {r['wall_runs']}; median): --help "
                  f"{r['cli_start_s']:.2f} s ({r['cli_start_median_s']:.2f}), optimize {r['main_job_s']:.2f} s "
                  f"({r['main_job_median_s']:.2f}; its answer after {r['main_job_answer_s']:.2f} s), optimize "
                  f"--validate {r['main_job_validate_s']:.2f} s ({r['main_job_validate_median_s']:.2f}; answer "
                  f"{r['main_job_validate_answer_s']:.2f} s)",
                  f"library build --validate --workers 2 (default grid): {r['check_library_standing_poses']} standing "
                  f"poses in {r['library_wall_s']:.1f} s = {r['library_poses_per_min']:.0f} per minute"]
    return lines


def bench(spec: Spec, poses: int, repeat: int, action: ActionFile | None = None, wall_runs: int = 3
          ) -> TaskResult[JsonObject]:
    """``bench``: ``poses`` per batch, the best of ``repeat``; ``action``'s stock page for the motion figures (None:
    none); ``wall_runs`` fresh-process runs of the commands (0: none)."""
    from op2motion.bench import check_bench_action, run_bench

    checked = check_bench_action(action, spec) if action is not None else None
    r = run_bench(spec, poses, repeat, action=checked, wall_runs=wall_runs)
    return TaskResult(True, data=r, lines=("\n".join(_lines(r)),), value=r)
