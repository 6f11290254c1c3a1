"""The emulated OP2's devices answer as the CM-730 firmware and the MX-28 do: bytes into :class:`Wire`, status packets
out (no physics engine: the joints' positions are a constant)."""

from __future__ import annotations

import pytest

from op2motion.bus import protocol as p
from op2motion.bus.emulator.devices import EmulatedServo
from op2motion.bus.emulator.faults import Faults, with_board
from op2motion.bus.emulator.wire import BOOT_S, Wire
from op2motion.bus.tables import CM730, CM730_ID, CM730_MODEL_NUMBER, CM740_MODEL_NUMBER, LED_HEAD_AT_POWER_ON, MX28

SERVO = 13                     # the servo most tests talk to
JOINT_TICKS = 2048             # every joint's position (a powering-up servo's goal)
SUPPLY_V = 12.0                # within the servos' voltage limits: no input-voltage error standing
CW, CCW = 1000, 3000           # angle limits set for the tests [tick]


class Rig:
    """A wire with the servos powered and booted, and its simulated clock."""

    def __init__(self, spec, faults: Faults | None = None):
        self.t = 1.0
        self.wire = Wire(spec, faults or Faults(), now=lambda: self.t, present_ticks=lambda: [JOINT_TICKS] * 20)
        for servo in self.wire.servos:
            servo.voltage_v = SUPPLY_V
        self.power_on()

    def power_on(self) -> None:
        self.send(p.write(CM730_ID, CM730["dynamixel_power"].address, b"\x01"))
        self.t += BOOT_S

    def send(self, data: bytes) -> list[p.Packet]:
        """The status packets ``data`` is answered with."""
        parser = p.StreamParser()
        return [packet for chunk in self.wire.feed(data) for packet in parser.feed(chunk)]

    def one(self, data: bytes) -> p.Packet:
        """The one status packet ``data`` is answered with."""
        replies = self.send(data)
        assert len(replies) == 1, replies
        return replies[0]

    def servo(self, device: int = SERVO) -> EmulatedServo:
        return self.wire.by_id[device]


@pytest.fixture()
def rig(spec) -> Rig:
    return Rig(spec)


def limited(rig: Rig) -> None:
    """Give the servo angle limits CW..CCW (joint mode)."""
    assert rig.one(p.write(SERVO, MX28["cw_angle_limit"].address, p.word_bytes(CW) + p.word_bytes(CCW))).code == 0


def sabotaged(packet: bytes) -> bytes:
    """``packet`` with its checksum wrong."""
    return packet[:-1] + bytes(((packet[-1] + 1) & 0xFF,))


# --- 1. angle limits -------------------------------------------------------------------------------------------------
def test_a_goal_beyond_the_angle_limits_is_flagged_and_clipped(rig):
    limited(rig)
    goal = MX28["goal_position"].address
    assert rig.one(p.write(SERVO, goal, p.word_bytes(CCW + 500))).code == p.ANGLE_LIMIT
    assert rig.servo().u16("goal_position") == CCW                       # clipped to the nearest limit
    assert rig.one(p.write(SERVO, goal, p.word_bytes(2000))).code == 0
    assert rig.servo().u16("goal_position") == 2000
    rig.send(p.sync_write(MX28["d_gain"].address, 6, {SERVO: bytes((0, 0, 32, 0)) + p.word_bytes(CW - 400)}))
    assert rig.servo().u16("goal_position") == CW
    assert rig.one(p.encode(SERVO, p.Instruction.REG_WRITE, bytes((goal,)) + p.word_bytes(4000))).code == p.ANGLE_LIMIT
    assert rig.one(p.encode(SERVO, p.Instruction.ACTION)).code == p.ANGLE_LIMIT
    assert rig.servo().u16("goal_position") == CCW


def test_angle_limits_are_ignored_in_wheel_mode_and_can_shut_the_torque_down(rig):
    goal = MX28["goal_position"].address
    assert rig.one(p.write(SERVO, MX28["cw_angle_limit"].address, bytes(4))).code == 0           # wheel mode
    assert rig.one(p.write(SERVO, goal, p.word_bytes(4000))).code == 0
    limited(rig)
    assert rig.one(p.write(SERVO, MX28["alarm_shutdown"].address, bytes((p.ANGLE_LIMIT,)))).code == 0
    assert rig.one(p.write(SERVO, MX28["torque_enable"].address, b"\x01")).code == 0
    assert rig.one(p.write(SERVO, goal, p.word_bytes(CW - 1))).code == p.ANGLE_LIMIT
    assert rig.servo().get("torque_enable") == 0


