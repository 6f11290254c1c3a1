"""The MX-28 servo as a physical model, shared by every physics engine (parameters: the spec's ``[servo]``).

The firmware turns the position error into a PWM duty, ``duty = clip(duty_per_p_rad * P * (q* - q), ±max_duty)``,
and the coreless DC motor behind the 193:1 gearbox gives, at the supply's rating (stall torque, no-load speed),

    tau = stall * duty - Kd_emf * dq/dt - viscous * dq/dt - friction * sign(dq/dt),   Kd_emf = stall / no_load,

so the active part is a torque-level P controller, ``Kp = duty_per_p_rad * P * stall`` [N·m/rad], clipped at
``max_duty * stall``; the available torque in the direction of motion falls linearly with speed,
``tau_avail(dq/dt) = max_duty * stall - Kd_emf * |dq/dt|``, to zero near the no-load speed; and the motor's back-EMF
is a damper (the framework's D gain is 0, so it is the only damping). Rotor inertia reflected through the gearbox
(``armature``) adds to the joint's inertia. Engines apply the active torque explicitly and the damping, friction
and armature implicitly (a 1e-4 kg·m² foot on a 0.44 N·m·s/rad damper is unstable if integrated explicitly at
1 kHz).

An action page's compliance byte sets the P gain per joint: ``P = (256 >> n) << 2`` for the high (clockwise) and
low (counter-clockwise) nibbles (ROBOTIS framework ``Action.cpp``): 0x55 -> 32, 0x44 -> 64, 0x66 -> 16, 0x77 -> 8.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.spec import Spec

MAX_STIFFNESS_SCALE = 10.0


@dataclass(frozen=True)
class ServoModel:
    """The servo model of one run: per-joint stiffness and the motor's limits and losses (SI units)."""

    kp: np.ndarray              # (20,) [N·m/rad]
    kd_emf: float               # back-EMF damping [N·m·s/rad]
    viscous: float              # viscous friction [N·m·s/rad]
    friction: float             # Coulomb friction [N·m]
    torque_max: float           # max_duty x stall torque [N·m]
    armature: float             # reflected rotor inertia [kg·m²]
    stall_torque: float         # [N·m] at the supply voltage
    no_load_speed: float        # [rad/s] at the supply voltage
    p_gains: tuple[int, ...]    # the firmware P gains behind kp
    kp_per_p: float = 0.0       # stiffness per unit of P gain [N·m/rad]: duty_per_p_rad x stall x stiffness scale
    stiffness_scale: float = 1.0
    supply_voltage: float = 12.0

    @classmethod
    def of(cls, spec: Spec, p_gains: np.ndarray | None = None, stiffness_scale: float = 1.0,
           voltage: float | None = None) -> "ServoModel":
        """The model of ``spec``'s servo at P gains (20,) (default: the framework's P for every joint), with the
        stiffness multiplied by ``stiffness_scale`` (for sensitivity studies), at a rated supply ``voltage`` [V]
        (default: the spec's)."""
        s = spec.servo
        rated = [r.voltage_v for r in s.ratings]
        if voltage is not None:
            if voltage not in rated:
                raise InputError(f"expected one of the rated voltages {rated}, got {voltage!r}", "voltage")
            s = replace(s, supply_voltage_v=float(voltage))
        if not (np.isfinite(stiffness_scale) and 0 < stiffness_scale <= MAX_STIFFNESS_SCALE):
            raise InputError(f"expected a factor in (0, {MAX_STIFFNESS_SCALE:g}], got {stiffness_scale!r}",
                             "stiffness")
        gains = np.full(len(spec.joints), s.p_gain_default) if p_gains is None else np.asarray(p_gains)
        if gains.shape != (len(spec.joints),) or np.any(gains < 0) or np.any(gains > 1024):
            raise InputError(f"expected {len(spec.joints)} P gains 0..1024, got {gains!r}", "p_gains")
        per_p = s.duty_per_p_rad * s.stall_torque_nm * stiffness_scale
        return cls(per_p * gains, s.stall_torque_nm / s.no_load_speed_rad_s, s.viscous_nm_s_rad, s.friction_nm,
                   s.max_duty * s.stall_torque_nm, s.armature_kg_m2, s.stall_torque_nm, s.no_load_speed_rad_s,
                   tuple(int(g) for g in gains), per_p, float(stiffness_scale), s.supply_voltage_v)

    def kp_of(self, p_gains: np.ndarray) -> np.ndarray:
        """The stiffness [N·m/rad] of servos at firmware P gains ``p_gains`` (the one place Kp follows from P)."""
        return self.kp_per_p * np.asarray(p_gains, dtype=float)

    @property
    def damping(self) -> float:
        """Total viscous damping at the joint [N·m·s/rad]: back-EMF plus viscous friction."""
        return self.kd_emf + self.viscous

    def active_torque(self, goal: np.ndarray, q: np.ndarray, kp: np.ndarray | None = None,
                      limit: np.ndarray | None = None) -> np.ndarray:
        """The torque the PWM drives [N·m] (before damping and friction): clip(Kp (goal - q), ±torque_max), with
        this model's Kp or the given one (a motion's P gains), and within a lower per-joint ``limit`` [N·m] if
        given (the servo's torque-limit register)."""
        torque = (self.kp if kp is None else kp) * (goal - q)
        cap = self.torque_max if limit is None else np.minimum(limit, self.torque_max)
        active: np.ndarray = np.minimum(np.maximum(torque, -cap), cap)    # np.clip, at a third the cost
        return active

    def motor_torque(self, goal: np.ndarray, q: np.ndarray, dq: np.ndarray, kp: np.ndarray | None = None,
                     limit: np.ndarray | None = None) -> np.ndarray:
        """The torque the motor delivers to the joint [N·m]: active torque minus back-EMF and viscous damping."""
        return self.active_torque(goal, q, kp, limit) - self.damping * dq

    def available(self, dq: np.ndarray, torque: np.ndarray | None = None) -> np.ndarray:
        """Largest torque magnitude [N·m] the motor can deliver at joint speed ``dq`` [rad/s]: at full duty,
        ``max_duty x stall - Kd_emf dq`` in the direction of ``torque`` (default: the direction of motion), so it
        falls linearly to zero near the no-load speed when the torque drives the motion and grows when it brakes
        it (the back-EMF then adds to the drive: a braking servo is not at its limit). Not below 0."""
        along = np.abs(dq) if torque is None else np.sign(torque) * dq
        most: np.ndarray = np.maximum(self.torque_max - self.kd_emf * along, 0.0)
        return most

    def describe(self) -> str:
        """One line naming the model and its numbers."""
        p = sorted(set(self.p_gains))
        scale = f" x {self.stiffness_scale:g}" if self.stiffness_scale != 1.0 else ""
        return (f"MX-28 at {self.supply_voltage:g} V, P {'/'.join(str(v) for v in p)}: Kp "
                f"{'/'.join(f'{k:.1f}' for k in sorted(set(np.round(self.kp, 1))))} N·m/rad{scale}, "
                f"Kd {self.damping:.2f} N·m·s/rad, torque <= {self.torque_max:.2f} N·m, "
                f"friction {self.friction:g} N·m, "
                f"armature {self.armature:g} kg·m²")
