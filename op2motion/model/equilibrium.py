"""Where compliant servos hold a pose still: the statically sagged joint angles (full nonlinear model, pinocchio).

Each servo is a spring about its goal, ``tau = Kp (q* - q)`` [N·m], and at rest it must supply the static torque
that holds the body on its support (:meth:`.dynamics.Dynamics.static_torques`: gravity balanced by the contact
wrench at the support sole). On one foot the sagged angles solve

    Kp (q* - q) = tau_static(q)                                                  (20 equations, 20 unknowns).

On two feet the load split is statically indeterminate: it follows from the legs' compliance. With the left sole
held and the right sole's wrench w [N, N·m] (its own frame) as six more unknowns,

    Kp (q* - q) = tau_left(q) - J_rel(q)^T w,    log6(T_rel(q*)^-1 T_rel(q)) = 0     (26 equations, 26 unknowns)

where ``tau_left`` holds the body on the left sole alone, ``J_rel`` maps joint speeds to the right sole's twist
with the left sole still, and ``T_rel`` is the right sole's placement seen from the left sole: friction keeps the
feet where they were put down. Both are solved by Newton's method with a finite-difference Jacobian taken once at
the goal (the chord method: the gravity stiffness changes little over a few degrees of sag). Gravity is a negative
stiffness against the servos'; where it wins in some direction, or a servo would need more than its largest torque,
no equilibrium exists and ``None`` is returned, as it is where a sole would have to pull on the floor or press
outside itself (then the physics check starts from the goals and ramps gravity in).

The physics check starts a held pose here with gravity at full strength (:mod:`op2motion.physics.loop`), so the start
is not an impact: a pose loaded by a gravity ramp overshoots its sag (the OP2 on one leg at P = 32 is a 1 Hz
oscillator with about a quarter of critical damping), and near a foot's edge that overshoot alone tips it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from op2motion.model.dynamics import dynamics_for
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

TOLERANCE_NM = 1e-6          # largest torque imbalance [N·m] of a solution
MAX_ITERATIONS = 30
PROBE_RAD = 1e-6             # finite-difference step [rad]
MAX_SAG_RAD = 0.6            # a solution farther than this from the goal is not the pose's equilibrium
CHORD_REUSE_RAD = 0.05       # a Jacobian taken at a goal starts the solves of goals this close (each joint) [rad]


def sagged_angles(goal: np.ndarray, support: Support | SupportName, spec: Spec, kp: np.ndarray,
                  torque_max: float) -> np.ndarray | None:
    """The servo angles (20,) [rad] at which servos of stiffness ``kp`` (20,) [N·m/rad] holding ``goal`` (20,)
    [rad] carry the body at rest on ``support``; ``None`` where no equilibrium exists within the servos'
    ``torque_max`` [N·m] (see the module docstring)."""
    found = _sagged(goal, support, spec, kp, torque_max)
    return None if found is None or found[1] < 0.0 else found[0]


def loaded_foot_margin(goal: np.ndarray, spec: Spec, kp: np.ndarray, torque_max: float,
                       chord: Chord | None = None) -> float:
    """On two feet: the margin [m] of the loaded sole's own centre of pressure to its edge where the compliant servos
    hold ``goal`` (20,) [rad] at rest (the statically indeterminate split solved as in the module docstring). In a
    lean the robot tips where the loaded foot's own CoP reaches its edge, whatever the hull of both soles says;
    where the split puts the lighter foot's CoP outside it, that foot rolls onto its edge and the loaded one takes
    the rest of the moment (:func:`_feet_margins`). -inf where no equilibrium exists. A caller solving a run of
    nearby goals (the rows of a line) passes one :class:`Chord` to every call."""
    found = _sagged(goal, Support.DOUBLE, spec, kp, torque_max, loaded_only=True, chord=chord)
    return -math.inf if found is None else found[1]


@dataclass
class Chord:
    """The finite-difference Jacobian of the last fresh solve and the goal (20,) [rad] it was taken at, shared by a
    run of solves of nearby goals: the chord method converges with a Jacobian taken a little way off too, so a goal
    within :data:`CHORD_REUSE_RAD` of that one starts with it (it costs 26 evaluations of the model to take, a
    solve about five); where that solve does not converge, a fresh Jacobian is taken at the goal and the verdict is
    that solve's, as without a Chord."""

    goal: np.ndarray | None = None
    jac: np.ndarray | None = None

    def serves(self, goal: np.ndarray) -> bool:
        """Whether the kept Jacobian may start the solve of ``goal`` (20,) [rad]."""
        return (self.goal is not None and self.goal.shape == goal.shape
                and float(np.max(np.abs(goal - self.goal))) <= CHORD_REUSE_RAD)


