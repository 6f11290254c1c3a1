"""The stock ROBOTIS Walking module, emulated tick for tick: what the framework (v1.6.0, ``Walking.cpp``) sends the
servos every 8 ms for a :class:`~.stock_config.StockConfig` and the commanded step.

The generator (facts restated in ``../shared/reference/op2_facts.md`` section 5):

* **Clock**: walking time runs in 8 ms units over one period (two steps) and wraps. The left foot swings over
  ``[(1-s)T/4, (1+s)T/4]`` and the right over ``[(3-s)T/4, (3+s)T/4]`` (``s`` = 1 - the double-support share).
  Settings are latched at phases: the timing at the period's start and in the middle double support, the commanded
  step in the middle of each swing; after :meth:`StockWalking.stop` the step is zeroed at the next timing latch and
  the walk halts at the one after.
* **Foot end-points** (mm and rad, each foot in its own hip frame, z up from the straight leg): a body sway common
  to both feet (fore-aft ``X_MOVE x step_forward_back_ratio`` at half the period, sideways ``swing_right_left`` at
  the period, up-down ``swing_top_down`` at half the period) plus each foot's move, half a sine across its swing
  window and held outside it, plus the offsets (``x_offset``, ``±y_offset/2``, ``z_offset``, roll, pitch, yaw).
  The swing foot rises ``foot_height`` and comes back within its window.
* **Joints**: the framework's closed-form leg IK (here :func:`op2motion.kinematics.leg_ik.leg_ik` on a leg with the
  framework's own lengths, ``Kinematics.h``: the firmware uses them whatever robot it runs on), then ticks with the
  framework's truncations (``(int)(angle x 11.378)``): the hip pitches lean forward by ``hip_pitch_offset``; a
  sine bump adds ``pelvis_offset`` to the support hip's roll (0.35 of it to the swing hip's) during single support;
  the shoulder pitches swing ``arm_swing_gain`` deg per mm of forward step about the stock arm pose.
* **Gyro balance** (:meth:`StockWalking.tick` with the gyro in counts from the centre, as ``MotionStatus`` has them):
  hip roll += roll·hip_roll_gain·4, knee and ankle pitch -= pitch·gain·4, ankle roll -= roll·ankle_roll_gain·4
  (ticks, times each joint's direction).

The output is ticks for the walking joints (legs and shoulder pitches) and the P gains the module sets (legs
``p_gain``, arms 8); :func:`ticks_of_stance` gives the stance before the first step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from op2motion.gait.stock_config import StockConfig
from op2motion.kinematics.leg_ik import Leg, leg_ik, leg_of, rot_x, rot_y, rot_z
from op2motion.robot.framework import CONTROL_PERIOD_S, FRAMEWORK_TICKS_PER_DEG
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side

TIME_UNIT_MS = CONTROL_PERIOD_S * 1000.0
CENTER_TICK, MAX_TICK = 2048, 4095
ARM_P_GAIN = 8                       # the Walking constructor's P gain of the arm servos
#: The joints the module drives, in its own order, and the direction of each (Walking.cpp ``dir``).
JOINTS = ("r_hip_yaw", "r_hip_roll", "r_hip_pitch", "r_knee", "r_ank_pitch", "r_ank_roll", "l_hip_yaw", "l_hip_roll",
          "l_hip_pitch", "l_knee", "l_ank_pitch", "l_ank_roll", "r_sho_pitch", "l_sho_pitch")
DIRECTION = (-1, -1, 1, 1, -1, 1, -1, -1, -1, -1, 1, 1, 1, -1)
#: The stock arm pose (Walking constructor) [deg]: shoulder pitch (the swing's centre), shoulder roll, elbow.
ARM_POSE_DEG = {"r_sho_pitch": -48.345, "l_sho_pitch": 41.313, "r_sho_roll": -17.873, "l_sho_roll": 17.580,
                "r_el": 29.300, "l_el": -29.593}
_HIP_ROLL, _HIP_PITCH, _KNEE, _ANKLE_PITCH, _ANKLE_ROLL = 1, 2, 3, 4, 5


def angle_to_tick(degrees: float) -> int:
    """``MX28::Angle2Value``: degrees to a goal tick, truncated as the framework does."""
    return int(degrees * FRAMEWORK_TICKS_PER_DEG) + CENTER_TICK


def _wsin(t: float, period: float, shift: float, mag: float, mag_shift: float) -> float:
    """The module's sine: ``mag sin(2π t / period - shift) + mag_shift``."""
    return mag * math.sin(2.0 * math.pi / period * t - shift) + mag_shift


