"""Every ``op2motion robot`` command against the emulated OP2 in lockstep behind the real wire (1 Mbps, return
delays, the FTDI's packets, a 1 ms latency timer): ``--port lockstep:...`` on the command line, or its port from
Python, and each injected fault's named outcome; the link too slow for the loop refused by name. Lockstep runs are
deterministic and faster than real time, so the walks here are whole ones."""

from __future__ import annotations

import io
import math
import os
import sys

import numpy as np
import pytest
from bus_support import lockstep, robot_json
from helpers import POSES, STOCK, run_cli

from op2motion.bus.emulator.faults import Faults
from op2motion.bus.safety import FALL_TORQUE_LIMIT, WrongModel
from op2motion.errors import CheckFailed, InputError
from op2motion.formats.posefile import read_pose, write_pose
from op2motion.gait.closing import CLOSED_M, apart
from op2motion.onrobot.stand import play_on_robot
from op2motion.onrobot.tasks import Limp, Options, limp_question, setup, teach
from op2motion.onrobot.walks import walk
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.imu import FALL_TILT_RAD
from op2motion.robot.limbs import limb_groups, select_joints
from op2motion.robot.pose import Pose

GOAL_TOL_DEG = 1.5             # the acceptance's "every servo commanded within 1.5° of the pose"
TICK_DEG = 360.0 / 4096        # one position tick
STANDING_TILT_DEG = 15.0       # a torso tilted less than this still stands
WALKED_M = 0.2                 # a stop is asked for once the robot has walked this far [m]
BEYOND_PAGE, BEYOND_TICK = 9, 4000   # the stock walk-ready page, its head_pan beyond its range (ends at 3402)
ODOMETRY_TOL_M = 0.05          # a stopped walk's leg odometry within this of where the emulated torso went [m]
HORN_OFF_TICKS = 1707          # head_pan reads tick 3755 (150°; its range ends at 119°), as in the audit [ticks]
FAULT_AT_S = 4.0               # the overheating knee's moment, into the motion [s]
AX12_AS_L_KNEE = "l_knee (ID 14) reports model 12 (AX-12?), expected the MX-28 (29)"
EVERY_ERROR_BIT = "input voltage, angle limit, overheating, range, checksum, overload, instruction"
LIMP_WAIT_S = 1.5              # joints limp this long [s, simulated]: legs let go, a standing robot is down by then
FALL_TILT_DEG = math.degrees(FALL_TILT_RAD)
FALLEN_Z_M = 0.15              # a torso below this lies (standing: 0.34 m) [m]


def _goals_deg(report: dict, spec) -> np.ndarray:
    """The servos' goals [deg] from an emulator's report."""
    return (np.array(report["goal_ticks"]) - spec.servo.center_tick) * TICK_DEG


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
    code, _, err = run_cli(capsys, "robot", "status", "--port", "lockstep:wire=fast")
    assert code == 2 and "expected wire=real or wire=instant" in _one_line(err)


@pytest.mark.physics
def test_status_all_well_with_the_link_measured(capsys):
    code, status, _ = robot_json(capsys, "robot", "status", "--port", "lockstep")
    assert code == 0 and status["ok"] and status["board"]["power"] and not status["warnings"]
    assert [s["answers"] for s in status["servos"]] == [True] * 20
    assert {s["model"] for s in status["servos"]} == {"MX-28"} and {s["return_delay_us"] for s in status["servos"]} \
        == {0}
    assert status["board"]["tilt_deg"] < STANDING_TILT_DEG
    assert status["link"]["ping_round_trip_ms"]["max"] == pytest.approx(1.0, abs=0.05)     # the 1 ms timer
    plan = status["read_plan"]
    assert 10 <= plan["servos_per_tick"] <= 20 and plan["bulk_read_ms"] <= 3.5   # its planned share of the tick


@pytest.mark.physics
def test_an_emulator_faster_than_any_wire_is_read_as_well(capsys):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:wire=instant")
    assert code == 0 and [s["answers"] for s in status["servos"]] == [True] * 20, err   # replies at once: taken
    assert status["read_plan"]["servos_per_tick"] == 20
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep:wire=instant",
                                   str(POSES / "walkready.json"))
    assert code == 0 and result["runs"]["motion"]["missed_reads"] == 0, err


