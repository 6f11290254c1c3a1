"""What the ROBOTIS framework fixes and op2motion follows: its motion timer's period and its servo gains.

The OP2 Linux framework (``MotionManager``, ``Action.cpp``) calls its motion modules every
:data:`CONTROL_PERIOD_S`: goals go to the servos every 8 ms, an action page plays one step of its profile per call,
an action file counts time in 8 ms units, and op2motion's planners and physics loop run on the same clock.

Each servo's P gain comes from a compliance byte, ``P = (256 >> n) << 2`` with ``n`` its high (clockwise) nibble
(ROBOTIS writes both nibbles equal): 0x55 -> 32 (the default), 0x44 -> 64, 0x66 -> 16, 0x77 -> 8; a nibble of 9 or
more gives 0.
"""

from __future__ import annotations

from op2motion.errors import InputError

CONTROL_PERIOD_S = 0.008       # one call of the framework's motion timer: goals every 8 ms
MIN_SEGMENT_S = 3 * CONTROL_PERIOD_S   # the shortest step the robot moves (24 ms)
MAX_SEGMENT_S = 60.0           # op2motion's cap on one step's duration or pause [s]
MAX_MOTION_S = 300.0           # ... on a whole motion's durations and pauses [s] (40 min took 88 s and 856 MB)
MAX_MOTION_POSES = 2500        # ... and on its poses (a 60-s hand line is written as 2500 steps of 24 ms)
DEFAULT_COMPLIANCE = 0x55      # the compliance byte of a reset action page and of the framework's default
MAX_BYTE = 0xFF


def p_gain_of_slope(slope: int) -> int:
    """The MX-28 P gain a compliance byte sets (its clockwise nibble)."""
    if not 0 <= slope <= MAX_BYTE:
        raise InputError(f"expected a compliance byte 0..255, got {slope!r}", "slope")
    return (256 >> (slope >> 4)) << 2


DEFAULT_P_GAIN = p_gain_of_slope(DEFAULT_COMPLIANCE)   # 32


def slope_of_p_gain(p_gain: int) -> int:
    """The compliance byte (both nibbles equal) whose P gain is ``p_gain``: 32 -> 0x55."""
    for n in range(1, 8):
        if (256 >> n) << 2 == p_gain:
            return n << 4 | n
    raise InputError(f"expected a P gain an action page can carry (256, 128, 64, 32, 16, 8 or 4), got {p_gain}",
                     "p_gain")


# The framework's own servo constants (MX28.cpp, Kinematics.h, v1.6.0; ../shared/reference/op2_facts.md sections 1
# and 3); its leg lengths are the spec's ``[framework]`` table.
FRAMEWORK_TICKS_PER_DEG = 11.378    # MX28::RATIO_ANGLE2VALUE (4096/360, rounded): angle -> ticks, truncated
EYE_TILT_OFFSET_DEG = 40.0          # the head tilt at which the camera looks level (Kinematics.h)
