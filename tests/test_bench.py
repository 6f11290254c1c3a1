"""The benchmark reports every figure, and the work it times is right (speed itself is measured by
``op2motion bench``, not asserted)."""

import pytest
from helpers import STOCK

from op2motion.bench import run_bench
from op2motion.formats.action import ActionFile
from op2motion.motion.cartesian import LINE_TOL_M
from op2motion.posture.cost import SELF_CLEARANCE_M

DH_VS_PINOCCHIO_M = 1e-9      # the D-H joint centres equal pinocchio's on the generated URDF
PSO_REACH_M = 0.01            # the default problem's swarm lands the hand within a centimetre
STANDING_CLEARANCE_M = 0.010   # standing, the forearms hang 8 mm beside the thighs
WALK_SPEED_MPS = 0.20        # the forward preset's steady speed in PyBullet (issue "Walking": >= 0.20 m/s)
SMALL_GRID_TARGETS = 2        # the library figure's mechanism on a small grid (bench itself builds the default one)
LOCKSTEP_LOOP_S = 3.0          # the bench's lockstep loop holds this long [simulated s] (onrobot/bench.py LOOP_S)
LOCKSTEP_LOOP_TOL_S = 0.02     # ... to within a few ticks (it once ran 0.01 s: a hold is done at once)
FULL_COM_VS_PINOCCHIO_M = 1e-5  # the URDF's six 10-mg frame links are the only difference (2 µm)


#: The library figure's grid: its mechanism on two targets (bench itself builds the default grid, 108 targets).
SMALL_GRID = ["--hands", "left", "--supports", "left", "--x", "0.08", "0.12", "2", "--y", "0.03", "0.03", "1",
              "--z", "0.07", "0.07", "1"]


@pytest.mark.physics
def test_bench_reports_every_figure_and_its_work_is_right(spec):
    """Every figure, the wall-clock ones from fresh processes included, in one run (one set of wall runs: the library
    figure on :data:`SMALL_GRID`)."""
    result = run_bench(spec, n=500, repeat=1, action=ActionFile.read(STOCK), wall_runs=1, wall_grid=SMALL_GRID)
    assert result["poses"] == 500 and result["repeat"] == 1
    for key in ("fk_pb_40k_ms", "fk_dh_40k_ms", "fk_dh_full_com_40k_ms", "pinocchio_com_40k_ms", "validate_ms",
                "pso_solve_ms", "self_clearance_swarm_ms", "motion_play_ms", "motion_validate_ms",
                "walk_plan_ms", "walk_validate_ms", "validate_mujoco_ms", "walk_validate_mujoco_ms", "help_wall_s",
                "optimize_wall_s", "optimize_validate_wall_s", "cli_start_s", "main_job_s", "main_job_validate_s",
                "studio_update_ms", "robot_loop_p99_ms", "robot_status_ms", "library_poses_per_min"):
        assert result[key] > 0, key
    assert result["check_help_ok"] and result["check_optimize_reached"] and result["check_optimize_validate_stands"]
    assert result["check_library_targets"] == SMALL_GRID_TARGETS and result["check_library_standing_poses"] > 0
    assert result["check_main_job_files_written"] is True
    assert 0 < result["main_job_answer_s"] <= result["main_job_s"]
    assert result["validate_ended"] == "settled" and result["validate_simulated_s"] < result["validate_seconds"]
    assert result["check_dh_vs_pinocchio_m"] < DH_VS_PINOCCHIO_M
    assert result["check_full_com_vs_pinocchio_m"] < FULL_COM_VS_PINOCCHIO_M
    assert result["check_standing_stands"] is True
    assert 0.0 < result["check_standing_clearance_m"] < STANDING_CLEARANCE_M
    assert result["check_pso_hand_error_m"] < PSO_REACH_M
    assert result["check_motion_ticks"] == 464 and result["check_motion_stands"] is True
    assert result["check_walk_fell"] is False and result["check_walk_speed_mps"] > WALK_SPEED_MPS
    assert result["check_studio_readout"] is True
    assert result["check_robot_status_servos"] == 20 and result["robot_loop_ticks"] > 0   # (how many: the bench)
    assert abs(result["check_robot_lockstep_s"] - LOCKSTEP_LOOP_S) < LOCKSTEP_LOOP_TOL_S    # the hold ran its length
    assert result["check_route_clearance_m"] >= SELF_CLEARANCE_M and result["check_line_deviation_m"] <= LINE_TOL_M
    assert result["book_matlab_dh_40k_ms"] == 3350.0 and result["book_matlab_pb_40k_ms"] == 780.0


def test_the_shell_figures_run_the_program_a_user_runs_until_it_exits(tmp_path):
    """cli_start_s, main_job_s, main_job_validate_s: fresh runs of the ``op2motion`` program (the console script
    beside this interpreter, else ``python -m op2motion``), timed to their exit; the best and the median."""
    from op2motion.bench_wall import program, shell_runs

    argv0 = program()
    assert argv0[-1].endswith("op2motion") and (len(argv0) == 1 or argv0[1:] == ["-m", "op2motion"])
    runs = shell_runs(["--help"], 2)
    assert runs.ok and len(runs.seconds) == 2 and 0 < runs.best <= runs.median and "COMMAND" in runs.text
    assert all(0 < answer <= seconds for answer, seconds in zip(runs.answers, runs.seconds))
    assert not shell_runs(["no-such-command"], 1).ok


def test_a_run_that_names_a_file_it_did_not_write_fails_the_check(tmp_path):
    from op2motion.bench_wall import files_written

    (tmp_path / "poses").mkdir()
    (tmp_path / "poses" / "a.json").write_text("{}")
    (tmp_path / "poses" / "a.png").write_bytes(b"")
    said = "left hand to (0.100, 0.050, 0.070) m on the left foot, br 0.7: reached\n  wrote {}\n"
    assert files_written(said.format("poses/a.json"), tmp_path)
    assert not files_written(said.format("poses/a.json, poses/a.png"), tmp_path)              # empty
    assert not files_written(said.format("poses/a.json, poses/b.png"), tmp_path)              # missing
    assert not files_written("reached\n", tmp_path)                                        # none named