@pytest.mark.physics
def test_a_return_delay_of_250_is_named_refused_and_set_to_0(capsys, spec):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:return-delay=250")
    assert code == 0 and {s["return_delay_us"] for s in status["servos"]} == {500}
    assert status["read_plan"]["servos_per_tick"] < 20
    assert "return delay of up to 250" in status["warnings"][0] and "robot setup" in status["warnings"][0]
    code, walked, err = robot_json(capsys, "robot", "walk", "--port", "lockstep:return-delay=250", "--steps", "4")
    assert code == 0 and 2 <= walked["runs"]["walk"]["read_plan"]["servos_per_tick"] < 10, err   # walks, reading less
    assert walked["runs"]["walk"]["max_blind_ticks"] == 0 and walked["emulated"]["truth"]["x_m"] > 0.15
    code, _, err = run_cli(capsys, "robot", "walk", "--port", "lockstep:return-delay=254,latency-timer-ms=2",
                           "--steps", "4")
    assert code == 2 and "return delay is up to 254" in _one_line(err) and "--return-delay 0" in err
    code, _, err = run_cli(capsys, "robot", "setup", "--port", "lockstep:return-delay=250", "--return-delay", "0")
    assert code == 2 and "expected --yes" in _one_line(err)                 # no terminal to ask on
    with lockstep(spec, return_delay=250) as (emulator, port):
        asked: list[str] = []
        done = setup(port, spec, 0, lambda question: asked.append(question) or True)
        assert len(done.written) == 20 and done.already == (200,) and not done.failed and "EEPROM" in asked[0]
        assert {s.get("return_delay_time") for s in emulator.servos} == {0}
        assert setup(port, spec, 0, lambda question: False).written == {}    # nothing to change: not asked
        result = play_on_robot(port, spec, str(POSES / "walkready.json"))
    assert result.ended == "done" and result.runs[-1][1].plan["servos_per_tick"] >= 10


@pytest.mark.physics
def test_a_16_ms_latency_timer_is_refused_by_name(capsys):
    code, status, _ = robot_json(capsys, "robot", "status", "--port", "lockstep:latency-timer-ms=16")
    assert code == 0 and status["link"]["ping_round_trip_ms"]["max"] == pytest.approx(16.0, abs=0.5)
    assert status["read_plan"]["servos_per_tick"] == 0 and "too slow" in status["warnings"][0]
    code, result, err = robot_json(capsys, "robot", "walk", "--port", "lockstep:latency-timer-ms=16", "--steps", "4")
    line = _one_line(err)
    assert code == 2 and result is None
    assert "latency timer" in line and "nothing moved" in line
    assert "echo 1 | sudo tee /sys/bus/usb-serial/devices/" in line


@pytest.mark.physics
def test_a_robot_just_switched_on_is_powered_without_a_move(capsys):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:cold=1,start=lying_back")
    assert code == 0 and status["powered_now"] and status["board"]["power"], err
    assert [s["answers"] for s in status["servos"]] == [True] * 20
    assert not any(s["torque_on"] for s in status["servos"])                  # powered up limp


@pytest.mark.physics
def test_status_names_a_missing_servo(capsys):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:missing=7")
    assert code == 1 and "r_hip_yaw (ID 7): not answering" in _one_line(err)
    assert [s["id"] for s in status["servos"] if not s["answers"]] == [7]