def _sagged(goal: np.ndarray, support: Support | SupportName, spec: Spec, kp: np.ndarray, torque_max: float,
            loaded_only: bool = False, chord: Chord | None = None) -> tuple[np.ndarray, float] | None:
    """The sagged angles and, on two feet, the least CoP margin of the soles (``loaded_only``: the loaded sole's
    once the other has rolled onto its edge; +inf on one foot); None where the servos cannot hold the pose. On two
    feet ``chord`` may lend the Jacobian of a nearby solve (:class:`Chord`)."""
    dyn = dynamics_for(spec)
    support = Support.of(support)
    goal = np.asarray(goal, dtype=float)
    kp = np.broadcast_to(np.asarray(kp, dtype=float), goal.shape)
    n = goal.size
    if support.is_double:
        rel_goal, _ = _right_from_left(dyn, goal)

        def residual(x: np.ndarray) -> np.ndarray:
            rel, jac_rel = _right_from_left(dyn, x[:n])
            held = dyn.static_torques(x[:n], "left").torques - jac_rel.T @ x[n:]
            return np.concatenate([kp * (goal - x[:n]) - held, dyn.pin.log6(rel_goal.actInv(rel)).vector])

        x0 = np.concatenate([goal, np.zeros(6)])
    else:
        def residual(x: np.ndarray) -> np.ndarray:
            unbalanced: np.ndarray = kp * (goal - x) - dyn.static_torques(x, support).torques
            return unbalanced

        x0 = goal.copy()
    r0 = residual(x0)
    x = None
    if chord is not None and chord.jac is not None and support.is_double and chord.serves(goal):
        x = _newton(residual, x0, r0, chord.jac, goal)
    if x is None:
        jac = np.empty((x0.size, x0.size))
        for j in range(x0.size):
            probe = x0.copy()
            probe[j] += PROBE_RAD
            jac[:, j] = (residual(probe) - r0) / PROBE_RAD
        if chord is not None and support.is_double:
            chord.goal, chord.jac = goal.copy(), jac
        if not support.is_double and np.max(np.linalg.eigvals(jac).real) >= 0.0:
            return None                           # gravity is stiffer than the servos in some direction
        x = _newton(residual, x0, r0, jac, goal)
    if x is None:
        return None
    q = x[:n]
    if np.max(np.abs(kp * (goal - q))) > torque_max:
        return None
    if not support.is_double:
        return q, math.inf
    raw, loaded = _feet_margins(dyn, q, x[n:])
    return q, (loaded if loaded_only else min(raw))


def _newton(residual: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, r0: np.ndarray, jac: np.ndarray,
            goal: np.ndarray) -> np.ndarray | None:
    """Newton's chord iterations from ``x0`` (its residual ``r0``) with the fixed Jacobian ``jac``: the root, or None
    where they do not converge to one within :data:`MAX_SAG_RAD` of ``goal`` (20,) [rad] (its first 20 entries)."""
    x, r = x0, r0
    for _ in range(MAX_ITERATIONS):
        if np.max(np.abs(r)) < TOLERANCE_NM:
            return x
        try:
            x = x - np.linalg.solve(jac, r)
        except np.linalg.LinAlgError:             # singular: the servos and gravity balance in some direction
            return None
        if not np.all(np.isfinite(x)) or np.max(np.abs(x[:goal.size] - goal)) > MAX_SAG_RAD:
            return None
        r = residual(x)
    return None