@dataclass
class _Latched:
    """What the module copies from its settings at its phases: the timing and the commanded step."""

    period: float = 600.0
    ssp: float = 0.9
    x_move: float = 0.0
    y_move: float = 0.0
    y_shift: float = 0.0
    a_move: float = 0.0
    a_shift: float = 0.0

    @property
    def start_l(self) -> float:
        return (1.0 - self.ssp) * self.period / 4.0

    @property
    def end_l(self) -> float:
        return (1.0 + self.ssp) * self.period / 4.0

    @property
    def start_r(self) -> float:
        return (3.0 - self.ssp) * self.period / 4.0

    @property
    def end_r(self) -> float:
        return (3.0 + self.ssp) * self.period / 4.0


@dataclass(frozen=True)
class StockTick:
    """One tick's output: goal ticks {joint: tick} of the joints the module drives and their P gains {joint: P};
    ``swinging``: the foot in its swing window ("left", "right" or None); ``time_ms``: the walking time it was
    computed at."""

    ticks: dict[str, int]
    p_gains: dict[str, int]
    swinging: str | None
    time_ms: float


def framework_leg(spec: Spec, side: Side) -> Leg:
    """The ``side`` leg as the framework's IK sees it: the spec's joint order and directions, the framework's
    lengths (the spec's ``[framework]`` table; the shipped spec's when a spec states none), the hip at the origin."""
    lengths = spec.framework_leg_m
    if lengths is None:
        from op2motion.robot.specfile import default_spec

        lengths = default_spec().framework_leg_m
    if lengths is None:
        from op2motion.errors import SpecError

        raise SpecError("expected a [framework] table (the firmware's leg lengths) in the spec", spec.path)
    thigh, calf, ankle = lengths
    return replace(leg_of(spec, side), hip=np.zeros(3), thigh=thigh, calf=calf, ankle_to_sole=ankle)


