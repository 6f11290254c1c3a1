"""Work a user can multiply is capped, and the cap is in the message, before any work starts: a motion's poses and
seconds (flags and files alike), route planning in all, and the simulated time of a request (runs x seconds: bodies,
engines, pushes, trials, steps). Each refusal comes at once, as one line, with nothing written."""

from __future__ import annotations

import json
import time

import pytest
from helpers import pose_path, run_cli

from op2motion.errors import InputError
from op2motion.physics.runner import MAX_SIMULATED_S, check_work
from op2motion.robot.framework import MAX_MOTION_POSES, MAX_MOTION_S

STAND, INIT = pose_path("standing"), pose_path("init")
AT_ONCE_S = 10.0               # a refused request ends within this (the 40-minute motion took 88 s) [s]


def _refused(capsys, tmp_path, *argv) -> str:
    t0 = time.monotonic()
    code, out, err = run_cli(capsys, *argv)
    took = time.monotonic() - t0
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and took < AT_ONCE_S, (code, err, took)
    assert not [p for p in tmp_path.iterdir() if p.name != "in"], "nothing written"
    return lines[0]


def test_a_forty_minute_motion_from_flags_is_refused_at_once(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    poses = [INIT, STAND] * 41
    line = _refused(capsys, tmp_path, "motion", "plan", *poses, "--durations", "60", "--out", "m.json")
    assert "--durations" in line and f"{MAX_MOTION_S:g} s" in line


def test_a_motion_file_over_the_cap_names_the_file_and_field(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    stand = json.loads(open(STAND, encoding="utf-8").read())["servo_deg"]
    steps = [{"servo_deg": stand}] + [{"servo_deg": stand, "duration_s": 50.0, "pause_s": 10.0}] * 6
    (tmp_path / "in").mkdir()
    path = tmp_path / "in" / "long.json"
    path.write_text(json.dumps({"schema": "op2motion.motion/1", "name": "long", "steps": steps}), encoding="utf-8")
    line = _refused(capsys, tmp_path, "motion", "plan", str(path), "--out", "m.json")
    assert "long.json" in line and "steps" in line and f"{MAX_MOTION_S:g} s" in line and "--durations" not in line
    path.write_text(json.dumps({"schema": "op2motion.motion/1", "name": "long", "steps": [
        {"servo_deg": stand}, {"servo_deg": stand, "duration_s": 61.0}]}), encoding="utf-8")
    line = _refused(capsys, tmp_path, "motion", "plan", str(path))
    assert "steps[1]" in line and "duration_s" in line and "--durations" not in line
    path.write_text(json.dumps({"schema": "op2motion.motion/1", "name": "many", "steps": [
        {"servo_deg": stand}] + [{"servo_deg": stand, "duration_s": 0.024}] * MAX_MOTION_POSES}), encoding="utf-8")
    line = _refused(capsys, tmp_path, "motion", "plan", str(path))
    assert "steps" in line and str(MAX_MOTION_POSES) in line


def test_simulated_time_is_capped_before_any_run(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    line = _refused(capsys, tmp_path, "validate", STAND, "--robust", "--seconds", "60", "--engine", "both",
                    "--push", "10")
    assert f"{MAX_SIMULATED_S:g} s of simulated time" in line and "bodies" in line
    line = _refused(capsys, tmp_path, "walk", "--steps", "200", "--validate", "--engine", "both", "--trials", "100",
                    "--plot", "w.png")
    assert f"{MAX_SIMULATED_S:g} s of simulated time" in line


def test_the_cap_is_a_product_of_runs_and_seconds():
    check_work(10, MAX_SIMULATED_S / 10)                      # exactly at the cap: allowed
    with pytest.raises(InputError, match="simulated time"):
        check_work(11, MAX_SIMULATED_S / 10)
