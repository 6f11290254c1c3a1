"""The control tables of the OP2's devices as data: the MX-28 (Protocol 1.0, model number 29) and the CM-730
sub-controller (ID 200), register by register: address, size [bytes], access, default, unit; and the values a write
may give each writable register. The model numbers op2motion accepts, and names for the ones it does not.

Sources: ROBOTIS e-manual, MX-28 (Protocol 1.0) control table (emanual.robotis.com/docs/en/dxl/mx/mx-28; repository
ROBOTIS-GIT/emanual); ROBOTIS DARwIn-OP / OP2 framework ``Framework/include/CM730.h`` and ``MX28.h`` (forks
darwinop-ens/darwin-op, Yen60229/Robotis-OP2-WeightLifting); the CM-730 firmware ``CM_DXL_COM.c`` / ``CM_DXL_COM.h``
(ROBOTIS 2010, model 0x7300, firmware 0x13); ``reference/bus_notes.md``. Multi-byte registers are little-endian
words. The OP2's servos run at 1 Mbps (baud number 1) with a return delay of 0 (the framework's firmware installer
sets both).

* MX-28: the e-manual's registers, and the ones only the framework's ``MX28.h`` names (10 system data 2,
  19 operating mode, 45 pause time, 50-67 reserved, potentiometer, PWM output and the PID terms): read-only here and
  0 (what a real servo reports there is not documented; the e-manual's Realtime Tick at 50 comes with firmware 40,
  and the table reports firmware 30). Byte 29 (``P_RESERVED``) is no register: the framework's sync write of 26..31
  writes it. Value limits: the e-manual's ranges.
* CM-730: 0..80 as ``CM730.h`` names them (``MAXNUM_ADDRESS`` 81; the firmware build with 81 bytes has the same
  layout); the firmware build whose ``CM_DXL_COM.h`` has ``CONTROL_TABLE_LEN`` 90 adds 81..89 (buzzer data,
  remote-control data, ZigBee ID; it orders its ADCs differently, and ``CM730.h`` is kept for 0..80), so the table
  runs to 89. The firmware's ``gbpParameterRange`` gives every byte's range: bytes of no register are read-only
  (range error), the LED panel takes 0..7, the head and eye LEDs 15-bit colours, the power switch 0..1. Power-on LED
  colours from its ``ProcessInit`` (head green, eye blue).

Model numbers (register 0, what a device reports it is): the MX-28 29; the sub-controller of a DARwIn-OP, the CM-730,
0x7300 (its firmware above); the OP2's CM-740 **0x7400**: ROBOTIS e-manual, ROBOTIS OP2, "Sub Controller (CM-740)",
EEPROM area: Model Number (L) 0 (0x00), Model Number (H) 116 (0x74) (emanual.robotis.com/docs/en/platform/op2/
getting_started; repository ROBOTIS-GIT/emanual ``docs/en/platform/op2/getting_started.md``, commit 160f8a5). The
same page gives the CM-740's control table (0..80) as the CM-730's, so one table serves both boards. Other
Protocol 1.0 servos, only to name what a wrong one reports: the numbers of ROBOTIS's DynamixelWorkbench model list
(``dynamixel_item.h``: AX-12 12, AX-18 18, AX-12W 300, RX-10 10, RX-24F 24, RX-28 28, RX-64 64, EX-106+ 107,
MX-12W 360, MX-64 310, MX-106 320).

Speed and load registers carry a magnitude in bits 0-9 and the direction in bit 10 (set: clockwise, i.e. the
servo angle decreasing); :func:`signed` and :func:`magnitude` convert.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

MX28_MODEL_NUMBER = 29
CM730_MODEL_NUMBER = 0x7300        # what the CM-730 reports at address 0 (Bold Hearts' CM730 snapshot, 0x7300)
CM740_MODEL_NUMBER = 0x7400        # ... the OP2's CM-740 (e-manual, OP2, CM-740 EEPROM area: 0x00, 0x74)
#: The sub-controllers op2motion drives an OP2 through, by the model number they report.
BOARD_MODELS = {CM730_MODEL_NUMBER: "CM-730", CM740_MODEL_NUMBER: "CM-740"}
#: Other Protocol 1.0 servos by model number (module docstring): named when one stands where an MX-28 should.
OTHER_SERVO_MODELS = {12: "AX-12", 18: "AX-18", 300: "AX-12W", 10: "RX-10", 24: "RX-24F", 28: "RX-28", 64: "RX-64",
                      107: "EX-106+", 360: "MX-12W", 310: "MX-64", 320: "MX-106"}
CM730_ID = 200                     # the sub-controller's Dynamixel ID (CM730.h ID_CM)
BAUD_NUMBER_1MBPS = 1              # baud = 2 Mbps / (n + 1)
SPEED_RPM_PER_UNIT = 0.114         # MX-28 moving / present speed unit [rpm]
SPEED_RAD_S_PER_UNIT = SPEED_RPM_PER_UNIT * 2.0 * math.pi / 60.0
LOAD_FULL_SCALE = 1023             # present load: 1023 = the most torque the motor gives (about 0.1 % a unit)
TORQUE_LIMIT_FULL = 1023           # torque limit / max torque: 1023 = all of it
DIRECTION_BIT = 0x400              # bit 10 of speed and load: clockwise (servo angle decreasing)
VOLTS_PER_UNIT = 0.1               # voltage registers [V]


@dataclass(frozen=True)
class Register:
    """One register: ``name``, ``address``, ``size`` [bytes], ``access`` ("R" or "RW"), ``default`` (None: set by
    the device at power-up), ``unit`` and the memory ``area`` ("EEPROM" kept over power cycles, "RAM")."""

    name: str
    address: int
    size: int
    access: str
    default: int | None
    unit: str
    area: str

    @property
    def end(self) -> int:
        """The address after the register."""
        return self.address + self.size


@dataclass(frozen=True)
class ControlTable:
    """A device's control table: its registers and size [bytes]; ``limits`` {name: (lowest, highest)} the values a
    write may give a register (others: whatever fits its size); ``gaps_writable`` whether a write may cover bytes of
    no register (they take what is written) or is refused with a range error."""

    device: str
    model_number: int
    size: int
    registers: tuple[Register, ...]
    limits: dict[str, tuple[int, int]] = field(default_factory=dict, repr=False, compare=False)
    gaps_writable: bool = True
    by_name: dict[str, Register] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "by_name", {r.name: r for r in self.registers})

    def limits_of(self, register: Register) -> tuple[int, int]:
        """The lowest and highest value a write may give ``register``."""
        return self.limits.get(register.name, (0, (1 << (8 * register.size)) - 1))

    def __getitem__(self, name: str) -> Register:
        try:
            return self.by_name[name]
        except KeyError:
            raise KeyError(f"{self.device} has no register {name!r}") from None

    def at(self, address: int) -> Register | None:
        """The register that starts at ``address`` (None if none does)."""
        return next((r for r in self.registers if r.address == address), None)

    def writable(self, address: int) -> bool:
        """Whether the byte at ``address`` belongs to a writable register."""
        return any(r.address <= address < r.end and r.access == "RW" for r in self.registers)

    def defaults(self) -> bytearray:
        """The table's bytes after power-up (registers without a default are 0 until the device fills them)."""
        table = bytearray(self.size)
        for r in self.registers:
            if r.default is not None:
                table[r.address:r.end] = r.default.to_bytes(r.size, "little")
        return table


