"""What the robot commands will not do, by name: the thresholds and the policy when something goes wrong.

Before anything is driven (:func:`refuse_other_models`): the board reports the model number of a CM-730 or a CM-740
and every servo that of the MX-28; a device of another model is refused, naming its ID, its joint and what it
reported (:class:`WrongModel`, exit 2, whatever ``--force`` says: op2motion's tables, ticks and limits are the
MX-28's).

Before a motion (:func:`preflight`): every servo answers, none reports an error (a status packet with error bits is
an answer: the bits are named), none is at or above :data:`HOT_START_C`, and the supply (board and servos) is at
least the MX-28's lowest rated voltage (the spec's ``operating_voltage_v``, 10 V): otherwise the motion is refused,
naming the joint and its ID (exit 1).

During a motion (:class:`Watch`, every 8 ms tick), a fault stops it:

* a servo that misses :data:`BLIND_TICKS` reads in a row (40 ms blind; each missed read holds its last value);
* a status error bit of :data:`STOP_ERRORS` (overheating, overload, input voltage), or a temperature of
  :data:`HOT_STOP_C` or more (each servo's full state is read every 20 ticks, in turn);
* the serial port failing (:class:`~op2motion.errors.PortFailed`: the USB cable pulled, a bridge that ended): the
  run ends at once (:data:`PORT_FAILED`; nothing reaches the servos any more: they hold the last goals they got);
* a fall: the torso tilted beyond :data:`FALL_TILT_RAD` (the accelerometer's gravity, low-passed over
  :data:`TILT_TAU_S`), or the framework's own test (the fore-aft count beyond FALLEN_F/B_LIMIT over 30 ticks);
  not for a controller that deals with falls itself (``handles_falls``: a supervisor lets the robot land with the
  torque limits lowered, gets it up and walks on).

The policy (:data:`HOLD`): the goals stop where they are (a walk first reaches its next double support, at most a
step away, so it stops on both feet) and stay held with the torque on: torque is never dropped under a standing
robot unless the user asks (``robot read --limp``). A fall lowers every servo's torque limit to
:data:`FALL_TORQUE_LIMIT` while it lasts (the gears take the impact softly), then the goals go to where the joints
are and the limit back up. Goals are always clipped to the joints' mechanical ranges (:func:`clip_goals`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from op2motion.bus.tables import BOARD_MODELS, CM730_ID, MX28_MODEL_NUMBER, model_name
from op2motion.errors import CheckFailed, InputError, PortFailed
from op2motion.jsonout import JsonObject
from op2motion.robot.imu import ARM_TILT_RAD, FALL_TILT_RAD, FallWatch, attitude
from op2motion.robot.joints import joint_range
from op2motion.robot.spec import ImuSpec, Spec

HOT_START_C = 70                   # a servo this hot (or hotter) refuses to start a motion
HOT_STOP_C = 75                    # ... and stops one (the MX-28 shuts itself down at 80 °C by default)
BLIND_TICKS = 5                    # missed reads in a row (5 x 8 ms = 40 ms blind) stop the motion
STOP_ERRORS = ("overheating", "overload", "input voltage")
TILT_TAU_S = 0.1                   # low-pass of the accelerometer before its tilt is taken (steps' impacts)
FALL_TORQUE_LIMIT = 300            # every servo's torque limit while falling (of 1023)
FALL_SETTLE_S = 1.0                # after a fall is seen, this long at the low limit before the goals relax
RANGE_SLACK_RAD = math.radians(1.0)   # a reading this far beyond a joint's mechanical range is held at the range's
                                      # end when the torque goes on (a tick or two of wear); further is refused
PORT_FAILED = "port failed"        # the fault of a run whose serial port failed
HOLD = "hold"                      # the stop policy: hold the goals (a walk: on both feet)
POLICIES = (HOLD,)
WRONG_MODEL = "wrong model"        # the kind of a fault for a device of another model


@dataclass(frozen=True)
class Fault:
    """Why a motion stopped or may not start: ``kind`` (``not answering``, an error bit's name or several joined,
    ``hot``, ``fell``, :data:`WRONG_MODEL`), the joint and servo ID (None for the board or the whole robot), the
    details in words, and ``reports``: what the device said of itself, when that is the fault (its error bits, its
    model number), told as ``<who> reports <reports>``."""

    kind: str
    joint: str | None
    id: int | None
    detail: str
    reports: str = ""

    def describe(self) -> str:
        """``r_knee (ID 13): overheating (84 °C)``; ``r_knee (ID 13) reports errors: overload, instruction``;
        ``the serial port failed: ...``."""
        if self.kind == PORT_FAILED:
            return f"the serial port failed: {self.detail}"
        who = f"{self.joint} (ID {self.id})" if self.joint else (f"the sub-controller (ID {self.id})" if self.id else
                                                                "the robot")
        if self.reports:
            return f"{who} reports {self.reports}"
        return f"{who}: {self.kind}" + (f" ({self.detail})" if self.detail else "")

    def as_dict(self) -> JsonObject:
        """JSON-ready."""
        return {"kind": self.kind, "joint": self.joint, "id": self.id, "detail": self.detail,
                "text": self.describe()}


def after_fault(fault: Fault) -> str:
    """What the robot does after ``fault`` stopped a motion (the policy, in words for the person watching)."""
    if fault.kind == "fell":
        return (f"the servos' torque limits went down to {FALL_TORQUE_LIMIT} of 1023 while it fell, then the servos "
                f"hold the joints where it lies (torque on)")
    if fault.kind == "not answering" and fault.id == 200:
        return "the servos hold their last goals (torque on); the IMU is not read, so a fall would not be seen"
    return "the servos hold their last goals (torque on; a walk first reached both feet)"


def port_fault(error: PortFailed) -> Fault:
    """The fault of a run that ``error`` ended (its message names the port)."""
    return Fault(PORT_FAILED, None, None, error.message)


class Refused(CheckFailed):
    """A motion refused before it started (preflight): exit 1."""


class WrongModel(InputError):
    """A device on the bus is not what an OP2 has there (a servo not an MX-28, a board neither a CM-730 nor a
    CM-740): nothing is driven (exit 2)."""


def _model(number: int, hex_digits: bool = False) -> str:
    """``12 (AX-12?)``, ``0x7400 (CM-740)``, ``999``: a model number, with the device it may be."""
    name = model_name(number)
    text = f"{number:#06x}" if hex_digits else str(number)
    return f"{text} ({name}?)" if name else text


def board_model_problem(model_number: int) -> Fault | None:
    """A fault if the sub-controller's model number is neither a CM-730's nor a CM-740's."""
    if model_number in BOARD_MODELS:
        return None
    expected = " or ".join(f"the {name} ({number:#06x})" for number, name in BOARD_MODELS.items())
    return Fault(WRONG_MODEL, None, CM730_ID, f"model {model_number:#06x}",
                 f"model {_model(model_number, True)}, expected {expected}")


