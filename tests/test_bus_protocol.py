"""The bus wing's fast lane: Protocol 1.0 packets byte for byte, the control tables, the IMU mapping, the safety
rules, the emulated devices' tables, the port's refusals and the client's retries on a real pseudo-terminal (no
physics)."""

from __future__ import annotations

import math
import os
import threading
import time
import tty

import numpy as np
import pytest

from op2motion.bus import protocol as p
from op2motion.bus.emulator.devices import Board, EmulatedServo
from op2motion.bus.safety import (
    BLIND_TICKS,
    FALL_TILT_RAD,
    HOT_START_C,
    HOT_STOP_C,
    Refused,
    Watch,
    WrongModel,
    clip_goals,
    mechanical_bounds,
    min_supply_v,
    preflight,
    preflight_problems,
)
from op2motion.bus.tables import (
    CM730,
    CM730_MODEL_NUMBER,
    CM740_MODEL_NUMBER,
    MX28,
    MX28_MODEL_NUMBER,
    magnitude,
    model_name,
    signed,
)
from op2motion.errors import InputError
from op2motion.robot.imu import FallWatch, attitude, decode_imu, encode_imu, imu_of
from op2motion.robot.spec import GRAVITY_M_S2

GYRO_TOL_RAD_S = 0.03          # half a count of the gyro (0.0545 rad/s a count)
ACCEL_TOL_M_S2 = 0.04          # half a count of the accelerometer (0.0766 m/s² a count)


def test_ping_packet_is_the_emanual_example():
    # e-manual Protocol 1.0: PING to ID 1 is FF FF 01 02 01 FB
    assert p.ping(1) == bytes.fromhex("FFFF010201FB")
    assert p.read(1, 0x2B, 1) == bytes.fromhex("FFFF010402 2B01CC".replace(" ", ""))


def test_sync_write_and_bulk_read_layouts():
    packet = p.sync_write(26, 6, {1: bytes((0, 0, 32, 0, 0x00, 0x08)), 2: bytes((0, 0, 32, 0, 0xFF, 0x07))})
    assert packet[:5] == bytes((0xFF, 0xFF, 0xFE, 2 + 2 + 2 * 7, 0x83))
    assert packet[5:7] == bytes((26, 6)) and packet[7] == 1 and packet[14] == 2
    bulk = p.bulk_read([(200, 24, 30), (13, 36, 2)])
    assert bulk[4] == 0x92 and bulk[5] == 0x00
    assert bulk[6:12] == bytes((30, 200, 24, 2, 13, 36))          # (length, id, address) triples
    with pytest.raises(ValueError):
        p.sync_write(26, 6, {1: b"\x00"})


def test_parser_finds_packets_in_noise_split_and_damaged_streams():
    good = p.status(13, 0, bytes((0x00, 0x08)))
    damaged = bytearray(p.status(7, 0, bytes((1, 2))))
    damaged[-2] ^= 0x10
    parser = p.StreamParser()
    stream = b"\x00\x13\xff" + bytes(damaged) + b"\xff" + good + p.status(200, 4)
    packets = []
    for k in range(0, len(stream), 3):                             # arrives in 3-byte pieces
        packets += parser.feed(stream[k:k + 3])
    assert [(x.id, x.code, x.params) for x in packets] == [(13, 0, bytes((0, 8))), (200, 4, b"")]
    assert parser.bad_checksums == 1 and parser.discarded > 0
    assert packets[1].errors == ("overheating",)


def test_error_bits_by_name():
    assert p.error_names(0) == ()
    assert p.error_names(0x01 | 0x20) == ("input voltage", "overload")
    assert p.error_names(0x80) == ("bit 7",)


def test_tables_match_the_notes():
    assert (MX28["torque_enable"].address, MX28["p_gain"].address, MX28["goal_position"].address) == (24, 28, 30)
    assert (MX28["moving_speed"].address, MX28["torque_limit"].address, MX28["present_position"].address) == (32, 34,
                                                                                                              36)
    assert (MX28["present_voltage"].address, MX28["present_temperature"].address, MX28["moving"].address) == (42, 43,
                                                                                                              46)
    assert MX28["alarm_shutdown"].default == 36 and MX28["temperature_limit"].default == 80
    assert (CM730["dynamixel_power"].address, CM730["gyro_z"].address, CM730["accel_x"].address,
            CM730["voltage"].address) == (24, 38, 44, 50)
    assert not MX28.writable(36) and MX28.writable(30)
    for value in (-1023, -5, 0, 7, 1023):
        assert signed(magnitude(value)) == value


