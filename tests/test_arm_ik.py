"""Taylor arm IK: the book's printed numbers, the linearisation against finite differences, the iterated mode."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import run_cli

from op2motion.book import ARM_RUNS
from op2motion.errors import ModelError
from op2motion.jsonout import SIGNIFICANT_DIGITS
from op2motion.kinematics.arm_ik import ARMS, _hands, _with_arm, book_step, pb_hand_jacobian, solve_arm_ik
from op2motion.robot.joints import BookAngles

BOOK_DEG = 0.01          # the book prints two decimals
BOOK_EEP_M = 0.006       # the book prints eep_dif to 0.01 m
TOL_M = 1e-4             # the iterated mode's target: 0.1 mm
FD_STEP = 1e-6           # rad
FD_TOL = 1e-8            # m/rad: central differences of a smooth map at this step

BOOK_RUNS = [(r.hand, r.delta_m, r.deltas_deg, r.eep_dif_m) for r in ARM_RUNS]

#: Figures read back from --json carry 6 significant digits (op2motion.jsonout): agreement to this share.
JSON_REL = 10.0 ** -(SIGNIFICANT_DIGITS - 1)


def book_pose(hand: str) -> BookAngles:
    run = next(r for r in ARM_RUNS if r.hand == hand)
    return BookAngles.from_deg(run.th_deg, run.phi_deg, [0, 0, 0], "left")


@pytest.mark.parametrize("hand, delta, deg, eep", BOOK_RUNS)
def test_single_step_reproduces_the_book(spec, hand, delta, deg, eep):
    step = np.degrees(book_step(book_pose(hand), hand, delta, spec))
    assert step == pytest.approx(deg, abs=BOOK_DEG)
    res = solve_arm_ik(book_pose(hand), hand, delta, spec, single_step=True)
    assert np.degrees(res.deltas) == pytest.approx(deg, abs=BOOK_DEG)
    assert res.achieved == pytest.approx(eep, abs=BOOK_EEP_M)        # the book's eep_dif
    assert res.error_m == pytest.approx(np.linalg.norm(res.achieved - np.array(delta)), abs=1e-15)
    assert res.error_m < 0.016   # "misses by up to about 1 cm" (1.5 cm on the 5 cm diagonal right-arm run)


@pytest.mark.parametrize("hand, delta, deg, eep", BOOK_RUNS)
@pytest.mark.parametrize("model", ["pb", "dh"])
def test_iterated_mode_on_the_book_runs(spec, hand, delta, deg, eep, model):
    res = solve_arm_ik(book_pose(hand), hand, delta, spec, model=model)
    assert res.error_m == pytest.approx(np.linalg.norm(res.achieved - np.array(delta)), abs=1e-15)
    assert res.limit_violations == []
    # Two targets lie outside what the three arm joints can reach within their limits (checked against a global
    # search while developing): +2 cm sideways on the projection model (0.5 mm short) and -2 cm forward on the
    # D-H model. Everywhere else the iteration lands within 0.1 mm in a handful of steps.
    unreachable = (model, delta) in (("pb", (0, 0.02, 0)), ("dh", (-0.02, 0, 0)))
    if unreachable:
        assert res.error_m > TOL_M
    else:
        assert res.error_m <= TOL_M and res.iterations <= 10


@pytest.mark.parametrize("model", ["pb", "dh"])
def test_iterated_mode_reaches_reachable_targets(spec, rng, model):
    """Targets made by moving the arm joints up to ±20° (so reachable): within 0.1 mm, in a few iterations."""
    base = book_pose("left")
    arm = ARMS["left"]
    iterations, misses = [], 0
    for _ in range(40):
        q0 = np.radians([rng.uniform(150, 250), rng.uniform(20, 120), rng.uniform(185, 240)])
        q1 = q0 + np.radians(rng.uniform(-20, 20, 3))
        start = _with_arm(base, arm, q0)
        delta = _hands(base, arm, q1, spec, model)[0] - _hands(base, arm, q0, spec, model)[0]
        res = solve_arm_ik(start, "left", delta, spec, model=model, enforce_limits=False)
        misses += res.error_m > TOL_M
        iterations.append(res.iterations)
    assert misses == 0
    assert np.median(iterations) <= 6


def test_book_linearisation_matches_finite_differences(spec, rng):
    """At random bent-arm poses: the book's 2x2 sagittal matrix and coronal derivative, and the full exact
    Jacobian, equal central differences of the projection model's hand."""
    arm = ARMS["left"]
    checked = 0
    while checked < 25:
        q = np.radians([rng.uniform(120, 260), rng.uniform(15, 150), rng.uniform(160, 250)])
        pose = _with_arm(book_pose("left"), arm, q)
        a, b = math.radians(90) + q[0], math.radians(90) + q[0] + q[1]
        if min(abs(math.sin(a)), abs(math.sin(b)), abs(math.cos(q[2]))) < 0.05 or math.sin(b) * b < 0:
            continue  # stay off the kinks of |sin|, |cos| and where the book's sign(B) differs from sign(sin B)
        probes = np.vstack([q + FD_STEP * e for e in np.eye(3)] + [q - FD_STEP * e for e in np.eye(3)])
        hands = _hands(book_pose("left"), arm, probes, spec, "pb")
        fd = ((hands[:3] - hands[3:]) / (2 * FD_STEP)).T
        assert np.abs(pb_hand_jacobian(pose, "left", spec) - fd).max() < FD_TOL
        # The book's single step solves the x/z rows with the sagittal block and the y row with d y/d phi.
        dx, dz, dy = 1e-3, -2e-3, 1.5e-3
        step = book_step(pose, "left", (dx, dy, dz), spec)
        assert fd[[0, 2]][:, :2] @ step[:2] == pytest.approx([dx, dz], abs=FD_TOL * np.abs(step).max())
        assert fd[1, 2] * step[2] == pytest.approx(dy, abs=FD_TOL * abs(step[2]))
        checked += 1