@pytest.mark.physics
def test_read_writes_the_present_pose_and_limp_holds_what_it_read(spec):
    with lockstep(spec) as (emulator, port):
        pose, notes = teach(port, spec, "here")
        assert pose.support == "double" and not notes and not pose.provenance["fallen"]
        assert np.allclose(np.degrees(pose.servo), np.degrees(emulator.body.joint_angles()), atol=2 * TICK_DEG)
    with lockstep(spec, start="lying_back") as (emulator, port):
        with pytest.raises(CheckFailed, match="the robot lies.*--force"):         # a fallen robot's pose: refused
            teach(port, spec, "lying")
        waited = []
        limp = Limp(spec.joint_names, lambda question: True, lambda: waited.append(port.clock.now()))
        pose, notes = teach(port, spec, "limp", limp=limp, force=True)
        assert waited and all(s.get("torque_enable") == 1 for s in emulator.servos)    # the torque is back on
        assert np.allclose(_goals_deg(emulator.report(), spec), np.degrees(pose.servo), atol=2 * TICK_DEG)
    assert pose.provenance["fallen"] and pose.provenance["tilt_deg"] > FALL_TILT_DEG and "fallen" in notes[0]


def test_limbs_are_the_spec_joints_by_name(spec):
    names = spec.joint_names
    groups = limb_groups(names)
    limbs = [joint for limb in ("head", "left_arm", "right_arm", "left_leg", "right_leg") for joint in groups[limb]]
    assert sorted(limbs) == sorted(names)                                         # each joint in one limb
    assert [len(groups[g]) for g in ("head", "left_arm", "arms", "right_leg", "legs", "all")] == [2, 3, 6, 6, 12, 20]
    assert set(groups["arms"]) == set(groups["left_arm"] + groups["right_arm"]) and "r_knee" in groups["right_leg"]
    assert select_joints("left_arm, head", names) == ("l_sho_pitch", "l_sho_roll", "l_el", "head_pan", "head_tilt")
    assert select_joints("r_knee", names) == ("r_knee",) and select_joints("all", names) == names
    assert select_joints("legs,left_leg,r_el", names) == ("r_el", *groups["legs"])
    with pytest.raises(InputError, match="got 'arm'"):
        select_joints("arm", names)
    standing, lying = math.radians(2.0), math.radians(90.0)
    for joints, tilt, falls in ((("r_knee",), standing, True), (groups["legs"], standing, True),
                                (groups["arms"], standing, False), (groups["legs"], lying, False)):
        assert ("sag and fall" in limp_question(spec, joints, tilt)) == falls, (joints, tilt)


class Terminal(io.StringIO):
    """Standard input that is a terminal, with what the user types."""

    def isatty(self) -> bool:
        return True


def test_limp_without_a_way_to_confirm_does_nothing(tmp_path, capsys, monkeypatch):
    out, port = tmp_path / "pose.json", str(tmp_path / "ttyUSB9")     # no such port: refused before opening it
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    for flags, expected in ((["--limp", "legs", "--wait", "1"], "--yes: expected --yes to switch the torque off in "
                                                                "legs (12 joints)"),
                            (["--limp", "--wait", "1"], "--yes: expected --yes to switch the torque off in all (20"),
                            (["--limp", "arms", "--yes"], "--wait: expected --wait S with --limp"),
                            (["--yes"], "--yes: expected --limp with --yes"),
                            (["--wait", "0"], "--wait: expected --limp with --wait"),
                            (["--limp", "arm", "--yes", "--wait", "1"], "--limp: expected comma-separated limbs")):
        code, _, err = run_cli(capsys, "robot", "read", "--port", port, "--out", str(out), *flags)
        assert code == 2 and expected in _one_line(err) and not out.exists(), err


@pytest.mark.physics
def test_limp_asks_on_the_terminal_and_a_no_does_nothing(spec, tmp_path, capsys, monkeypatch):
    out = tmp_path / "pose.json"
    monkeypatch.setattr(sys, "stdin", Terminal("n\n"))
    code, _, err = run_cli(capsys, "robot", "read", "--port", "lockstep", "--out", str(out), "--limp", "legs")
    assert code == 2 and err.endswith("op2motion: error: --yes: not confirmed: nothing done (--yes confirms)\n")
    assert not out.exists()
    assert "legs (12 joints), though the robot stands" in err and "it will sag and fall" in err and "[y/N]" in err
    monkeypatch.setattr(sys, "stdin", Terminal("y\n\n"))                  # yes, then Enter once they are moved
    code, _, err = run_cli(capsys, "robot", "read", "--port", "lockstep", "--out", str(out), "--limp", "head")
    assert code == 0 and "press Enter" in err and read_pose(out, spec).provenance["limp_joints"] == ["head_pan",
                                                                                                   "head_tilt"]
    with lockstep(spec) as (emulator, port):
        before = emulator.report()
        with pytest.raises(InputError, match="not confirmed"):
            teach(port, spec, "no", limp=Limp(("r_knee",), lambda question: False))
        after = emulator.report()
    assert after["torque_enable"] == before["torque_enable"] == [1] * 20          # nothing went limp ...
    assert after["goal_ticks"] == before["goal_ticks"]                            # ... and nothing moved


