"""Joint conventions: the book's variables <-> servo angles by official joint name <-> Dynamixel ticks.

Book variables (seed 001, code 2.4/2.10): ``th`` (11 sagittal angles, positive about -Y), ``phi`` (6 coronal
angles, positive about +X), ``psi`` (3 transverse angles, positive about +Z) and the support foot. th1-th3,
phi1-phi2, psi1 belong to the support leg, th4-th6, phi3-phi4, psi2 to the swing leg. Servo angles follow the
official ROBOTIS description (0 at tick 2048). The spec holds the per-joint linear map for each support foot, so
book -> servo -> book is exact and servo -> ticks -> servo is within half a tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence, get_args

import numpy as np

from op2motion import book
from op2motion.errors import InputError, LimitKind, LimitViolation
from op2motion.robot.spec import BOOK_VARS, Joint, Spec
from op2motion.robot.support import Side, Support

N_TH, N_PHI, N_PSI = 11, 6, 3
#: The joints of one leg from the hip down, by official name without the side's ``l_``/``r_`` prefix.
LEG_JOINTS = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ank_pitch", "ank_roll")
LIMIT_SLACK_RAD = 1e-9   # angles this close outside a limit count as on it (rounding of degrees in files)


def _angles(name: str, values: object, n: int) -> np.ndarray:
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"expected {n} numbers, got {values!r}", name) from None
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != n:
        got = arr.shape[-1] if arr.ndim else 0
        raise InputError(f"expected {n} angles, got {got}", name)
    if not np.all(np.isfinite(arr)):
        raise InputError("expected finite angles, got NaN or infinity", name)
    return arr


@dataclass(frozen=True)
class BookAngles:
    """A batch of N poses in the book's variables [rad]: th (N,11), phi (N,6), psi (N,3), one support foot."""

    th: np.ndarray
    phi: np.ndarray
    psi: np.ndarray
    support: Support

    def __post_init__(self) -> None:
        object.__setattr__(self, "support", Support.single(self.support))

    @classmethod
    def make(cls, th: object, phi: object, psi: object = None, support: Support | Side = "left") -> "BookAngles":
        """Validate angles [rad] (one pose as 1-D sequences, or N poses as 2-D arrays)."""
        th_a, phi_a = _angles("th", th, N_TH), _angles("phi", phi, N_PHI)
        psi_a = np.zeros((th_a.shape[0], N_PSI)) if psi is None else _angles("psi", psi, N_PSI)
        n = {th_a.shape[0], phi_a.shape[0], psi_a.shape[0]}
        if len(n) != 1:
            raise InputError(f"expected the same number of poses in th, phi and psi, got {sorted(n)}")
        return cls(th_a, phi_a, psi_a, Support.single(support))

    @classmethod
    def from_deg(cls, th: object, phi: object, psi: object = None, support: Support | Side = "left") -> "BookAngles":
        """Like :meth:`make` with angles in degrees."""
        def conv(v: object, name: str, n: int) -> np.ndarray:
            radians: np.ndarray = np.radians(_angles(name, v, n))
            return radians

        return cls.make(conv(th, "th", N_TH), conv(phi, "phi", N_PHI),
                        None if psi is None else conv(psi, "psi", N_PSI), support)

    @classmethod
    def standing(cls, support: Support | Side = "left", n: int = 1) -> "BookAngles":
        """The book's standing pose, repeated ``n`` times."""
        def rep(v: Sequence[float]) -> np.ndarray:
            radians: np.ndarray = np.radians(np.tile(np.array(v, dtype=float), (n, 1)))
            return radians

        return cls.make(rep(book.STANDING_TH_DEG), rep(book.STANDING_PHI_DEG), rep(book.STANDING_PSI_DEG), support)

    @classmethod
    def from_vector(cls, x: np.ndarray, support: Support | Side = "left") -> "BookAngles":
        """From the PSO vector layout (N,20) = [th(11), phi(6), psi(3)] [rad] (book code 2.11)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if x.shape[1] != N_TH + N_PHI + N_PSI:
            raise InputError(f"expected 20 values per pose, got {x.shape[1]}", "book vector")
        return cls(x[:, :N_TH], x[:, N_TH:N_TH + N_PHI], x[:, N_TH + N_PHI:], Support.single(support))

    @classmethod
    def random(cls, n: int, rng: np.random.Generator, support: Support | Side = "left",
               psi: bool = True) -> "BookAngles":
        """``n`` poses drawn uniformly from the book's PSO box (psi = 0 unless ``psi``)."""
        lo, hi = np.radians(book.PSO_LOWER_DEG), np.radians(book.PSO_UPPER_DEG)
        x = lo + (hi - lo) * rng.random((n, lo.size))
        if not psi:
            x[:, N_TH + N_PHI:] = 0.0
        return cls.from_vector(x, support)

    @property
    def n(self) -> int:
        """Number of poses in the batch."""
        return int(self.th.shape[0])

    def vector(self) -> np.ndarray:
        """The (N,20) vector [th, phi, psi] [rad]."""
        return np.concatenate([self.th, self.phi, self.psi], axis=1)

    def row(self, i: int) -> "BookAngles":
        """Pose ``i`` as a batch of one."""
        return BookAngles(self.th[i:i + 1], self.phi[i:i + 1], self.psi[i:i + 1], self.support)

    def degrees(self, i: int = 0) -> dict[str, list[float]]:
        """Pose ``i`` as ``{"th": [...], "phi": [...], "psi": [...]}`` in degrees (for humans and JSON)."""
        return {k: [float(v) for v in np.degrees(getattr(self, k)[i])] for k in ("th", "phi", "psi")}


