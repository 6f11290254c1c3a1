"""Taylor-linearised arm inverse kinematics on the projection model (book eqs. 2.110-2.129, code 2.15/2.17).

In the projection model the hand of the left arm, relative to its shoulder-roll point, is

    h = l9 v(A, F) + l10 v(B, F),   v(T, F) = (|cos F| cos T, -|sin T| sin F, |cos F| sin T),

with A = th1237, B = th12378, F = phi125 (right arm: th1239, th123910, phi126). The book linearises sin and cos
about the current angles (eq. 2.111) and solves the sagittal changes (th7, th8) from the x and z rows with a 2x2
inverse, and the coronal change (phi5) from the y row alone: :func:`book_step`, exactly as the code computes it.

:func:`solve_arm_ik` iterates damped linearised steps (Levenberg-Marquardt with the exact 3x3 Jacobian of the
projection model's hand, or of the D-H model's hand by central differences) until the hand is within ``tol`` of
the target or progress stops, and reports the honest residual. Each accepted step reduces the error, so it
cannot overshoot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import partial
from typing import Callable

import numpy as np

from op2motion.errors import InputError, LimitViolation, ModelError
from op2motion.kinematics import ModelName, forward
from op2motion.robot.joints import BookAngles, book_bounds, book_to_servo, limit_violations
from op2motion.robot.sides import Side, as_side
from op2motion.robot.spec import Spec

TOL_M = 1e-4                # iterated mode: stop when the hand is this close to the target [m]
MAX_ITER = 50
SINGULAR_REL_DET = 1e-6     # |det| of the 2x2 sagittal matrix below this fraction of l_upper*l_lower (cos F)^2
FD_STEP_RAD = 1e-5          # central-difference step for the D-H Jacobian
MAX_STEP_RAD = 0.1          # trust region: no joint moves more than this per iteration (keeps steps linear)
_PROGRESS_M = 1e-9          # an accepted step must shrink the error by at least this much [m]


@dataclass(frozen=True)
class Arm:
    """Which book variables move one arm: indices into th (upper, lower arm) and phi, and the hand's point name."""

    th_upper: int
    th_lower: int
    phi: int
    hand: str           # the hand's point name (``left_hand``)
    side: Side

    @property
    def names(self) -> tuple[str, str, str]:
        """Book names of the three arm variables, e.g. ("th7", "th8", "phi5")."""
        return (f"th{self.th_upper + 1}", f"th{self.th_lower + 1}", f"phi{self.phi + 1}")


ARMS = {"left": Arm(6, 7, 4, "left_hand", "left"), "right": Arm(8, 9, 5, "right_hand", "right")}


def _arm(hand: object) -> Arm:
    return ARMS[as_side(hand, "hand")]


def _delta(delta: object) -> np.ndarray:
    d = np.asarray(delta, dtype=float).reshape(-1)
    if d.size != 3 or not np.all(np.isfinite(d)):
        raise InputError(f"expected 3 finite numbers [m], got {delta!r}", "delta")
    return d


def _arm_angles(angles: BookAngles, arm: Arm) -> tuple[float, float, float]:
    """(A, B, F): absolute sagittal angles of upper and lower arm and the arm's coronal angle [rad]."""
    th, phi = angles.th[0], angles.phi[0]
    a = th[0] + th[1] + th[2] + th[arm.th_upper]
    return a, a + th[arm.th_lower], phi[0] + phi[1] + phi[arm.phi]


def book_step(angles: BookAngles, hand: Side, delta: object, spec: Spec) -> np.ndarray:
    """The book's single Taylor step: changes (d_upper, d_lower, d_phi) [rad] for a hand displacement [m].

    Code 2.15 (left arm) / 2.17 (right arm). The coronal denominator uses ``sign(th12378)`` (``sign(th123910)``),
    the sign of the raw angle sum in radians, where the derivation calls for sign(sin(.)). This reproduces what
    the book's code computes; the two agree whenever that angle lies in (0, pi) modulo 2 pi (so for every case
    the book prints). A singular 2x2 matrix (straight arm) or a zero coronal derivative is a :class:`ModelError`.
    """
    arm, d = _arm(hand), _delta(delta)
    g = spec.geometry
    l_up, l_low = g.upper_arm, g.lower_arm
    a, b, f = _arm_angles(angles, arm)
    s = np.sign(math.cos(f))

    def p_cs(x: float, y: float) -> float:          # book P_cs
        return math.cos(x) * math.sin(y)

    def p_cc(x: float, y: float) -> float:          # book P_cc
        return math.cos(x) * math.cos(y)

    m = np.array([[-s * (l_up * p_cs(f, a) + l_low * p_cs(f, b)), -s * l_low * p_cs(f, b)],
                  [s * (l_up * p_cc(f, a) + l_low * p_cc(f, b)), s * l_low * p_cc(f, b)]])
    det = float(np.linalg.det(m))
    if abs(det) < SINGULAR_REL_DET * l_up * l_low * max(math.cos(f) ** 2, 1e-12):
        raise ModelError(f"singular arm linearisation (determinant {det:.3g} m²): the {hand} arm is straight or "
                         "its plane is edge-on; bend the elbow first")
    d_upper, d_lower = np.linalg.solve(m, [d[0], d[2]])
    den = np.sign(math.sin(a)) * l_up * p_cs(f, a) + np.sign(b) * l_low * p_cs(f, b)  # sign(b): the book's code
    if abs(den) < 1e-12:
        raise ModelError(f"singular coronal linearisation for the {hand} arm: its hand cannot move sideways here")
    return np.array([d_upper, d_lower, -d[1] / den])


