"""The pose studio's model: one pose being edited, and what it looks like after every edit.

A :class:`PoseEdit` holds servo angles (20,) [rad] and a support (left, right or double). Edits go through it
(:meth:`PoseEdit.set_joint`, :meth:`PoseEdit.jog`, :meth:`PoseEdit.set_support`): a value outside the joint's
mechanical range or not a finite number is refused with an :class:`~op2motion.errors.InputError` naming the joint
and the range, and the pose is left as it was. After each edit :meth:`PoseEdit.readout` says what the page shows:
both centres of mass with their margins (the book's lumped CoM against its foot rectangle; the full-inertia CoM
against the real support polygon, on one foot also where it settles on the compliant servos), the swing foot's
clearance, the least clearance between the collision shapes (and which links), and each joint in degrees and ticks
with its cable-safe range. Nothing is written unless :meth:`PoseEdit.save` is called. World frame: the stance
foot's sole centre, X forward, Y left, Z up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from op2motion.errors import InputError
from op2motion.fileio import write_atomic
from op2motion.formats.posefile import pose_to_json
from op2motion.kinematics.dh_chain import matrix_frames
from op2motion.kinematics.report import pose_report
from op2motion.kinematics.shapes import self_clearance, shape_set
from op2motion.model.compliance import Compliance
from op2motion.robot.balance import (
    COM_MODEL_FULL,
    polygon_margin,
    rectangle_margin,
    support_extents,
    support_polygon,
)
from op2motion.robot.joints import book_to_servo, joint_range, servo_to_book, servo_to_ticks
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Side, Support, SupportName, as_side

CLEARANCE_WARN_M = 0.004      # links closer than this are highlighted (the optimiser's self-clearance floor)


@dataclass(frozen=True)
class JointState:
    """One joint as the page shows it: angle [deg], ticks, and the ranges [deg]."""

    name: str
    degrees: float
    ticks: int
    cable_safe: tuple[float, float]
    mechanical: tuple[float, float]

    @property
    def outside_cable_safe(self) -> bool:
        """Beyond the cable-safe range (allowed, marked)."""
        return not self.cable_safe[0] <= self.degrees <= self.cable_safe[1]


@dataclass(frozen=True)
class Readout:
    """What the page shows after an edit (lengths [m], world = stance sole frame)."""

    support: SupportName
    com_lumped: tuple[float, float, float]
    com_full: tuple[float, float, float]
    margin_lumped_m: float               # lumped CoM to the book's foot rectangle (single support; NaN on two feet)
    margin_full_m: float                 # full-inertia CoM to the real support polygon (rigid servos)
    margin_settled_m: float              # one foot: where it settles on the compliant servos (NaN on two feet)
    swing_clearance_m: float             # one foot: the lifted foot's lowest corner above the floor (NaN on two)
    self_clearance_m: float
    closest_links: tuple[str, str]
    joints: tuple[JointState, ...] = field(repr=False)
    polygon: tuple[tuple[float, float], ...] = ()   # the support polygon's corners (x, y) [m] on the floor
    hands: dict[str, tuple[float, float, float]] = field(default_factory=dict)   # left_hand, right_hand [m]

    @property
    def colliding(self) -> bool:
        """Links closer than :data:`CLEARANCE_WARN_M`."""
        return self.self_clearance_m < CLEARANCE_WARN_M

    def lines(self) -> list[str]:
        """The readout in words (one fact a line)."""
        def mm(v: float) -> str:
            return "n/a" if not math.isfinite(v) else f"{v * 1000:+.1f} mm"

        out = [f"support: {self.support}",
               f"CoM full inertia ({self.com_full[0]:+.3f}, {self.com_full[1]:+.3f}, {self.com_full[2]:.3f}) m, "
               f"margin {mm(self.margin_full_m)}" + ("" if math.isnan(self.margin_settled_m) else
                                                      f", settled on the servos {mm(self.margin_settled_m)}"),
               f"CoM lumped (book) ({self.com_lumped[0]:+.3f}, {self.com_lumped[1]:+.3f}, {self.com_lumped[2]:.3f}) m"
               + ("" if math.isnan(self.margin_lumped_m) else f", margin {mm(self.margin_lumped_m)}")]
        if math.isfinite(self.swing_clearance_m):
            out.append(f"swing foot {mm(self.swing_clearance_m)} above the floor")
        state = "COLLISION" if self.colliding else "clear"
        out.append(f"self-clearance {mm(self.self_clearance_m)} ({' / '.join(self.closest_links)}): {state}")
        return out


class PoseEdit:
    """One pose under edit (see the module docstring)."""

    def __init__(self, spec: Spec, pose: Pose):
        self.spec, self.name = spec, pose.name
        self.servo = np.array(pose.servo, dtype=float)
        self.support = Support.of(pose.support)
        self._index = {n: i for i, n in enumerate(spec.joint_names)}
        self._compliance = Compliance(spec)
        self.action: Any = None           # an open action file (op2motion.formats.action.ActionFile), in memory
        self.played: Any = None           # the played page's trajectory

    def joint_index(self, name: str) -> int:
        """The servo index of joint ``name``; :class:`InputError` for an unknown name."""
        if name not in self._index:
            raise InputError(f"expected one of {', '.join(self.spec.joint_names)}, got {name!r}", "joint")
        return self._index[name]

    def set_joint(self, name: str, degrees: object) -> Readout:
        """Set one joint [deg] within its mechanical range; the pose is unchanged when refused."""
        i = self.joint_index(name)
        try:
            value = float(degrees)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise InputError(f"expected a number of degrees, got {degrees!r}", name) from None
        lo, hi = (math.degrees(v) for v in joint_range(self.spec.joints[i], "mechanical"))
        if not (math.isfinite(value) and lo - 1e-9 <= value <= hi + 1e-9):
            raise InputError(f"expected {lo:.1f}° to {hi:.1f}° (its mechanical range), got {degrees!r}", name)
        self.servo[i] = math.radians(value)
        return self.readout()

    def jog(self, name: str, delta_deg: float) -> Readout:
        """Move one joint by ``delta_deg`` [deg], stopping at its mechanical range."""
        i = self.joint_index(name)
        lo, hi = (math.degrees(v) for v in joint_range(self.spec.joints[i], "mechanical"))
        return self.set_joint(name, min(max(math.degrees(self.servo[i]) + float(delta_deg), lo), hi))

    def set_support(self, support: Support | SupportName) -> Readout:
        """Stand on ``left``, ``right`` or ``double``."""
        self.support = Support.of(support)
        return self.readout()

    def pose(self) -> Pose:
        """The pose as it is now."""
        return Pose(self.name, self.support, self.servo.copy(), provenance={"command": "op2motion studio"})

    def save(self, path: str | Path) -> Path:
        """Write the pose file atomically; returns its path."""
        target = Path(path)
        write_atomic(target, pose_to_json(self.pose(), self.spec))
        return target

    def readout(self) -> Readout:
        """What the page shows for the pose as it is (see :class:`Readout`)."""
        spec, stance = self.spec, self.support.stance
        angles = servo_to_book(self.servo[None], stance, spec)
        report = pose_report(angles, spec, "dh")
        points, full = report.points, report.com_full
        frames = matrix_frames(angles.vector(), spec, stance)
        clearance, pair = self_clearance(frames, shape_set(spec, stance))
        links = shape_set(spec, stance).pair_names()[int(pair[0])]
        nan = float("nan")
        hands = {h: (float(p[0]), float(p[1]), float(p[2])) for h, p in
                 ((h, points.point(h)[0]) for h in ("left_hand", "right_hand"))}
        if self.support.is_double:
            hull = Support.DOUBLE.polygon({s: points.foot_corners(s)[0] for s in SIDES})
            polygon = hull
            margin_full, margin_lumped, settled_margin, swing = float(polygon_margin(full[:2], hull)[0]), nan, nan, nan
        else:
            margin_full = float(rectangle_margin(np.array([full[0]]), np.array([full[1]]),
                                                 support_extents(spec, stance, 1.0, COM_MODEL_FULL))[0])
            margin_lumped = report.stability_margin_m
            polygon = support_polygon(spec, stance, 1.0, com_model=COM_MODEL_FULL)
            settled = self._compliance.settle(points, full[:, None]).com_xy[:, 0]
            settled_margin = float(rectangle_margin(settled[:1], settled[1:],
                                                    support_extents(spec, stance, 1.0, COM_MODEL_FULL))[0])
            swing = report.swing_foot_min_z
        return Readout(self.support.value, tuple(report.com), tuple(full), margin_lumped, margin_full,
                       settled_margin, swing, float(clearance[0]), links, self._joints(),
                       tuple((float(x), float(y)) for x, y in np.asarray(polygon)[:, :2]), hands)

    # -- action files -------------------------------------------------------------------------------------------
    def open_action(self, path: str | Path) -> int:
        """Open a ROBOTIS action file (kept in memory; nothing is written); returns its number of pages in use."""
        from op2motion.formats.action import ActionFile
        from op2motion.formats.actionlayout import NUM_PAGES

        self.action = ActionFile.read(path)
        return sum(1 for i in range(1, NUM_PAGES) if not self.action.is_empty(i))

    def _opened(self) -> Any:
        if self.action is None:
            raise InputError("expected an action file: open one first", "action file")
        return self.action

    def play(self, page: int) -> float:
        """Play ``page`` of the open file as the robot does (8 ms goals); returns its length [s]. The pose follows
        :meth:`scrub`."""
        from op2motion.motion.pipeline import play_page

        played = play_page(self._opened(), int(page), self.spec)
        self.played = played.trajectory
        seconds: float = (len(self.played.goals) - 1) * self.played.dt
        return seconds

    def scrub(self, t_s: float) -> Readout:
        """The pose at time ``t_s`` [s] of the played page (its goal of that 8 ms tick)."""
        played = self.played
        if played is None:
            raise InputError("expected a played page: play one first", "page")
        if isinstance(t_s, bool) or not isinstance(t_s, (int, float)) or not math.isfinite(t_s):
            raise InputError(f"expected a time [s], got {t_s!r}", "time [s]")
        row = int(min(max(round(float(t_s) / played.dt), 0), len(played.goals) - 1))
        self.servo, self.support = np.array(played.goals[row], dtype=float), Support.of(played.supports[row])
        return self.readout()

    def add_to_page(self, page: int, seconds: float, overwrite: bool = False) -> int:
        """Put the pose as a one-step page of ``seconds`` (at least 24 ms) at ``page`` of the open file (in memory);
        an occupied page only with ``overwrite``. Returns the page."""
        done = self._opened().with_poses([self.pose()], self.spec, int(page), float(seconds), overwrite)
        action, first = done.action, done.first
        self.action = action
        return int(first)

    def save_action(self, path: str | Path) -> Path:
        """Write the open action file atomically."""
        target = Path(path)
        write_atomic(target, self._opened().data)
        return target

    def balance(self, hand: Side, pinned: list[str], on_iteration: Any = None) -> tuple[Readout, str]:
        """Re-solve the body with the optimiser from the pose as it is: the ``hand`` kept where it is, the
        ``pinned`` joints kept at their angles, the rest free within the optimiser's box; the pose is adopted only
        when the optimiser reaches (hand within 1 mm, balanced, clear of itself). Returns the readout and the
        optimiser's message. One foot only."""
        if self.support.is_double:
            raise InputError("expected one foot: the optimiser balances on the left or the right foot", "support")
        if hand not in ("left", "right"):
            raise InputError(f"expected left or right, got {hand!r}", "hand")
        for name in pinned:
            self.joint_index(name)
        from op2motion.posture.cost import PostureProblem
        from op2motion.posture.pso import PSOSettings, SearchSpace, variable_bounds
        from op2motion.posture.solve import optimize_posture
        from op2motion.robot.spec import BOOK_VARS

        support = self.support.stance                 # one foot (refused above): its value
        start = servo_to_book(self.servo[None], support, self.spec).vector()[0]
        target = self.readout().hands[f"{hand}_hand"]
        problem = PostureProblem(as_side(support, "support"), as_side(hand, "hand"), target, 1.0)
        lo, hi = variable_bounds(problem, self.spec)
        lo, hi = np.minimum(lo, start), np.maximum(hi, start)         # the pose as it is lies in the box
        for name in pinned:
            k = BOOK_VARS.index(self.spec.joint(name).book[support].var)
            lo[k] = hi[k] = start[k]
        result = optimize_posture(problem, self.spec, PSOSettings(), on_iteration=on_iteration,
                                  space=SearchSpace((lo, hi), start))
        if result.reached:
            self.servo = book_to_servo(result.angles, self.spec)[0]
        return self.readout(), result.message

    def reach(self, hand: Side, target: object) -> tuple[Readout, float]:
        """Move one hand towards ``target`` (x, y, z) [m] with its arm's three joints (the project's arm IK, within
        the cable-safe ranges); returns the readout and the distance [m] left to the target."""
        if hand not in ("left", "right"):
            raise InputError(f"expected left or right, got {hand!r}", "hand")
        try:
            goal = np.asarray(target, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            goal = np.full(1, np.nan)
        if goal.shape != (3,) or not np.all(np.isfinite(goal)):
            raise InputError(f"expected 3 finite numbers [m], got {target!r}", "target")
        from op2motion.kinematics import forward
        from op2motion.kinematics.arm_ik import solve_arm_ik

        stance = self.support.stance
        angles = servo_to_book(self.servo[None], stance, self.spec)
        now = forward(angles, self.spec, "dh").point(f"{hand}_hand")[0]
        ik = solve_arm_ik(angles, hand, goal - now, self.spec, model="dh")
        self.servo = book_to_servo(ik.angles, self.spec)[0]
        return self.readout(), ik.error_m

    def _joints(self) -> tuple[JointState, ...]:
        ticks = servo_to_ticks(self.servo, self.spec)
        return tuple(JointState(j.name, round(math.degrees(q), 3), int(t),
                                tuple(round(math.degrees(v), 2) for v in joint_range(j, "cable-safe")),  # type: ignore[arg-type]
                                tuple(round(math.degrees(v), 2) for v in joint_range(j, "mechanical")))  # type: ignore[arg-type]
                     for j, q, t in zip(self.spec.joints, self.servo, ticks))
