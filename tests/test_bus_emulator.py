"""The emulated OP2 itself: byte compatibility with ROBOTIS's own dynamixel-sdk, the power switch, the bulk read's
order and silence, no reply to broadcast; and a 20-step walk through the bus in both engines behind it, against the
same walk in ``walk --validate``."""

from __future__ import annotations

import json
import math
import time

import pytest
from bus_support import BLIND_BUS, cli, emulator_process, finish, run

from op2motion.bus import protocol as p
from op2motion.bus.client import Bus
from op2motion.bus.port import open_port
from op2motion.bus.robot import POWER_ON_WAIT_S

SPEED_TOL = 0.10               # the walk through the bus: speed within 10 % of walk --validate's
HEADING_TOL_DEG = 5.0          # ... heading within 5°
STEPS = 20
FIRST_MOVE_S = 1.0             # the follower's first goals reach the servos within this, however loaded the machine [s]

pytestmark = pytest.mark.physics


def test_dynamixel_sdk_talks_to_it(tmp_path):
    sdk = pytest.importorskip("dynamixel_sdk")
    with emulator_process(tmp_path) as emulator:      # its own process: the SDK polls, holding this interpreter
        port = sdk.PortHandler(emulator.link)
        assert port.openPort() and port.setBaudRate(1_000_000)
        try:
            handler = sdk.PacketHandler(1.0)
            model, result, error = handler.ping(port, 200)
            assert (model, result, error) == (0x7300, sdk.COMM_SUCCESS, 0)
            model, result, _ = handler.ping(port, 13)
            assert (model, result) == (29, sdk.COMM_SUCCESS)
            goal, result, _ = handler.read2ByteTxRx(port, 13, 30)
            assert result == sdk.COMM_SUCCESS and goal == emulator.report()["goal_ticks"][12]
            result, error = handler.write1ByteTxRx(port, 13, 25, 1)
            assert (result, error) == (sdk.COMM_SUCCESS, 0)
            assert handler.read1ByteTxRx(port, 13, 25)[:2] == (1, sdk.COMM_SUCCESS)
            _, result, _ = handler.ping(port, 42)
            assert result == sdk.COMM_RX_TIMEOUT
        finally:
            port.closePort()


def test_power_switch_bulk_read_and_broadcast(tmp_path):
    with emulator_process(tmp_path, "mujoco", "standing", "--missing", "5") as emulator:
        with open_port(emulator.link) as port:
            bus = Bus(port, retries=0, latency_s=0.02)
            spans = [(200, 24, 30), (3, 36, 2), (4, 36, 2), (5, 36, 2), (6, 36, 2)]
            got = bus.bulk_read(spans, 0.02)
            assert sorted(got) == [3, 4, 200] and len(got[200].params) == 30   # 6 waits for 5's reply in vain
            assert bus.write(200, 24, b"\x00") is not None                     # servos' power off
            assert bus.ping(13) is None and bus.ping(200) is not None
            assert bus.write(200, 24, b"\x01") is not None
            time.sleep(POWER_ON_WAIT_S)
            reply = bus.read(13, 24, 1)
            assert reply is not None and reply.params == b"\x00"                 # powered up with its torque off
            bus.write(p.BROADCAST_ID, 25, b"\x01")
            assert bus._collect(p.write(p.BROADCAST_ID, 25, b"\x01"), {13: 0}, 0.05) == {}   # no reply to broadcast
            assert all(bus.read(d, 25, 1).params == b"\x01" for d in (1, 4, 6, 13, 20))


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_twenty_steps_through_the_bus_walk_as_in_physics(spec, tmp_path, engine):
    validate = cli("walk", "--steps", str(STEPS), "--validate", "--engine", engine, "--json")   # meanwhile
    with emulator_process(tmp_path, engine) as emulator:
        for _ in range(2):                               # once more only if the whole bus went blind (BLIND_BUS)
            before = emulator.truth()
            code, out, err = run("robot", "walk", "--port", emulator.link, "--steps", str(STEPS), "--json")
            if not (code == 1 and BLIND_BUS in err):
                break
        time.sleep(0.5)
        after = emulator.truth()
    done, physics, why = finish(validate)
    assert done == 0, why
    summary = json.loads(physics)["physics"]["engines"][engine]
    distance, heading = summary["distance_m"], summary["heading_error_deg"]
    result = json.loads(out)
    assert code == 0, err
    assert math.degrees(after["tilt_rad"]) < 15.0 and result["ended"] == "done"             # no fall, ends standing
    travel = math.hypot(after["x_m"] - before["x_m"], after["y_m"] - before["y_m"])
    assert abs(travel - distance) <= SPEED_TOL * distance, (travel, distance)             # same time: same speed
    turned = math.degrees(math.remainder(after["yaw_rad"] - before["yaw_rad"], 2 * math.pi))
    assert abs(turned - heading) <= HEADING_TOL_DEG, (turned, heading)
    walk = result["runs"]["walk"]
    assert walk["max_blind_ticks"] < 5 and walk["period_ms"]["p50"] == pytest.approx(8.0, abs=0.5)
    assert abs(result["travel"]["distance_m"] - travel) <= SPEED_TOL * distance           # leg odometry


def test_the_robot_follows_a_target_at_a_capped_speed(spec, tmp_path):
    from op2motion.bus.follow import FOLLOW_SPEED_RAD_S, Follower

    joint = spec.joint_names.index("r_sho_pitch")        # an arm: a knee alone would tip the robot over
    with emulator_process(tmp_path) as emulator:
        follower = Follower(emulator.link, spec)
        follower.start()
        try:
            start = follower.pose()
            target = start.copy()
            target[joint] += math.radians(30.0)
            follower.set_target(target)
            t0 = time.monotonic()

            def moved() -> float:
                goal_rad = math.radians(abs((emulator.report()["goal_ticks"][joint] - 2048) * 360 / 4096))
                return goal_rad - abs(start[joint])

            while moved() <= 0.0 and time.monotonic() - t0 < FIRST_MOVE_S:     # a loaded machine: the first goals
                time.sleep(0.02)                                              # may take a few periods to arrive
            so_far, elapsed = moved(), time.monotonic() - t0
            assert 0.0 < so_far <= FOLLOW_SPEED_RAD_S * elapsed + math.radians(2.0), (so_far, elapsed)  # capped
            time.sleep(1.0)
            goal_deg = (emulator.report()["goal_ticks"][joint] - 2048) * 360 / 4096
            assert goal_deg == pytest.approx(math.degrees(target[joint]), abs=0.2)
            assert follower.running()
        finally:
            report = follower.close()
    assert report.ended == "stopped" and report.fault is None
