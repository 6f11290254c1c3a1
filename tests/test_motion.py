"""Planned motions: the planner's profiles, balance along one-foot segments, the checks along a trajectory, motion
files, export as action pages (round trip through the player) and the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import POSES, STOCK, pose_path, run_cli

from op2motion.errors import CheckFailed, PoseFileError
from op2motion.formats.action import ActionFile
from op2motion.formats.actionlayout import PAGE_SIZE, is_empty, reset_file
from op2motion.formats.motionfile import read_motion
from op2motion.formats.posefile import read_pose
from op2motion.motion.checks import check_trajectory, require_clear
from op2motion.motion.planner import SPEED_FRACTION, action_pages, robot_steps, trajectory_through
from op2motion.motion.player import play, start_ticks
from op2motion.motion.shift import settled_coms, with_weight_shifts
from op2motion.motion.trajectory import from_playback
from op2motion.motion.waypoint import Waypoint
from op2motion.robot.framework import CONTROL_PERIOD_S

SETTLED_COM_TOL_M = 2e-4      # the balanced rows' settled CoM against its straight-line target
SPEED_TOL = 1e-6              # relative, on the stretched peak speed
ZMP_INSIDE_M = 0.0            # the example motions' planned ZMP stays inside the support polygon
#: The example motions played in PyBullet as well as MuJoCo: one on both feet, one reaching on one foot.
BOTH_ENGINES_MOTIONS = ("stand_sit_stand", "stand_book_2_44")


def _pose(spec, name):
    return read_pose(pose_path(name), spec)


def _waypoints(spec, names, duration=1.5, pauses=None):
    pauses = pauses or [0.0] * len(names)
    return [Waypoint(n, _pose(spec, n).servo, 0.0 if k == 0 else duration, pauses[k], _pose(spec, n).support)
            for k, n in enumerate(names)]


def test_quintic_starts_and_ends_at_rest_on_the_poses(spec):
    traj = trajectory_through(_waypoints(spec, ["standing", "walkready"]), spec)
    assert np.allclose(traj.goals[0], _pose(spec, "standing").servo)
    assert np.allclose(traj.goals[-1], _pose(spec, "walkready").servo)
    assert traj.duration_s == pytest.approx(np.ceil(1.5 / CONTROL_PERIOD_S) * CONTROL_PERIOD_S)   # whole 8 ms units
    v = np.diff(traj.goals, axis=0) / traj.dt
    assert np.abs(v[0]).max() < 0.02 and np.abs(v[-1]).max() < 0.02      # [rad/s]: a quintic leaves and lands at rest


def test_a_segment_too_fast_for_the_servos_is_stretched_with_a_note(spec):
    traj = trajectory_through(_waypoints(spec, ["standing", "sit_down"], duration=0.1), spec)
    peak = np.abs(np.diff(traj.goals, axis=0) / traj.dt).max()
    assert peak <= SPEED_FRACTION * spec.servo.no_load_speed_rad_s * (1 + SPEED_TOL)
    assert traj.duration_s > 0.1 and any("stretched" in n for n in traj.notes)


def test_one_foot_segments_keep_the_settled_com_on_its_line(spec):
    waypoints = _waypoints(spec, ["init", "book_2_44", "init"], pauses=[0.0, 0.5, 0.0])
    traj = trajectory_through(waypoints, spec)
    assert sum(s == "left" for s in traj.supports) > 100     # the lift and the pose stand on the left foot alone
    k = traj.segment_names.index("init@left+lift -> book_2_44")
    rows = traj.goals[traj.segment == k]
    ends = settled_coms(np.array([rows[0], rows[-1]]), "left", spec)
    com = settled_coms(rows, "left", spec)
    direction = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
    off_line = (com - ends[0]) @ np.array([-direction[1], direction[0]])
    assert np.abs(off_line).max() < SETTLED_COM_TOL_M
    shifted, notes = with_weight_shifts(waypoints, spec)
    assert [w.support for w in shifted][:3] == ["double", "double", "left"] and len(notes) == 2


def test_an_arm_driven_into_the_torso_is_refused_naming_segment_and_links(spec):
    init = _pose(spec, "init").servo
    inside = init.copy()
    for joint, deg in (("r_sho_pitch", -45.0), ("r_sho_roll", -90.0), ("r_el", 0.0)):
        inside[spec.joint_names.index(joint)] = np.radians(deg)
    traj = trajectory_through([Waypoint("init", init, 0.0, 0.0, "double"),
                               Waypoint("arm_in", inside, 1.0, 0.0, "double")], spec, planner="none")
    with pytest.raises(CheckFailed, match=r"init -> arm_in.*(body_link|r_el_link)"):
        require_clear(traj, spec)


def test_example_motions_pass_the_checks_along_the_way(spec):
    for name in ("stand_sit_stand", "stand_book_2_44"):
        motion = read_motion(POSES / "motions" / f"{name}.json", spec)
        waypoints = [Waypoint(s.pose.name, s.pose.servo, s.duration_s, s.pause_s, s.pose.support) for s in motion.steps]
        traj = trajectory_through(waypoints, spec)
        require_clear(traj, spec)
        checks = check_trajectory(traj, spec).summary()
        assert checks["zmp_margin_min_m"] > ZMP_INSIDE_M and checks["torque_ratio_max"] < 1.0


def test_motion_files_reject_bad_documents(tmp_path, spec):
    good = json.loads((POSES / "motions" / "stand_sit_stand.json").read_text())
    for change, message in ((lambda d: d.update(schema="op2motion.motion/9"), "schema"),
                            (lambda d: d["steps"][1].pop("duration_s"), "duration_s"),
                            (lambda d: d["steps"][0].update(extra=1), "unknown field"),
                            (lambda d: d.update(p_gain=1000), "p_gain")):
        doc = json.loads(json.dumps(good))
        change(doc)
        path = POSES / "motions" / "_bad_test.json"
        try:
            path.write_text(json.dumps(doc))
            with pytest.raises(PoseFileError, match=message):
                read_motion(path, spec)
        finally:
            path.unlink(missing_ok=True)


def test_a_motion_exported_as_pages_imports_and_plays_back_the_same(spec):
    waypoints = _waypoints(spec, ["standing", "walkready", "sit_down", "stand_up"], duration=4.5,
                           pauses=[0.0, 0.5, 3.0, 0.0])
    pages, _ = action_pages(waypoints, spec, "sitdown", 30)
    assert len(pages) >= 2                                   # split steps and a long pause: more than 7 steps
    data = bytearray(reset_file())
    for k, page in enumerate(pages):
        data[(30 + k) * PAGE_SIZE:(31 + k) * PAGE_SIZE] = page
    steps, _, _ = robot_steps(waypoints, spec, SPEED_FRACTION * spec.servo.no_load_speed_rad_s)
    imported = [s for p in ActionFile(bytes(data)).pages(spec) for s in p.steps]
    assert [(s.time, s.pause) for s in imported] == [(s.time, s.pause) for s in steps]
    assert [s.ticks for s in imported] == [s.words for s in steps]
    played = from_playback(play(ActionFile(bytes(data)), 30, start_ticks(waypoints[0].servo, spec)), spec)
    planned = trajectory_through(waypoints, spec, "robot", shift_weight=False)
    assert np.array_equal(np.round(played.goals, 9), np.round(planned.goals, 9))


def test_cli_play_reports_ticks_and_goals(capsys):
    code, out, _ = run_cli(capsys, "motion", "play", STOCK, "--page", "9", "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["ticks"] == 129 and doc["duration_s"] == pytest.approx(129 * CONTROL_PERIOD_S)
    assert doc["pages_played"] == [9] and len(doc["goals"]) == 130 and len(doc["goals"][0]) == 20


def test_cli_export_writes_empty_pages_only(tmp_path, capsys):
    out = tmp_path / "m.bin"
    code, text, _ = run_cli(capsys, "motion", "export", POSES / "motions" / "stand_sit_stand.json",
                            "--format", "action", "--base", STOCK, "-o", out, "--json")
    assert code == 0
    doc = json.loads(text)
    data, stock = out.read_bytes(), STOCK.read_bytes()
    assert all(is_empty(stock, p) for p in doc["pages"])
    untouched = [i for i in range(256) if i not in doc["pages"]]
    assert all(data[i * PAGE_SIZE:(i + 1) * PAGE_SIZE] == stock[i * PAGE_SIZE:(i + 1) * PAGE_SIZE] for i in untouched)
    code, _, err = run_cli(capsys, "motion", "export", POSES / "motions" / "stand_sit_stand.json", "--format",
                           "action", "--base", STOCK, "--page", "1", "-o", tmp_path / "x.bin")
    assert code == 2 and "--force" in err and not (tmp_path / "x.bin").exists()


def test_stand_to_a_one_leg_pose_and_back_is_the_example_motion_checked_in_physics(spec):
    """Waypoints through a one-leg pose plan the very schedule of ``stand_book_2_47.json``, whose physics check
    is :func:`test_every_example_motion_stands`'s."""
    from op2motion.motion.pipeline import plan_motion

    traj = trajectory_through(_waypoints(spec, ["init", "book_2_47", "init"], pauses=[0.0, 0.5, 0.0]), spec)
    assert "right" in traj.supports
    example = plan_motion(read_motion(POSES / "motions" / "stand_book_2_47.json", spec), spec)
    assert np.array_equal(traj.goals, example.goals) and traj.supports == example.supports