def test_straight_arm_is_a_clear_singular_error(spec):
    with pytest.raises(ModelError, match="singular"):
        book_step(BookAngles.standing("left"), "left", (0.01, 0, 0), spec)



@pytest.mark.slow
def test_cli_keys_and_exit_codes(capsys, tmp_path):
    pose = ["--th", *map(str, ARM_RUNS[0].th_deg), "--phi", *map(str, ARM_RUNS[0].phi_deg)]
    code, out, err = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "0.02", "0", "0", *pose, "--single-step",
                          "--json")
    doc = json.loads(out)
    assert code == 0 and err == ""
    assert doc["joint_deltas_deg"]["th7"] == pytest.approx(17.87, abs=BOOK_DEG)
    assert set(doc["joint_deltas_deg"]) == {"th7", "th8", "phi5"}
    assert doc["th"][6] == pytest.approx(217.87, abs=BOOK_DEG) and len(doc["phi"]) == 6
    assert doc["error_m"] == pytest.approx(np.linalg.norm(np.subtract(doc["achieved_delta"], [0.02, 0, 0])),
                                           rel=JSON_REL)
    png = tmp_path / "ik.png"
    code, out, _ = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "0", "0", "0.02", *pose, "--plot", str(png))
    assert code == 0 and png.read_bytes()[:4] == b"\x89PNG"
    # Unreachable: result printed, one line on stderr, exit 1.
    code, out, err = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "-0.02", "0", "0", *pose, "--model", "dh")
    assert code == 1 and "not reached" in err and err.count("\n") == 1 and "error" in out
    # A step that would bend the elbow past its limit is refused unless allowed.
    code, _, err = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "-0.08", "0", "-0.05", *pose, "--single-step")
    assert code == 1 and "refused" in err
    code, _, _ = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "-0.08", "0", "-0.05", *pose, "--single-step",
                      "--allow-limits")
    assert code == 0
    # Singular and malformed input: exit 2.
    code, _, err = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "0.01", "0", "0", "--th", "90", "0", "0",
                        "180", "0", "0", "180", "0", "180", "0", "0", "--phi", "0", "0", "180", "0", "180", "180",
                        "--single-step")
    assert code == 2 and "singular" in err
    code, _, err = run_cli(capsys, "arm-ik", "--hand", "left", "--delta", "nan", "0", "0", *pose)
    assert code == 2 and "finite" in err
