"""The emulated OP2 itself: the power switch, the bulk read's order and silence, no reply to broadcast; a 20-step walk
through the bus in lockstep behind the real wire, against the same walk in ``walk --validate``, and the same run
twice giving the same rows (with lost and damaged replies); the studio's follower in lockstep;
and one end-to-end run in real time on a real pseudo-terminal: ROBOTIS's dynamixel-sdk, ``robot status``, a walk
stopped by Ctrl-C, and ``robot emulate`` cleaning up."""

from __future__ import annotations

import json
import math
import os
import signal
import time

import numpy as np
import pytest
from bus_support import WIRE_1MS, cli, emulator_process, finish, lockstep, robot_json, run

from op2motion.bus import protocol as p
from op2motion.bus.client import Bus
from op2motion.bus.robot import POWER_ON_WAIT_S
from op2motion.onrobot.tasks import Options
from op2motion.onrobot.walks import walk

SPEED_TOL = 0.10               # the walk through the bus: distance within 10 % of walk --validate's
HEADING_TOL_DEG = 5.0          # ... heading within 5°
STEPS = 20
STANDING_TILT_DEG = 15.0       # a torso tilted less than this still stands
CTRL_C_EXIT_S = 3.0            # Ctrl-C mid-walk: exit 130 within this long [s]
WALK_BEFORE_CTRL_C_S = 6.0     # ... sent this long after the command started [s]
FOLLOW_TOL_RAD = math.radians(0.2)   # the follower's goal ends on its target [rad]
TICK_RAD = 2.0 * math.pi / 4096      # one MX-28 position tick [rad]
PYTHON_STEPS = 4               # the Python path's walk
PYTHON_WALKED_M = 0.05         # ... goes forward at least this far [m]

pytestmark = pytest.mark.physics


def test_power_switch_bulk_read_and_broadcast(spec):
    from op2motion.bus.emulator.faults import Faults

    with lockstep(spec, faults=Faults(missing={5})) as (_, port):
        bus = Bus(port, retries=0)
        spans = [(200, 24, 30), (3, 36, 2), (4, 36, 2), (5, 36, 2), (6, 36, 2)]
        got = bus.bulk_read(spans, 0.0)
        assert sorted(got) == [3, 4, 200] and len(got[200].params) == 30       # 6 waits for 5's reply in vain
        assert bus.write(200, 24, b"\x00") is not None                         # servos' power off
        assert bus.ping(13) is None and bus.ping(200) is not None
        assert bus.write(200, 24, b"\x01") is not None
        port.clock.sleep_until(port.clock.now() + POWER_ON_WAIT_S)
        reply = bus.read(13, 24, 1)
        assert reply is not None and reply.params == b"\x00"                     # powered up with its torque off
        bus.write(p.BROADCAST_ID, 25, b"\x01")
        assert bus._collect(p.write(p.BROADCAST_ID, 25, b"\x01"), {13: 0}, 0.05) == {}   # no reply to broadcast
        assert all(bus.read(d, 25, 1).params == b"\x01" for d in (1, 4, 6, 13, 20))


def test_twenty_steps_through_the_bus_walk_as_in_physics(capsys, engine="mujoco"):
    validate = cli("walk", "--steps", str(STEPS), "--validate", "--engine", engine, "--json")   # meanwhile
    code, result, err = robot_json(capsys, "robot", "walk", "--port", f"lockstep:engine={engine}", "--steps",
                                   str(STEPS))
    done, physics, why = finish(validate)
    assert done == 0, why
    summary = json.loads(physics)["physics"]["engines"][engine]
    distance, heading = summary["distance_m"], summary["heading_error_deg"]
    assert code == 0, err
    truth = result["emulated"]["truth"]
    assert math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG and result["ended"] == "done"   # ends standing
    travel = math.hypot(truth["x_m"], truth["y_m"])
    assert abs(travel - distance) <= SPEED_TOL * distance, (travel, distance)          # same time: same speed
    assert abs(math.degrees(truth["yaw_rad"]) - heading) <= HEADING_TOL_DEG, (truth, heading)
    walked = result["runs"]["walk"]
    assert walked["max_blind_ticks"] < 5 and walked["period_ms"]["p99"] == pytest.approx(8.0, abs=0.01)
    assert walked["late_ticks"] == 0 and walked["bus"]["stray_packets"] == 0
    assert abs(result["travel"]["distance_m"] - travel) <= SPEED_TOL * distance          # leg odometry


