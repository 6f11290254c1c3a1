"""Every ``op2motion robot`` command against the emulated OP2 on a real pseudo-terminal, and each injected fault's
named outcome. The emulator runs in real time: the motions here are short."""

from __future__ import annotations

import json
import math
import os
import signal
import time

import numpy as np
import pytest
from bus_support import cli, emulated, emulator_process, finish, interrupt_when_walked, run, run_motion
from helpers import POSES, STOCK, run_cli

from op2motion.bus.emulator.faults import Faults
from op2motion.bus.safety import FALL_TORQUE_LIMIT
from op2motion.formats.posefile import read_pose, write_pose
from op2motion.robot.pose import Pose

GOAL_TOL_DEG = 1.5             # the acceptance's "every servo commanded within 1.5° of the pose"
TICK_DEG = 360.0 / 4096        # one position tick
STANDING_TILT_DEG = 15.0       # a torso tilted less than this still stands
CTRL_C_EXIT_S = 3.0            # Ctrl-C mid-walk: exit 130 within this long
WALKED_M = 0.2                 # ... sent once the robot has walked this far [m]


@pytest.fixture()
def robot(spec, tmp_path):
    """A fresh emulated OP2, standing (one at a time: two emulators in one process would share its interpreter)."""
    with emulated(spec, tmp_path) as (emulator, link):
        yield emulator, link


def _goals_deg(emulator, spec) -> np.ndarray:
    """The servos' goals [deg], from an emulator in this process or one in its own (its report)."""
    if hasattr(emulator, "servos"):
        return np.array([(s.u16("goal_position") - spec.servo.center_tick) * TICK_DEG for s in emulator.servos])
    return (np.array(emulator.report()["goal_ticks"]) - spec.servo.center_tick) * TICK_DEG


def _one_line(err: str) -> str:
    """The one error (or interrupted) line of a run's stderr (progress lines aside)."""
    lines = [line for line in err.splitlines() if line.startswith(("op2motion: error:", "op2motion: interrupted:"))]
    assert len(lines) == 1, err
    return lines[0]


def test_status_ports_that_are_not_a_robot(tmp_path, capsys):
    code, _, err = run_cli(capsys, "robot", "status", "--port", str(tmp_path / "ttyUSB7"))
    assert code == 2 and "--port: no such serial port" in _one_line(err)
    (tmp_path / "plain").write_text("x")
    code, _, err = run_cli(capsys, "robot", "status", "--port", str(tmp_path / "plain"))
    assert code == 2 and "expected a serial device, got a regular file" in _one_line(err)
    master, slave = os.openpty()
    try:
        code, _, err = run_cli(capsys, "robot", "status", "--port", os.ttyname(slave))
        assert code == 2 and "nothing answers at ID 200" in _one_line(err)
    finally:
        os.close(master)
        os.close(slave)


@pytest.mark.physics
def test_status_all_well(robot, capsys):
    emulator, link = robot
    code, out, _ = run_cli(capsys, "robot", "status", "--port", link, "--json")
    status = json.loads(out)
    assert code == 0 and status["ok"] and status["board"]["power"]
    assert [s["answers"] for s in status["servos"]] == [True] * 20
    assert {s["model"] for s in status["servos"]} == {"MX-28"}
    assert status["board"]["tilt_deg"] < STANDING_TILT_DEG


@pytest.mark.physics
def test_status_names_a_missing_servo(spec, tmp_path, capsys):
    with emulated(spec, tmp_path, faults=Faults(missing={7})) as (_, link):
        code, out, err = run_cli(capsys, "robot", "status", "--port", link, "--json")
    assert code == 1 and "r_hip_yaw (ID 7): not answering" in _one_line(err)
    assert [s["id"] for s in json.loads(out)["servos"] if not s["answers"]] == [7]


@pytest.mark.physics
def test_read_writes_the_present_pose(robot, spec, tmp_path, capsys):
    emulator, link = robot
    code, _, _ = run_cli(capsys, "robot", "read", "--port", link, "--out", str(tmp_path / "here.json"))
    pose = read_pose(tmp_path / "here.json", spec)
    assert code == 0 and pose.name == "here" and pose.support == "double"
    assert np.allclose(np.degrees(pose.servo), np.degrees(emulator.body.joint_angles()), atol=2 * TICK_DEG)


@pytest.mark.physics
def test_read_limp_then_holds_what_it_read(spec, tmp_path, capsys):
    with emulated(spec, tmp_path, start="lying_back") as (emulator, link):
        code, out, _ = run_cli(capsys, "robot", "read", "--port", link, "--out", str(tmp_path / "t.json"), "--limp",
                               "--wait", "0.3", "--json")
        assert code == 0 and json.loads(out)["limp"]
        assert all(s.get("torque_enable") == 1 for s in emulator.servos)      # the torque is back on
        pose = read_pose(tmp_path / "t.json", spec)
        assert np.allclose(_goals_deg(emulator, spec), np.degrees(pose.servo), atol=2 * TICK_DEG)


@pytest.mark.physics
def test_play_a_pose_commands_every_servo(spec, tmp_path):
    with emulator_process(tmp_path) as emulator:
        code, out, err = run_motion("robot", "play", "--port", emulator.link, str(POSES / "walkready.json"),
                                    "--json")
        goals = _goals_deg(emulator, spec)
    result = json.loads(out)
    target = np.degrees(read_pose(POSES / "walkready.json", spec).servo)
    assert code == 0 and result["ended"] == "done" and result["checked"].startswith("checked in physics"), (err, out)
    assert np.max(np.abs(goals - target)) <= GOAL_TOL_DEG
    assert result["runs"]["motion"]["max_blind_ticks"] < 5


