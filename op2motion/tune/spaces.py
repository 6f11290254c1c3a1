"""The search spaces ``op2motion tune`` searches by default: per walking direction for op2motion's walk, and the
stock Walking module's ``[Walking Config]`` for the stock firmware.

Each range is within what the setting allows (the preset's :data:`~op2motion.gait.params.RANGES`, the config's
keys) and around what walks today; ``--param NAME LOW HIGH`` narrows or moves one (:meth:`~.space.ParameterSpace.
narrowed`), ``--only NAME ...`` searches just those (the others keep the base preset's values).

The swing shaping keys (``swing_level``, ``swing_level_roll``, ``swing_toe_deg``) are searched only when asked for
too. The servos' P gain is not searched unless asked for (``--param p_gain 32 48``): a walk tuned on stiffer servos
leans on a setting that a simulator driving the servos by their own model, or a robot whose firmware resets it, does
not apply, and then walks on servos softer than it was tuned for (the first shipped ``fast`` walk, P 40, fell on the
soft bodies of an independent simulator that way).
"""

from __future__ import annotations

from op2motion.errors import InputError
from op2motion.tune.space import Param, ParameterSpace
from op2motion.tune.trial import Direction


def _gait(name: str, low: float, high: float, unit: str = "") -> Param:
    from op2motion.gait.params import RANGES

    return Param(name, low, high, unit, allowed=RANGES[name])


def _shared() -> tuple[Param, ...]:
    """What every direction's walk searches: timing, lift, hips, servo gain, the speed share and feedback gains."""
    return (_gait("step_s", 0.28, 0.38, "s"), _gait("double_support_ratio", 0.03, 0.25),
            _gait("step_height_m", 0.008, 0.025, "m"), _gait("hip_lower_m", 0.025, 0.055, "m"),
            _gait("swing_ramp", 0.05, 0.15), _gait("max_speed_share", 0.9, 1.2),
            _gait("gyro_gain_scale", 0.5, 2.5), _gait("gyro_stiff_share", 0.0, 2.0),
            _gait("heading_gain_scale", 0.5, 2.0))


def walk_space(direction: Direction) -> ParameterSpace:
    """The default space of op2motion's walk in ``direction`` (forward, backward, sideways, turn)."""
    stride = {"forward": (_gait("step_length_m", 0.08, 0.105, "m"), _gait("zmp_offset_x_m", -0.01, 0.01, "m"),
                          _gait("torso_pitch_deg", 0.0, 6.0, "deg")),
              "backward": (_gait("step_length_m", -0.08, -0.04, "m"), _gait("zmp_offset_x_m", -0.01, 0.01, "m")),
              "sideways": (_gait("step_side_m", 0.015, 0.035, "m"), _gait("zmp_offset_y_m", -0.01, 0.005, "m")),
              "turn": (_gait("turn_deg", 8.0, 22.0, "deg"), _gait("zmp_offset_y_m", -0.01, 0.005, "m"))}
    if direction not in stride:
        raise InputError(f"expected one of {', '.join(stride)}, got {direction!r}", "direction")
    return ParameterSpace(stride[direction] + _shared(), optional=(_gait("p_gain", 28, 48), *_swing()))


def _swing() -> tuple[Param, ...]:
    """The walk controller's swing shaping (:mod:`op2motion.gait.swing_foot`), searched only when asked for
    (``--param swing_level 0.4 1``): off in every shipped preset that was tuned without it."""
    return (_gait("swing_level", 0.4, 1.0), _gait("swing_level_roll", 0.0, 1.0),
            _gait("swing_toe_deg", 0.0, 8.0, "deg"))


def stock_space() -> ParameterSpace:
    """The default space of the stock Walking module: the forward amplitude it is tuned for and the config keys that
    shape its step and hold it (``[op2motion] x_move_amplitude_mm`` and ``[Walking Config]`` keys by their attribute
    names; the P gain only when asked for, see the module docstring)."""
    from op2motion.gait.stock_config import KEYS, OWN_KEYS

    allowed = {name: (low, high) for name, low, high, _ in (*KEYS.values(), *OWN_KEYS.values())}

    def key(name: str, low: float, high: float, unit: str = "") -> Param:
        return Param(name, low, high, unit, allowed=allowed[name])

    return ParameterSpace((key("x_move_amplitude_mm", 25.0, 45.0, "mm"), key("period_time_ms", 480.0, 700.0, "ms"),
                        key("dsp_ratio", 0.05, 0.3), key("step_fb_ratio", 0.1, 0.4),
                        key("foot_height_mm", 20.0, 45.0, "mm"), key("swing_right_left_mm", 10.0, 30.0, "mm"),
                        key("swing_top_down_mm", 0.0, 10.0, "mm"), key("pelvis_offset_deg", 0.0, 6.0, "deg"),
                        key("x_offset_mm", -20.0, 5.0, "mm"), key("z_offset_mm", 15.0, 35.0, "mm"),
                        key("hip_pitch_offset_deg", 8.0, 18.0, "deg"), key("yaw_offset_deg", -3.0, 3.0, "deg"),
                        key("balance_knee_gain", 0.0, 0.6), key("balance_ankle_pitch_gain", 0.3, 1.5),
                        key("balance_hip_roll_gain", 0.2, 1.0), key("balance_ankle_roll_gain", 0.4, 1.6),
                        key("arm_swing_gain", 0.0, 2.5, "deg/mm")),
                       optional=(key("p_gain", 24.0, 64.0, "MX-28 P"),))