def _rows(spec, **faults) -> tuple[np.ndarray, dict]:
    """Every tick's goals and readings of a 6-step walk in lockstep (with ``faults``), and the emulator's report."""
    from op2motion.bus.emulator.faults import Faults

    rows: list[np.ndarray] = []
    with lockstep(spec, faults=Faults(**faults)) as (emulator, port):
        walk(port, spec, steps=6, options=Options(on_tick=lambda tick: rows.append(
            np.concatenate([[tick.t_s], tick.goals, tick.positions, tick.gyro_rad_s, tick.accel_m_s2]))))
        return np.array(rows), emulator.report()


def test_lockstep_runs_are_deterministic(spec):
    first, report = _rows(spec, lose=0.02, corrupt=0.01, seed=5)
    second, again = _rows(spec, lose=0.02, corrupt=0.01, seed=5)
    assert first.shape == second.shape and len(first) > 500 and np.array_equal(first, second)
    assert report["truth"] == again["truth"] and report["stats"] == again["stats"] and report["stats"]["lost"] > 0
    assert report["truth"]["x_m"] > 0.3 and math.degrees(report["truth"]["tilt_rad"]) < STANDING_TILT_DEG


def test_the_robot_follows_a_target_at_a_capped_speed(spec):
    """Once moved to a pose by a checked move, an edit within a jog step is followed at the capped speed."""
    from op2motion.onrobot.follow import FOLLOW_SPEED_RAD_S, JOG_STEP_RAD, Follower
    from op2motion.robot.pose import Pose

    joint = spec.joint_names.index("r_sho_pitch")        # an arm: a knee alone would tip the robot over
    with lockstep(spec) as (emulator, port):
        follower = Follower(port, spec)
        seen: list[tuple[float, float]] = []
        follower.start()                                 # the loop runs free in its thread, in simulated time
        try:
            start = follower.pose()
            follower.move_to(Pose("here", "double", start))
            deadline = time.monotonic() + 60.0
            while follower.state != "following the pose" and time.monotonic() < deadline:
                time.sleep(0.005)
            target = start.copy()
            target[joint] += JOG_STEP_RAD
            follower.request(Pose("edited", "double", target))
            while time.monotonic() < deadline:
                goal = (emulator.servos[joint].u16("goal_position") - 2048) * 2 * math.pi / 4096
                seen.append((port.clock.now(), goal))
                if abs(goal - target[joint]) < FOLLOW_TOL_RAD:
                    break
                time.sleep(0.001)
        finally:
            report = follower.close()
    times, goals = np.array(seen).T
    assert follower.state == "following the pose"
    assert abs(goals[-1] - target[joint]) < FOLLOW_TOL_RAD
    assert times[-1] - times[0] >= (JOG_STEP_RAD - FOLLOW_TOL_RAD) / FOLLOW_SPEED_RAD_S - 0.016    # 5° at 1 rad/s
    speeds = np.abs(np.diff(goals)) - FOLLOW_SPEED_RAD_S * np.diff(times)
    # capped between any two looks: the clock and the goal are read one after the other while the loop runs (one
    # tick's move may fall between them) and a goal is whole position ticks
    assert speeds.max() <= FOLLOW_SPEED_RAD_S * 0.008 + TICK_RAD
    assert report.ended == "stopped" and report.fault is None