def _map_arrays(spec: Spec, support: Support | Side) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    idx = np.array([BOOK_VARS.index(j.book[support].var) for j in spec.joints])
    sign = np.array([float(j.book[support].sign) for j in spec.joints])
    offset = np.array([j.book[support].offset for j in spec.joints])
    return idx, sign, offset


def book_to_servo(angles: BookAngles, spec: Spec) -> np.ndarray:
    """Servo angles (N,20) [rad] in Dynamixel ID order (``spec.joint_names``)."""
    idx, sign, offset = _map_arrays(spec, angles.support)
    servo: np.ndarray = sign * angles.vector()[:, idx] + offset
    return servo


def servo_to_book(servo: np.ndarray, support: Support | Side, spec: Spec) -> BookAngles:
    """Book variables for servo angles (N,20) or (20,) [rad] in ID order, seen from ``support``."""
    servo = _angles("servo angles", servo, len(spec.joints))
    idx, sign, offset = _map_arrays(spec, Support.single(support))
    vec = np.empty_like(servo)
    vec[:, idx] = (servo - offset) * sign
    return BookAngles.from_vector(vec, support)


def servo_from_mapping(values: Mapping[str, object], spec: Spec, degrees: bool = True) -> np.ndarray:
    """A (20,) servo vector [rad] from ``{joint name: angle}``; every joint exactly once."""
    if not isinstance(values, Mapping):
        raise InputError(f"expected an object {{joint: angle}}, got {type(values).__name__}", "servo angles")
    names = spec.joint_names
    unknown = sorted(str(k) for k in set(values) - set(names))
    if unknown:
        raise InputError(f"unknown joint {unknown[0]!r}; expected the official names ({names[0]}, ...)",
                         "servo angles")
    missing = [n for n in names if n not in values]
    if missing:
        raise InputError(f"expected all 20 joints, missing {', '.join(missing)}", "servo angles")
    out = np.array([_scalar(values[n], n) for n in names])
    return np.radians(out) if degrees else out


def _scalar(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"expected a finite number, got {value!r}", name)
    return float(value)