def test_imu_round_trip_and_signs(spec):
    imu = imu_of(spec)
    gyro, accel = np.array([0.4, -1.2, 2.0]), np.array([1.0, -2.0, 9.5])
    back_g, back_a = decode_imu(imu, encode_imu(imu, gyro, accel))
    assert np.allclose(back_g, gyro, atol=GYRO_TOL_RAD_S) and np.allclose(back_a, accel, atol=ACCEL_TOL_M_S2)
    pitching_forward = encode_imu(imu, np.array([0.0, 1.0, 0.0]), np.zeros(3))
    assert pitching_forward[40] < imu.centre_count             # FB_GYRO falls as the torso pitches forward
    lying_down = encode_imu(imu, np.zeros(3), np.array([-GRAVITY_M_S2, 0.0, 0.0]))
    assert lying_down[46] < imu.fallen_front_count              # face down reads as the framework's FALLEN_F
    saturated = encode_imu(imu, np.array([100.0, 0.0, 0.0]), np.zeros(3))
    assert saturated[42] in (0, imu.max_count)


def test_fall_watch_is_the_frameworks_test(spec):
    imu = imu_of(spec)
    watch = FallWatch(imu)
    face_up = encode_imu(imu, np.zeros(3), np.array([GRAVITY_M_S2, 0.0, 0.0]))
    verdicts = [watch.add(face_up) for _ in range(imu.fallen_window)]
    assert verdicts[:-1] == [None] * (imu.fallen_window - 1) and verdicts[-1] == "back"
    upright = encode_imu(imu, np.zeros(3), np.array([0.0, 0.0, GRAVITY_M_S2]))
    watch = FallWatch(imu)
    assert [watch.add(upright) for _ in range(imu.fallen_window)][-1] is None


def test_attitude_from_gravity():
    lean = math.radians(10.0)
    pitch, roll, tilt = attitude(np.array([-math.sin(lean), 0.0, math.cos(lean)]) * GRAVITY_M_S2)
    assert pitch == pytest.approx(lean) and roll == pytest.approx(0.0, abs=1e-12) and tilt == pytest.approx(lean)


class _State:
    def __init__(self, **kw):
        self.__dict__.update(dict(answers=True, errors=(), temperature_c=40, voltage_v=12.0, joint="r_knee", id=13,
                                  model_number=MX28_MODEL_NUMBER, position_rad=0.0))
        self.__dict__.update(kw)


def _board(**kw) -> _State:
    return _State(**{"model_number": CM740_MODEL_NUMBER, **kw})


def test_preflight_names_each_problem(spec):
    board = _board(voltage_v=12.0)
    assert preflight_problems(board, [_State()], spec) == []
    problems = preflight_problems(_board(voltage_v=9.5), [_State(answers=False, joint="l_knee", id=14),
                                                          _State(temperature_c=HOT_START_C),
                                                          _State(errors=("overload",))], spec)
    kinds = [(f.kind, f.id) for f in problems]
    assert kinds == [("low supply", 200), ("not answering", 14), ("hot", 13), ("overload", 13)]
    assert min_supply_v(spec) == pytest.approx(10.0)
    assert "l_knee (ID 14): not answering" in problems[1].describe()


def test_a_device_of_another_model_is_refused_by_name_whatever_else(spec):
    """A CM-730 and a CM-740 both pass; a servo reporting the AX-12's model, or a board of another model, is refused
    with the bad-input error (exit 2), naming ID, joint and the number it reported, ahead of every other problem."""
    assert model_name(CM740_MODEL_NUMBER) == "CM-740" and CM740_MODEL_NUMBER == 0x7400      # e-manual: 0x00, 0x74
    for board in (_board(model_number=CM730_MODEL_NUMBER), _board()):
        preflight(board, [_State()], spec)                                  # no problem: nothing raised
    ax12 = _State(model_number=12, joint="l_knee", id=14)
    with pytest.raises(WrongModel) as caught:
        preflight(_board(voltage_v=9.5), [_State(temperature_c=HOT_START_C), ax12], spec)
    assert caught.value.exit_code == 2
    assert str(caught.value) == "l_knee (ID 14) reports model 12 (AX-12?), expected the MX-28 (29)"
    with pytest.raises(WrongModel, match=r"the sub-controller \(ID 200\) reports model 0x1234, expected the CM-730 "
                                         r"\(0x7300\) or the CM-740 \(0x7400\) \(and 1 more\)"):
        preflight(_board(model_number=0x1234), [ax12], spec)
    kinds = [(f.kind, f.id) for f in preflight_problems(_board(voltage_v=9.5), [ax12, _State()], spec)]
    assert kinds == [("wrong model", 14), ("low supply", 200)]    # nothing else read from another model's table


