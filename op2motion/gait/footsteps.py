"""Footstep planning: where each foot lands, in the world frame of the start (X forward, Y left, Z up).

The body follows a path of poses ``c_0, c_1, ...`` (x [m], y [m], yaw [rad]), ``c_0`` at the origin between the
feet; step k puts its foot at ``c_k`` moved half the step width to its side, so each foot advances twice the
per-step displacement when it swings, and the last step closes the feet side by side. The first swing foot is the
one on the side the walk goes to (left for a left turn or a step to the left, else left for straight walking): the
leading foot opens the gap, the trailing one closes it, so the feet never cross.

Every swing is checked against the standing foot: the two sole rectangles, grown by :data:`FOOT_GAP_M`, must not
overlap anywhere along the swing's path seen from above (start, landing and the straight line between). A plan
that would let the feet touch is an error naming the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.gait.params import GaitParams
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side

FOOT_GAP_M = 0.005          # soles closer than this from above count as colliding
PATH_SAMPLES = 9            # poses checked along each swing (start and landing included)

TARGET_REACH_M = 1.0        # a walk target lies within this many metres of the start, each way
MAX_TARGET_STEPS = 200      # and within as many steps as --steps allows


@dataclass(frozen=True)
class Footstep:
    """A foot placement: ``side`` (left/right), sole centre (x, y) [m] and yaw [rad] in the world frame."""

    side: Side
    x: float
    y: float
    yaw: float

    @property
    def pose(self) -> np.ndarray:
        """(x, y, yaw) [m, m, rad]."""
        return np.array([self.x, self.y, self.yaw])


@dataclass(frozen=True)
class Footsteps:
    """The start placements of both feet and the steps, in order: step k moves ``steps[k].side`` from where that
    foot stood to ``steps[k]``."""

    start: dict[str, Footstep]
    steps: tuple[Footstep, ...]

    def stance_before(self, k: int) -> tuple[Footstep, Footstep]:
        """(standing foot, swing foot's previous placement) for step ``k``."""
        where = dict(self.start)
        for step in self.steps[:k]:
            where[step.side] = step
        side = self.steps[k].side
        other = "right" if side == "left" else "left"
        return where[other], where[side]


def moved(pose: np.ndarray, dx: float, dy: float, dyaw: float) -> np.ndarray:
    """``pose`` (x, y, yaw) moved by (dx, dy) in its own frame and turned by ``dyaw``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array([pose[0] + c * dx - s * dy, pose[1] + s * dx + c * dy, pose[2] + dyaw])


def foot_at(side: Side, centre: np.ndarray, width: float) -> Footstep:
    half = width / 2.0 if side == "left" else -width / 2.0
    x, y, yaw = moved(centre, 0.0, half, 0.0)
    return Footstep(side, float(x), float(y), float(yaw))


def step_width(params: GaitParams, spec: Spec) -> float:
    """Distance between the feet centres side by side [m]: the preset's, or the spec's hip width when it is 0."""
    return params.step_width_m or 2.0 * spec.geometry.hip_half_width


def leading_side(dy: float, dyaw: float) -> Side:
    """The foot that swings first towards a move of ``dy`` [m] sideways and ``dyaw`` [rad] of turn: the one on the
    side of the turn, or of the side step (left for a walk straight ahead or back), so the leading foot opens the gap
    and the feet never cross."""
    return "right" if dyaw < 0.0 or (dyaw == 0.0 and dy < 0.0) else "left"


def first_side(params: GaitParams) -> Side:
    """The foot that swings first (see the module docstring)."""
    return leading_side(params.step_side_m, params.turn_rad)


def place_footsteps(params: GaitParams, spec: Spec, target: tuple[float, float, float] | None = None) -> Footsteps:
    """The footsteps of ``params.steps`` steps; with ``target`` (x [m], y [m], yaw [rad]) the body walks there
    instead, in as few steps as the per-step advance allows (the step length, side and turn of ``params`` are the
    largest per step), the last step closing the feet."""
    width = step_width(params, spec)
    centre = np.zeros(3)
    start = {side: foot_at(side, centre, width) for side in ("left", "right")}
    moves = _target_moves(params, target) if target is not None else (
        [(params.step_length_m, params.step_side_m, params.turn_rad)] * (params.steps - 1))
    side = first_side(params) if target is None else leading_side(moves[0][1], moves[0][2])
    steps = []
    for dx, dy, dyaw in list(moves) + [(0.0, 0.0, 0.0)]:
        centre = moved(centre, dx, dy, dyaw)
        steps.append(foot_at(side, centre, width))
        side = "right" if side == "left" else "left"
    footsteps = Footsteps(start, tuple(steps))
    check_clear(footsteps, spec)
    return footsteps


def _target_moves(params: GaitParams, target: tuple[float, float, float]) -> list[tuple[float, float, float]]:
    """Equal moves (dx, dy, dyaw) per step reaching ``target`` in the body's start frame, each within the
    preset's per-step advance (at least 1 mm forward/sideways and 1° of turn per step allowed)."""
    x, y, yaw = (float(v) for v in target)
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise InputError(f"expected a finite target (x, y, yaw), got {target}", "target")
    if max(abs(x), abs(y)) > TARGET_REACH_M or abs(yaw) > math.pi + 1e-9:
        raise InputError(f"expected x and y within ±{TARGET_REACH_M:g} m and a heading within ±180°, got "
                         f"({x:g} m, {y:g} m, {math.degrees(yaw):g}°)", "target")
    limits = (max(abs(params.step_length_m), 1e-3), max(abs(params.step_side_m), 1e-3),
              max(abs(params.turn_rad), math.radians(1.0)))
    n = max(1, *(math.ceil(abs(v) / lim - 1e-9) for v, lim in zip((x, y, yaw), limits)))
    if n > MAX_TARGET_STEPS:
        raise InputError(f"expected a target within {MAX_TARGET_STEPS} steps of the {params.name!r} preset "
                         f"({abs(params.step_length_m) * 1000:g} mm, {abs(params.step_side_m) * 1000:g} mm and "
                         f"{math.degrees(abs(params.turn_rad)):g}° a step), got one {n} steps away", "target")
    # the body path is a straight line in the start frame with the heading turning evenly
    moves, pose = [], np.zeros(3)
    for k in range(1, n + 1):
        goal = np.array([x * k / n, y * k / n, yaw * k / n])
        c, s = math.cos(pose[2]), math.sin(pose[2])
        d = goal[:2] - pose[:2]
        moves.append((c * d[0] + s * d[1], -s * d[0] + c * d[1], goal[2] - pose[2]))
        pose = goal
    return moves


def zmp_margins(zmp: np.ndarray, contacts: Sequence[str], feet: Mapping[str, np.ndarray], spec: Spec) -> np.ndarray:
    """Margin [m] of each row's ZMP (K, 2) to the sole(s) of its contact (K,) on the floor (positive inside); the
    feet (x, y, z, yaw) (K, 4) per side."""
    from op2motion.robot.balance import point_margin
    from op2motion.robot.support import Support

    out = np.empty(len(zmp))
    points = np.asarray(zmp, dtype=float).tolist()
    for i, contact in enumerate(contacts):
        support = Support.of(contact)
        corners = {side: sole_rectangle(spec, Footstep(side, *feet[side][i, [0, 1, 3]])) for side in support.feet}
        x, y = points[i]
        out[i] = point_margin(x, y, support.polygon(corners))
    return out


def sole_rectangle(spec: Spec, step: Footstep, grow: float = 0.0) -> np.ndarray:
    """Corners (4, 2) [m] of the sole under ``step``, seen from above, grown by ``grow`` [m] on every side."""
    front, back, left, right = spec.sole_extents(step.side)
    local = np.array([[front + grow, left + grow], [-back - grow, left + grow], [-back - grow, -right - grow],
                      [front + grow, -right - grow]])
    c, s = math.cos(step.yaw), math.sin(step.yaw)
    corners: np.ndarray = local @ np.array([[c, s], [-s, c]]) + np.array([step.x, step.y])
    return corners


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Do two convex polygons (n, 2) overlap (separating-axis test)? (On floats: a plan tests a few thousand pairs
    of rectangles, where NumPy's call overhead was the cost.)"""
    pa, pb = np.asarray(a, dtype=float).tolist(), np.asarray(b, dtype=float).tolist()
    for poly in (pa, pb):
        for (x0, y0), (x1, y1) in zip(poly, poly[1:] + poly[:1]):
            nx, ny = -(y1 - y0), x1 - x0                                  # the edge's normal
            on_a, on_b = [x * nx + y * ny for x, y in pa], [x * nx + y * ny for x, y in pb]
            if max(on_a) < min(on_b) or max(on_b) < min(on_a):
                return False
    return True


def swing_clear(stand: Footstep, before: Footstep, step: Footstep, spec: Spec) -> bool:
    """Does the swing from ``before`` to ``step`` keep the soles :data:`FOOT_GAP_M` apart from the ``stand`` foot's
    all along its path seen from above (start, landing and the straight line between)?"""
    fixed = sole_rectangle(spec, stand, FOOT_GAP_M / 2.0)
    for u in np.linspace(0.0, 1.0, PATH_SAMPLES):
        moving = Footstep(step.side, *(before.pose + u * (step.pose - before.pose)))
        if _overlap(sole_rectangle(spec, moving, FOOT_GAP_M / 2.0), fixed):
            return False
    return True


def check_clear(footsteps: Footsteps, spec: Spec) -> None:
    """Raise :class:`InputError` if a swing foot comes within :data:`FOOT_GAP_M` of the standing foot."""
    for k, step in enumerate(footsteps.steps):
        stand, before = footsteps.stance_before(k)
        if not swing_clear(stand, before, step, spec):
            raise InputError(f"expected the feet to stay {FOOT_GAP_M * 1000:.0f} mm apart, got step {k + 1} "
                             f"({step.side} foot to x {step.x:.3f} m, y {step.y:.3f} m, yaw "
                             f"{math.degrees(step.yaw):.1f}°) touching the {stand.side} foot", "footsteps")
