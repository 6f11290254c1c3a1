"""Cartesian moves: a hand along a straight line while the whole body keeps its balance (the teach pendant's linear jog
on a humanoid).

:func:`line_move` puts the hand's target on the line from where it starts to where it should end, with a
minimum-jerk progress (10 s³ - 15 s⁴ + 6 s⁵ of the time share s), every 8 ms row; the whole-body IK
(:mod:`.whole_body`: feet fixed, CoM held softly, torso upright, joints in range) finds the rows in one of the ways
of :mod:`.line_solve` (forward from the start, crouching, or from the end back), the first that passes the checks.
The least clearance reported is exact (:func:`.checks.clearance`). A pointing direction of the forearm may be held
(``keep``) or turned to a new one by quaternion slerp. The result is refused
(:class:`~op2motion.errors.CheckFailed`) where the hand leaves the line by more than :data:`LINE_TOL_M`, links come
closer than :data:`~op2motion.posture.cost.SELF_CLEARANCE_M`, the CoM or the multibody ZMP nearer than
:data:`LINE_MARGIN_M` to the support's edge, or on two feet the loaded sole's own centre of pressure, the servos
sagging, nearer than :data:`FEET_MARGIN_M` to its edge (each lowered to what the start pose has); a duration too
short for the servos is bad input naming the joint. Frames: the stance sole's (world = support foot: X forward,
Y left, Z up; on both feet the left sole's).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from op2motion.errors import CheckFailed, InputError
from op2motion.formats.motionfile import Motion, MotionStep
from op2motion.jsonout import JsonObject, json_object
from op2motion.motion.body_checks import BodyChecks
from op2motion.motion.checks import check_trajectory, clearance
from op2motion.motion.line_solve import END_SEEDS_RAD, END_TOL_M, EndSearch, Rows, ways
from op2motion.motion.planner import SPEED_FRACTION
from op2motion.motion.trajectory import Trajectory
from op2motion.motion.waypoint import MAX_SEGMENT_S
from op2motion.motion.whole_body import WholeBodyIk
from op2motion.posture.cost import SELF_CLEARANCE_M, TARGET_LIMIT_M
from op2motion.robot.framework import CONTROL_PERIOD_S, DEFAULT_P_GAIN
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

LINE_TOL_M = 0.002          # the hand may leave the line by this much
LINE_MARGIN_M = 0.005       # the CoM stays this far inside the support (settled on one foot)
MIN_LINE_S = 0.1            # the shortest move [s]
MAX_LINE_M = 0.3            # the longest line [m]: about the OP2's arm span
ROW_STRIDE = 3              # a motion-file step every 3 rows (24 ms, the robot's shortest step)
GIVE_UP_M = 2 * LINE_TOL_M  # a way whose hand is this far off its row's target has failed there
FEET_MARGIN_M = 0.01       # on two feet the loaded sole's own CoP stays this far inside it, servos sagged (a
#                            lean that kept 5.7 mm fell in both engines, rocking on the foot; 21.7 mm stood)
FEET_EVERY = 6             # on two feet the soles' own CoP margins are solved every this many rows (48 ms)
SPEED_LAG_SHARE = 0.99      # a hand off the line while an arm joint ran this close to its limit: too fast
ORIENTATIONS = ("free", "keep")


@dataclass(frozen=True)
class LineRequest:
    """Which ``hand`` moves, to ``target_m`` (3,) [m] in the stance sole's frame or by ``delta_m`` (3,) [m] (one of
    the two), in ``duration_s`` [s]; ``orientation``: ``free``, ``keep`` (the forearm's direction held) or a
    direction (3,) to turn the forearm to; ``back``: then back to the start along the line in as long again."""

    hand: Side
    duration_s: float
    target_m: tuple[float, float, float] | None = None
    delta_m: tuple[float, float, float] | None = None
    orientation: str | tuple[float, float, float] = "free"
    back: bool = False

    def validated(self) -> "LineRequest":
        """Check the fields; raise :class:`InputError` naming the flag."""
        if self.hand not in ("left", "right"):
            raise InputError(f"expected 'left' or 'right', got {self.hand!r}", "hand")
        if (self.target_m is None) == (self.delta_m is None):
            raise InputError("expected exactly one of a target point or a displacement", "to")
        for name, v in (("to", self.target_m), ("by", self.delta_m)):
            if v is not None and (len(v) != 3 or not all(math.isfinite(c) and abs(c) <= TARGET_LIMIT_M for c in v)):
                raise InputError(f"expected 3 finite numbers within ±{TARGET_LIMIT_M:g} m, got {list(v)}", name)
        if not (math.isfinite(self.duration_s) and MIN_LINE_S <= self.duration_s <= MAX_SEGMENT_S):
            raise InputError(f"expected {MIN_LINE_S:g} to {MAX_SEGMENT_S:g} s, got {self.duration_s}", "duration")
        o = self.orientation
        if isinstance(o, str):
            if o not in ORIENTATIONS:
                raise InputError(f"expected free, keep or a direction DX DY DZ, got {o!r}", "orientation")
            return self
        if len(o) != 3 or not all(isinstance(c, (int, float)) and math.isfinite(c) for c in o):
            raise InputError(f"expected free, keep or a direction of 3 finite numbers DX DY DZ, got {o!r}",
                             "orientation")
        scale = max(abs(float(c)) for c in o)            # scaled first: (1e154, 1e154, 0) has no finite norm
        if scale == 0.0:
            raise InputError(f"expected a direction (not all zero), got {o!r}", "orientation")
        unit = np.array(o, dtype=float) / scale
        unit /= np.linalg.norm(unit)
        return replace(self, orientation=(float(unit[0]), float(unit[1]), float(unit[2])))


@dataclass(frozen=True)
class LineFigures:
    """A line move's figures: the hand, where it starts and ends [m], the line's length [m], the hand's largest
    deviation from it [m], the least CoM margin [m] and clearance [m] along it, the fastest joint's speed [rad/s],
    how it was solved, the time spent changing the arm's branch first [s], and the largest pointing error [deg]
    (None: the hand's direction was not held)."""

    hand: Side
    hand_start_m: tuple[float, ...]
    hand_end_m: tuple[float, ...]
    length_m: float
    line_deviation_max_m: float
    com_margin_min_m: float
    min_clearance_m: float
    joint_speed_max_rad_s: float
    joint_speed_joint: str
    solved: str
    reconfigure_s: float
    pointing_error_max_deg: float | None


@dataclass(frozen=True)
class LineMove:
    """A planned line: the goals (K, 20) [rad] every 8 ms, the hand's line (start, end) [m], its path (K, 3) [m]
    and distance from the line (K,) [m], the CoM margin (K,) [m] and least clearance (K,) [m] along the way, the
    joint speeds (K, 20) [rad/s] and the forearm's angle from its commanded direction (K,) [rad] (None: free)."""

    pose: Pose
    hand: Side
    start_m: np.ndarray
    end_m: np.ndarray
    goals: np.ndarray
    hand_path: np.ndarray
    deviation_m: np.ndarray
    com_margin_m: np.ndarray
    clearance_m: np.ndarray
    speeds: np.ndarray
    pointing_error_rad: np.ndarray | None
    how: str = "forward"
    reconfigure_s: float = 0.0

    @property
    def times(self) -> np.ndarray:
        """Time of each row [s] (K,)."""
        return np.arange(len(self.goals)) * CONTROL_PERIOD_S

    def figures(self, spec: Spec) -> LineFigures:
        """The figures of the move (joint names from ``spec``)."""
        worst = np.unravel_index(int(np.argmax(np.abs(self.speeds))), self.speeds.shape)
        pointing = self.pointing_error_rad
        return LineFigures(self.hand, tuple(float(v) for v in self.start_m), tuple(float(v) for v in self.end_m),
                           float(np.linalg.norm(self.end_m - self.start_m)), float(self.deviation_m.max()),
                           float(self.com_margin_m.min()), float(self.clearance_m.min()),
                           float(abs(self.speeds[worst])), spec.joint_names[int(worst[1])], self.how,
                           self.reconfigure_s, None if pointing is None else math.degrees(float(pointing.max())))

    def as_dict(self, spec: Spec) -> JsonObject:
        """:meth:`figures` for reports and ``--json`` (the pointing error only where the hand's direction was
        held)."""
        out = json_object(self.figures(spec))
        if out["pointing_error_max_deg"] is None:
            del out["pointing_error_max_deg"]
        return out

    def trajectory(self, p_gain: int = DEFAULT_P_GAIN) -> Trajectory:
        """The goals as a trajectory on the pose's support (for the checks and physics)."""
        k = len(self.goals)
        segment = np.zeros(k, dtype=int)
        segment[0] = -1
        return Trajectory(self.goals, np.full(self.goals.shape, float(p_gain)), (self.pose.support.value,) * k,
                          segment, (f"{self.hand} hand line",))

    def motion(self, name: str, p_gain: int = DEFAULT_P_GAIN) -> Motion:
        """The move as a motion file's steps: the start pose, then every :data:`ROW_STRIDE`-th row inline."""
        last_row = len(self.goals) - 1
        rows = [r for r in range(ROW_STRIDE, last_row, ROW_STRIDE) if last_row - r >= ROW_STRIDE] + [last_row]
        steps = [MotionStep(self.pose, None, 0.0, 0.0)]
        last = 0
        for k, r in enumerate(rows, start=1):
            pose = Pose(f"{name}{k}", self.pose.support, self.goals[r])
            steps.append(MotionStep(pose, None, (r - last) * CONTROL_PERIOD_S, 0.0))
            last = r
        return Motion(name, tuple(steps), "quintic", p_gain)


def _slerp_directions(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unit vectors (K, 3) turned from ``a`` towards ``b`` by the shares ``s`` (K,): the quaternion of the shortest
    rotation from a to b, slerped from the identity (for a single rotation that is the rotation by s times its
    angle about its axis)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    sin, cos = np.linalg.norm(axis), float(a @ b)
    if sin < 1e-12:
        return np.repeat(a[None], len(s), axis=0)
    axis, angle = axis / sin, math.atan2(sin, cos)
    theta = s[:, None] * angle                  # slerp(1, q, s) = cos(s θ/2) + sin(s θ/2) u
    out: np.ndarray = a * np.cos(theta) + np.cross(axis, a) * np.sin(theta) + axis * (axis @ a) * (1 - np.cos(theta))
    return out


def _progress(k: int) -> np.ndarray:
    tau = np.linspace(0.0, 1.0, k)
    return 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    span = b - a
    t = np.clip((points - a) @ span / max(float(span @ span), 1e-18), 0.0, 1.0)
    out: np.ndarray = np.linalg.norm(points - (a + t[:, None] * span), axis=1)
    return out


def _targets(request: LineRequest, start: np.ndarray, end: np.ndarray, pointing: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One way: the progress (K,), the hand's targets (K, 3) [m] and the forearm's directions (K, 3) (None: free)
    per row."""
    s = _progress(int(math.ceil(request.duration_s / CONTROL_PERIOD_S - 1e-9)) + 1)
    o = request.orientation
    points = None if o == "free" else _slerp_directions(pointing, pointing if o == "keep"
                                                          else np.asarray(o, dtype=float), s)
    return s, start + s[:, None] * (end - start), points


class TooFast(InputError):
    """A way kept to the line and the balance but its joints would pass the servos' speed: a longer duration
    helps."""


def _refuse_off_line(request: LineRequest, off: np.ndarray, share: np.ndarray, speeds: np.ndarray,
                     arm: np.ndarray, spec: Spec) -> None:
    """Bad input where the hand lags with an arm joint at its speed limit; a failed check where the hand leaves the
    line."""
    worst = int(np.argmax(off))
    limit = SPEED_FRACTION * spec.servo.no_load_speed_rad_s
    lagging = np.abs(speeds[:worst + 1, arm]).max(axis=0)
    if off[worst] > LINE_TOL_M and lagging.max() > SPEED_LAG_SHARE * limit:
        raise InputError(f"expected more than {request.duration_s:g} s: the hand lags the line by "
                         f"{off[worst] * 1000:.1f} mm at {worst * CONTROL_PERIOD_S:.2f} s with "
                         f"{spec.joint_names[int(arm[np.argmax(lagging)])]} at its speed limit ({limit:.2f} rad/s, "
                         f"{SPEED_FRACTION:.0%} of the MX-28's no-load speed)", "duration")
    if off[worst] > LINE_TOL_M:
        raise CheckFailed(f"the {request.hand} hand cannot follow the line: {off[worst] * 1000:.1f} mm off at "
                          f"{worst * CONTROL_PERIOD_S:.2f} s ({share[worst]:.0%} of the way, expected at most "
                          f"{LINE_TOL_M * 1000:.0f} mm): the arm's three joints and the legs cannot hold it there")


def _refuse_too_fast(request: LineRequest, speeds: np.ndarray, spec: Spec) -> None:
    """Bad input (:class:`TooFast`) where a joint's speed (K, 20) [rad/s] passes the servos' limit."""
    limit = SPEED_FRACTION * spec.servo.no_load_speed_rad_s
    fastest = np.unravel_index(int(np.argmax(np.abs(speeds))), speeds.shape)
    if abs(speeds[fastest]) > limit:
        need = request.duration_s * abs(speeds[fastest]) / limit
        raise TooFast(f"expected at least {need:.2f} s: in {request.duration_s:g} s "
                      f"{spec.joint_names[int(fastest[1])]} would turn at {abs(speeds[fastest]):.2f} rad/s (over "
                      f"{limit:.2f} rad/s, {SPEED_FRACTION:.0%} of the MX-28's no-load speed)", "duration")


def _feet_margin_of(spec: Spec) -> Callable[[np.ndarray], float]:
    """The loaded sole's own CoP margin [m] of goals (20,) [rad] on two feet, the default servos sagging
    (:func:`~op2motion.model.equilibrium.loaded_foot_margin`); each pose solved once (a forward way watches the rows
    the final check measures again), nearby poses sharing a Jacobian (:class:`~op2motion.model.equilibrium.Chord`)."""
    from op2motion.model.equilibrium import Chord, loaded_foot_margin
    from op2motion.model.servo import ServoModel

    servo = ServoModel.of(spec)
    known: dict[bytes, float] = {}
    chord = Chord()             # the rows of a line lie close together: one Jacobian serves a run of them

    def margin(goal: np.ndarray) -> float:
        key = np.asarray(goal, dtype=float).tobytes()
        if key not in known:
            known[key] = loaded_foot_margin(goal, spec, servo.kp, servo.torque_max, chord)
        return known[key]
    return margin


def _feet_margins(goals: np.ndarray, margin: Callable[[np.ndarray], float]) -> np.ndarray:
    """On two feet, the loaded sole's own CoP margin [m] (``margin`` of a pose) at every :data:`FEET_EVERY`-th row
    and the last (K,), each row taking the margin of the last one measured."""
    rows = sorted(set(range(0, len(goals), FEET_EVERY)) | {len(goals) - 1})
    measured = np.array([margin(goals[r]) for r in rows])
    return measured[np.searchsorted(rows, np.arange(len(goals)), side="right") - 1]


def _refuse_unbalanced(margin: np.ndarray, close: np.ndarray, zmp: np.ndarray, feet: np.ndarray | None) -> None:
    """A failed check where the CoM margin (K,) [m], the ZMP's margin (K,) [m], on two feet the loaded sole's own
    CoP margin (K,) [m], or the clearance (K,) [m] falls below the limits (or below what the first row has)."""
    margin_floor = min(LINE_MARGIN_M, float(margin[0]))
    clear_floor = min(SELF_CLEARANCE_M, float(close[0]))
    if margin.min() < margin_floor:
        i = int(np.argmin(margin))
        raise CheckFailed(f"the centre of mass comes {margin[i] * 1000:.1f} mm from the support's edge at "
                          f"{i * CONTROL_PERIOD_S:.2f} s (expected at least {margin_floor * 1000:.1f} mm)")
    if feet is not None and feet.min() < min(FEET_MARGIN_M, float(feet[0])):
        i = int(np.argmin(feet))
        raise CheckFailed(f"the loaded foot's own centre of pressure comes {feet[i] * 1000:.1f} mm from its edge at "
                          f"{i * CONTROL_PERIOD_S:.2f} s where the servos sag under the load (expected at least "
                          f"{min(FEET_MARGIN_M, float(feet[0])) * 1000:.1f} mm): the robot would tip over it")
    zmp_floor = min(LINE_MARGIN_M, float(zmp[0]))
    if zmp.min() < zmp_floor:
        i = int(np.argmin(zmp))
        raise CheckFailed(f"the ZMP comes {zmp[i] * 1000:.1f} mm from the support's edge at "
                          f"{i * CONTROL_PERIOD_S:.2f} s (expected at least {zmp_floor * 1000:.1f} mm): the body "
                          f"accelerates too hard there; a longer --duration may help")
    if close.min() < clear_floor:
        i = int(np.argmin(close))
        raise CheckFailed(f"links come {close[i] * 1000:.1f} mm close at {i * CONTROL_PERIOD_S:.2f} s "
                          f"(expected at least {clear_floor * 1000:.1f} mm): move the hand another way")


def _checked(pose: Pose, request: LineRequest, spec: Spec, ik: WholeBodyIk, rows: Rows, start: np.ndarray,
             end: np.ndarray, feet_margin: Callable[[np.ndarray], float]) -> LineMove:
    """The move of ``rows`` after every check (raises :class:`CheckFailed` or :class:`InputError`); on two feet
    ``feet_margin`` gives a pose's loaded-sole CoP margin [m]."""
    goals = rows.goals
    reached = ik.features(goals)
    speeds = np.gradient(goals, CONTROL_PERIOD_S, axis=0)
    share = (rows.targets - start) @ (end - start) / max(float(np.sum((end - start) ** 2)), 1e-18)
    _refuse_off_line(request, np.linalg.norm(reached["hand"] - rows.targets, axis=1), share, speeds, ik.arm, spec)
    measured = BodyChecks(spec, None if Support.of(pose.support).is_double else pose.support.stance).measure(goals)
    pointing = None
    if rows.points is not None:
        pointing = np.arccos(np.clip(np.einsum("ij,ij->i", reached["point"], rows.points), -1.0, 1.0))
    move = LineMove(pose, request.hand, start, end, goals, reached["hand"],
                    _distance_to_segment(reached["hand"], start, end), measured.margin, clearance(goals, spec)[0],
                    speeds, pointing, rows.how, rows.reconfigure_s)
    feet = _feet_margins(goals, feet_margin) if Support.of(pose.support).is_double else None
    _refuse_unbalanced(measured.margin, move.clearance_m, check_trajectory(move.trajectory(), spec).zmp_margin_m, feet)
    _refuse_too_fast(request, speeds, spec)
    return move


def _most_useful(request: LineRequest, end: np.ndarray, failures: list[Exception], search: EndSearch) -> Exception:
    """Of the ways' failures, the one to report: the end out of reach where no arm configuration holds the hand
    there, else a way that only needs a longer duration, else the first way's failure."""
    if search.found == 0:
        return CheckFailed(f"the {request.hand} hand cannot reach the line's end ({', '.join(f'{v:+.3f}' for v in end)}"
                           f" m): from {len(END_SEEDS_RAD)} starting arm configurations the nearest comes "
                           f"{search.closest_m * 1000:.1f} mm short (expected at most {END_TOL_M * 1000:.1f} mm)")
    durations = [e for e in failures if isinstance(e, TooFast)]
    return durations[0] if durations else failures[0]


def line_move(pose: Pose, request: LineRequest, spec: Spec) -> LineMove:
    """The hand of ``request`` moved along a straight line from ``pose`` (see the module docstring): the ways of
    :mod:`.line_solve` in turn, the first that passes every check."""
    request = request.validated()
    ik = WholeBodyIk(spec, pose.support, request.hand, pose.servo)
    first = ik.features(pose.servo[None])
    start = first["hand"][0]
    end = np.asarray(request.target_m, dtype=float) if request.target_m is not None else start + request.delta_m
    if np.linalg.norm(end - start) > MAX_LINE_M:
        raise InputError(f"expected a line of at most {MAX_LINE_M:g} m, got {np.linalg.norm(end - start):.3f} m",
                         "to" if request.target_m is not None else "by")
    _, targets, points = _targets(request, start, end, first["point"][0])
    crouching = WholeBodyIk(spec, pose.support, request.hand, pose.servo, crouch=True)
    failures: list[Exception] = []
    search = EndSearch()
    tips = None
    margin = _feet_margin_of(spec)
    if Support.of(pose.support).is_double:               # a forward way stops where a foot would tip
        floor = min(FEET_MARGIN_M, margin(pose.servo))

        def tips(goal: np.ndarray) -> bool:
            return margin(goal) < floor
    for rows in ways(ik, crouching, targets, points, request.back, GIVE_UP_M, search, tips):
        try:
            return _checked(pose, request, spec, ik, rows, start, end, margin)
        except (CheckFailed, InputError) as e:
            failures.append(e)
    raise _most_useful(request, end, failures, search)
