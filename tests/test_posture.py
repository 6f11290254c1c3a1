"""PSO posture optimisation: the book's four scenarios, the cost, pyswarms hygiene, the optimize command."""

from __future__ import annotations

import json
import logging
import os

import numpy as np
import pytest
from helpers import run_cli

from op2motion.book import DEFAULT_PROBLEM, SCENARIOS
from op2motion.formats.posefile import read_pose
from op2motion.kinematics import forward
from op2motion.kinematics.dh_chain import matrix_frames
from op2motion.kinematics.points import ROW
from op2motion.model.compliance import Compliance, SwingLegSag
from op2motion.physics import ENGINES, Schedule, check
from op2motion.posture.cost import SAG_TILT_LIMIT_RAD, CostModel, PostureProblem, evaluate_cost
from op2motion.posture.pso import PSOSettings, run_pso, variable_bounds
from op2motion.posture.solve import optimize_posture
from op2motion.robot.balance import COM_MODEL_LUMPED, penalty_stability, rectangle_margin, stability_margin
from op2motion.robot.joints import BookAngles, book_to_servo

POSES = os.path.join(os.path.dirname(__file__), "..", "poses")
PSO_REACH_M = 5e-3
REFINED_REACH_M = 1e-3
# The book's scenarios (figs. 2.44-2.47): support, hand, target [m], br, committed pose.
BOOK = [(s.support, s.hand, s.target, s.br, s.pose) for s in SCENARIOS]


def test_book_cost_agrees_with_the_book_penalties(spec, rng):
    """With the book's body (lumped masses, rigid joints) the cost is the book's eq. 2.87."""
    problem = PostureProblem.from_scenario(DEFAULT_PROBLEM, com_model=COM_MODEL_LUMPED)
    book = BookAngles.random(500, rng, "left")
    terms = evaluate_cost(book, problem, spec)
    pts = forward(book, spec)
    com_xy = pts.com[:2].T
    assert np.array_equal(terms.margin < 0, penalty_stability(com_xy, spec, "left", 0.7) > 0)
    assert np.allclose(terms.margin, stability_margin(com_xy, spec, "left", 0.7), atol=1e-15)
    hand = np.linalg.norm(pts.point("left_hand") - np.array(problem.target), axis=1)
    assert np.allclose(terms.hand_error, hand, atol=1e-15) and np.all(terms.sag_tilt == 0)
    # Feasible poses always cost less than infeasible ones (the book's 100 dominates the tie-breakers).
    feasible = (terms.margin >= 0) & (terms.swing_lift >= 0) & (terms.collision == 0)
    assert terms.total[feasible].max() < 100 <= terms.total[~feasible].min()
    # One by one equals batched.
    for i in (0, 7, 499):
        assert evaluate_cost(book.row(i), problem, spec).total[0] == pytest.approx(terms.total[i], abs=1e-12)


def test_full_cost_balances_the_settled_full_inertia_com(spec, rng):
    """The default body: full inertia on compliant servos; the margin is the settled CoM's to the real sole."""
    problem = PostureProblem.from_scenario(DEFAULT_PROBLEM)
    angles = BookAngles.random(300, rng, "left")
    terms = evaluate_cost(angles, problem, spec)
    pts = forward(angles, spec, full_com=True)
    settled = Compliance(spec).settle(pts, pts.com_full)
    xy = np.nan_to_num(settled.com_xy, posinf=1.0, neginf=-1.0)
    assert np.allclose(terms.margin, rectangle_margin(xy[0], xy[1], spec.sole_extents("left", 0.7)), atol=1e-15)
    assert np.allclose(terms.sag_tilt, settled.tilt)
    unstable = (terms.margin < 0) | (terms.sag_tilt > SAG_TILT_LIMIT_RAD)
    assert np.array_equal(unstable, terms.book - terms.hand_error - np.where(terms.swing_lift < 0, 100, 0) > 0)


def test_a_load_over_the_joints_does_not_sag(spec):
    """Known answer: a straight support leg with the whole robot's CoM straight above its joints has no gravity
    torque to sag under: the settled CoM is the CoM and the torso does not turn."""
    model = Compliance(spec)
    pts = forward(BookAngles.standing("left"), spec, full_com=True)
    com = pts.com_full.copy()
    com[:2] = pts.point("l_ank_pitch")[:, :2].T            # the CoM over the ankle (and the knee and hip above it)
    # the leg's own links sit on its axis too, so nothing loads the pitch or roll joints
    settled = model.settle(pts, com)
    assert settled.com_xy[:, 0] == pytest.approx(com[:2, 0], abs=1e-6) and settled.tilt[0] < 1e-3
    com[0] += 0.01                                          # 10 mm ahead: every pitch joint sags forward, amplified
    settled = model.settle(pts, com)
    assert settled.com_xy[0, 0] - com[0, 0] > 0.01 and settled.tilt[0] > 0.01