@pytest.mark.physics
def test_stock_page_played_in_physics(spec):
    from op2motion.motion.pipeline import play_page
    from op2motion.physics import check

    action = ActionFile.read(STOCK)
    played = play_page(action, 15, spec)                    # sit down, from page 1's end (init)
    assert played.start.name == "init"
    verdict = check(played.trajectory.schedule(spec), spec, ("mujoco",)).run
    assert verdict.stable, verdict.reasons
    assert not action.is_empty(15)


@pytest.mark.physics
@pytest.mark.parametrize("name", sorted(p.stem for p in (POSES / "motions").glob("*.json")   # those lying and the
                                         if not p.stem.startswith(("getup_", "roll_", "kick_"))))  # kicks: tools/
def test_every_example_motion_stands(spec, name):                          # getup_table.py, kick_table.py, test_getup
    """In MuJoCo, and in PyBullet too for :data:`BOTH_ENGINES_MOTIONS` (PyBullet costs seven times MuJoCo's CPU per
    simulated second; each stood in both when measured)."""
    from op2motion.motion.pipeline import plan_motion
    from op2motion.physics import check

    engines = ("pybullet", "mujoco") if name in BOTH_ENGINES_MOTIONS else ("mujoco",)
    report = check(plan_motion(read_motion(POSES / "motions" / f"{name}.json", spec), spec).schedule(spec), spec,
                   engines)
    assert report.agree and report.stable, [e.run.reasons for e in report.engines.values()]
    for engine in report.engines.values():                # each engine measured how the servos followed
        assert engine.run.motion.tracking_max_deg and engine.run.motion.worst_torque.torque_nm > 0.0