def _right_from_left(dyn: Any, q: np.ndarray) -> tuple[Any, np.ndarray]:
    """The right sole's placement in the left sole's frame (pinocchio SE3) and the Jacobian (6, 20) of its twist
    (own frame: linear [m/rad], angular [rad/rad]) w.r.t. the servo angles with the left sole held still."""
    pin, model, data = dyn.pin, dyn.model, dyn.data
    config = dyn.level_configuration(q, "left")
    pin.computeJointJacobians(model, data, config)
    pin.framesForwardKinematics(model, data, config)
    left, right = dyn.sole_ids["left"], dyn.sole_ids["right"]
    jl = pin.getFrameJacobian(model, data, left, pin.ReferenceFrame.LOCAL)
    jr = pin.getFrameJacobian(model, data, right, pin.ReferenceFrame.LOCAL)
    joints = dyn.v_index
    rel_jac = jr[:, joints] - jr[:, :6] @ np.linalg.solve(jl[:, :6], jl[:, joints])
    return data.oMf[left].actInv(data.oMf[right]), rel_jac


def _feet_margins(dyn: Any, q: np.ndarray, right_wrench: np.ndarray) -> tuple[list[float], float]:
    """Each sole's margin [m] of its own centre of pressure to its edge when the right one carries
    ``right_wrench`` (own frame), -inf for a sole that would pull (a sole cannot pull, nor press outside itself);
    and the loaded sole's margin once the lighter one, where its CoP falls outside it, has rolled onto its edge:
    its CoP clamped into the sole, the loaded sole taking over the moment (the total CoP stays where gravity puts
    it); -inf where the lighter one would pull (it lifts)."""
    pin, model, data = dyn.pin, dyn.model, dyn.data
    config = dyn.level_configuration(q, "left")
    zero = np.zeros(model.nv)
    gravity = pin.rnea(model, data, config, zero, zero)
    pin.computeJointJacobians(model, data, config)
    pin.framesForwardKinematics(model, data, config)
    jl, jr = (pin.getFrameJacobian(model, data, dyn.sole_ids[s], pin.ReferenceFrame.LOCAL) for s in ("left", "right"))
    left_wrench = np.linalg.solve(jl[:, :6].T, gravity[:6] - jr[:, :6].T @ right_wrench)
    feet = []
    for side, wrench in (("left", left_wrench), ("right", right_wrench)):
        force, moment = wrench[:3], wrench[3:]
        cop = np.array([-moment[1], moment[0]]) / force[2] if force[2] > 0.0 else np.zeros(2)
        front, back, left, right = dyn.spec.sole_extents(side)
        margin = min(front - cop[0], cop[0] + back, left - cop[1], cop[1] + right) if force[2] > 0.0 else -math.inf
        turn = data.oMf[dyn.sole_ids[side]].rotation[:2, :2]
        feet.append((float(force[2]), cop, margin, (front, back, left, right), turn))
    heavy, light = sorted(feet, key=lambda f: -f[0])
    load, cop, _, (front, back, left, right), turn = heavy
    if light[0] <= 0.0:                                  # the lighter sole would pull: it lifts
        return [f[2] for f in feet], -math.inf
    if light[2] < 0.0:                                   # the lighter sole rolls onto its edge
        l_load, l_cop, _, (l_front, l_back, l_left, l_right), l_turn = light
        clamped = np.array([np.clip(l_cop[0], -l_back, l_front), np.clip(l_cop[1], -l_right, l_left)])
        cop = cop + turn.T @ (l_turn @ (l_load * (l_cop - clamped))) / load
    loaded = min(front - cop[0], cop[0] + back, left - cop[1], cop[1] + right)
    return [f[2] for f in feet], float(loaded)
