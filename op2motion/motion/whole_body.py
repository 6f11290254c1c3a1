"""Whole-body differential IK: one hand to a point while the feet stay put, the CoM holds and the torso stays upright.

The unknowns are the torso's pose in the stance sole's frame (world = support foot: X forward, Y left, Z up; a
shift [m] and a small rotation vector [rad] from where it started) and the moving hand's three arm joints; the
standing leg (on both feet: both legs) follows from the closed-form leg IK (:mod:`op2motion.kinematics.leg_ik`), so the
soles stay exactly where they are (a bent leg stretches to at most :data:`MAX_REACH_SHARE` of its length, away
from the straight knee's singularity; a sole beyond that is pulled in, and the feet task sees it); on one foot
the swing leg keeps its joints. Levenberg-Marquardt on weighted tasks, each an error in the stance sole's
frame measured on the D-H chain, the Jacobian by forward differences with all the perturbed poses in one batch:

* the hand point [m] (weight :data:`W_HAND`);
* on both feet, the other sole's four corners [m] where they started (:data:`W_FEET`);
* the full-inertia CoM's x, y [m] where it started (:data:`W_COM`);
* a knee that started straight held straight (:data:`W_STRAIGHT_KNEE`): there the leg IK turns a sink of a
  fraction of a millimetre into degrees of knee, a jolt the servos cannot follow (with ``crouch`` not: the body may
  sink, at a small cost :data:`W_CROUCH_Z`, its derivative taken downwards, where a straight leg can go);
* links apart: how far the least clearance between the collision shapes is below :data:`CLEAR_TASK_M`
  (:data:`W_CLEAR`);
* the torso's x and z axes where they started (:data:`W_TORSO`), and optionally the forearm's direction (the
  elbow-to-hand unit vector: the OP2's 3-joint arm can hold a pointing direction, not a full orientation)
  (:data:`W_POINT`);
* regulation: the unknowns pulled towards the start (:data:`W_POSTURE`: the torso moves only where the arm alone
  cannot do it, by about a millimetre of hand error per centimetre), damping from :data:`DAMPING`;  one
  call moves the unknowns no more than :data:`ROW_STEP` and each leg joint no more than :data:`JOINT_ROW_STEP`
  (what one 8 ms row may: the hand lags rather than the body jumping) and keeps every joint
  :data:`LIMIT_MARGIN_RAD` inside its mechanical range (widened to include the start). :meth:`WholeBodyIk.settle`
  solves for a point however many rows it takes (an end configuration).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from op2motion.errors import InputError, ModelError
from op2motion.kinematics.leg_ik import Leg, leg_fk, leg_of
from op2motion.kinematics.points import row_of
from op2motion.motion.body_checks import body_cost
from op2motion.posture.cost import CLEARANCE_EXACT_M, torso_axes
from op2motion.robot.joints import joint_range, servo_to_book
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, SupportName, other_side

W_HAND = 1.0
W_FEET = 10.0
W_COM = 0.01
W_TORSO = 0.005
W_POINT = 0.01
W_CLEAR = 1.0
JOINT_ROW_STEP = 0.023      # [rad] a leg joint turns at most this much in one row (half the no-load speed)
W_STRAIGHT_KNEE = 1e-2      # per rad² that a knee which started straight bends
STRAIGHT_KNEE_RAD = 0.09    # a knee within 5° of straight started straight
CLEAR_TASK_M = 0.008        # links closer than this push apart (the check after wants SELF_CLEARANCE_M)
W_POSTURE = np.array([1e-3, 1e-3, 1e-1] + [1e-4] * 3 + [1e-6] * 3)  # per m² of torso shift (rising and sinking
#                            most), rad² of its turn, rad² of the arm
MAX_REACH_SHARE = 0.985     # a bent leg stretches to at most this share of its length (the knee stays ~20° bent)
DAMPING = 1e-7
SOLVE_TOL_M = 1e-4
MAX_ITERATIONS = 15
FD_STEP = 1e-6                # [m] for the torso shift, [rad] for its rotation and the arm
ROW_STEP = np.array([0.001] * 3 + [0.002] * 3 + [0.023] * 3)  # per 8 ms row at most: torso [m], its turn and
#                            the arm [rad] (0.25 m/s, 2.5 rad/s, 2.9 rad/s: half the MX-28's no-load speed)
LIMIT_MARGIN_RAD = 0.035      # joints stay 2° inside their mechanical range
ARM_JOINTS = ("sho_pitch", "sho_roll", "el")
W_SMOOTH = np.array([1e2] * 3 + [1e0] * 3 + [0.0] * 3)   # per m² (rad²) of the torso's change of speed in a row
W_CROUCH_Z = 1e-3           # per m² of torso sinking when the body may crouch
SETTLE_CALLS = 40           # solves at most to settle on a point,
SETTLE_ROWS = 5.0           # each moving as far as this many rows may
MIN_GAIN = 1e-3             # a step that lowers the weighted error by less than this share ends the row's solve
RECENT = 8                  # points whose pose and features a solver remembers


class WholeBodyIk:
    """The IK of one hand on a robot standing on ``support`` (``left``, ``right`` or ``double``: then the left sole
    is the frame), prepared at the pose ``start`` (20,) [rad]."""

    def __init__(self, spec: Spec, support: Support | SupportName, hand: Side, start: np.ndarray, crouch: bool = False):
        self.spec, self.hand = spec, hand
        sup = Support.of(support)
        self.frame = sup.stance
        self.double = sup.is_double
        self.start = np.asarray(start, dtype=float).copy()
        self.arm = np.array([spec.joint_names.index(f"{hand[0]}_{j}") for j in ARM_JOINTS])
        self.legs: list[Leg] = [leg_of(spec, s) for s in (("left", "right") if self.double else (self.frame,))]
        stance = leg_of(spec, self.frame)
        sole, rot = leg_fk(stance, self.start[list(stance.index)])      # the stance sole in the torso frame
        self.torso_rot = rot[0].T                                         # the torso in the stance sole's frame
        self.torso_pos = -self.torso_rot @ sole[0]
        self.soles_world = {}
        for leg in self.legs:                                              # each sole in the stance sole's frame
            p, r = leg_fk(leg, self.start[list(leg.index)])
            self.soles_world[leg.side] = (self.torso_rot @ p[0] + self.torso_pos, self.torso_rot @ r[0])
        self.reach = {}
        for leg in self.legs:                                              # how far each leg may stretch
            p, r = self.soles_world[leg.side]
            local = self.torso_rot.T @ (p - self.torso_pos)
            ankle = local + (self.torso_rot.T @ r) @ np.array([0.0, 0.0, leg.ankle_to_sole])
            share = float(np.linalg.norm(ankle - leg.hip)) / (leg.thigh + leg.calf)
            self.reach[leg.side] = max(share, MAX_REACH_SHARE)
        moved = np.concatenate([self.arm] + [np.array(leg.index) for leg in self.legs])
        knees = np.array([spec.joint_names.index(f"{leg.side[0]}_knee") for leg in self.legs])
        self._straight_knees = knees[np.abs(self.start[knees]) < STRAIGHT_KNEE_RAD] if not crouch else knees[:0]
        self._w_posture = W_POSTURE.copy()
        self._fd_step = np.full(9, FD_STEP)
        if crouch:                                   # sinking is free, and measured downwards (a straight leg
            self._w_posture[2] = W_CROUCH_Z          # cannot rise: its upward difference is zero)
            self._fd_step[2] = -FD_STEP
        self._leg_arrays = (np.array([leg.hip for leg in self.legs]),
                            np.array([[leg.thigh, leg.calf, leg.ankle_to_sole] for leg in self.legs]),
                            np.array([leg.sign for leg in self.legs], dtype=float),
                            np.array([leg.index for leg in self.legs]),
                            np.array([self.soles_world[leg.side][0] for leg in self.legs]),
                            np.array([self.soles_world[leg.side][1] for leg in self.legs]),
                            np.array([self.reach[leg.side] for leg in self.legs]))
        hard = np.array([joint_range(spec.joints[i], "mechanical") for i in moved])
        self._moved = moved
        self._leg_joints = np.concatenate([np.array(leg.index) for leg in self.legs])
        self.lower = np.minimum(hard[:, 0] + LIMIT_MARGIN_RAD, self.start[moved])
        self.upper = np.maximum(hard[:, 1] - LIMIT_MARGIN_RAD, self.start[moved])
        plan = body_cost(spec, self.frame).kernel_plan()
        if plan is None:
            raise ModelError("expected the D-H model's compiled plan for the whole-body IK", "model")
        self._plan = plan
        self._hand_row = row_of(f"{hand}_hand")
        self._elbow_row = row_of(f"{hand[0]}_el")
        first = row_of(f"{other_side(self.frame)}_foot_0")
        self._foot_rows = slice(first, first + 4)
        self._recent: dict[bytes, tuple[np.ndarray, dict[str, np.ndarray]]] = {}
        self.x0 = np.concatenate([np.zeros(6), self.start[self.arm]])
        ref = self.features(self.servo(self.x0[None]))
        self.feet0, self.com0, self.torso0 = ref["feet"][0], ref["com"][0], ref["torso"][0]

    def _one(self, x: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The pose (20,) [rad] and the features (each (1, m)) of unknowns ``x`` (9,): the first row of
        :meth:`_stencil`."""
        q, f = self._stencil(x)
        return q[0], {k: v[:1] for k, v in f.items()}

    def _stencil(self, x: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The poses (10, 20) [rad] and features (each (10, m)) of unknowns ``x`` (9,) and of ``x`` with each unknown
        moved by its finite-difference step, remembered for the last few ``x``: a trial step is costed on its
        first row and, taken, its Jacobian comes from the rest (one batch is not much dearer than one pose)."""
        key = np.asarray(x, dtype=float).tobytes()
        found = self._recent.get(key)
        if found is None:
            batch = np.asarray(x, dtype=float)[None] + np.vstack([np.zeros(len(self._fd_step)), np.diag(self._fd_step)])
            q = self.servo(batch)
            found = (q, self.features(q))
            self._recent[key] = found
            if len(self._recent) > RECENT:
                self._recent.pop(next(iter(self._recent)))
        return found

    def servo(self, x: np.ndarray) -> np.ndarray:
        """Poses (N, 20) [rad] of unknowns (N, 9): torso shift [m], torso rotation vector [rad], arm joints [rad]
        (one compiled loop: :func:`~op2motion.motion.whole_body_kernel.servo_rows`)."""
        from op2motion.motion.whole_body_kernel import HIP_BELOW, servo_rows

        x = np.ascontiguousarray(np.atleast_2d(x), dtype=float)
        out = np.empty((len(x), len(self.start)))
        failed = servo_rows(x, (self.torso_rot, self.torso_pos, self.start, self.arm), self._leg_arrays,
                            (self._moved, self.lower, self.upper), out)
        if failed >= 0:
            leg, why = self.legs[failed // 3], failed % 3
            raise InputError(f"expected the {leg.side} sole within the leg's reach with the hip above the ankle, got "
                             f"{'a hip below its ankle' if why == HIP_BELOW else 'a sole out of reach'}", "leg")
        return out

    def features(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Hand (N, 3), forearm direction (N, 3), other sole's corners (N, 12), CoM x, y (N, 2), torso x, z
        axes (N, 6) and how far links are inside :data:`CLEAR_TASK_M` of each other (N, 1) of poses (N, 20)
        [rad, m] (the D-H model's points, full-inertia CoM and clearance in one compiled loop:
        :func:`~op2motion.posture.kernel.body_features`)."""
        from op2motion.posture.kernel import body_features

        angles = servo_to_book(q, self.frame, self.spec)
        features = body_features(self._plan, angles.vector(), CLEARANCE_EXACT_M)
        pts, com, clearance = features.points, features.com, features.clearance
        hand, elbow = pts[:, self._hand_row], pts[:, self._elbow_row]
        forearm = hand - elbow
        axes = torso_axes(pts.transpose(1, 2, 0), self.spec)
        return {"hand": hand, "point": forearm / np.linalg.norm(forearm, axis=1, keepdims=True),
                "feet": pts[:, self._foot_rows].reshape(len(q), -1), "com": com[:, :2],
                "torso": np.concatenate([axes[0].T, axes[2].T], axis=1),
                "close": np.maximum(CLEAR_TASK_M - clearance, 0.0)[:, None], "knees": q[:, self._straight_knees]}

    def _stack(self, f: dict[str, np.ndarray], hand: np.ndarray, point: np.ndarray | None) -> tuple[np.ndarray,
                                                                                                    np.ndarray]:
        """Task values (N, m) and their targets (m,), each scaled by the square root of its weight."""
        parts = [(f["hand"], hand, W_HAND), (f["com"], self.com0, W_COM), (f["torso"], self.torso0, W_TORSO),
                 (f["close"], np.zeros(1), W_CLEAR), (f["knees"], self.start[self._straight_knees], W_STRAIGHT_KNEE)]
        if self.double:
            parts.append((f["feet"], self.feet0, W_FEET))
        if point is not None:
            parts.append((f["point"], point, W_POINT))
        values = np.concatenate([v * np.sqrt(w) for v, _, w in parts], axis=1)
        target = np.concatenate([t * np.sqrt(w) for _, t, w in parts])
        return values, target

    def _cost(self, x: np.ndarray, hand: np.ndarray, point: np.ndarray | None,
              pulls: list[tuple[np.ndarray, np.ndarray]]) -> float:
        values, target = self._stack(self._one(x)[1], hand, point)
        return float(np.sum((target - values[0]) ** 2) + sum(np.sum(w * (x - ref) ** 2) for w, ref in pulls))

    def _bounded(self, x: np.ndarray, trial: np.ndarray, legs: np.ndarray, rows: float) -> np.ndarray:
        """``trial`` pulled back towards ``x`` until no leg joint turns more than ``rows`` times
        :data:`JOINT_ROW_STEP` from ``legs`` (near a straight knee a fraction of a millimetre of sinking is degrees
        of knee)."""
        if np.abs(self._one(trial)[0][self._leg_joints] - legs).max() <= rows * JOINT_ROW_STEP:
            return trial
        shares = np.linspace(1.0, 0.0, 33)[:, None]
        batch = np.repeat(trial[None], len(shares), axis=0)
        batch[:, :6] = x[:6] + shares * (trial[:6] - x[:6])      # the legs follow the torso alone
        turn = np.abs(self.servo(batch)[:, self._leg_joints] - legs).max(axis=1)
        bounded: np.ndarray = batch[int(np.flatnonzero(turn <= rows * JOINT_ROW_STEP)[0])]
        return bounded

    def solve(self, x: np.ndarray, hand: np.ndarray, point: np.ndarray | None = None, rows: float = 1.0,
              before: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """Unknowns (9,) from ``x`` that put the hand at ``hand`` (3,) [m] (and the forearm along ``point`` (3,), if
        given) with the other tasks held, moving as far as ``rows`` rows may, and the hand's remaining error [m].
        Given the row ``before`` ``x``, the torso keeps its speed (:data:`W_SMOOTH`: its acceleration moves the
        ZMP). A step that does not lower the weighted error is retried with more damping."""
        x = np.asarray(x, dtype=float).copy()
        pulls = [(self._w_posture, self.x0)]
        if before is not None:
            pulls.append((W_SMOOTH, 2.0 * x - before))
        n, low, high = len(x), x - rows * ROW_STEP, x + rows * ROW_STEP
        legs = self._one(x)[0][self._leg_joints]
        damping, cost = DAMPING, self._cost(x, hand, point, pulls)
        for _ in range(MAX_ITERATIONS):
            f = self._stencil(x)[1]
            error = float(np.linalg.norm(f["hand"][0] - hand))
            feet = float(np.abs(f["feet"][0] - self.feet0).max()) if self.double else 0.0
            if error < SOLVE_TOL_M and feet < SOLVE_TOL_M:
                break
            values, target = self._stack(f, hand, point)
            jac = (values[1:] - values[0]).T / self._fd_step            # (m, n)
            normal = jac.T @ jac + np.diag(sum(w for w, _ in pulls))
            rhs = jac.T @ (target - values[0]) - sum(w * (x - ref) for w, ref in pulls)
            for _ in range(8):
                trial = self._bounded(x, np.clip(x + np.linalg.solve(normal + damping * np.eye(n), rhs), low, high),
                                      legs, rows)
                trial_cost = self._cost(trial, hand, point, pulls)
                if trial_cost < cost:
                    gain = (cost - trial_cost) / max(cost, 1e-30)
                    x, cost, damping = trial, trial_cost, max(damping / 3.0, DAMPING)
                    break
                damping *= 10.0
            else:
                break
            if gain < MIN_GAIN:                       # stalled (at a speed bound or a limit): this row is done
                break
        return x, float(np.linalg.norm(self._one(x)[1]["hand"][0] - hand))

    def settle(self, x: np.ndarray, hand: np.ndarray, point: np.ndarray | None = None,
               known: Callable[[np.ndarray], bool] | None = None) -> tuple[np.ndarray, float]:
        """Unknowns (9,) from ``x`` that put the hand at ``hand`` (3,) [m] (the forearm along ``point``, if given),
        in at most :data:`SETTLE_CALLS` solves of :data:`SETTLE_ROWS` rows each (sooner where ``known`` says the
        unknowns have come to a solution already found), and the hand's remaining error [m]."""
        error = np.inf
        for _ in range(SETTLE_CALLS):
            previous = x
            x, error = self.solve(x, hand, point, SETTLE_ROWS)
            if error < SOLVE_TOL_M or np.abs(x - previous).max() < FD_STEP or (known is not None and known(x)):
                break
        return x, error