def test_a_servo_reporting_error_bits_is_refused_naming_them(spec):
    every = p.error_names(0x7F)
    with pytest.raises(Refused) as caught:
        preflight(_board(), [_State(errors=every, joint="l_knee", id=14)], spec)
    assert caught.value.exit_code == 1
    assert str(caught.value) == ("refused to start: l_knee (ID 14) reports errors: input voltage, angle limit, "
                                 "overheating, range, checksum, overload, instruction")


def test_watch_blind_errors_heat_and_falls(spec):
    imu = imu_of(spec)
    watch = Watch(spec, imu, 0.008, [j.id for j in spec.joints], spec.joint_names)
    everyone = {200, *(j.id for j in spec.joints)}
    for _ in range(BLIND_TICKS - 1):
        assert watch.reads(everyone - {13}) is None
    fault = watch.reads(everyone - {13})
    assert (fault.kind, fault.joint, fault.id) == ("not answering", "r_knee", 13)
    assert watch.status(13, ("overheating",), 84).kind == "overheating"
    assert watch.status(13, ("angle limit",), None) is None
    assert watch.status(13, (), HOT_STOP_C).kind == "overheating"
    assert watch.status(13, (), HOT_STOP_C - 1) is None
    upright = np.array([0.0, 0.0, GRAVITY_M_S2])
    words = encode_imu(imu, np.zeros(3), upright)
    assert watch.body(upright, words) is None                     # arms: upright
    tipped = np.array([-math.sin(FALL_TILT_RAD + 0.3), 0.0, math.cos(FALL_TILT_RAD + 0.3)]) * GRAVITY_M_S2
    faults = [watch.body(tipped, encode_imu(imu, np.zeros(3), tipped)) for _ in range(60)]
    assert any(f is not None and f.kind == "fell" for f in faults)
    lying = Watch(spec, imu, 0.008, [j.id for j in spec.joints], spec.joint_names)
    down = np.array([-GRAVITY_M_S2, 0.0, 0.0])
    assert all(lying.body(down, encode_imu(imu, np.zeros(3), down)) is None for _ in range(60))   # never upright


def test_goals_clipped_to_mechanical_ranges(spec):
    lower, upper = mechanical_bounds(spec)
    goals = np.zeros(len(spec.joints))
    goals[12] = upper[12] + 0.5
    clipped, where = clip_goals(goals, lower, upper)
    assert clipped[12] == upper[12] and where.tolist() == [i == 12 for i in range(len(goals))]


def test_emulated_servo_table_rules():
    servo = EmulatedServo(13)
    servo.voltage_v, servo.temperature_c = 12.0, 40.0
    servo.power_up(2048)
    assert servo.get("torque_enable") == 0 and servo.u16("goal_position") == 2048
    assert servo.write(36, b"\x00\x00") & p.RANGE                  # present position is read-only
    assert servo.write(28, bytes((255,))) & p.RANGE                # P gain above 254
    assert servo.write(26, bytes((0, 0, 32, 0, 0x10, 0x08))) == 0  # the framework's 6 bytes (29 between registers)
    assert servo.u16("goal_position") == 0x0810
    assert servo.write(31, b"\x09") & p.RANGE and servo.u16("goal_position") == 0x0810   # half a word: refused
    assert servo.read(70, 10)[0] & p.RANGE
    servo.write(24, b"\x01")
    servo.temperature_c = 85.0
    servo.enforce_alarms()
    assert servo.get("torque_enable") == 0 and servo.conditions() & p.OVERHEATING
    board = Board()
    assert board.write(24, b"\x01") == 0 and board.power_changed
    assert board.write(30, b"\x01") & p.RANGE                      # the buttons are read-only


