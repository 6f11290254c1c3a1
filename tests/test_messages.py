"""Messages name what the user typed: a value read from a file names the file and its field, not a flag the user did
not type; +180° (tick 4096, which the servo does not have) is one rule in every reader; ``--orientation`` is
scaled before its length is taken; a pose whose own links pass through each other is refused as such, not as a
path to search for."""

from __future__ import annotations

import json
import math

import pytest
from helpers import pose_path, run_cli

from op2motion.errors import InputError
from op2motion.formats.posefile import pose_to_json, read_pose
from op2motion.physics.sweeps import servo_pose
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.pose import Pose
from op2motion.robot.support import Support
from op2motion.studio.session import PoseEdit

STAND, INIT, WALKREADY = pose_path("standing"), pose_path("init"), pose_path("walkready")
LAST_TICK_DEG = 179.912       # tick 4095: the last angle the MX-28 can be told [deg]


def _fail(capsys, *argv) -> str:
    code, _, err = run_cli(capsys, *argv)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, (code, err)
    return lines[0]


def _with_joint(tmp_path, name: str, joint: str, degrees: float) -> str:
    doc = json.loads(open(STAND, encoding="utf-8").read())
    doc["servo_deg"][joint] = degrees
    doc.pop("book_deg", None)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)


def test_values_from_a_motion_file_name_the_file_and_field(capsys, tmp_path):
    stand = json.loads(open(STAND, encoding="utf-8").read())["servo_deg"]
    path = tmp_path / "mine.json"
    for step, field in (({"servo_deg": stand, "duration_s": 1.0, "pause_s": -1}, "pause_s"),
                        ({"servo_deg": stand, "duration_s": 0.001}, "duration_s"),
                        ({"servo_deg": stand, "duration_s": "1"}, "duration_s")):
        path.write_text(json.dumps({"schema": "op2motion.motion/1", "name": "m", "steps": [{"servo_deg": stand},
                                                                                          step]}), encoding="utf-8")
        line = _fail(capsys, "motion", "plan", str(path))
        assert "mine.json" in line and "steps[1]" in line and field in line and "--" not in line.split(":")[2], line


def test_plus_180_is_one_rule_everywhere(capsys, tmp_path, spec):
    at_180 = _with_joint(tmp_path, "at180", "l_sho_pitch", 180.0)
    last = _with_joint(tmp_path, "last", "l_sho_pitch", LAST_TICK_DEG)
    for argv in (["fk", "--pose", at_180], ["export", "--format", "action", at_180, "-o", str(tmp_path / "a.bin")],
                 ["convert", "--servo-deg", at_180, "--support", "left"], ["validate", at_180],
                 ["export", "--format", "webots", at_180, "-o", str(tmp_path / "a.motion")]):
        line = _fail(capsys, *argv)
        assert "l_sho_pitch" in line and "179.9" in line, line
    with pytest.raises(InputError, match="l_sho_pitch"):
        PoseEdit(spec, read_pose(STAND, spec)).set_joint("l_sho_pitch", 180.0)
    code, out, _ = run_cli(capsys, "export", "--format", "action", last, "-o", str(tmp_path / "a.bin"))
    assert code == 0
    assert servo_to_ticks(read_pose(last, spec).servo, spec)[spec.joint_names.index("l_sho_pitch")] == 4095
    assert PoseEdit(spec, read_pose(STAND, spec)).set_joint("l_sho_pitch", -180.0).joints[1].ticks == 0
    assert not (tmp_path / "a.motion").exists()


def test_orientation_is_scaled_before_its_length(capsys, tmp_path):
    from op2motion.motion.cartesian import LineRequest

    units = [LineRequest("right", 1.0, delta_m=(0.02, 0.0, 0.0), orientation=d).validated().orientation
             for d in ((1e154, 1e154, 0.0), (1.0, 1.0, 0.0), (1e-300, 1e-300, 0.0))]
    for unit in units:
        assert unit == pytest.approx((0.5 ** 0.5, 0.5 ** 0.5, 0.0))
    code, out, err = run_cli(capsys, "motion", "line", WALKREADY, "--hand", "right", "--by", "0.02", "0", "0",
                             "--duration", "1", "--orientation", "1e154", "1e154", "0", "--json")
    assert code == 0 and math.isfinite(json.loads(out)["pointing_error_max_deg"]), err
    for bad in (["0", "0", "0"], ["1e400", "0", "0"], ["nan", "1", "0"]):
        line = _fail(capsys, "motion", "line", WALKREADY, "--hand", "right", "--by", "0.02", "0", "0",
                     "--duration", "1", "--orientation", *bad)
        assert "--orientation" in line


@pytest.mark.parametrize("planner", ["rrt", "none"])
def test_a_pose_through_itself_is_refused_as_such(capsys, tmp_path, spec, planner):
    through = Pose("through", Support.DOUBLE, servo_pose(spec, l_sho_roll=75.0))      # upper arm in the torso
    path = tmp_path / "through.json"
    path.write_text(pose_to_json(through, spec), encoding="utf-8")
    code, _, err = run_cli(capsys, "motion", "plan", INIT, str(path), "--durations", "1", "--planner", planner,
                           "--out", str(tmp_path / "m.json"))
    assert code == 1 and "pose through itself has" in err and "through each other" in err, err
    assert "seed" not in err and "in between" not in err and not (tmp_path / "m.json").exists()
