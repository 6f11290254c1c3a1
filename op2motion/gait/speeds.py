"""Plans the servos can follow: every planned joint within a share of the MX-28's no-load speed.

A position servo follows its goal no faster than its motor turns unloaded (5.76 rad/s at 12 V, 4.92 rad/s at
11.1 V: the spec's ``[[servo.rating]]`` at its supply voltage). Past about 90 % of it the loaded servo saturates,
the joint lags its plan, and the swing foot lands late and low. :func:`speed_check` measures the planned joint
angles' speeds (central differences at the 8 ms period; the servo feed-forward's slow sag offsets are left out,
they are not motion the joint makes); :func:`gait_within_speed` plans a gait and either refuses a plan past the
limit (naming the joint, its speed and the slowest step that would do) or re-times it: it lengthens the step
(``step_s``, the stride kept, so the walk is slower) until every joint is within the limit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.gait.generator import Gait, generate_gait
from op2motion.gait.params import RANGES, GaitParams
from op2motion.robot.joints import LIMIT_SLACK_RAD, joint_range
from op2motion.robot.spec import Spec

SPEED_SHARE = 0.9          # a planned joint may move at most this share of the no-load speed
RETIME_MARGIN = 1.03       # re-timing lengthens the step this much beyond the measured ratio
RETIME_TRIES = 4           # speed does not scale exactly with time (the preview plan changes): a few passes


@dataclass(frozen=True)
class SpeedCheck:
    """The fastest planned joint: its name, its peak speed [rad/s], the limit [rad/s] (``share`` of the no-load speed
    at ``voltage_v`` [V]: the preset's ``max_speed_share``) and whether the plan is within it."""

    joint: str
    peak_rad_s: float
    limit_rad_s: float
    voltage_v: float
    share: float = SPEED_SHARE

    @property
    def ok(self) -> bool:
        """Every planned joint within the limit."""
        return self.peak_rad_s <= self.limit_rad_s

    @property
    def ratio(self) -> float:
        """Peak speed over the limit (above 1: too fast)."""
        return self.peak_rad_s / self.limit_rad_s


def speed_check(gait: Gait, spec: Spec) -> SpeedCheck:
    """The fastest joint of a gait's planned angles against its preset's ``max_speed_share`` (by default
    :data:`SPEED_SHARE`) of the no-load speed."""
    speeds = np.abs(np.gradient(gait.joints, gait.dt, axis=0)) if len(gait.joints) > 1 else np.zeros_like(gait.joints)
    peaks = speeds.max(axis=0)
    worst = int(np.argmax(peaks))
    share = getattr(gait.params, "max_speed_share", SPEED_SHARE)
    return SpeedCheck(spec.joint_names[worst], float(peaks[worst]), share * spec.servo.no_load_speed_rad_s,
                      spec.servo.supply_voltage_v, share)


def too_fast_message(check: SpeedCheck, step_s: float) -> str:
    """Why a plan is refused, and the step that would do."""
    return (f"expected every joint within {check.share:.0%} of the MX-28's no-load speed ({check.limit_rad_s:.2f} "
            f"rad/s at {check.voltage_v:g} V), got {check.joint} at {check.peak_rad_s:.2f} rad/s; a step of about "
            f"{step_s * check.ratio * RETIME_MARGIN:.2f} s (the preset's step_s) would do, or re-time the plan)")


def gait_within_speed(params: GaitParams, spec: Spec, target: tuple[float, float, float] | None = None,
                      retime: bool = False, on_progress: Callable[[float, float], Any] | None = None) -> Gait:
    """:func:`~.generator.generate_gait` with the speed limit: the plan, re-timed if ``retime`` (the gait's
    ``params.step_s`` says the step it got). Raises :class:`InputError` on the preset when a joint is too fast
    (without ``retime``, or when even the longest step allowed is)."""
    gait = generate_gait(params, spec, target, on_progress)
    for _ in range(RETIME_TRIES):
        check = speed_check(gait, spec)
        if check.ok:
            return within_range(gait, spec)
        longest = RANGES["step_s"][1]
        if not retime or params.step_s >= longest:
            raise InputError(too_fast_message(check, params.step_s), "preset")
        params = replace(params, step_s=min(longest, round(params.step_s * check.ratio * RETIME_MARGIN, 3)))
        gait = generate_gait(params, spec, target, on_progress)
    check = speed_check(gait, spec)
    if not check.ok:
        raise InputError(too_fast_message(check, params.step_s), "preset")
    return within_range(gait, spec)


def within_range(gait: Gait, spec: Spec) -> Gait:
    """``gait``, if every goal lies inside its joint's mechanical range; else :class:`InputError` on the preset
    naming the joint (values each in range can still ask for the impossible together, e.g. a P gain of 1 whose
    sag compensation would turn a knee past its stop)."""
    goals = gait.goals
    lower, upper = (np.array([joint_range(j, "mechanical")[k] for j in spec.joints]) for k in (0, 1))
    beyond = np.maximum(lower - goals.min(axis=0), goals.max(axis=0) - upper)
    worst = int(np.argmax(beyond))
    if beyond[worst] > LIMIT_SLACK_RAD:
        joint = spec.joints[worst]
        got = goals[:, worst].max() if goals[:, worst].max() > upper[worst] else goals[:, worst].min()
        span = f"{np.degrees(lower[worst]):.0f}..{np.degrees(upper[worst]):.0f}°"
        raise InputError(f"expected goals inside every joint's mechanical range, got {joint.name} at "
                         f"{np.degrees(got):.0f}° (range {span}; check the preset's p_gain and hip_lower_m)", "preset")
    return gait