def test_ctrl_c_mid_walk_from_the_command_line_ends_standing():
    """``robot walk`` as a user runs it, stopped by Ctrl-C: exit 130 within 3 s, standing (the emulated OP2 in
    lockstep held to the wall clock)."""
    walking = cli("robot", "walk", "--port", "lockstep:pace=1", "--steps", "20", "--json")
    time.sleep(WALK_BEFORE_CTRL_C_S)                     # started, checked, on its way (a 13 s walk, paced)
    walking.send_signal(signal.SIGINT)
    sent = time.monotonic()
    code, out, err = finish(walking)
    took = time.monotonic() - sent
    assert code == 130 and "stopped on request" in err, err
    truth = json.loads(out)["emulated"]["truth"]
    assert took < CTRL_C_EXIT_S and math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG


def test_end_to_end_in_real_time_on_a_pseudo_terminal(tmp_path):
    """One emulator in real time behind the real wire (1 ms timer), as a user runs it: the SDK, ``robot status``
    (the link measured), then ``robot emulate`` stopped by Ctrl-C. (Motions in real time meet whatever else the
    machine runs: the suite's own load once left the loop blind for 40 ms, which stops a motion as it must; they are
    checked in lockstep, below and in test_robot_cli.py.)"""
    sdk = pytest.importorskip("dynamixel_sdk")
    assert WIRE_1MS.latency_timer_s == 0.001
    with emulator_process(tmp_path) as emulator:
        port = sdk.PortHandler(emulator.link)
        assert port.openPort() and port.setBaudRate(1_000_000)
        try:
            handler = sdk.PacketHandler(1.0)
            assert handler.ping(port, 200) == (0x7300, sdk.COMM_SUCCESS, 0)
            model, result, _ = handler.ping(port, 13)
            assert (model, result) == (29, sdk.COMM_SUCCESS)
            goal, result, _ = handler.read2ByteTxRx(port, 13, 30)
            assert result == sdk.COMM_SUCCESS and goal == emulator.report()["goal_ticks"][12]
            assert handler.write1ByteTxRx(port, 13, 25, 1) == (sdk.COMM_SUCCESS, 0)
            assert handler.read1ByteTxRx(port, 13, 25)[:2] == (1, sdk.COMM_SUCCESS)
            assert handler.ping(port, 42)[1] == sdk.COMM_RX_TIMEOUT
        finally:
            port.closePort()
        code, out, err = run("robot", "status", "--port", emulator.link, "--json")
        status = json.loads(out)
        assert code == 0 and status["ok"] and status["link"]["ping_round_trip_ms"]["median"] is not None, err
        emulator.process.send_signal(signal.SIGINT)
        code, _, err = finish(emulator.process, 10)
    assert code == 130 and "link is removed" in err
    assert not os.path.lexists(emulator.link)


def test_a_controller_from_python_starts_with_the_checked_approach_or_is_refused(spec):
    """docs/robot.md's Python path: ``run_on_robot(port, spec, walk)`` moves the robot to the walk's first pose by a
    checked move first and walks; given an OP2 already taken control of, a controller whose first goals are far
    from the joints is refused before any goal is sent (the first tick used to ask for 119° at the elbows)."""
    from op2motion.bus.loop import run_controller
    from op2motion.bus.session import Session
    from op2motion.errors import CheckFailed
    from op2motion.gait.controller import WalkController
    from op2motion.onrobot.walks import run_on_robot

    with lockstep(spec) as (emulator, port):
        result = run_on_robot(port, spec, WalkController.from_preset("forward", steps=PYTHON_STEPS))
        truth = emulator.truth()
    assert [name for name, _ in result.runs] == ["approach", "run"] and "checked in physics" in result.checked
    report = result.last
    assert report.ended == "done" and report.fault is None
    assert truth["x_m"] > PYTHON_WALKED_M and math.degrees(truth["tilt_rad"]) < STANDING_TILT_DEG, truth
    with lockstep(spec) as (emulator, port), Session(port, spec) as session:
        session.ready_for_motion()
        held = list(emulator.report()["goal_ticks"])
        with pytest.raises(CheckFailed, match="first goal for .* from where the joint is"):
            run_controller(WalkController.from_preset("forward", steps=PYTHON_STEPS), session.robot)
        assert emulator.report()["goal_ticks"] == held