def pb_hand_jacobian(angles: BookAngles, hand: Side, spec: Spec) -> np.ndarray:
    """Exact 3x3 Jacobian [m/rad] of the projection model's hand w.r.t. (upper th, lower th, phi) of one arm."""
    arm = _arm(hand)
    g = spec.geometry
    a, b, f = _arm_angles(angles, arm)
    sf, cf = math.sin(f), math.cos(f)

    def d_dt(t: float) -> np.ndarray:
        st, ct = math.sin(t), math.cos(t)
        return np.array([-abs(cf) * st, -np.sign(st) * ct * sf, abs(cf) * ct])

    def d_df(t: float) -> np.ndarray:
        st, ct = math.sin(t), math.cos(t)
        return np.array([-np.sign(cf) * sf * ct, -abs(st) * cf, -np.sign(cf) * sf * st])

    j = np.empty((3, 3))
    j[:, 0] = g.upper_arm * d_dt(a) + g.lower_arm * d_dt(b)
    j[:, 1] = g.lower_arm * d_dt(b)
    j[:, 2] = g.upper_arm * d_df(a) + g.lower_arm * d_df(b)
    return j


def _with_arm(angles: BookAngles, arm: Arm, q: np.ndarray) -> BookAngles:
    """Copies of ``angles`` with the arm variables set to each row of q (k, 3)."""
    q = np.atleast_2d(q)
    th = np.repeat(angles.th[:1], q.shape[0], axis=0)
    phi = np.repeat(angles.phi[:1], q.shape[0], axis=0)
    psi = np.repeat(angles.psi[:1], q.shape[0], axis=0)
    th[:, arm.th_upper], th[:, arm.th_lower], phi[:, arm.phi] = q[:, 0], q[:, 1], q[:, 2]
    return BookAngles(th, phi, psi, angles.support)


def _hands(angles: BookAngles, arm: Arm, q: np.ndarray, spec: Spec, model: ModelName) -> np.ndarray:
    return forward(_with_arm(angles, arm, q), spec, model).point(arm.hand)


@dataclass(frozen=True)
class ArmIKResult:
    """Outcome of one arm IK solve; angles in rad, lengths in m."""

    hand: Side
    model: ModelName
    mode: str
    initial: BookAngles
    angles: BookAngles
    deltas: np.ndarray
    requested: np.ndarray
    achieved: np.ndarray
    iterations: int
    limit_violations: list[LimitViolation]

    @property
    def error_m(self) -> float:
        """Distance between the achieved and the requested hand displacement [m]."""
        return float(np.linalg.norm(self.achieved - self.requested))


def solve_arm_ik(angles: BookAngles, hand: Side, delta: object, spec: Spec, model: ModelName = "pb", *,
                 single_step: bool = False, tol: float = TOL_M, enforce_limits: bool = True) -> ArmIKResult:
    """Move one hand by ``delta`` [m] (world frame) with that arm's three joints.

    ``single_step`` applies :func:`book_step` once; otherwise damped linearised steps on ``model`` ("pb": exact
    projection Jacobian, "dh": central differences on the D-H model) run until the hand is within ``tol`` [m] of
    the target or no step improves it (at most :data:`MAX_ITER` per start). With ``enforce_limits`` the iterates
    stay inside the servo limits.
    """
    arm, d = _arm(hand), _delta(delta)
    one = angles.row(0)
    if not (math.isfinite(tol) and tol > 0):
        raise InputError(f"expected a positive length [m], got {tol!r}", "tol")
    q0 = np.array([one.th[0, arm.th_upper], one.th[0, arm.th_lower], one.phi[0, arm.phi]])
    start = _hands(one, arm, q0, spec, model)[0]
    bounds = book_bounds(spec, one.support, arm.names, "cable-safe") if enforce_limits else None
    if single_step:
        q, iterations = q0 + book_step(one, hand, d, spec), 1
    else:
        q, iterations = _ArmSolve(one, arm, spec, model, tol, bounds).multi_start(q0, d, start + d)
    final = _with_arm(one, arm, q)
    achieved = _hands(one, arm, q, spec, model)[0] - start
    servo = book_to_servo(final, spec)[0]
    arm_joints = {j.name for j in spec.joints if j.book[one.support].var in arm.names}
    violations = [v for v in limit_violations(servo, spec, "cable-safe") if v.joint in arm_joints]
    return ArmIKResult(hand, model, "single-step" if single_step else "iterated", one, final, q - q0, d, achieved,
                       iterations, violations)


ELBOW_GRID = 241  # elbow samples for the distance seeds