@pytest.mark.physics
def test_only_the_chosen_joints_go_limp_and_then_hold(spec):
    chosen = select_joints("left_arm,head", spec.joint_names)
    with lockstep(spec) as (emulator, port):
        asked, during = [], []
        limp = Limp(chosen, lambda question: asked.append(question) or True,
                    lambda: during.append(emulator.report()["torque_enable"]), LIMP_WAIT_S)
        pose, notes = teach(port, spec, "arm", limp=limp)
        after = emulator.report()
    off = {name for name, on in zip(spec.joint_names, during[0]) if not on}
    assert off == set(chosen) and after["torque_enable"] == [1] * 20             # the others held throughout
    assert "head, left_arm (5 joints) (they go limp" in asked[0] and "fall" not in asked[0]
    assert math.degrees(after["truth"]["tilt_rad"]) < STANDING_TILT_DEG and not pose.provenance["fallen"]
    assert pose.provenance["limp_joints"] == list(chosen) and not notes


@pytest.mark.physics
def test_legs_limp_drop_a_standing_robot_whose_pose_is_refused_unless_forced(spec, tmp_path, capsys):
    out = tmp_path / "dropped.json"
    argv = ("robot", "read", "--port", "lockstep", "--out", str(out), "--limp", "legs", "--yes", "--wait",
            str(LIMP_WAIT_S))
    code, _, err = run_cli(capsys, *argv)
    assert code == 1 and "refused: the robot fell while limp" in _one_line(err) and not out.exists()
    assert "its legs give way and it will sag and fall unless you hold it up? yes (--yes)" in err   # it was told
    code, result, err = robot_json(capsys, *argv, "--force")
    assert code == 0 and result["fallen"] and result["tilt_deg"] > FALL_TILT_DEG, err
    provenance = read_pose(out, spec).provenance
    assert provenance["fallen"] and provenance["limp_joints"] == list(limb_groups(spec.joint_names)["legs"])
    with lockstep(spec) as (emulator, port):                   # the emulated OP2 really falls, then its legs hold
        teach(port, spec, "dropped", limp=Limp(select_joints("legs", spec.joint_names), lambda question: True,
                                               None, LIMP_WAIT_S), force=True)
        report = emulator.report()
    assert math.degrees(report["truth"]["tilt_rad"]) > FALL_TILT_DEG and report["truth"]["z_m"] < FALLEN_Z_M
    assert report["torque_enable"] == [1] * 20


@pytest.mark.physics
def test_read_from_the_command_line(tmp_path, capsys, spec):
    code, _, err = run_cli(capsys, "robot", "read", "--port", "lockstep", "--out", str(tmp_path / "here.json"))
    pose = read_pose(tmp_path / "here.json", spec)
    assert code == 0 and pose.name == "here" and pose.support == "double", err


@pytest.mark.physics
def test_play_a_pose_commands_every_servo(spec, capsys):
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep", str(POSES / "walkready.json"))
    target = np.degrees(read_pose(POSES / "walkready.json", spec).servo)
    assert code == 0 and result["ended"] == "done" and result["checked"].startswith("checked in physics"), err
    assert np.max(np.abs(_goals_deg(result["emulated"], spec) - target)) <= GOAL_TOL_DEG
    assert result["runs"]["motion"]["max_blind_ticks"] == 0 and result["runs"]["motion"]["late_ticks"] == 0