# --- 2. checksum ----------------------------------------------------------------------------------------------------
def test_a_damaged_packet_is_answered_with_the_checksum_error_and_not_executed(rig):
    led = MX28["led"].address
    reply = rig.one(sabotaged(p.write(SERVO, led, b"\x01")))
    assert (reply.id, reply.code) == (SERVO, p.CHECKSUM) and rig.servo().get("led") == 0
    assert rig.one(sabotaged(p.read(CM730_ID, 24, 1))).code == p.CHECKSUM
    assert rig.send(sabotaged(p.ping(SERVO))) == []                                 # the firmware skips a PING
    assert rig.send(sabotaged(p.write(p.BROADCAST_ID, led, b"\x01"))) == []         # ... and never answers broadcast
    then = rig.send(sabotaged(p.ping(CM730_ID)) + p.ping(SERVO))                     # what follows is still read
    assert [r.id for r in then] == [SERVO] and rig.wire.stats["bad_packets"] == 5


# --- 3. REG_WRITE and ACTION -----------------------------------------------------------------------------------------
def test_reg_write_waits_in_registered_until_action(rig):
    registered, led = MX28["registered"].address, MX28["led"].address
    assert rig.one(p.encode(SERVO, p.Instruction.ACTION)).code == p.INSTRUCTION   # nothing registered
    assert rig.one(p.encode(SERVO, p.Instruction.REG_WRITE, bytes((led, 1)))).code == 0
    assert rig.one(p.read(SERVO, registered, 1)).params == b"\x01" and rig.servo().get("led") == 0
    assert rig.send(p.encode(p.BROADCAST_ID, p.Instruction.ACTION)) == []
    assert rig.servo().get("led") == 1 and rig.one(p.read(SERVO, registered, 1)).params == b"\x00"
    assert rig.one(p.encode(CM730_ID, p.Instruction.REG_WRITE, bytes((25, 1)))).code == p.INSTRUCTION


# --- 4. cold start ---------------------------------------------------------------------------------------------------
def test_a_cold_start_leaves_the_servos_unpowered_until_the_power_register_is_set(rig):
    assert rig.one(p.write(SERVO, MX28["torque_enable"].address, b"\x01")).code == 0
    rig.one(p.write(CM730_ID, CM730["led_head"].address, p.word_bytes(0x001F)))
    rig.wire.cold_start()
    assert rig.one(p.read(CM730_ID, CM730["dynamixel_power"].address, 1)).params == b"\x00"
    assert rig.wire.board.get("led_head") == LED_HEAD_AT_POWER_ON
    assert rig.send(p.ping(SERVO)) == [] and not rig.wire.powered()
    rig.power_on()
    state = rig.one(p.read(SERVO, MX28["torque_enable"].address, MX28["goal_position"].end - 24)).params
    assert state[0] == 0 and p.word(state[6], state[7]) == JOINT_TICKS               # torque off, goal where it is


# --- 5. the CM-730's table -------------------------------------------------------------------------------------------
def test_the_board_table_runs_to_address_89(rig):
    assert CM730.size == 90 and CM730["zigbee_id"].end == 90 and CM730["adc15"].address == 79
    assert rig.one(p.read(CM730_ID, 81, 9)).params == bytes(9)
    beyond = rig.one(p.read(CM730_ID, 89, 2))
    assert beyond.code == p.RANGE and beyond.params == b""
    assert rig.one(p.write(CM730_ID, CM730["buzzer_data0"].address, b"\x05")).code == 0
    assert rig.one(p.write(CM730_ID, 31, b"\x01")).code == p.RANGE                   # a byte of no register


# --- 6. broadcast PING -----------------------------------------------------------------------------------------------
def test_a_broadcast_ping_is_answered_by_the_board_alone(rig):
    replies = rig.send(p.ping(p.BROADCAST_ID))
    assert [(r.id, r.code) for r in replies] == [(CM730_ID, 0)]


# --- 7. RESET --------------------------------------------------------------------------------------------------------
def test_reset_does_nothing_on_the_board_and_is_refused_by_a_servo(rig):
    rig.one(p.write(CM730_ID, CM730["led_panel"].address, b"\x05"))
    before = bytes(rig.wire.board.table)
    assert rig.one(p.encode(CM730_ID, p.Instruction.RESET)).code == 0
    assert bytes(rig.wire.board.table) == before
    assert rig.one(p.encode(SERVO, p.Instruction.RESET)).code == p.INSTRUCTION
    assert rig.servo().get("id") == SERVO


# --- 8. LED panel ----------------------------------------------------------------------------------------------------
def test_the_led_panel_takes_0_to_7(rig):
    panel = CM730["led_panel"].address
    assert rig.one(p.write(CM730_ID, panel, b"\x07")).code == 0
    assert rig.one(p.write(CM730_ID, panel, b"\x08")).code == p.RANGE
    assert rig.wire.board.get("led_panel") == 7
    assert rig.one(p.write(CM730_ID, CM730["led_head"].address, p.word_bytes(0x8000))).code == p.RANGE