SETTLE_PREDICTION_M = 0.010   # the compliance model against MuJoCo's settled CoM on standing one-leg poses
# The settled swing-foot height: predicted at most this much lower / higher (the model neglects static friction and
# errs towards more sag: 4-8 mm lower on these poses).
SWING_BELOW_M, SWING_ABOVE_M = 0.010, 0.002
                                              # or higher than MuJoCo's (the model errs towards more sag)


@pytest.mark.physics
def test_compliance_predicts_where_physics_settles(spec):
    problem = PostureProblem.from_scenario(DEFAULT_PROBLEM)
    checked = 0
    model = Compliance(spec)
    for seed in range(4):
        pso = run_pso(problem, spec, PSOSettings(seed=seed, iterations=120))
        angles = BookAngles.from_vector(pso.x, "left")
        pts = forward(angles, spec, full_com=True)
        settled = model.settle(pts, pts.com_full)
        predicted = settled.com_xy[:, 0]
        swing = pts.data[ROW["right_foot_0"]:ROW["right_foot_0"] + 4]
        frames = matrix_frames(angles.vector(), spec, "left")
        swing_z = (model.settled_heights(pts, settled, swing) + SwingLegSag(spec, "left").heights(frames, swing)
                   ).min(axis=0)[0]
        v = check(Schedule.hold(book_to_servo(angles, spec)[0], "left", spec, 3.0), spec, ("mujoco",)).run
        if v.stable:
            assert np.hypot(*(predicted - v.com_settled[:2])) < SETTLE_PREDICTION_M, seed
            assert -SWING_BELOW_M <= swing_z - v.swing_foot_min_z_m <= SWING_ABOVE_M, (seed, swing_z, v)
            checked += 1
    assert checked >= 2


@pytest.mark.parametrize("support, hand, target, br, name", BOOK)
def test_book_scenarios_are_solved_on_the_books_body(spec, support, hand, target, br, name):
    problem = PostureProblem(support, hand, target, br, com_model=COM_MODEL_LUMPED)
    pso = run_pso(problem, spec, PSOSettings(seed=0))
    lo, hi = variable_bounds(problem, spec)
    assert np.all(pso.x >= lo - 1e-12) and np.all(pso.x <= hi + 1e-12)     # the box is respected
    assert np.all(np.diff(pso.history) <= 1e-15)                            # the best cost never rises
    res = optimize_posture(problem, spec, PSOSettings(seed=0), restarts=2)
    assert res.reached, res.message
    assert res.terms.hand_error[0] <= REFINED_REACH_M
    assert res.terms.margin[0] >= 0 and res.terms.swing_lift[0] >= 0 and res.terms.collision[0] == 0
    unrefined = optimize_posture(problem, spec, PSOSettings(seed=0), refine_result=False, restarts=2)
    assert unrefined.terms.hand_error[0] <= PSO_REACH_M


@pytest.mark.physics
@pytest.mark.parametrize("support, hand, target, br, name", BOOK)
def test_committed_book_poses_reach_balance_on_the_full_body_and_stand(spec, support, hand, target, br, name):
    """The committed scenario poses were solved on the full body and validated: they reach, their settled
    full-inertia CoM is inside the br-shrunk sole, and they stand in both engines."""
    pose = read_pose(os.path.join(POSES, f"{name}.json"), spec)
    assert pose.support == support and pose.provenance["com_model"] == "full"
    problem = PostureProblem(support, hand, target, br)
    terms = evaluate_cost(pose.book(spec), problem, spec)
    assert terms.hand_error[0] <= REFINED_REACH_M + 1e-6
    assert terms.margin[0] >= -1e-6 and terms.swing_lift[0] >= 0 and terms.sag_tilt[0] <= SAG_TILT_LIMIT_RAD
    for engine in ENGINES:
        v = check(Schedule.hold(pose.servo, pose.support, spec, 3.0), spec, (engine,)).run
        assert v.stable, (engine, v.reason)