def _r(name: str, address: int, size: int, access: str, default: int | None, unit: str = "",
       area: str = "RAM") -> Register:
    return Register(name, address, size, access, default, unit, area)


#: The e-manual's ranges of the MX-28's writable registers (Protocol 1.0).
MX28_LIMITS = {
    "id": (0, 253), "baud_rate": (0, 254), "return_delay_time": (0, 254), "cw_angle_limit": (0, 4095),
    "ccw_angle_limit": (0, 4095), "temperature_limit": (0, 100), "min_voltage_limit": (50, 250),
    "max_voltage_limit": (50, 250), "max_torque": (0, TORQUE_LIMIT_FULL), "status_return_level": (0, 2),
    "alarm_led": (0, 127), "alarm_shutdown": (0, 127), "resolution_divider": (1, 4), "torque_enable": (0, 1),
    "led": (0, 1), "d_gain": (0, 254), "i_gain": (0, 254), "p_gain": (0, 254), "goal_position": (0, 4095),
    "moving_speed": (0, 1023), "torque_limit": (0, TORQUE_LIMIT_FULL), "lock": (0, 1), "punch": (0, 1023),
    "goal_acceleration": (0, 254),
}

MX28 = ControlTable("MX-28", MX28_MODEL_NUMBER, 74, (
    _r("model_number", 0, 2, "R", MX28_MODEL_NUMBER, area="EEPROM"),
    _r("firmware_version", 2, 1, "R", 30, area="EEPROM"),
    _r("id", 3, 1, "RW", 1, area="EEPROM"),
    _r("baud_rate", 4, 1, "RW", 34, "2 Mbps/(n+1)", "EEPROM"),
    _r("return_delay_time", 5, 1, "RW", 250, "2 µs", "EEPROM"),
    _r("cw_angle_limit", 6, 2, "RW", 0, "tick", "EEPROM"),
    _r("ccw_angle_limit", 8, 2, "RW", 4095, "tick", "EEPROM"),
    _r("system_data2", 10, 1, "R", 0, "MX28.h only", "EEPROM"),
    _r("temperature_limit", 11, 1, "RW", 80, "°C", "EEPROM"),
    _r("min_voltage_limit", 12, 1, "RW", 60, "0.1 V", "EEPROM"),
    _r("max_voltage_limit", 13, 1, "RW", 160, "0.1 V", "EEPROM"),
    _r("max_torque", 14, 2, "RW", 1023, "1/1023 of the most", "EEPROM"),
    _r("status_return_level", 16, 1, "RW", 2, "0 ping only, 1 reads, 2 all", "EEPROM"),
    _r("alarm_led", 17, 1, "RW", 36, "error bits", "EEPROM"),
    _r("alarm_shutdown", 18, 1, "RW", 36, "error bits", "EEPROM"),
    _r("operating_mode", 19, 1, "R", 0, "MX28.h only", "EEPROM"),
    _r("multi_turn_offset", 20, 2, "RW", 0, "tick", "EEPROM"),
    _r("resolution_divider", 22, 1, "RW", 1, "", "EEPROM"),
    _r("torque_enable", 24, 1, "RW", 0),
    _r("led", 25, 1, "RW", 0),
    _r("d_gain", 26, 1, "RW", 0),
    _r("i_gain", 27, 1, "RW", 0),
    _r("p_gain", 28, 1, "RW", 32),
    _r("goal_position", 30, 2, "RW", None, "tick"),
    _r("moving_speed", 32, 2, "RW", 0, "0.114 rpm (0: as fast as it can)"),
    _r("torque_limit", 34, 2, "RW", None, "1/1023 of the most"),
    _r("present_position", 36, 2, "R", None, "tick"),
    _r("present_speed", 38, 2, "R", None, "0.114 rpm, bit 10 clockwise"),
    _r("present_load", 40, 2, "R", None, "1/1023 of the most, bit 10 clockwise"),
    _r("present_voltage", 42, 1, "R", None, "0.1 V"),
    _r("present_temperature", 43, 1, "R", None, "°C"),
    _r("registered", 44, 1, "R", 0, "1: a REG_WRITE waits for ACTION"),
    _r("pause_time", 45, 1, "R", 0, "MX28.h only"),
    _r("moving", 46, 1, "R", 0),
    _r("lock", 47, 1, "RW", 0),
    _r("punch", 48, 2, "RW", 0),
    _r("reserved4", 50, 1, "R", 0, "MX28.h only"),
    _r("reserved5", 51, 1, "R", 0, "MX28.h only"),
    _r("pot", 52, 2, "R", 0, "MX28.h only"),
    _r("pwm_out", 54, 2, "R", 0, "MX28.h only"),
    _r("p_error", 56, 2, "R", 0, "MX28.h only"),
    _r("i_error", 58, 2, "R", 0, "MX28.h only"),
    _r("d_error", 60, 2, "R", 0, "MX28.h only"),
    _r("p_error_out", 62, 2, "R", 0, "MX28.h only"),
    _r("i_error_out", 64, 2, "R", 0, "MX28.h only"),
    _r("d_error_out", 66, 2, "R", 0, "MX28.h only"),
    _r("goal_acceleration", 73, 1, "RW", 0, "8.583 °/s²"),
), MX28_LIMITS)