def model_problems(board: Any, servos: Sequence[Any]) -> list[Fault]:
    """Every device that answered with another model number than an OP2's (``board`` may be None: not read)."""
    problem = None if board is None else board_model_problem(board.model_number)
    out = [] if problem is None else [problem]
    for s in servos:
        if s.answers and s.model_number != MX28_MODEL_NUMBER:
            out.append(Fault(WRONG_MODEL, s.joint, s.id, f"model {s.model_number}",
                             f"model {_model(s.model_number)}, expected the MX-28 ({MX28_MODEL_NUMBER})"))
    return out


def refuse_other_models(board: Any, servos: Sequence[Any]) -> None:
    """Refuse (:class:`WrongModel`, exit 2) a bus with a device of another model on it, naming the first and how
    many more."""
    wrong = model_problems(board, servos)
    if wrong:
        more = f" (and {len(wrong) - 1} more)" if len(wrong) > 1 else ""
        raise WrongModel(wrong[0].describe() + more)


def errors_fault(device: int, joint: str | None, errors: Sequence[str]) -> Fault:
    """A device's status error bits, by name: ``r_knee (ID 14) reports errors: input voltage, overload``."""
    return Fault(", ".join(errors), joint, device, "status error bits",
                 f"error{'s' if len(errors) > 1 else ''}: {', '.join(errors)}")


def min_supply_v(spec: Spec) -> float:
    """The lowest supply the MX-28 is rated to work at (the spec's ``operating_voltage_v``: 10 V) [V]."""
    return spec.servo.operating_voltage_v[0]


def preflight_problems(board: Any, servos: Sequence[Any], spec: Spec) -> list[Fault]:
    """Everything that forbids starting a motion (see the module docstring), worst first: devices of another model,
    then the supply and each servo."""
    out: list[Fault] = model_problems(board, servos)
    low = min_supply_v(spec)
    if board is not None and board.voltage_v < low:
        out.append(Fault("low supply", None, 200, f"{board.voltage_v:.1f} V, below the MX-28's lowest rating "
                                                   f"{low:g} V"))
    for s in servos:
        if not s.answers:
            out.append(Fault("not answering", s.joint, s.id, "no reply to a read"))
            continue
        if s.model_number != MX28_MODEL_NUMBER:
            continue                                    # its registers are not an MX-28's: nothing more to read
        if s.errors:
            out.append(errors_fault(s.id, s.joint, s.errors))
        if s.temperature_c >= HOT_START_C:
            out.append(Fault("hot", s.joint, s.id, f"{s.temperature_c} °C, at or above {HOT_START_C} °C"))
        if s.voltage_v < low:
            out.append(Fault("low supply", s.joint, s.id, f"{s.voltage_v:.1f} V, below {low:g} V"))
        beyond = out_of_range(s.joint, s.position_rad, spec)
        if beyond:
            out.append(Fault("out of range", s.joint, s.id, beyond))
    return out