@pytest.mark.physics
def test_play_an_action_page_and_refuse_a_file_without_page(capsys):
    code, _, err = run_cli(capsys, "robot", "play", "--port", "lockstep", str(STOCK))
    assert code == 2 and "--page: " in _one_line(err)
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep", str(STOCK), "--page", "9")
    assert code == 0 and result["what"].startswith("page 9") and result["runs"]["motion"]["ticks"] > 100, err
    assert math.degrees(result["emulated"]["truth"]["tilt_rad"]) < STANDING_TILT_DEG


@pytest.mark.physics
def test_refused_unless_forced_and_a_fall_lowers_the_torque(spec, tmp_path):
    stand = read_pose(POSES / "standing.json", spec).servo.copy()
    for name, sign in (("r_ank_pitch", -1), ("l_ank_pitch", 1)):
        stand[spec.joint_names.index(name)] = math.radians(45.0) * sign        # toes far down: it tips over
    write_pose(Pose("tipping", "double", stand), tmp_path / "tipping.json", spec)
    with lockstep(spec) as (emulator, port):
        before = emulator.report()["goal_ticks"]
        with pytest.raises(CheckFailed, match="refused.*--force"):
            play_on_robot(port, spec, str(tmp_path / "tipping.json"))
        assert emulator.report()["goal_ticks"] == before                        # nothing moved
        result = play_on_robot(port, spec, str(tmp_path / "tipping.json"), options=Options(force=True))
        port.clock.sleep_until(port.clock.now() + 0.3)
        report = emulator.report()
    assert result.fault is not None and result.fault.kind == "fell"
    assert report["torque_limit_min"] == FALL_TORQUE_LIMIT                    # lowered while it fell
    assert min(report["torque_limit"]) > FALL_TORQUE_LIMIT                    # ... and back up once it lay


def _stop_after(emulator, walked_m: float, asked: list | None = None):
    """A stop event set once the emulated torso has gone ``walked_m`` forward, the ``on_tick`` that sets it (noting
    the tick in ``asked``) and where the torso started [m]."""
    stop = __import__("threading").Event()
    start = emulator.truth()["x_m"]

    def on_tick(tick) -> None:
        if not stop.is_set() and emulator.truth()["x_m"] - start >= walked_m:
            stop.set()
            if asked is not None:
                asked.append(tick.index)
    return stop, on_tick, start


class _OpenLoopStop:
    """A walk controller without its hooks: the loop cannot tell it to stop, so a stop freezes it on its next double
    support (one foot ahead), as any plan played open loop is stopped."""

    def __init__(self, walk):
        self.walk, self.plan = walk, walk.plan

    def start(self, joint_positions):
        return self.walk.start(joint_positions)

    def step(self, t_s, gyro, accel, joint_positions):
        return self.walk.step(t_s, gyro, accel, joint_positions)

    @property
    def done(self) -> bool:
        return self.walk.done


@pytest.mark.physics
def test_a_stop_mid_walk_closes_the_feet_and_leaves_no_closing_step_to_take(spec):
    """Stopped mid-walk (20 steps), the planned walk stops as a steered one does: within two steps, its feet side by
    side, standing, done before the loop would freeze it; its leg odometry says how far it walked (not the whole
    plan); the next motion needs no closing step (the test below has a next walk close the feet)."""
    from op2motion.bus.stopping import SOFT_STOP_MAX_S
    from op2motion.gait.closing import CLOSED_RAD, closing_gait
    from op2motion.gait.footsteps import step_width
    from op2motion.gait.presets import load_preset

    with lockstep(spec) as (emulator, port):
        asked: list[int] = []
        stop, on_tick, start = _stop_after(emulator, WALKED_M, asked)
        result = walk(port, spec, steps=20, options=Options(stop=stop, on_tick=on_tick))
        truth = emulator.truth()
        angles = emulator.body.joint_angles()
    stance = apart(angles, spec, step_width(load_preset("forward"), spec))
    walked = dict(result.runs)["walk"]
    assert result.ended == "stopped" and result.fault is None and walked.ended == "stopped"
    assert (walked.ticks - asked[0]) * CONTROL_PERIOD_S < SOFT_STOP_MAX_S     # done, not frozen by the loop
    assert math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG and WALKED_M < truth["x_m"] - start < 0.6
    assert stance.behind_m <= CLOSED_M and stance.turned_rad <= CLOSED_RAD, stance
    assert abs(result.travel["x_m"] - (truth["x_m"] - start)) < ODOMETRY_TOL_M, (result.travel, truth)
    assert closing_gait(angles, spec, load_preset("forward")) is None      # the next motion needs no closing step