def servo_to_ticks(servo: np.ndarray, spec: Spec) -> np.ndarray:
    """Goal-position ticks for servo angles [rad] (nearest tick); angles beyond the servo's range are an error."""
    s = spec.servo
    ticks = np.rint(np.asarray(servo, dtype=float) / s.rad_per_tick).astype(np.int64) + s.center_tick
    bad = (ticks < s.min_tick) | (ticks > s.max_tick)
    if np.any(bad):
        flat = int(np.argwhere(bad.reshape(-1))[0][0])
        i = flat % len(spec.joints)
        lo, hi = ((t - s.center_tick) * math.degrees(s.rad_per_tick) for t in (s.min_tick, s.max_tick))
        got = math.degrees(float(np.asarray(servo, dtype=float).reshape(-1)[flat]))
        raise InputError(f"expected {lo:+.1f}° to {hi:+.1f}° (ticks {s.min_tick} to {s.max_tick}: +180° would be "
                         f"tick {s.max_tick + 1}), got {got:+.3f}°", spec.joints[i].name)
    return ticks


def ticks_to_servo(ticks: np.ndarray, spec: Spec) -> np.ndarray:
    """Servo angles [rad] for goal-position ticks."""
    return (np.asarray(ticks, dtype=float) - spec.servo.center_tick) * spec.servo.rad_per_tick


LIMIT_KINDS: tuple[LimitKind, ...] = get_args(LimitKind)


def joint_range(joint: Joint, kind: LimitKind) -> tuple[float, float]:
    """The ``mechanical`` (hard) or ``cable-safe`` (advice) range of a joint [rad]."""
    return joint.mechanical if kind == "mechanical" else joint.safe


def hip_roll_sign(spec: Spec, side: str) -> float:
    """The hip-roll change that undoes an ankle-roll change of the ``side`` (``l``/``left`` or ``r``/``right``) leg,
    so the torso stays level: with the pitch joints cancelling, the roll from torso to foot is a_hip q_hip +
    a_ankle q_ankle (a: the axes' x components)."""
    s = side[0]
    return -spec.joint(f"{s}_ank_roll").axis[0] / spec.joint(f"{s}_hip_roll").axis[0]


def limit_violations(servo: np.ndarray | Sequence[float], spec: Spec,
                     kind: LimitKind = "mechanical") -> list[LimitViolation]:
    """Joints of one pose (servo angles (20,) [rad]) outside their ``kind`` range (see :data:`LIMIT_KINDS`)."""
    out: list[LimitViolation] = []
    for joint, q in zip(spec.joints, np.asarray(servo, dtype=float).reshape(-1)):
        lower, upper = joint_range(joint, kind)
        if not lower - LIMIT_SLACK_RAD <= q <= upper + LIMIT_SLACK_RAD:
            out.append(LimitViolation(joint.name, round(math.degrees(q), 4), round(math.degrees(lower), 4),
                                      round(math.degrees(upper), 4), kind))
    return out


def book_bounds(spec: Spec, support: Support | Side, variables: Sequence[str] = BOOK_VARS,
                kind: LimitKind = "cable-safe") -> tuple[np.ndarray, np.ndarray]:
    """Bounds [rad] (lower, upper) of book ``variables`` that keep every servo inside its ``kind`` range, seen
    from ``support`` (each book variable drives exactly one servo: ``servo = sign * var + offset``)."""
    lo, hi = np.empty(len(variables)), np.empty(len(variables))
    for k, var in enumerate(variables):
        joint = next(j for j in spec.joints if j.book[support].var == var)
        m = joint.book[support]
        lower, upper = joint_range(joint, kind)
        lo[k], hi[k] = sorted(((lower - m.offset) * m.sign, (upper - m.offset) * m.sign))
    return lo, hi


def servo_dict(servo_row: np.ndarray | Sequence[float], spec: Spec, degrees: bool = True) -> dict[str, float]:
    """``{joint name: angle}`` for one pose, in degrees by default."""
    conv = math.degrees if degrees else float
    return {j.name: conv(float(q)) for j, q in zip(spec.joints, servo_row)}
