"""User tasks return one shape (op2motion.tasks): a "no" is a result with its phrase, never an exception; the task
writes nothing itself (its outputs are for the caller, and only on a yes); the command-line modules that deliver
tasks hold no verdict logic of their own."""

from __future__ import annotations

import ast
import json

import pytest
from helpers import DATA, POSES, ROOT, run_cli, source_tree

from op2motion.tasks.result import Output, TaskResult

#: Command modules that only parse, call a task and deliver its result (the rest still build their reports and are
#: listed in STILL_BUILDING until they move to op2motion.tasks).
DELIVERING = ("bench.py", "deliver.py", "files.py", "kinematics.py", "library.py", "motion.py", "motion_line.py",
              "motion_run.py", "physics.py", "posture.py", "robot.py", "studio.py", "tune.py", "walk.py",
              "walk_commands.py")
STILL_BUILDING: set[str] = set()


def test_a_result_has_a_problem_exactly_when_it_is_a_no():
    assert TaskResult(True).as_dict() == {}
    assert TaskResult(True, data={"files": {}}).as_dict() == {"files": {}}
    no = TaskResult(False, "page 9: does not get through", (), {"plot": Output("a.png", b"png")},
                    {"page": 9, "files": {}})
    assert no.as_dict({"plot": "a.png"}) == {"page": 9, "warnings": [], "files": {"plot": "a.png"}}
    keyed = TaskResult(True, outputs={"gui_png": Output("b.png", b"png", key="png")}, data={"pose": "x"})
    assert keyed.as_dict({"gui_png": "b.png"}) == {"pose": "x", "png": "b.png"}
    for ok, problem in ((True, "why"), (False, None)):
        with pytest.raises(ValueError, match="problem exactly when"):
            TaskResult(ok, problem)
    with pytest.raises(TypeError):
        no.data["page"] = 10                                    # type: ignore[index]
    assert not TaskResult.refused("goals out of range").checked


@pytest.mark.slow
def test_a_page_played_is_a_result_and_writes_nothing_itself(spec, tmp_path):
    from op2motion.formats.action import ActionFile
    from op2motion.tasks.motion import MotionCheck, play_page_task

    plot, csv = tmp_path / "p.png", tmp_path / "p.csv"
    check = MotionCheck(plot=str(plot), csv=str(csv))
    result = play_page_task(ActionFile.read(DATA / "motion_4096.bin"), 9, spec, check)
    assert result.ok and result.problem is None and result.checked
    assert set(result.outputs) == {"plot", "csv"} and not plot.exists() and not csv.exists()
    assert result.outputs["plot"].content[:8] == b"\x89PNG\r\n\x1a\n"
    data = result.as_dict()
    assert data["page"] == 9 and data["checks"]["min_clearance_m"] > 0 and "physics" not in data
    assert result.lines[0].startswith("page 9 (")


def test_goals_beyond_a_joints_range_are_refused_as_a_result(spec):
    """A motion whose goals leave the mechanical range is a "no" before any check, not an exception."""
    import numpy as np

    from op2motion.formats.posefile import read_pose
    from op2motion.motion.trajectory import Trajectory
    from op2motion.tasks.motion import MotionCheck, Told, check_motion

    pose = read_pose(POSES / "walkready.json", spec)
    rows = 10
    goals = np.tile(pose.servo, (rows, 1))
    goals[5, spec.joint_names.index("r_knee")] = np.radians(250.0)
    trajectory = Trajectory(goals, np.full(goals.shape, 32), ("double",) * rows, np.zeros(rows, dtype=int), ("bent",))
    result = check_motion(trajectory, spec, MotionCheck(validate=True), Told("bent", {}, []))
    assert not result.ok and not result.checked and "r_knee" in str(result.problem) and not result.outputs


def test_the_cli_delivers_a_yes_with_its_files_and_todays_keys(tmp_path, capsys):
    """motion play through the task: a yes writes its plot; the JSON keys are today's."""
    plot = tmp_path / "page.png"
    code, out, err = run_cli(capsys, "motion", "play", DATA / "motion_4096.bin", "--page", "9", "--plot", plot,
                             "--json")
    assert code == 0, err
    data = json.loads(out)
    assert set(data) == {"page", "name", "start", "ticks", "duration_s", "pages_played", "ids", "goals", "checks",
                         "files"}
    assert data["files"] == {"plot": str(plot)} and plot.is_file()


@pytest.mark.parametrize("name", DELIVERING)
def test_delivering_commands_hold_no_verdict_logic(name):
    """No result dict built, no physics verdict asked for, no check run in the module: the task does that."""
    tree = source_tree(ROOT / "op2motion" / "commands" / name)
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Subscript) for t in node.targets):
            raise AssertionError(f"{name}:{node.lineno}: a result built by item assignment")
        if isinstance(node, ast.AnnAssign) and isinstance(node.value, ast.Dict):
            raise AssertionError(f"{name}:{node.lineno}: a result dict built")
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "emit" and any(
                isinstance(a, ast.Dict) for a in node.args):
            raise AssertionError(f"{name}:{node.lineno}: a result dict printed")
        if isinstance(node, ast.Attribute) and node.attr in ("problem", "stable", "agree") and isinstance(
                node.ctx, ast.Load) and not (isinstance(node.value, ast.Name) and node.value.id == "result"):
            raise AssertionError(f"{name}:{node.lineno}: a verdict computed ({node.attr})")


def test_only_the_delivery_prints_a_report_or_says_no():
    """Every command's report goes through ``commands/deliver.py`` (the one place that prints a result and turns a no
    into exit 1): no other command module calls ``emit``, writes JSON, or raises a failed check."""
    for path in sorted((ROOT / "op2motion" / "commands").glob("*.py")):
        if path.name in ("deliver.py", "common.py"):
            continue
        tree = source_tree(path)
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) in (
                    "emit", "dump", "dumps"):
                raise AssertionError(f"{path.name}:{node.lineno}: prints a report itself")
            if isinstance(node, ast.Name) and node.id in ("CheckFailed", "Unreachable"):
                raise AssertionError(f"{path.name}:{node.lineno}: says no itself")


def test_the_list_of_commands_still_building_reports_is_the_truth():
    """Every command module is either delivering a task or listed as still building its report (the list shrinks as
    commands move to op2motion.tasks; a module that moved must leave it)."""
    present = {p.name for p in (ROOT / "op2motion" / "commands").glob("*.py")} - {"__init__.py", "common.py"}
    assert present == set(DELIVERING) | STILL_BUILDING
    assert not set(DELIVERING) & STILL_BUILDING
