"""What a new user meets in a first hour, without surprises: a double-support pose measured on both feet,
progress in a log, a walk in place that does not claim a speed."""

from __future__ import annotations

import json

from helpers import pose_path, run_cli, without_progress

from op2motion.commands import common


def test_fk_of_a_double_support_pose_measures_it_on_both_feet(capsys):
    code, out, _ = run_cli(capsys, "fk", "--pose", pose_path("walkready"), "--json")
    doc = json.loads(out)
    assert code == 0 and doc["support"] == "double" and doc["double_support_margin_m"] > 0.03
    code, text, _ = run_cli(capsys, "fk", "--pose", pose_path("walkready"))
    assert "double support" in text and "hull of both soles" in text and "swing foot" not in text


def test_progress_in_a_log_is_a_plain_line_now_and_then(capsys, monkeypatch):
    clock = iter([1.0, common.PLAIN_EVERY_S + 1.0, common.PLAIN_EVERY_S + 2.0])
    ticker = common.PlainTicker("physics", "s", 5.0)
    monkeypatch.setattr(ticker, "_clock", lambda: next(clock))
    ticker._start = ticker._last = 0.0
    ticker.update(1.0)                                       # 1 s after the start: quiet
    ticker.update(1.0)                                       # past PLAIN_EVERY_S: one line
    ticker.update(1.0)                                       # 1 s after that line: quiet
    err = capsys.readouterr().err
    assert err == f"op2motion: physics: 2/5 s ({common.PLAIN_EVERY_S + 1:.0f} s)\n" and without_progress(err) == ""


def test_a_walk_in_place_has_no_steady_speed(capsys):
    code, out, _ = run_cli(capsys, "walk", "--target", "0", "0", "0", "--json")
    doc = json.loads(out)
    assert code == 0 and doc["distance_m"] == 0.0 and doc["planned_speed_mps"] == 0.0


def test_the_cop_track_is_drawn_in_the_plot_s_own_frame(spec):
    from op2motion.formats.posefile import read_pose
    from op2motion.motion.checks import in_sole_frame

    init = read_pose(pose_path("init"), spec).servo
    track = [(0.0, 0.0, 0.0), (1.0, 0.01, 0.0)]
    assert in_sole_frame(track, init, "left", "left", spec) == track
    moved = in_sole_frame(track, init, "left", "right", spec)            # the left sole seen from the right one
    width = spec.geometry.hip_y * 2 if hasattr(spec.geometry, "hip_y") else None
    assert abs(moved[0][1]) < 0.005 and moved[0][2] > 0.05                # beside it, to the left
    assert abs((moved[1][1] - moved[0][1]) - 0.01) < 1e-3 and abs(moved[1][2] - moved[0][2]) < 1e-3
    assert width is None or abs(moved[0][2] - width) < 0.01