def test_port_refuses_what_is_not_a_free_serial_device(tmp_path):
    from op2motion.bus.port import open_port

    with pytest.raises(InputError, match="no such serial port") as e:
        open_port(str(tmp_path / "ttyUSB9"))
    assert e.value.param == "port"
    plain = tmp_path / "file"
    plain.write_text("x")
    with pytest.raises(InputError, match="got a regular file"):
        open_port(str(plain))
    with pytest.raises(InputError, match="got a directory"):
        open_port(str(tmp_path))
    with pytest.raises(InputError, match="another kind of character device"):
        open_port("/dev/null")
    master, slave = os.openpty()
    try:
        name = os.ttyname(slave)
        first = open_port(name)
        try:
            with pytest.raises(InputError, match="busy"):
                open_port(name)
        finally:
            first.close()
        open_port(name).close()                                   # free again (other holders: test_bus_port.py)
    finally:
        os.close(master)
        os.close(slave)


def test_client_retries_through_lost_and_damaged_replies():
    """A responder on a real pseudo-terminal drops the first reply and damages the second; the third counts."""
    from op2motion.bus.client import Bus
    from op2motion.bus.port import open_port

    master, slave = os.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)
    os.close(slave)
    answers = []

    def respond() -> None:
        parser = p.StreamParser()
        while len(answers) < 3:
            try:
                data = os.read(master, 256)
            except OSError:                                        # the client has not opened its side yet
                time.sleep(0.001)
                continue
            for packet in parser.feed(data):
                answers.append(packet)
                reply = bytearray(p.status(packet.id, 0, bytes((0x34, 0x12))))
                if len(answers) == 1:
                    continue
                if len(answers) == 2:
                    reply[-1] ^= 0xFF
                os.write(master, bytes(reply))

    port = open_port(name)
    thread = threading.Thread(target=respond, daemon=True)
    thread.start()
    try:
        bus = Bus(port, retries=3, margin_s=0.2)          # the responder is a thread of this busy interpreter
        reply = bus.read(5, 36, 2)
        assert reply is not None and p.word(*reply.params) == 0x1234
        assert bus.stats.retries == 2 and bus.stats.bad_checksums == 1 and bus.stats.timeouts == 2
    finally:
        port.close()
        thread.join(timeout=2)
        os.close(master)


def test_gyro_centres_only_from_a_still_robot(spec):
    from op2motion.robot.imu import GYRO_STILL_SD, gyro_centres

    imu = imu_of(spec)
    rng = np.random.default_rng(7)
    biased = [{c.register: 515 + int(rng.integers(0, 2)) for c in imu.gyro} for _ in range(100)]
    centres = gyro_centres(imu, biased)
    assert all(515.0 <= v <= 516.0 for v in centres.values())
    gyro, _ = decode_imu(imu, {**biased[0], **{c.register: 512 for c in imu.accel}}, centres)
    assert np.all(np.abs(gyro) <= imu.gyro[0].scale)                      # the bias is gone
    moving = [{c.register: 512 + int(4 * GYRO_STILL_SD * math.sin(k)) for c in imu.gyro} for k in range(100)]
    assert gyro_centres(imu, moving) is None


def test_timed_fault_flags():
    from op2motion.bus.emulator.faults import parse_timed

    assert parse_timed("13@4:85", "overheat", 85.0) == (13, 4.0, 85.0)
    assert parse_timed("13@4.5", "overheat", 85.0) == (13, 4.5, 85.0)
    assert parse_timed("5@0.3", "unplug")[:2] == (5, 0.3)
    for bad in ("5@0.3:9", "x@1", "5"):
        with pytest.raises(InputError) as e:
            parse_timed(bad, "unplug")
        assert e.value.param == "unplug"


def test_a_stop_waits_for_both_feet_on_a_walk_only(spec):
    from op2motion.bus.stopping import stop_row
    from op2motion.physics import Plan

    contact = ("double", "double", "left", "left", "left", "double", "double", "double", "right", "right")
    goals, gains = np.zeros((len(contact), 20)), np.full((len(contact), 20), 32.0)
    walk = Plan("walk", goals, gains, contact, 0.008, 0.0, 1.0, contact=contact)
    assert (stop_row(walk, 0), stop_row(walk, 2), stop_row(walk, 8)) == (1, 6, 8)   # one row into a double support
    motion = Plan("motion", goals, gains, contact, 0.008, 0.0, 1.0)
    assert stop_row(motion, 3) == 3                                             # anything else: where it is
