"""What a steered walk may be asked: the envelope of speeds that pass the robustness family, and how fast the
speeds may change.

A command (vx [m/s] forward, vy [m/s] to the left, yaw rate [rad/s] to the left) becomes a *stride*: what the body
advances per step, in its own frame (the speed times the step time, as the stock ROBOTIS gait's X/Y/A amplitudes).
:meth:`Envelope.clamp` keeps a command inside the envelope: each axis within its measured limit (forward and backward
apart), and the axes together within :attr:`Envelope.combined` (the sum of each axis's share of its own limit):
forward at full speed while turning at full rate asks the stance leg for both at once. Where they are too much
together the turn keeps its rate and the steps shorten: a heading lost to a clamp stays lost, a shorter stride only
arrives later. :meth:`Envelope.towards`
moves one step's stride towards the commanded one within the acceleration limits.

The default limits (:data:`STEER_ENVELOPE`) are the measured ones: ``tools/steer_envelope.py`` walks each direction
at rising speeds across the robustness family in PyBullet and MuJoCo (docs/steering.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from op2motion.errors import InputError


@dataclass(frozen=True)
class Stride:
    """The body's advance in one step, in its own frame: ``dx`` forward [m], ``dy`` to the left [m], ``dyaw`` turn
    to the left [rad]."""

    dx: float = 0.0
    dy: float = 0.0
    dyaw: float = 0.0

    @property
    def still(self) -> bool:
        """No advance at all."""
        return self.dx == 0.0 and self.dy == 0.0 and self.dyaw == 0.0

    def scaled(self, share: float) -> "Stride":
        """This stride times ``share``."""
        return Stride(self.dx * share, self.dy * share, self.dyaw * share)


@dataclass(frozen=True)
class Envelope:
    """Speed limits [m/s, rad/s] (forward, backward, sideways, turning), how far the axes may combine (the sum of
    each one's share of its limit), and the acceleration limits [m/s², rad/s²] per axis."""

    forward_m_s: float
    backward_m_s: float
    sideways_m_s: float
    turn_rad_s: float
    combined: float = 1.0
    accel_x_m_s2: float = 0.4
    accel_y_m_s2: float = 0.3
    accel_yaw_rad_s2: float = 1.5

    def __post_init__(self) -> None:
        for name in ("forward_m_s", "backward_m_s", "sideways_m_s", "turn_rad_s", "combined", "accel_x_m_s2",
                     "accel_y_m_s2", "accel_yaw_rad_s2"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise InputError(f"expected a positive number, got {value!r}", name)

    def clamp(self, vx: float, vy: float, yaw_rate: float) -> tuple[float, float, float]:
        """The command (vx [m/s], vy [m/s], yaw rate [rad/s]) within the envelope: each axis to its limit, then,
        until their shares sum to at most :attr:`combined`, the translation scaled down (the turn kept), and the turn
        too if it is more than that alone."""
        for name, value in (("vx_m_s", vx), ("vy_m_s", vy), ("yaw_rate_rad_s", yaw_rate)):
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise InputError(f"expected a finite number, got {value!r}", name)
        vx = min(max(vx, -self.backward_m_s), self.forward_m_s)
        vy = min(max(vy, -self.sideways_m_s), self.sideways_m_s)
        yaw_rate = min(max(yaw_rate, -self.turn_rad_s), self.turn_rad_s)
        moving = (vx / self.forward_m_s if vx >= 0.0 else -vx / self.backward_m_s) + abs(vy) / self.sideways_m_s
        turning = abs(yaw_rate) / self.turn_rad_s
        if moving + turning <= self.combined:
            return vx, vy, yaw_rate
        if turning >= self.combined:
            return 0.0, 0.0, yaw_rate * self.combined / turning
        keep = (self.combined - turning) / moving
        return vx * keep, vy * keep, yaw_rate

    def stride(self, vx: float, vy: float, yaw_rate: float, step_s: float) -> Stride:
        """The stride of a command (clamped) for steps of ``step_s`` [s]."""
        cx, cy, cw = self.clamp(vx, vy, yaw_rate)
        return Stride(cx * step_s, cy * step_s, cw * step_s)

    def towards(self, now: Stride, target: Stride, step_s: float) -> Stride:
        """The next step's stride: from ``now`` towards ``target``, each axis changing by at most its acceleration
        limit over one step (a speed change of accel x step_s is a stride change of accel x step_s²)."""
        def move(a: float, b: float, accel: float) -> float:
            most = accel * step_s * step_s
            return a + min(max(b - a, -most), most)

        return Stride(move(now.dx, target.dx, self.accel_x_m_s2), move(now.dy, target.dy, self.accel_y_m_s2),
                      move(now.dyaw, target.dyaw, self.accel_yaw_rad_s2))


#: The envelope of the ``steer`` preset: the fastest commands that every member of the robustness family walks in
#: both engines (the commanded walk's judge), each axis alone and forward while turning (``combined``: the sum of the
#: shares of each axis's limit). How it was found and what failed beyond it: docs/steering.md
#: (``tools/steer_envelope.py`` measures it again).
STEER_ENVELOPE = Envelope(forward_m_s=0.25, backward_m_s=0.15, sideways_m_s=0.07, turn_rad_s=0.4, combined=1.15)