@pytest.mark.physics
def test_a_walk_frozen_with_a_foot_ahead_is_closed_by_the_next_motion_unforced(spec):
    """A plan played open loop and stopped freezes on both feet with one foot ahead; the next motion (``robot
    stand``, as every motion starts), not forced, starts with the step that closes the feet (checked in physics) and
    moves on (it was refused: "slip: a supporting sole slid 19 mm")."""
    from op2motion.gait.controller import WalkController
    from op2motion.gait.footsteps import step_width
    from op2motion.gait.presets import load_preset
    from op2motion.onrobot.stand import stand
    from op2motion.onrobot.walks import run_on_robot

    with lockstep(spec) as (emulator, port):
        stop, on_tick, _ = _stop_after(emulator, WALKED_M)
        frozen = run_on_robot(port, spec, _OpenLoopStop(WalkController.from_preset("forward", 8, spec)),
                              options=Options(stop=stop, on_tick=on_tick))
        apart_before = apart(emulator.body.joint_angles(), spec, step_width(load_preset("forward"), spec))
        again = stand(port, spec)
        after = emulator.truth()
        apart_after = apart(emulator.body.joint_angles(), spec, step_width(load_preset("forward"), spec))
    assert dict(frozen.runs)["run"].ended == "stopped" and apart_before.behind_m > CLOSED_M     # one foot ahead
    assert again.ended == "done" and [name for name, _ in again.runs] == ["close the feet", "motion"], again.runs
    assert "checked in physics" in again.checked and math.degrees(after["tilt_rad"]) < STANDING_TILT_DEG
    assert apart_after.closed


@pytest.mark.physics
def test_an_overheating_knee_stops_the_walk(capsys):
    code, result, err = robot_json(capsys, "robot", "walk", "--port", f"lockstep:overheat=13@{FAULT_AT_S:g}:85",
                                   "--steps", "10")
    walked = result["runs"]["walk"]
    assert code == 1 and "r_knee (ID 13): overheating" in _one_line(err)
    assert walked["ended"] == "fault" and walked["fault"]["id"] == 13 and walked["seconds"] > FAULT_AT_S / 2


@pytest.mark.physics
def test_a_servo_unplugged_mid_motion_stops_it(capsys):
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep:unplug=5@0.3",
                                   str(POSES / "walkready.json"))
    assert code == 1 and "r_el (ID 5): not answering" in _one_line(err)
    assert result["runs"]["motion"]["max_blind_ticks"] >= 5


@pytest.mark.physics
def test_lost_and_corrupted_replies_are_ridden_through(capsys):
    code, result, err = robot_json(capsys, "robot", "walk", "--port", "lockstep:lose=0.02,corrupt=0.01,seed=3",
                                   "--steps", "20")
    walked, stats = result["runs"]["walk"], result["emulated"]["stats"]
    assert code == 0, err
    assert stats["lost"] > 0 and stats["corrupted"] > 0
    assert walked["missed_reads"] > 0 and walked["max_blind_ticks"] < 5 and walked["bus"]["bad_checksums"] > 0
    truth = result["emulated"]["truth"]
    assert math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG and truth["x_m"] > 0.8
    assert abs(math.degrees(truth["yaw_rad"])) < 10.0


@pytest.mark.physics
def test_a_low_supply_refuses_to_start(spec, capsys):
    code, _, err = run_cli(capsys, "robot", "play", "--port", "lockstep:supply=9.5", str(POSES / "walkready.json"))
    assert code == 1 and "refused to start" in err and "low supply" in _one_line(err)