LED_COLOUR_MAX = 0x7FFF            # the head and eye LEDs: 5 bits each of red, green, blue (high byte at most 127)
LED_HEAD_AT_POWER_ON = 0x03E0      # CM_DXL_COM.c ProcessInit: the head LED green ...
LED_EYE_AT_POWER_ON = 0x7C00       # ... and the eye LED blue

#: The CM-730 firmware's ranges (``gbpParameterRange`` of CM_DXL_COM.c).
CM730_LIMITS = {
    "id": (0, 253), "baud_rate": (1, 254), "return_delay_time": (0, 254), "status_return_level": (0, 2),
    "dynamixel_power": (0, 1), "led_panel": (0, 7), "led_head": (0, LED_COLOUR_MAX), "led_eye": (0, LED_COLOUR_MAX),
}

CM730 = ControlTable("CM-730", CM730_MODEL_NUMBER, 90, (
    _r("model_number", 0, 2, "R", CM730_MODEL_NUMBER, area="EEPROM"),
    _r("firmware_version", 2, 1, "R", 0x0F, area="EEPROM"),
    _r("id", 3, 1, "RW", CM730_ID, area="EEPROM"),
    _r("baud_rate", 4, 1, "RW", BAUD_NUMBER_1MBPS, "2 Mbps/(n+1)", "EEPROM"),
    _r("return_delay_time", 5, 1, "RW", 0, "2 µs", "EEPROM"),
    _r("status_return_level", 16, 1, "RW", 2, "0 ping only, 1 reads, 2 all", "EEPROM"),
    _r("dynamixel_power", 24, 1, "RW", 0, "1: the servos' supply on"),
    _r("led_panel", 25, 1, "RW", 0, "bits 0-2"),
    _r("led_head", 26, 2, "RW", LED_HEAD_AT_POWER_ON, "RGB 5:5:5"),
    _r("led_eye", 28, 2, "RW", LED_EYE_AT_POWER_ON, "RGB 5:5:5"),
    _r("button", 30, 1, "R", 0, "bit 0 mode, bit 1 start"),
    _r("gyro_z", 38, 2, "R", 512, "count, 512 = 0"),
    _r("gyro_y", 40, 2, "R", 512, "count, 512 = 0"),
    _r("gyro_x", 42, 2, "R", 512, "count, 512 = 0"),
    _r("accel_x", 44, 2, "R", 512, "count, 512 = 0"),
    _r("accel_y", 46, 2, "R", 512, "count, 512 = 0"),
    _r("accel_z", 48, 2, "R", 512, "count, 512 = 0"),
    _r("voltage", 50, 1, "R", None, "0.1 V"),
    _r("left_mic", 51, 2, "R", 0),
    _r("adc2", 53, 2, "R", 0), _r("adc3", 55, 2, "R", 0), _r("adc4", 57, 2, "R", 0), _r("adc5", 59, 2, "R", 0),
    _r("adc6", 61, 2, "R", 0), _r("adc7", 63, 2, "R", 0), _r("adc8", 65, 2, "R", 0),
    _r("right_mic", 67, 2, "R", 0),
    _r("adc10", 69, 2, "R", 0), _r("adc11", 71, 2, "R", 0), _r("adc12", 73, 2, "R", 0), _r("adc13", 75, 2, "R", 0),
    _r("adc14", 77, 2, "R", 0), _r("adc15", 79, 2, "R", 0),
    _r("buzzer_data0", 81, 1, "RW", 0), _r("buzzer_data1", 82, 1, "RW", 0),
    _r("tx_remocon_data", 83, 2, "RW", 0), _r("rx_remocon_data", 85, 2, "R", 0),
    _r("rx_remocon_data_arrived", 87, 1, "R", 0), _r("zigbee_id", 88, 2, "R", 0),
), CM730_LIMITS, gaps_writable=False)