def _with_elbow(q0: np.ndarray, elbow: float) -> np.ndarray:
    """The arm angles ``q0`` (3,) [rad] with the elbow at ``elbow`` [rad]."""
    return np.array([q0[0], elbow, q0[2]])


@dataclass(frozen=True)
class _ArmSolve:
    """One iterated arm solve: the pose, the arm, the model, the tolerance [m] and the bounds [rad] (or None)."""

    angles: BookAngles
    arm: Arm
    spec: Spec
    model: ModelName
    tol: float
    bounds: tuple[np.ndarray, np.ndarray] | None

    def hand_at(self, q: np.ndarray) -> np.ndarray:
        """The hand's position [m] (3,) with the arm at ``q`` (3,) [rad]."""
        hand: np.ndarray = _hands(self.angles, self.arm, q, self.spec, self.model)[0]
        return hand

    def multi_start(self, q0: np.ndarray, d: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, int]:
        """Damped Newton from the start pose; if that stalls (a local minimum near a singular arm), again from the
        book's Taylor guess, on the D-H model from the projection model's solution, and from the elbow angles that
        give the target's distance. Best residual wins."""
        a, arm, spec = self.angles, self.arm, self.spec
        seeds: list[Callable[[], np.ndarray]] = [lambda: q0,
                                                 lambda: q0 + book_step(a, arm.side, d, spec)]
        if self.model == "dh":
            pb = replace(self, model="pb")
            seeds.append(lambda: pb.damped_newton(q0, _hands(a, arm, q0, spec, "pb")[0] + d)[0])
        seeds += [partial(_with_elbow, q0, elbow) for elbow in self.elbow_seeds(q0, target)]
        best, best_err, total = q0, math.inf, 0
        for seed in seeds:
            try:
                start = seed()
            except ModelError:  # singular Taylor guess: skip that seed
                continue
            q, used = self.damped_newton(start, target)
            total += used
            err = float(np.linalg.norm(target - self.hand_at(q)))
            if err < best_err:
                best, best_err = q, err
            if best_err <= self.tol:
                break
        return best, total

    def elbow_seeds(self, q0: np.ndarray, target: np.ndarray) -> list[float]:
        """Elbow angles at which the shoulder-roll-to-hand distance equals the target's distance (as analytic arm
        IK fixes the elbow first); pitch and roll are then left to the damped solver."""
        bounds = self.bounds
        lo, hi = (bounds[0][1], bounds[1][1]) if bounds is not None else (q0[1] - math.pi, q0[1] + math.pi)
        grid = np.linspace(lo, hi, ELBOW_GRID)
        q = np.repeat(q0[None, :], ELBOW_GRID, axis=0)
        q[:, 1] = grid
        pts = forward(_with_arm(self.angles, self.arm, q), self.spec, self.model)
        root = pts.point(f"{self.arm.hand[0]}_sho_roll")
        reach = np.linalg.norm(pts.point(self.arm.hand) - root, axis=1) - np.linalg.norm(target - root[0])
        cross = np.nonzero(np.sign(reach[:-1]) * np.sign(reach[1:]) <= 0)[0]
        return [float(grid[i] - reach[i] * (grid[i + 1] - grid[i]) / (reach[i + 1] - reach[i] or 1.0))
                for i in cross]

    def damped_newton(self, q: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, int]:
        """Levenberg-Marquardt on the hand position; returns the final arm angles and the iterations used."""
        bounds = self.bounds
        if bounds is not None:
            q = np.clip(q, *bounds)
        err = target - self.hand_at(q)
        mu = 1e-8
        for it in range(1, MAX_ITER + 1):
            if np.linalg.norm(err) <= self.tol:
                return q, it - 1
            jac = _jacobian(self.angles, self.arm, q, self.spec, self.model)
            jtj, jte = jac.T @ jac, jac.T @ err
            improved = False
            while mu < 1e6:
                step = np.linalg.solve(jtj + mu * np.eye(3), jte)
                step *= min(1.0, MAX_STEP_RAD / max(float(np.max(np.abs(step))), 1e-300))
                trial = q + step if bounds is None else np.clip(q + step, *bounds)
                trial_err = target - self.hand_at(trial)
                if np.linalg.norm(trial_err) < np.linalg.norm(err) - _PROGRESS_M:
                    q, err, improved = trial, trial_err, True
                    mu = max(mu / 10.0, 1e-12)
                    break
                mu *= 10.0
            if not improved:
                return q, it
        return q, MAX_ITER


def _jacobian(angles: BookAngles, arm: Arm, q: np.ndarray, spec: Spec, model: ModelName) -> np.ndarray:
    if model == "pb":
        return pb_hand_jacobian(_with_arm(angles, arm, q), arm.side, spec)
    h = FD_STEP_RAD
    probes = np.vstack([q + h * e for e in np.eye(3)] + [q - h * e for e in np.eye(3)])
    hands = _hands(angles, arm, probes, spec, model)
    jacobian: np.ndarray = ((hands[:3] - hands[3:]) / (2 * h)).T
    return jacobian