@pytest.mark.physics
def test_a_lying_robot_is_not_played_unchecked(capsys):
    code, status, _ = robot_json(capsys, "robot", "status", "--port", "lockstep:start=lying_front")
    assert code == 0 and status["board"]["tilt_deg"] > 70.0
    code, _, err = run_cli(capsys, "robot", "play", "--port", "lockstep:start=lying_front",
                           str(POSES / "walkready.json"))
    assert code == 1 and "lies" in _one_line(err)


def test_faults_on_a_lockstep_port_are_checked(capsys):
    code, _, err = run_cli(capsys, "robot", "status", "--port", "lockstep:lose=0.9")
    assert code == 2 and "expected a share from 0 to 0.5" in _one_line(err)
    code, _, err = run_cli(capsys, "robot", "status", "--port", "lockstep:speed=3")
    assert code == 2 and "expected lockstep keys among" in _one_line(err)


def test_lockstep_faults_parse(spec):
    from op2motion.bus.emulator.lockstep import parse_lockstep

    setup = parse_lockstep("lockstep:engine=pybullet,latency-timer-ms=16,return-delay=250,missing=3+4,"
                           "unplug=5@0.3,overheat=13@4:85,push=30@2,supply=11,seed=7")
    assert setup.engine == "pybullet" and setup.timing.latency_timer_s == 0.016 and setup.return_delay == 250
    assert setup.faults == Faults({3, 4}, [(5, 0.3)], 0.0, 0.0, [(13, 4.0, 85.0)], 11.0, 7, [(30.0, 2.0)])


@pytest.mark.physics
def test_a_servo_reading_outside_its_range_is_named_and_nothing_moves(capsys):
    """head_pan mounted 150° off (it reads tick 3755, its range ends at 3402): status names it, and a motion
    is refused before the torque goes on (no goal outside the range, no jump), even forced."""
    port = f"lockstep:horn=19:{HORN_OFF_TICKS}"
    code, result, _ = robot_json(capsys, "robot", "status", "--port", port)
    assert code == 1 and any(p["kind"] == "out of range" and p["id"] == 19 for p in result["problems"]), result
    for argv in (("robot", "play", str(POSES / "walkready.json")), ("robot", "play", str(POSES / "walkready.json"),
                                                                    "--force"), ("robot", "getup")):
        code, out, err = run_cli(capsys, *argv, "--port", port)
        assert code == 1 and "head_pan (ID 19): out of range" in err and "outside its mechanical range" in err, err
        assert len(err.strip().splitlines()) == 1, err


@pytest.mark.physics
def test_a_servo_of_another_model_is_named_and_nothing_moves_even_forced(spec, capsys):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:model=14:12")
    assert code == 2 and status is None and _one_line(err) == f"op2motion: error: {AX12_AS_L_KNEE}"
    code, _, err = run_cli(capsys, "robot", "play", "--force", "--port", "lockstep:model=14:12",
                           str(POSES / "walkready.json"))
    assert code == 2 and AX12_AS_L_KNEE in _one_line(err)
    with lockstep(spec, faults=Faults(models={14: 12})) as (emulator, port):
        before = emulator.report()
        with pytest.raises(WrongModel, match=r"l_knee \(ID 14\) reports model 12"):
            play_on_robot(port, spec, str(POSES / "walkready.json"), options=Options(force=True))
        with pytest.raises(WrongModel):
            teach(port, spec, "here", limp=True)
        after = emulator.report()
    assert after["motion_s"] is None                            # no SYNC_WRITE: not one goal sent
    assert after["goal_ticks"] == before["goal_ticks"] and after["torque_enable"] == before["torque_enable"]


@pytest.mark.physics
def test_a_cm740_is_named_and_a_board_of_another_model_refused(capsys):
    code, out, err = run_cli(capsys, "robot", "status", "--port", "lockstep:board=cm740")
    assert code == 0 and out.startswith("CM-740 (ID 200): model 0x7400,"), err
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:model=200:0x1234")
    assert code == 2 and status is None
    assert ("the sub-controller (ID 200) reports model 0x1234, expected the CM-730 (0x7300) or the CM-740 (0x7400)"
            in _one_line(err))


