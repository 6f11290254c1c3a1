"""Cartesian moves (op2motion.motion.cartesian, .whole_body): a hand along a straight line with the whole body
balanced: on the line within 2 mm, the feet where they were, the CoM inside the support, in physics too."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from helpers import POSES, run_cli

from op2motion.errors import CheckFailed
from op2motion.formats.motionfile import read_motion
from op2motion.formats.posefile import read_pose
from op2motion.motion.cartesian import LINE_MARGIN_M, LINE_TOL_M, LineRequest, _slerp_directions, line_move
from op2motion.motion.checks import check_trajectory
from op2motion.motion.line_solve import RECONFIGURE_ACCEL_M_S2, RECONFIGURE_SPEED_RAD_S
from op2motion.motion.pipeline import plan_motion
from op2motion.motion.whole_body import WholeBodyIk
from op2motion.physics import check
from op2motion.posture.cost import SELF_CLEARANCE_M
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.specfile import default_spec

MOVE_M = 0.05
FEET_TOL_M = 1e-4            # the other sole's corners stay this close to where they were
END_TOL_M = LINE_TOL_M      # the hand ends within the line's tolerance of its end (or its start, going back)
REPLAY_TOL_M = LINE_TOL_M    # the motion file, planned again, keeps the hand as close to the line
POINT_TOL_RAD = np.radians(1.0)
PACE_TOL = 0.1               # the branch change's CoM acceleration and joint speed against their limits (the CoM
#                            is not linear in the unknowns; differences over 8 ms rows)
AXES = {f"{sign}{axis}": sign_v * np.eye(3)[k] * MOVE_M for k, axis in enumerate("XYZ")
        for sign, sign_v in (("+", 1.0), ("-", -1.0))}


def _move(spec, pose: str, hand: str, delta, back: bool = True, duration_s: float = 1.0, orientation="free"):
    if back and duration_s == 1.0 and orientation == "free" and spec is default_spec():
        return _move_and_back(pose, hand, tuple(float(v) for v in delta))
    return line_move(read_pose(POSES / f"{pose}.json", spec),
                     LineRequest(hand, duration_s, delta_m=tuple(delta), orientation=orientation, back=back), spec)


@functools.lru_cache(maxsize=None)
def _move_and_back(pose: str, hand: str, delta: tuple[float, float, float]):
    """The 1-s line there and back with the shipped spec, solved once per test process (the physics tests play
    lines the geometric tests have solved)."""
    return line_move(read_pose(POSES / f"{pose}.json", default_spec()),
                     LineRequest(hand, 1.0, delta_m=delta, orientation="free", back=True), default_spec())


def _assert_on_the_line_and_back(spec, move, hand: str) -> None:
    assert move.deviation_m.max() <= LINE_TOL_M
    assert move.com_margin_m.min() >= LINE_MARGIN_M and move.clearance_m.min() >= SELF_CLEARANCE_M
    half = len(move.goals) // 2
    assert np.linalg.norm(move.hand_path[half] - move.end_m) < END_TOL_M
    assert np.linalg.norm(move.hand_path[-1] - move.start_m) < END_TOL_M
    ik = WholeBodyIk(spec, "double", hand, move.goals[0])
    feet = ik.features(move.goals)["feet"]
    assert np.abs(feet - feet[0]).max() < FEET_TOL_M                     # both soles stay where they stood
    assert np.abs(move.speeds).max() <= 0.5 * spec.servo.no_load_speed_rad_s + 1e-9
    assert check_trajectory(move.trajectory(), spec).zmp_margin_m.min() >= LINE_MARGIN_M   # no lurch either


@pytest.mark.parametrize("hand, axis", [("right", a) for a in sorted(AXES)] + [("left", a) for a in ("+X", "+Y", "-Z")])
def test_five_centimetres_each_way_from_walkready_and_back(spec, hand, axis):
    _assert_on_the_line_and_back(spec, _move(spec, "walkready", hand, AXES[axis]), hand)


@pytest.mark.parametrize("hand, axis", [("right", a) for a in sorted(AXES) if a != "+Y"] + [("left", "+Z")])
def test_five_centimetres_each_way_from_the_straight_legged_standing_pose_and_back(spec, hand, axis):
    move = _move(spec, "standing", hand, AXES[axis])
    _assert_on_the_line_and_back(spec, move, hand)
    if axis == "-Z":                  # below what straight legs allow: the knees bend
        assert move.how == "crouching"
    if axis == "+Z":                  # the forearm hangs straight down: the arm changes branch first
        assert move.how == "from the end" and move.reconfigure_s > 0.0
        lead = move.goals[:int(round(move.reconfigure_s / CONTROL_PERIOD_S)) + 1]
        com = WholeBodyIk(spec, "double", hand, lead[0]).features(lead)["com"]
        accel = np.linalg.norm(np.diff(com, 2, axis=0), axis=1) / CONTROL_PERIOD_S ** 2
        assert accel.max() <= RECONFIGURE_ACCEL_M_S2 * (1 + PACE_TOL)
        assert np.abs(np.diff(lead, axis=0)).max() / CONTROL_PERIOD_S <= RECONFIGURE_SPEED_RAD_S * (1 + PACE_TOL)


@pytest.mark.slow
def test_inwards_from_standing_is_refused_where_a_foot_would_tip(spec, hand="right", axis="+Y"):
    # (the left hand inwards, -Y, is this move's mirror image: refused the same way, 5 s more of the suite)
    # The elbow stands 8 mm from the hip: the torso must lean away so far that, on straight legs with the servos
    # sagging, the lighter foot rolls onto its edge and the loaded foot's own CoP comes within 6 mm of its edge
    # (in physics the robot fell, while the hull of both soles still had 17 mm and the ZMP 12 mm).
    with pytest.raises(CheckFailed, match=r"the loaded foot's own centre of pressure comes \d\.\d mm from its edge"):
        _move(spec, "standing", hand, AXES[axis])


@pytest.mark.slow
def test_a_line_beyond_the_arm_is_refused_saying_where(spec):
    with pytest.raises(CheckFailed, match=r"the right hand cannot reach the line's end \(\+0.221, .* mm short"):
        _move(spec, "standing", "right", (0.2, 0.0, 0.0), back=False)


def test_the_forearm_keeps_or_turns_its_direction(spec):
    keep = _move(spec, "walkready", "left", (0.0, MOVE_M, 0.0), back=False, orientation="keep")
    assert keep.pointing_error_rad is not None and keep.pointing_error_rad.max() < POINT_TOL_RAD
    a, b = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 1.0])
    turned = _slerp_directions(a, b, np.linspace(0.0, 1.0, 11))
    angles = np.arccos(np.clip(turned @ a, -1.0, 1.0))
    assert np.allclose(np.linalg.norm(turned, axis=1), 1.0) and np.allclose(np.diff(angles), angles[-1] / 10)
    assert np.allclose(turned[-1], b / np.linalg.norm(b))


def test_cli_writes_a_motion_that_replays_on_the_line(tmp_path, spec, capsys):
    out = tmp_path / "line.json"
    code, stdout, _ = run_cli(capsys, "motion", "line", POSES / "walkready.json", "--hand", "right", "--by", "0.05",
                              "0", "0", "--duration", "1", "--out", out, "--json")
    result = json.loads(stdout)
    assert code == 0 and result["line_deviation_max_m"] <= LINE_TOL_M and result["com_margin_min_m"] >= LINE_MARGIN_M
    motion = read_motion(out, spec)
    replay = plan_motion(motion, spec)
    ik = WholeBodyIk(spec, "double", "right", replay.goals[0])
    hand = ik.features(replay.goals)["hand"]
    start, end = np.array(result["hand_start_m"]), np.array(result["hand_end_m"])
    span = end - start
    t = np.clip((hand - start) @ span / (span @ span), 0.0, 1.0)
    assert np.linalg.norm(hand - (start + t[:, None] * span), axis=1).max() <= REPLAY_TOL_M


@pytest.mark.parametrize("argv, flag", [
    (["--to", "0.1", "0", "0.2", "--by", "0", "0", "0.01"], "--by"),
    (["--by", "0", "0", "0.05", "--orientation", "sideways"], "--orientation"),
    (["--by", "0", "0", "0.05", "--orientation", "nan", "0", "0"], "--orientation"),
    (["--by", "0", "0", "2"], "--by"),
    pytest.param(["--by", "0.05", "0", "0", "--duration", "0.2"], "--duration", marks=pytest.mark.slow),  # planned
])
def test_cli_bad_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, argv, flag):
    out = tmp_path / "m.json"
    args = ["motion", "line", POSES / "walkready.json", "--hand", "right", *argv, "--out", out]
    if "--duration" not in argv:
        args += ["--duration", "1"]
    code, _, err = run_cli(capsys, *args)
    assert code == 2 and not out.exists() and flag in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.physics
@pytest.mark.parametrize("pose, axis", [("walkready", "-Z"), ("walkready", "+Y"), ("standing", "+Z"),
                                        ("standing", "-Z")])
def test_a_line_and_back_stands(spec, pose, axis):
    """In MuJoCo, and in PyBullet too for the first case (PyBullet costs seven times MuJoCo's CPU per simulated
    second; each stood in both when measured)."""
    move = _move(spec, pose, "right", AXES[axis])
    engines = ("pybullet", "mujoco") if (pose, axis) == ("walkready", "-Z") else ("mujoco",)
    report = check(move.trajectory().schedule(spec), spec, engines)
    assert report.agree and report.stable, [e.run.reasons for e in report.engines.values()]