@pytest.mark.physics
def test_play_an_action_page_and_refuse_a_file_without_page(tmp_path):
    with emulator_process(tmp_path) as emulator:
        code, _, err = run("robot", "play", "--port", emulator.link, str(STOCK))
        assert code == 2 and "--page: " in _one_line(err)
        code, out, err = run_motion("robot", "play", "--port", emulator.link, str(STOCK), "--page", "9", "--json")
    result = json.loads(out)
    assert code == 0 and result["what"].startswith("page 9") and result["runs"]["motion"]["ticks"] > 100, err


@pytest.mark.physics
def test_refused_unless_forced_and_a_fall_lowers_the_torque(spec, tmp_path, capsys):
    stand = read_pose(POSES / "standing.json", spec).servo.copy()
    for name, sign in (("r_ank_pitch", -1), ("l_ank_pitch", 1)):
        stand[spec.joint_names.index(name)] = math.radians(45.0) * sign        # toes far down: it tips over
    write_pose(Pose("tipping", "double", stand), tmp_path / "tipping.json", spec)
    with emulator_process(tmp_path) as emulator:
        before = _goals_deg(emulator, spec)
        code, _, err = run_cli(capsys, "robot", "play", "--port", emulator.link, str(tmp_path / "tipping.json"))
        assert code == 1 and "refused" in _one_line(err) and "--force" in err
        assert np.array_equal(_goals_deg(emulator, spec), before)             # nothing moved
        code, _, err = run("robot", "play", "--port", emulator.link, str(tmp_path / "tipping.json"), "--force")
        time.sleep(0.3)
        report = emulator.report()
    assert code == 1 and "fell" in _one_line(err)
    assert report["torque_limit_min"] == FALL_TORQUE_LIMIT                    # lowered while it fell
    assert min(report["torque_limit"]) > FALL_TORQUE_LIMIT                    # ... and back up once it lay


@pytest.mark.physics
def test_ctrl_c_mid_walk_stops_standing(tmp_path):
    with emulator_process(tmp_path) as emulator:
        walk = cli("robot", "walk", "--port", emulator.link, "--steps", "20")
        sent = interrupt_when_walked(walk, emulator, WALKED_M)
        code, _, err = finish(walk)
        took = time.monotonic() - sent
        time.sleep(0.5)
        truth = emulator.truth()
    assert code == 130 and "stopped on request" in _one_line(err), err
    assert took < CTRL_C_EXIT_S
    assert math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG and truth["x_m"] > WALKED_M   # walked, then stood


@pytest.mark.physics
def test_an_overheating_knee_stops_the_walk(tmp_path):
    with emulator_process(tmp_path, "mujoco", "standing", "--overheat", "13@4:85") as emulator:
        code, out, err = run("robot", "walk", "--port", emulator.link, "--steps", "6", "--json")
    walk = json.loads(out)["runs"]["walk"]
    assert code == 1 and "r_knee (ID 13): overheating" in _one_line(err)
    assert walk["ended"] == "fault" and walk["fault"]["id"] == 13 and walk["seconds"] > 2.0     # mid-walk


@pytest.mark.physics
def test_a_servo_unplugged_mid_motion_stops_it(tmp_path):
    with emulator_process(tmp_path, "mujoco", "standing", "--unplug", "5@0.3") as emulator:
        code, out, err = run("robot", "play", "--port", emulator.link, str(POSES / "walkready.json"), "--json")
    assert code == 1 and "r_el (ID 5): not answering" in _one_line(err)
    assert json.loads(out)["runs"]["motion"]["max_blind_ticks"] >= 5


@pytest.mark.physics
def test_lost_and_corrupted_replies_are_ridden_through(tmp_path):
    flags = ("--lose", "0.02", "--corrupt", "0.01", "--seed", "3")
    with emulator_process(tmp_path, "mujoco", "standing", *flags) as emulator:
        code, out, err = run_motion("robot", "play", "--port", emulator.link, str(POSES / "walkready.json"),
                                    "--json")
        stats = emulator.report()["stats"]
    motion = json.loads(out)["runs"]["motion"]
    assert code == 0, err
    assert stats["lost"] > 0 and stats["corrupted"] > 0
    assert motion["retried_ticks"] > 0 and motion["max_blind_ticks"] < 5


@pytest.mark.physics
def test_a_low_supply_refuses_to_start(spec, tmp_path, capsys):
    with emulated(spec, tmp_path, faults=Faults(supply_v=9.5)) as (_, link):
        code, _, err = run_cli(capsys, "robot", "play", "--port", link, str(POSES / "walkready.json"))
    assert code == 1 and "refused to start" in err and "low supply" in _one_line(err)


@pytest.mark.physics
def test_a_lying_robot_is_not_played_unchecked(spec, tmp_path, capsys):
    with emulated(spec, tmp_path, start="lying_front") as (_, link):
        code, out, _ = run_cli(capsys, "robot", "status", "--port", link, "--json")
        assert code == 0 and json.loads(out)["board"]["tilt_deg"] > 70.0
        code, _, err = run_cli(capsys, "robot", "play", "--port", link, str(POSES / "walkready.json"))
    assert code == 1 and "lies" in _one_line(err)


@pytest.mark.physics
def test_emulate_serves_until_ctrl_c_and_cleans_up(tmp_path):
    link = tmp_path / "op2"
    process = cli("robot", "emulate", "--link", str(link), "--engine", "mujoco")
    deadline = time.monotonic() + 60
    while not link.is_symlink() and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    code, out, _ = run("robot", "status", "--port", str(link), "--json")
    assert code == 0 and json.loads(out)["ok"]
    process.send_signal(signal.SIGINT)
    code, _, err = finish(process, 10)
    assert code == 130 and "link is removed" in _one_line(err)
    assert not os.path.lexists(link)