def out_of_range(joint: str, position_rad: float, spec: Spec) -> str:
    """Why a servo reading ``position_rad`` [rad] must not get the torque on (beyond its joint's mechanical range by
    more than :data:`RANGE_SLACK_RAD`: holding it there is a goal outside the range, and the first goal inside it a
    jump), in words; "" if it may."""
    names = spec.joint_names
    if joint not in names:
        return ""
    lower, upper = joint_range(spec.joints[names.index(joint)], "mechanical")
    if lower - RANGE_SLACK_RAD <= position_rad <= upper + RANGE_SLACK_RAD:
        return ""
    return (f"reads {math.degrees(position_rad):+.1f}°, outside its mechanical range {math.degrees(lower):+.1f}° to "
            f"{math.degrees(upper):+.1f}°: the torque stays off there; bring the joint into range by hand (robot read "
            f"--limp) or check the servo's horn and ID")


def preflight(board: Any, servos: Sequence[Any], spec: Spec) -> None:
    """Refuse a motion the robot is not fit to start: a device of another model (:class:`WrongModel`, exit 2), else
    any problem (:class:`Refused`, exit 1), naming the first and how many more."""
    refuse_other_models(board, servos)
    problems = preflight_problems(board, servos, spec)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise Refused("refused to start: " + problems[0].describe() + more)


def mechanical_bounds(spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """The joints' mechanical ranges (lower (20,), upper (20,)) [rad]."""
    lower, upper = zip(*(joint_range(j, "mechanical") for j in spec.joints))
    return np.array(lower), np.array(upper)


def clip_goals(goals: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Goals (20,) [rad] within the mechanical ranges, and which joints were clipped (bool (20,))."""
    clipped = np.minimum(np.maximum(goals, lower), upper)
    return clipped, clipped != goals


class Watch:
    """The per-tick checks of a running motion (see the module docstring)."""

    def __init__(self, spec: Spec, imu: ImuSpec, dt: float, ids: Sequence[int], joints: Sequence[str],
                 falls: bool = True):
        self.spec, self.dt, self.falls = spec, dt, falls
        self.ids, self.joints = tuple(ids), tuple(joints)
        self.missed = {d: 0 for d in (200, *self.ids)}
        self.fall = FallWatch(imu)
        self.gravity: np.ndarray | None = None
        self.armed = False
        self.tilt_rad = 0.0

    def _joint(self, device: int) -> str | None:
        return self.joints[self.ids.index(device)] if device in self.ids else None

    def reads(self, answered: set[int], asked: set[int] | None = None) -> Fault | None:
        """Count the missed reads of this tick (of the devices ``asked``, default all); a fault once a device has
        missed :data:`BLIND_TICKS` reads in a row."""
        for device in self.missed if asked is None else asked & self.missed.keys():
            self.missed[device] = 0 if device in answered else self.missed[device] + 1
        for device, n in self.missed.items():
            if n >= BLIND_TICKS:
                return Fault("not answering", self._joint(device), device,
                             f"{n} reads in a row missed ({n * self.dt * 1000:.0f} ms blind)")
        return None

    def status(self, device: int, errors: Sequence[str], temperature_c: int | None = None) -> Fault | None:
        """A servo's error bits (every tick) and temperature (when read): a fault if it must stop the motion."""
        stop = [e for e in errors if e in STOP_ERRORS]
        if stop:
            hot = temperature_c is not None and "overheating" in stop
            detail = f"{temperature_c} °C" if hot else "status error bit"
            return Fault(", ".join(stop), self._joint(device), device, detail)
        if temperature_c is not None and temperature_c >= HOT_STOP_C:
            return Fault("overheating", self._joint(device), device, f"{temperature_c} °C, at or above "
                                                                      f"{HOT_STOP_C} °C")
        return None

    def body(self, accel_m_s2: np.ndarray, words: dict[int, int]) -> Fault | None:
        """The IMU of this tick: a fault if the robot falls (only once it has been upright: a get-up from lying
        does not count as a fall)."""
        accel = np.asarray(accel_m_s2, dtype=float)
        blend = self.dt / (TILT_TAU_S + self.dt)
        self.gravity = accel.copy() if self.gravity is None else self.gravity + blend * (accel - self.gravity)
        self.tilt_rad = attitude(self.gravity)[2]
        framework = self.fall.add(words)
        if not self.falls:                              # the controller deals with falls (a supervisor)
            return None
        if not self.armed:
            self.armed = self.tilt_rad < ARM_TILT_RAD
            if self.armed:
                self.fall.samples.clear()               # the window must not hold the time it lay
            return None
        if self.tilt_rad > FALL_TILT_RAD:
            return Fault("fell", None, None, f"torso tilted {math.degrees(self.tilt_rad):.0f}° (limit "
                                             f"{math.degrees(FALL_TILT_RAD):.0f}°)")
        if framework is not None:
            side = "face down" if framework == "front" else "face up"
            return Fault("fell", None, None, f"{side}: the framework's accelerometer test (FALLEN_F/B_LIMIT)")
        return None