@pytest.mark.physics
def test_a_servo_reporting_every_error_bit_is_named_not_called_silent(capsys):
    code, status, err = robot_json(capsys, "robot", "status", "--port", "lockstep:errors=14:all")
    assert code == 1 and f"l_knee (ID 14) reports errors: {EVERY_ERROR_BIT}" in _one_line(err)
    knee = status["servos"][13]
    assert knee["answers"] and ", ".join(knee["errors"]) == EVERY_ERROR_BIT
    code, _, err = run_cli(capsys, "robot", "play", "--force", "--port", "lockstep:errors=14:all",
                           str(POSES / "walkready.json"))
    assert code == 1 and f"refused to start: l_knee (ID 14) reports errors: {EVERY_ERROR_BIT}" in _one_line(err)


def test_board_model_and_error_keys_parse_and_are_checked(capsys):
    from op2motion.bus.emulator.lockstep import parse_lockstep

    setup = parse_lockstep("lockstep:board=cm740,model=14:12,errors=13:all+3:0x24")
    assert setup.faults.models == {14: 12, 200: 0x7400} and setup.faults.errors == {13: 0x7F, 3: 0x24}
    for text, expected in (("board=cm530", "expected a board among cm730, cm740"),
                           ("board=cm740,model=200:0x7300", "expected a board or a model number for ID 200"),
                           ("model=14:all", "expected ID:VALUE"), ("model=21:12", "expected a servo ID 1..20"),
                           ("errors=14:0", "expected a value 1..255")):
        code, _, err = run_cli(capsys, "robot", "status", "--port", f"lockstep:{text}")
        assert code == 2 and expected in _one_line(err), text


@pytest.mark.physics
def test_robot_stand_goes_to_walk_ready_checked_and_refuses_lying(capsys):
    code, result, err = robot_json(capsys, "robot", "stand", "--port", "lockstep")
    assert code == 0 and result["ended"] == "done" and "checked in physics" in result["checked"], err
    assert result["target_error_deg"] < GOAL_TOL_DEG and "close the feet" not in result["runs"]   # side by side
    code, _, err = run_cli(capsys, "robot", "stand", "--port", "lockstep:start=lying_back")
    assert code == 1 and "getup first" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.physics
def test_a_refused_motion_still_prints_its_result_as_json(capsys):
    """cli.md: exit 1 is a check that ran and failed, and its result is still printed (it printed nothing)."""
    code, result, err = robot_json(capsys, "robot", "walk", "--port", "lockstep:start=lying_front", "--steps", "4")
    assert code == 1 and result["ended"] == "refused" and "robot getup first" in result["refused"], (result, err)
    assert len(err.strip().splitlines()) == 1


@pytest.mark.physics
def test_a_page_goal_beyond_its_range_is_refused_or_played_clipped_saying_so(capsys, tmp_path):
    """A page whose head_pan goal is beyond its range: refused as bad input (as import-action refuses it); forced,
    it plays clipped and the result says so (it was clipped silently)."""
    from op2motion.formats import actionlayout as layout

    data = bytearray(STOCK.read_bytes())
    off = BEYOND_PAGE * layout.PAGE_SIZE
    page = bytearray(data[off:off + layout.PAGE_SIZE])
    base = layout.step_offset(0)
    page[base + 2 * 19:base + 2 * 19 + 2] = BEYOND_TICK.to_bytes(2, "little")     # head_pan, ID 19
    data[off:off + layout.PAGE_SIZE] = layout.with_checksum(page)
    path = tmp_path / "beyond.bin"
    path.write_bytes(bytes(data))
    code, _, err = run_cli(capsys, "robot", "play", "--port", "lockstep", str(path), "--page", str(BEYOND_PAGE))
    assert code == 2 and "head_pan tick 4000" in err and "--force plays them clipped" in err, err
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep", str(path), "--page",
                                   str(BEYOND_PAGE), "--force")
    assert code == 0 and any("clipped" in n and "head_pan" in n for n in result["notes"]), (result, err)