class StockWalking:
    """The Walking module's state and generator (see the module docstring); ``command`` and ``start``/``stop`` as
    the framework's ``X/Y/A_MOVE_AMPLITUDE`` and ``Start()``/``Stop()``; :meth:`tick` is one ``Process()``."""

    def __init__(self, config: StockConfig, spec: Spec):
        self.config, self.spec = config, spec
        self._legs = {side: framework_leg(spec, side) for side in ("right", "left")}
        self.x_move_mm = self.y_move_mm = self.a_move_deg = 0.0
        self.ctrl_running = self.real_running = False
        self.time_ms = 0.0
        self._latched = _Latched()
        self._last: dict[str, int] = {}
        self._latch_time()
        self._latch_move()
        self._last = self._ticks(0.0, 0.0)[0]

    # -- the framework's controls ----------------------------------------------------------------------------------
    def command(self, x_mm: float, y_mm: float = 0.0, a_deg: float = 0.0) -> None:
        """The step to walk: forward [mm] (X_MOVE_AMPLITUDE), sideways [mm] (Y_MOVE), turn [deg] (A_MOVE); taken at
        the next swing's middle."""
        self.x_move_mm, self.y_move_mm, self.a_move_deg = float(x_mm), float(y_mm), float(a_deg)

    def start(self) -> None:
        """``Walking::Start()``."""
        self.ctrl_running = self.real_running = True

    def stop(self) -> None:
        """``Walking::Stop()``: the step is zeroed at the next timing latch, the walk halts at the one after."""
        self.ctrl_running = False

    # -- latches -----------------------------------------------------------------------------------------------------
    def _latch_time(self) -> None:
        self._latched.period = self.config.period_time_ms
        self._latched.ssp = 1.0 - self.config.dsp_ratio

    def _latch_move(self) -> None:
        lat = self._latched
        lat.x_move = self.x_move_mm
        lat.y_move = self.y_move_mm / 2.0
        lat.y_shift = abs(lat.y_move)
        lat.a_move = math.radians(self.a_move_deg) / 2.0
        lat.a_shift = abs(lat.a_move)

    def _maybe_halt(self) -> None:
        """At a timing latch after ``stop``: zero the step, or halt once it is zero."""
        if self.ctrl_running:
            return
        lat = self._latched
        if lat.x_move == 0.0 and lat.y_move == 0.0 and lat.a_move == 0.0:
            self.real_running = False
        else:
            self.x_move_mm = self.y_move_mm = self.a_move_deg = 0.0

    def _phase(self) -> None:
        lat, t, half = self._latched, self.time_ms, TIME_UNIT_MS / 2.0
        middles = ((lat.end_l + lat.start_l) / 2.0, (lat.start_r + lat.end_l) / 2.0, (lat.end_r + lat.start_r) / 2.0)
        if t == 0.0:
            self._latch_time()
            self._maybe_halt()
        elif middles[0] - half <= t < middles[0] + half or middles[2] - half <= t < middles[2] + half:
            self._latch_move()
        elif middles[1] - half <= t < middles[1] + half:
            self._latch_time()
            self.time_ms = middles[1]
            self._maybe_halt()

    # -- one tick ------------------------------------------------------------------------------------------------------
    def tick(self, rl_gyro_counts: float = 0.0, fb_gyro_counts: float = 0.0) -> StockTick:
        """One ``Process()``: the latches, the goals at the current walking time (the last ones where the IK has no
        solution), the gyro balance (counts from the centre: roll ``RL_GYRO``, pitch ``FB_GYRO``), then the clock
        moves on while running."""
        self._phase()
        t = self.time_ms
        ticks, swinging = self._ticks(rl_gyro_counts, fb_gyro_counts)
        if self.real_running:
            self.time_ms = t + TIME_UNIT_MS
            if self.time_ms >= self._latched.period:
                self.time_ms = 0.0
        self._last = ticks
        gains = {name: (self.config.p_gain if k < 12 else ARM_P_GAIN) for k, name in enumerate(JOINTS)}
        return StockTick(dict(ticks), gains, swinging, t)

    def _endpoints(self) -> tuple[np.ndarray, np.ndarray, float, float, str | None]:
        """Both feet's end-points (x, y, z [mm], roll, pitch, yaw [rad]) (right, left), the pelvis offsets [ticks]
        (right, left) and the swinging foot at the current walking time."""
        c, lat, t = self.config, self._latched, self.time_ms
        period = lat.period
        x_period, move_period, z_period = period / 2.0, period * lat.ssp, period * lat.ssp / 2.0
        x_swap = _wsin(t, x_period, math.pi, lat.x_move * c.step_fb_ratio, 0.0)
        y_swap = _wsin(t, period, 0.0, c.swing_right_left_mm + lat.y_shift * 0.04, 0.0)
        z_swap = _wsin(t, x_period, 1.5 * math.pi, c.swing_top_down_mm, c.swing_top_down_mm)
        s_l, e_l, s_r, e_r = lat.start_l, lat.end_l, lat.start_r, lat.end_r

        def move(at: float, second: bool, amplitude: float, shift: float, per: float) -> float:
            """A foot's move at walking time ``at``: half a sine across the first (left) or second (right) window."""
            start = s_r if second else s_l
            return _wsin(at, per, math.pi / 2.0 + 2.0 * math.pi / per * start + (math.pi if second else 0.0),
                         amplitude, shift)

        # where the horizontal moves are sampled (the window, the time) and where each foot's lift is
        if t <= s_l:
            plane, z_l, z_r = (False, s_l), (s_l,), (s_r,)
        elif t <= e_l:
            plane, z_l, z_r = (False, t), (t,), (s_r,)
        elif t <= s_r:
            plane, z_l, z_r = (False, e_l), (e_l,), (s_r,)
        elif t <= e_r:
            plane, z_l, z_r = (True, t), (e_l,), (t,)
        else:
            plane, z_l, z_r = (True, e_r), (e_l,), (e_r,)
        second, at = plane
        x_l = move(at, second, lat.x_move, 0.0, move_period)
        y_l = move(at, second, lat.y_move, lat.y_shift, move_period)
        a_l = move(at, second, lat.a_move, lat.a_shift, move_period)
        x_r = move(at, second, -lat.x_move, 0.0, move_period)
        y_r = move(at, second, -lat.y_move, -lat.y_shift, move_period)
        a_r = move(at, second, -lat.a_move, -lat.a_shift, move_period)
        lift, lift_shift = c.foot_height_mm / 2.0, c.foot_height_mm / 4.0
        zl = _wsin(z_l[0], z_period, math.pi / 2.0 + 2.0 * math.pi / z_period * s_l, lift, lift_shift)
        zr = _wsin(z_r[0], z_period, math.pi / 2.0 + 2.0 * math.pi / z_period * s_r, lift, lift_shift)
        offset_ticks = c.pelvis_offset_deg * FRAMEWORK_TICKS_PER_DEG
        swing_ticks = offset_ticks * 0.35
        swinging: str | None = None
        pelvis_r = pelvis_l = 0.0
        if s_l < t <= e_l:
            swinging = "left"
            bump = math.pi / 2.0 + 2.0 * math.pi / z_period * s_l
            pelvis_l = _wsin(t, z_period, bump, swing_ticks / 2.0, swing_ticks / 2.0)
            pelvis_r = _wsin(t, z_period, bump, -offset_ticks / 2.0, -offset_ticks / 2.0)
        elif s_r < t <= e_r:
            swinging = "right"
            bump = math.pi / 2.0 + 2.0 * math.pi / z_period * s_r
            pelvis_l = _wsin(t, z_period, bump, offset_ticks / 2.0, offset_ticks / 2.0)
            pelvis_r = _wsin(t, z_period, bump, -swing_ticks / 2.0, -swing_ticks / 2.0)
        roll, pitch, yaw = (math.radians(v) for v in (c.roll_offset_deg, c.pitch_offset_deg, c.yaw_offset_deg))
        right = np.array([x_swap + x_r + c.x_offset_mm, y_swap + y_r - c.y_offset_mm / 2.0, z_swap + zr + c.z_offset_mm,
                          -roll / 2.0, pitch, a_r - yaw / 2.0])
        left = np.array([x_swap + x_l + c.x_offset_mm, y_swap + y_l + c.y_offset_mm / 2.0, z_swap + zl + c.z_offset_mm,
                         roll / 2.0, pitch, a_l + yaw / 2.0])
        return right, left, pelvis_r, pelvis_l, swinging

    def _leg_degrees(self, side: Side, end: np.ndarray) -> np.ndarray | None:
        """The module's IK angles [deg] of one leg (its own joint order, direction not yet applied: our servo angle
        over the joint's direction), or None where the foot is out of reach."""
        leg = self._legs[side]
        sole = (end[:3] - np.array([0.0, 0.0, (leg.thigh + leg.calf + leg.ankle_to_sole) * 1000.0])) / 1000.0
        rot = rot_z(end[5]) @ rot_y(end[4]) @ rot_x(end[3])
        try:
            servo = leg_ik(leg, sole[None], rot[None])[0]
        except Exception:  # noqa: BLE001 (the framework keeps the last goals when its IK has no solution)
            return None
        first = 0 if side == "right" else 6
        degrees: np.ndarray = np.degrees(servo) * np.array(DIRECTION[first:first + 6])
        return degrees

    def _ticks(self, rl_gyro: float, fb_gyro: float) -> tuple[dict[str, int], str | None]:
        c = self.config
        right, left, pelvis_r, pelvis_l, swinging = self._endpoints()
        angles = [self._leg_degrees("right", right), self._leg_degrees("left", left)]
        if angles[0] is None or angles[1] is None:
            return dict(self._last), swinging
        lat = self._latched
        arm = 0.0 if lat.x_move == 0.0 else _wsin(self.time_ms, lat.period, 1.5 * math.pi,
                                                  lat.x_move * c.arm_swing_gain, 0.0)
        degrees = [*angles[0], *angles[1], -arm, arm]
        out: dict[str, int] = {}
        for k, (name, d) in enumerate(zip(JOINTS, DIRECTION)):
            offset = d * degrees[k] * FRAMEWORK_TICKS_PER_DEG
            if k in (1, 7):
                offset += d * (pelvis_r if k == 1 else pelvis_l)
            elif k in (2, 8):
                offset -= d * c.hip_pitch_offset_deg * FRAMEWORK_TICKS_PER_DEG
            out[name] = angle_to_tick(ARM_POSE_DEG.get(name, 0.0)) + int(offset)
        for k in (0, 6):                    # the balance, per leg (right, left)
            legs = JOINTS[k:k + 6]
            dirs = DIRECTION[k:k + 6]
            out[legs[_HIP_ROLL]] += int(dirs[_HIP_ROLL] * rl_gyro * c.balance_hip_roll_gain * 4)
            out[legs[_KNEE]] -= int(dirs[_KNEE] * fb_gyro * c.balance_knee_gain * 4)
            out[legs[_ANKLE_PITCH]] -= int(dirs[_ANKLE_PITCH] * fb_gyro * c.balance_ankle_pitch_gain * 4)
            out[legs[_ANKLE_ROLL]] -= int(dirs[_ANKLE_ROLL] * rl_gyro * c.balance_ankle_roll_gain * 4)
        return {name: min(max(v, 0), MAX_TICK) for name, v in out.items()}, swinging


def ticks_of_stance(config: StockConfig, spec: Spec) -> dict[str, int]:
    """The module's goals before the first step (``Initialize()``: the stance the walk starts from and ends in),
    with the stock arm pose's shoulder rolls and elbows: {joint: tick}."""
    walk = StockWalking(config, spec)
    ticks = walk.tick().ticks
    ticks.update({name: angle_to_tick(deg) for name, deg in ARM_POSE_DEG.items() if name not in ticks})
    return ticks