# --- 9. half a word --------------------------------------------------------------------------------------------------
def test_half_a_word_is_refused_but_the_frameworks_sync_write_is_not(rig):
    goal = MX28["goal_position"].address
    assert rig.one(p.write(SERVO, goal + 1, b"\x09")).code == p.RANGE
    assert rig.one(p.write(SERVO, goal, b"\x09")).code == p.RANGE
    assert rig.one(p.write(CM730_ID, CM730["led_eye"].address + 1, b"\x01")).code == p.RANGE
    assert rig.servo().u16("goal_position") == JOINT_TICKS
    rig.send(p.sync_write(MX28["d_gain"].address, 6, {SERVO: bytes((1, 2, 40, 0)) + p.word_bytes(2100)}))
    servo = rig.servo()
    assert (servo.get("d_gain"), servo.get("p_gain"), servo.u16("goal_position")) == (1, 40, 2100)


# --- 10. the reply goes out before the write -------------------------------------------------------------------------
def test_the_reply_follows_the_return_level_the_write_found(rig):
    level, led = MX28["status_return_level"].address, MX28["led"].address
    assert rig.one(p.write(SERVO, level, b"\x01")).code == 0                 # answered: made before the write
    assert rig.send(p.write(SERVO, led, b"\x01")) == []
    assert rig.one(p.read(SERVO, led, 1)).params == b"\x01"
    assert rig.send(p.write(SERVO, level, b"\x02")) == []                    # not answered: level 1 when it came
    assert rig.one(p.write(SERVO, led, b"\x00")).code == 0


# --- 11. the framework's debug registers ------------------------------------------------------------------------------
def test_the_registers_only_mx28_h_names_read_as_zero(rig):
    for name, address in (("system_data2", 10), ("operating_mode", 19), ("pause_time", 45), ("reserved4", 50),
                          ("d_error_out", 66)):
        assert MX28[name].address == address
    for address, length in ((10, 1), (19, 1), (45, 1), (50, 18)):
        reply = rig.one(p.read(SERVO, address, length))
        assert (reply.code, reply.params) == (0, bytes(length))
    assert rig.one(p.write(SERVO, MX28["pause_time"].address, b"\x01")).code == p.RANGE


# --- 12. bulk read ---------------------------------------------------------------------------------------------------
def test_a_silent_device_in_a_bulk_read_silences_the_ones_after_it(spec):
    rig = Rig(spec, Faults(missing={5}))
    spans = [(CM730_ID, 24, 30), (3, 36, 2), (5, 36, 2), (6, 36, 2)]
    assert [r.id for r in rig.send(p.bulk_read(spans))] == [CM730_ID, 3]
    assert rig.one(p.write(3, MX28["status_return_level"].address, b"\x00")).code == 0
    assert [r.id for r in rig.send(p.bulk_read(spans))] == [CM730_ID]       # level 0: no READ answered either


# --- 13. the board played, a servo of another model, error bits -------------------------------------------------------
def _model(rig: Rig, device: int) -> int:
    return p.word(*rig.one(p.read(device, MX28["model_number"].address, 2)).params)


def test_the_board_reports_a_cm730_or_a_cm740_and_a_servo_another_model(spec):
    assert _model(Rig(spec), CM730_ID) == CM730_MODEL_NUMBER == 0x7300
    rig = Rig(spec, Faults(models=with_board({14: 12}, "cm740", "board")))
    assert (_model(rig, CM730_ID), _model(rig, 14), _model(rig, 13)) == (CM740_MODEL_NUMBER, 12, MX28.model_number)
    rig.wire.cold_start()                                              # address 0 is EEPROM: kept over power cycles
    rig.power_on()
    assert _model(rig, 14) == 12
    assert Rig(spec, Faults(models={200: 0x1234})).wire.board.get("model_number") == 0x1234


def test_a_servo_given_error_bits_reports_them_in_every_reply(spec):
    rig = Rig(spec, Faults(errors={SERVO: 0x7F}))
    for request in (p.ping(SERVO), p.read(SERVO, MX28["present_position"].address, 2),
                    p.write(SERVO, MX28["led"].address, b"\x01")):
        assert rig.one(request).code == 0x7F
    assert rig.servo().get("led") == 1                                 # only the byte reported changes
    spans = [(CM730_ID, 24, 30), (12, 36, 2), (SERVO, 36, 2)]
    assert [(r.id, r.code) for r in rig.send(p.bulk_read(spans))] == [(CM730_ID, 0), (12, 0), (SERVO, 0x7F)]
