"""Gait parameters: one frozen dataclass, read from a preset TOML file (``walking/NAME.toml``) or built in code.

Every key carries its unit in its name. A step is one foot placement; the walking direction and speed come from
what the body advances per step (``step_length_m`` forward, ``step_side_m`` to the left, ``turn_deg`` to the
left), so the mean speed is about ``step_length_m / step_s``. Keys (defaults in :data:`DEFAULTS`):

==========================  ====================================================================================
``name``                    the gait's name (text)
``steps``                   foot placements, the last one closing the feet side by side
``step_length_m``           forward advance of the body per step [m] (negative: backward)
``step_side_m``             sideways advance per step [m] (positive: left)
``turn_deg``                turn per step [deg] (positive: left, counter-clockwise seen from above)
``step_width_m``            distance between the feet centres, side by side [m]; 0: the spec's hip width
``step_s``                  time of one step [s]: single support then double support
``double_support_ratio``    share of ``step_s`` on both feet
``step_height_m``           swing foot's highest lift above the floor [m]
``swing_ramp``              share of the swing the foot spends speeding up (and again slowing down) between lift-off
                            and its cruise; its peak speed is 1 / (1 - ramp) times the mean
``swing_settle``            share of the swing, at its end, in which the foot only descends: it is over its place
                            before it lands, so a touchdown a little early (sagging servos, a tilted body) loses
                            no stride
``hip_lower_m``             how far the hips sit below their straight-leg height [m]
``com_height_m``            the pendulum height [m]; 0 takes it from the model at the gait's standing pose
``torso_pitch_deg``         forward lean of the torso [deg]
``zmp_offset_x_m``          planned ZMP forward of the sole centre in single support [m]
``zmp_offset_y_m``          planned ZMP towards the other foot from the sole centre [m]
``preview_s``               preview horizon of the ZMP controller [s]
``zmp_weight``              weight of the ZMP tracking error in the preview controller's cost [1/m²]
``jerk_weight``             weight of the CoM jerk [s⁶/m²]
``zmp_passes``              multibody ZMP correction passes (pinocchio) after the pendulum plan
``arm_swing_deg``           shoulder pitch swing, forward and back, per unit of stride [deg]
``start_s``                 double support before the first step (the CoM moves over the first support foot) [s]
``end_s``                   double support after the last step (the CoM comes back to the middle) [s]
``p_gain``                  the servos' P gain during the walk (the framework's default is 32)
``servo_feedforward``       lead each goal by the servo model's inverse: the planned joint torque (inverse
                            dynamics with the planned contacts, plus the servo's damping, rotor inertia and
                            friction) over its stiffness Kp, so the joints sag and lag onto the plan (true/false)
``max_speed_share``         the fastest a planned joint may move, as a share of the MX-28's no-load speed (0.9:
                            past it a loaded servo saturates and lags; a tuned preset may state more, up to 1.25,
                            when it was proven across the robustness family in both engines with the servo model's
                            torque-speed line: the joint then lags its plan through the swing's peak, and the walk
                            holds anyway)
``gyro_gain_scale``         the walk controller's gyro damping gains times this (1: its own)
``gyro_stiff_share``        how much the gyro damping gains fall on servos measured stiffer than the model: the
                            gains over (measured stiffness) to this power (0: not at all; 1: the damping torque,
                            gain times stiffness, stays the model's), since the damping that holds soft servos
                            makes stiff ones oscillate
``heading_gain_scale``      the walk controller's heading loop gains times this (1: its own)
``swing_level``             share of the torso's measured pitch error the swing leg is solved against, so that its
                            sole stays level and at its planned place in the world (0: off, the sole follows the
                            torso; :mod:`.swing_foot`)
``swing_level_roll``        the same for the torso's roll error
``swing_toe_deg``           the swing sole's toe raised by this much at mid swing [deg] (0: flat)
==========================  ====================================================================================
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

from op2motion.errors import InputError
from op2motion.robot.framework import CONTROL_PERIOD_S, DEFAULT_P_GAIN

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

MIN_STEP_WIDTH_M = 0.06     # narrower side-by-side feet would overlap (the OP2's soles reach 23 mm inwards)


@dataclass(frozen=True)
class GaitParams:
    """The parameters of one gait (see the module docstring for units)."""

    name: str = "gait"
    steps: int = 20
    step_length_m: float = 0.0
    step_side_m: float = 0.0
    turn_deg: float = 0.0
    step_width_m: float = 0.0
    step_s: float = 0.3
    double_support_ratio: float = 0.2
    step_height_m: float = 0.03
    swing_ramp: float = 0.3
    swing_settle: float = 0.0
    hip_lower_m: float = 0.02
    com_height_m: float = 0.0
    torso_pitch_deg: float = 0.0
    zmp_offset_x_m: float = 0.0
    zmp_offset_y_m: float = 0.0
    preview_s: float = 1.6
    zmp_weight: float = 1.0
    jerk_weight: float = 1e-6
    zmp_passes: int = 2
    arm_swing_deg: float = 0.0
    start_s: float = 0.8
    end_s: float = 0.8
    p_gain: int = DEFAULT_P_GAIN
    servo_feedforward: bool = True
    max_speed_share: float = 0.9
    gyro_gain_scale: float = 1.0
    gyro_stiff_share: float = 0.0
    heading_gain_scale: float = 1.0
    swing_level: float = 0.0
    swing_level_roll: float = 0.0
    swing_toe_deg: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "servo_feedforward":
                if not isinstance(value, bool):
                    raise InputError(f"expected true or false, got {value!r}", f.name)
                continue
            if f.name == "name":
                if not isinstance(value, str) or not value:
                    raise InputError(f"expected a non-empty text, got {value!r}", "name")
                continue
            low, high = RANGES[f.name]
            whole = f.type in ("int", int)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or (whole and value != int(value)):
                raise InputError(f"expected {'a whole number' if whole else 'a number'}, got {value!r}", f.name)
            if not (math.isfinite(value) and low <= value <= high):
                raise InputError(f"expected {low:g} to {high:g}, got {value!r}", f.name)
        if 0.0 < self.step_width_m < MIN_STEP_WIDTH_M:
            raise InputError(f"expected 0 (the hip width) or {MIN_STEP_WIDTH_M:g} to 0.14 m, got "
                             f"{self.step_width_m!r}", "step_width_m")
        if self.double_support_ratio * self.step_s < CONTROL_PERIOD_S - 1e-12:
            raise InputError(f"expected at least one 8 ms tick of double support, got {self.double_support_ratio:g} "
                             f"x {self.step_s:g} s", "double_support_ratio")

    @property
    def single_s(self) -> float:
        """Single-support time of a step [s]."""
        return self.step_s * (1.0 - self.double_support_ratio)

    @property
    def double_s(self) -> float:
        """Double-support time of a step [s]."""
        return self.step_s * self.double_support_ratio

    @property
    def turn_rad(self) -> float:
        """Turn per step [rad]."""
        return math.radians(self.turn_deg)

    def with_steps(self, steps: int | None) -> "GaitParams":
        """These parameters with ``steps`` foot placements (unchanged for None)."""
        return self if steps is None else replace(self, steps=steps)


#: Allowed range of every numeric key (inclusive).
RANGES: dict[str, tuple[float, float]] = {
    "steps": (1, 200), "step_length_m": (-0.1, 0.12), "step_side_m": (-0.05, 0.05), "turn_deg": (-30.0, 30.0),
    "step_width_m": (0.0, 0.14), "step_s": (0.2, 2.0), "double_support_ratio": (0.0, 0.6),
    "step_height_m": (0.005, 0.06), "swing_ramp": (0.05, 0.5), "swing_settle": (0.0, 0.4),
    "hip_lower_m": (0.0, 0.06), "com_height_m": (0.0, 0.4),
    "torso_pitch_deg": (-10.0, 30.0), "zmp_offset_x_m": (-0.03, 0.03), "zmp_offset_y_m": (-0.02, 0.02),
    "preview_s": (0.4, 3.0), "zmp_weight": (1e-6, 1e6), "jerk_weight": (1e-12, 1.0), "zmp_passes": (0, 5),
    "arm_swing_deg": (0.0, 40.0), "start_s": (0.2, 5.0), "end_s": (0.2, 5.0), "p_gain": (1, 254),
    "max_speed_share": (0.5, 1.25), "gyro_gain_scale": (0.0, 3.0), "gyro_stiff_share": (0.0, 3.0),
    "heading_gain_scale": (0.0, 3.0),
    "swing_level": (0.0, 1.0), "swing_level_roll": (0.0, 1.0), "swing_toe_deg": (0.0, 15.0),
}
DEFAULTS = GaitParams()


def params_from_mapping(doc: Any, where: str = "<preset>") -> GaitParams:
    """Gait parameters from a TOML table; unknown keys and wrong types are errors naming ``where``."""
    if not isinstance(doc, dict):
        raise InputError(f"expected a table of gait keys in {where}, got {type(doc).__name__}", "preset")
    known = {f.name for f in fields(GaitParams)}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise InputError(f"expected only the keys {', '.join(sorted(known))} in {where}, got {', '.join(unknown)}",
                         "preset")
    try:
        return GaitParams(**doc)
    except InputError as e:
        raise InputError(f"{where}: {e.param}: {e.message}", "preset") from None


def read_preset(path: str | Path) -> GaitParams:
    """The gait of a preset file ``walking/NAME.toml`` (its name defaults to the file's stem)."""
    from op2motion.fileio import read_text

    path = Path(path)
    try:
        doc = tomllib.loads(read_text(path, "gait preset file"))
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"expected TOML in {str(path)!r}, got an error: {e}", "preset") from None
    doc.setdefault("name", path.stem)
    return params_from_mapping(doc, str(path))


def preset_text(params: GaitParams, header: list[str]) -> str:
    """A gait preset TOML: ``header`` as comments, then every key of ``params`` in order."""
    lines = [f"# {h}" if h else "#" for h in header]
    for f in fields(params):
        value = getattr(params, f.name)
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, str):
            text = '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
        elif isinstance(value, int):
            text = str(value)
        else:
            text = f"{value:.6g}" if "e" not in f"{value:.6g}" else repr(float(value))
            if "." not in text and "e" not in text:
                text += ".0"
        lines.append(f"{f.name} = {text}")
    return "\n".join(lines) + "\n"