def test_seeded_runs_are_identical_and_pyswarms_leaks_nothing(spec, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    root = logging.getLogger()
    mine = logging.getLogger("op2motion-test-user")
    handler = logging.StreamHandler()
    root.addHandler(handler)
    before = (list(root.handlers), root.level)
    try:
        problem = PostureProblem.from_scenario(DEFAULT_PROBLEM)
        a = run_pso(problem, spec, PSOSettings(iterations=15, seed=7))
        b = run_pso(problem, spec, PSOSettings(iterations=15, seed=7))
        c = run_pso(problem, spec, PSOSettings(iterations=15, seed=8))
        assert np.array_equal(a.x, b.x) and not np.array_equal(a.x, c.x)
        assert os.listdir(tmp_path) == []                       # no report.log
        assert (list(root.handlers), root.level) == before      # root logger untouched
        assert not mine.disabled
    finally:
        root.removeHandler(handler)



@pytest.mark.slow
def test_optimize_default_writes_pose_and_figures(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "optimize", "--json")
    doc = json.loads(out)
    assert code == 0 and err == ""
    for key in ("pose", "cost", "hand_error_m", "com", "stability_margin_m", "swing_foot_min_z", "iterations",
                "seconds"):
        assert key in doc
    assert doc["hand_error_m"] <= REFINED_REACH_M and doc["iterations"] == 200
    files = sorted(os.listdir(tmp_path / "poses"))
    assert files == ["reach-ll-100-50-70-br70.json", "reach-ll-100-50-70-br70.png", "reach-ll-100-50-70-br70_cost.png"]
    assert doc["pose"]["provenance"]["seed"] == 0 and doc["pose"]["metrics"]["br"] == 0.7


@pytest.mark.slow
def test_optimize_prints_its_answer_before_the_figures_and_names_the_files_once_written(capsys, tmp_path,
                                                                                         monkeypatch):
    """For a person the result comes as soon as it is known, while the figures are drawn; the files are named after
    all of them are written; the text is what it always was (the same lines, then the files)."""
    from op2motion.figures.background import Renderers

    monkeypatch.chdir(tmp_path)
    (tmp_path / "poses").mkdir()                     # the answer comes early where the outputs' folder exists
    at_each_wait = []
    wait = Renderers.result

    def result(self, job):
        at_each_wait.append((capsys.readouterr().out, any((tmp_path / "poses").iterdir())))
        return wait(self, job)

    monkeypatch.setattr(Renderers, "result", result)
    code, out, _ = run_cli(capsys, "optimize")
    shown, written_then = at_each_wait[0]
    assert code == 0 and "reached: hand" in shown and "wrote" not in shown and not written_then
    assert out == "  wrote poses/reach-ll-100-50-70-br70.json, poses/reach-ll-100-50-70-br70.png, " \
                  "poses/reach-ll-100-50-70-br70_cost.png\n"
    assert shown.count("\n") == 3 and (tmp_path / "poses" / "reach-ll-100-50-70-br70_cost.png").stat().st_size > 0


def test_unreachable_target_writes_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "optimize", "--target", "0.5", "0", "0.07", "--restarts", "0", "--iters", "60")
    assert code == 1 and "unreachable" in err and "nothing written" in err and err.count("\n") == 1
    assert "residual" in out
    assert not (tmp_path / "poses").exists()


@pytest.mark.parametrize("argv, needle", [
    (["optimize", "--br", "1.5"], "br"),
    (["optimize", "--target", "nan", "0", "0"], "finite"),
    (["optimize", "--particles", "1"], "particles"),
])
def test_optimize_bad_input(capsys, tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and needle in err and out == "" and os.listdir(tmp_path) == []


@pytest.mark.physics
def test_the_default_problems_figure_shows_both_coms_and_the_verdict(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, _ = run_cli(capsys, "optimize", "--validate", "--json")
    doc = json.loads(out)
    assert code == 0
    drawn = doc["figure"]
    assert drawn["stable"] is True and drawn["verdict"].startswith("STANDS")
    row = drawn["rows"][0]
    assert row["com_lumped"] == pytest.approx(doc["com"]) and row["com_full"] == pytest.approx(doc["com_full"])
    assert {"CoM, lumped (book masses)", "CoM, full inertia (physics)", "target"} <= set(drawn["legend"])
    assert "initial pose" not in drawn["legend"]                      # nothing is listed that is not drawn
    assert drawn["margin_full_m"] == pytest.approx(doc["stability_margin_full_m"], abs=1e-9)
    # plot draws the written pose the same way; the verdict comes from physics when asked
    code, out, _ = run_cli(capsys, "plot", doc["files"]["pose"], "--validate", "-o", "again.png", "--json")
    again = json.loads(out)["drawn"]
    assert code == 0 and again["stable"] is True and again["rows"][0]["com_full"] == pytest.approx(row["com_full"])
    # without --validate, the verdict recorded in the pose file is shown
    code, out, _ = run_cli(capsys, "plot", doc["files"]["pose"], "-o", "recorded.png", "--json")
    assert json.loads(out)["drawn"]["verdict"] == "STANDS in physics (recorded)"


def test_the_compiled_swarm_cost_and_skipped_collision_checks_leave_the_search_unchanged(spec, monkeypatch):
    """The PSO runs on the compiled kernel and checks self-collision only for particles that could beat their
    personal best; the swarm must move exactly as on the NumPy cost model with every particle checked."""
    problem = PostureProblem.from_scenario(DEFAULT_PROBLEM)
    fast = run_pso(problem, spec, PSOSettings(iterations=60))
    checked = []
    every = CostModel.__call__

    def check_all(self, angles, only_below=None):
        terms = every(self, angles)
        checked.append(np.isfinite(terms.clearance).all())
        return terms

    monkeypatch.setattr(CostModel, "kernel_plan", lambda self: None)      # the NumPy reference path
    monkeypatch.setattr(CostModel, "__call__", check_all)
    reference = run_pso(problem, spec, PSOSettings(iterations=60))
    assert len(checked) == 60 and all(checked)
    assert np.array_equal(fast.x, reference.x) and np.allclose(fast.history, reference.history, rtol=0, atol=1e-12)