#: The framework's per-tick read of the board: 30 bytes from the power register (24..53: power, LEDs, buttons,
#: gyro, accelerometer, voltage).
BOARD_SPAN = (CM730["dynamixel_power"].address, 30)
#: The framework's per-tick sync write: 6 bytes a servo from the D gain: D, I, P, (reserved), goal low, goal high.
SYNC_SPAN = (MX28["d_gain"].address, 6)
#: A servo's status block read once per rotation: present position to present temperature (36..43).
SERVO_STATE_SPAN = (MX28["present_position"].address,
                    MX28["present_temperature"].end - MX28["present_position"].address)


def model_name(number: int) -> str | None:
    """The device a model number belongs to (``MX-28``, ``CM-740``, ``AX-12``, ...); None for one op2motion does
    not know."""
    if number == MX28_MODEL_NUMBER:
        return MX28.device
    return BOARD_MODELS.get(number) or OTHER_SERVO_MODELS.get(number)


def signed(value: int) -> int:
    """A speed or load register as a signed magnitude (counter-clockwise, the servo angle increasing, positive)."""
    magnitude = value & (DIRECTION_BIT - 1)
    return -magnitude if value & DIRECTION_BIT else magnitude


def magnitude(value: float) -> int:
    """A signed speed or load as its register value (bits 0-9 magnitude, clipped to 1023; bit 10 if negative)."""
    m = min(int(round(abs(value))), DIRECTION_BIT - 1)
    return m | DIRECTION_BIT if value < 0 and m else m


def magnitudes(values: np.ndarray) -> np.ndarray:
    """:func:`magnitude` of each of ``values`` (finite), as an int64 array."""
    m = np.minimum(np.rint(np.abs(values)), DIRECTION_BIT - 1).astype(np.int64)
    # negative and a magnitude of 1 or more (0.5 rounds to the even 0, as round does)
    out: np.ndarray = np.where(values < -0.5, m | DIRECTION_BIT, m)
    return out
