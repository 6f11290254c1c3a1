"""Around, not through: a segment between two poses whose straight joint interpolation collides is re-planned.

A segment *collides* when, on the straight line between its poses (checked every :data:`LINE_STEP_RAD` of the
fastest joint), links pass through each other by more than the shapes' error
(:data:`~op2motion.motion.checks.OVERLAP_TOL_M`, the limit below which :func:`~.checks.require_clear` refuses), a
hand, elbow, knee, the head or the pelvis goes below the floor, or on one foot the swing foot comes down to the
floor (its lowest corner within :data:`~op2motion.robot.support.LIFTED_M`, the sag counted) while neither end has it
there. Such a segment is planned again in joint space (:func:`.rrt.rrt_connect`, our RRT-Connect, or with
``planner`` "ompl" OMPL's, :func:`.rrt_ompl.ompl_rrt_connect`; then :func:`.rrt.shortcut`):

* what may move: first only those of the joints below whose ends differ, then (if that finds nothing in
  :data:`NARROW_SHARE` of the budget) both arms and the head, and on one foot the swing leg; the rest (the standing
  leg or legs) moves along its straight line, the progress along it being one more coordinate of the search,
  weighted by how far those joints travel; so on two feet the legs stay as the straight plan has them;
* every state checked (:mod:`.body_checks`): joints inside their mechanical range, self-clearance at least
  :data:`~.body_checks.PLAN_CLEARANCE_M` (4 mm, plus 2 mm for the smoothing and the balance leans that follow),
  the CoM at least :data:`~.body_checks.PLAN_MARGIN_M` inside the support (on one foot: where it settles on the
  compliant servos), points off the floor, the swing foot lifted; each lowered to what the segment's ends have;
* the path's corners become via poses; the segment's time is shared among its pieces by length, then the planner
  times them within the servos' speed (:mod:`.planner`).

The same seed plans the same path (:class:`numpy.random.Generator` from ``seed`` and the segment's index).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from op2motion.errors import CheckFailed, InputError
from op2motion.formats.motionfile import PLANNERS, PlannerName
from op2motion.motion.body_checks import BodyChecks, Limits, Measures
from op2motion.motion.checks import OVERLAP_TOL_M, clearance
from op2motion.motion.rrt import Box, RrtSettings, Validity, rrt_connect, shortcut
from op2motion.motion.shift import segment_side
from op2motion.motion.waypoint import MIN_SEGMENT_S, Waypoint
from op2motion.robot.joints import LEG_JOINTS, joint_range
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

LINE_STEP_RAD = 0.01                # the straight line is checked every 0.6° of the fastest joint
ARMS_AND_HEAD = ("r_sho_pitch", "l_sho_pitch", "r_sho_roll", "l_sho_roll", "r_el", "l_el", "head_pan", "head_tilt")
MIN_PROGRESS_WEIGHT = 0.05          # the progress coordinate's weight when the held joints hardly move [rad]
MOVING_RAD = 1e-3                   # a joint whose ends differ by more than this moves in the segment
MAX_ROUTE_S = 60.0                  # a motion's segments are planned around for at most this long in all [s]
NARROW_SHARE = 0.4                  # the share of the budget tried with only the moving joints free
SEARCH_NAMES = {"rrt": "RRT-Connect", "ompl": "OMPL's RRT-Connect"}

Search = Callable[[np.ndarray, np.ndarray, Validity, Box, np.random.Generator, RrtSettings], "list[np.ndarray] | None"]


def _search(planner: PlannerName) -> Search:
    """The search function of ``planner`` ("rrt" or "ompl"; OMPL imported only when it is asked for)."""
    if planner == "ompl":
        from op2motion.motion.rrt_ompl import ompl_rrt_connect
        return ompl_rrt_connect
    return rrt_connect


@dataclass(frozen=True)
class Routed:
    """The waypoints with via poses inserted, the notes saying where, the indices (into the new sequence) of
    the segments that were planned around and of the via poses."""

    waypoints: list[Waypoint]
    notes: list[str]
    segments: list[int]
    vias: list[int]


class _Segment:
    """One segment's search space: the free joints plus the progress along the straight line of the rest."""

    def __init__(self, a: Waypoint, b: Waypoint, spec: Spec, only_moving: bool = False):
        self.a, self.b, self.spec = a, b, spec
        self.side = segment_side(a, b)
        names = list(ARMS_AND_HEAD)
        if self.side is not None:
            swing = "r" if self.side == "left" else "l"
            names += [f"{swing}_{j}" for j in LEG_JOINTS]
        free = [spec.joint_names.index(n) for n in names]
        moving = [i for i in free if abs(b.servo[i] - a.servo[i]) > MOVING_RAD]
        self.free = np.array(moving if only_moving and moving else free)
        held = np.setdiff1d(np.arange(len(spec.joints)), self.free)
        travel = float(np.linalg.norm(b.servo[held] - a.servo[held]))
        safe = np.array([joint_range(spec.joints[i], "cable-safe") for i in self.free])
        lower = np.minimum(safe[:, 0], np.minimum(a.servo[self.free], b.servo[self.free]))
        upper = np.maximum(safe[:, 1], np.maximum(a.servo[self.free], b.servo[self.free]))
        self.box = Box(np.append(lower, 0.0), np.append(upper, 1.0),
                       np.append(np.ones(len(self.free)), max(travel, MIN_PROGRESS_WEIGHT)))
        self.checks = BodyChecks(spec, self.side)
        self.start = np.append(a.servo[self.free], 0.0)
        self.goal = np.append(b.servo[self.free], 1.0)

    def servo(self, states: np.ndarray) -> np.ndarray:
        """Poses (N, 20) [rad] of search states (N, d)."""
        states = np.atleast_2d(states)
        out: np.ndarray = self.a.servo + states[:, -1:] * (self.b.servo - self.a.servo)
        out[:, self.free] = states[:, :-1]
        return out

    def measure(self, states: np.ndarray) -> Measures:
        return self.checks.measure(self.servo(states))

    def line(self) -> np.ndarray:
        """States along the straight segment, :data:`LINE_STEP_RAD` of the fastest joint apart."""
        n = max(2, int(math.ceil(float(np.abs(self.b.servo - self.a.servo).max()) / LINE_STEP_RAD)) + 1)
        states: np.ndarray = self.start + np.linspace(0.0, 1.0, n)[:, None] * (self.goal - self.start)
        return states


def _collision(seg: _Segment, ends: Limits) -> str | None:
    """Why the straight segment collides, in words; None when it does not."""
    m = seg.measure(seg.line())
    k = int(np.argmin(m.clearance))
    if m.clearance[k] < -OVERLAP_TOL_M:
        return f"links overlap by {-m.clearance[k] * 1000:.0f} mm on the way"
    if m.floor.min() < min(0.0, ends.floor):
        return f"a limb goes {-m.floor.min() * 1000:.0f} mm below the floor on the way"
    if seg.side is not None and m.swing.min() < min(0.0, ends.swing) - 1e-4:
        return "the swing foot comes down to the floor on the way"
    return None


def _durations(points: list[np.ndarray], total_s: float, box: Box) -> list[float]:
    lengths = np.array([float(box.distance(p, q)) for p, q in zip(points, points[1:])])
    share = lengths / max(float(lengths.sum()), 1e-12)
    return [max(MIN_SEGMENT_S, float(total_s * s)) for s in share]


def _plan(seg: _Segment, limits: Limits, rng: np.random.Generator, search: RrtSettings,
          settings: RrtSettings, planner: PlannerName = "rrt") -> list[np.ndarray] | None:
    """``planner``'s RRT-Connect then shortcuts in ``seg``'s space with every state within ``limits``; None if none
    found."""

    def valid(states: np.ndarray) -> np.ndarray:
        poses = seg.servo(states)
        ok: np.ndarray = seg.checks.within_joint_limits(poses) & limits.allows(seg.checks.measure(poses))
        return ok

    path = _search(planner)(seg.start, seg.goal, valid, seg.box, rng, search)
    return None if path is None else shortcut(path, valid, seg.box, rng, settings)


def route_segment(a: Waypoint, b: Waypoint, spec: Spec, seed: int, settings: RrtSettings = RrtSettings(),
                  planner: PlannerName = "rrt") -> tuple[list[Waypoint], str | None]:
    """The waypoints that replace ``b`` (via poses, then ``b``) and why the straight line needed them (None and
    ``[b]`` when it did not), searched by ``planner`` ("rrt" or "ompl"). Raises :class:`CheckFailed` when no path
    is found."""
    if planner not in SEARCH_NAMES:
        raise InputError(f"expected one of {', '.join(SEARCH_NAMES)}, got {planner!r}", "planner")
    seg = _Segment(a, b, spec)
    ends_measured = seg.measure(np.array([seg.start, seg.goal]))
    ends = ends_measured.least()
    why = _collision(seg, ends)
    if why is None:
        return [b], None
    for w, clear in zip((a, b), ends_measured.clearance):
        if clear < -OVERLAP_TOL_M:
            raise CheckFailed(f"no path from {a.name} to {b.name}: {w.name} itself has links {-clear * 1000:.0f} mm "
                              f"through each other")
    limits = Limits().relaxed_to(ends)
    rng = np.random.default_rng(seed)
    narrow = _Segment(a, b, spec, only_moving=True)
    path = None
    if len(narrow.free) < len(seg.free):          # first with only the joints that move anyway, then with all
        path = _plan(narrow, limits, rng, replace(settings, budget_s=settings.budget_s * NARROW_SHARE,
                                                  max_samples=int(settings.max_samples * NARROW_SHARE)), settings,
                     planner)
        seg = narrow if path is not None else seg
    if path is None:                              # the rest of the budget with every free joint
        rest = settings if len(narrow.free) == len(seg.free) else replace(
            settings, budget_s=settings.budget_s * (1.0 - NARROW_SHARE),
            max_samples=settings.max_samples - int(settings.max_samples * NARROW_SHARE))
        path = _plan(seg, limits, rng, rest, settings, planner)
    if path is None:
        tight = [(w, c) for w, c in zip((a, b), ends_measured.clearance) if c < Limits().clearance]
        if tight:                                 # no seed helps: the pose itself is where the search must end
            w, c = min(tight, key=lambda wc: wc[1])
            pair = " / ".join(clearance(w.servo[None], spec, seg.side or "left")[1][0])
            raise CheckFailed(f"no path from {a.name} to {b.name}: {w.name} itself has links {c * 1000:.1f} mm apart "
                              f"({pair}), closer than the {Limits().clearance * 1000:.0f} mm a planned path keeps "
                              f"between links: move them apart in {w.name}")
        raise CheckFailed(f"no path from {a.name} to {b.name} within {settings.budget_s:g} s and "
                          f"{settings.max_samples} samples ({why}): keeping {limits.clearance * 1000:.0f} mm between "
                          f"links, the CoM {limits.margin * 1000:.0f} mm inside the support; add a pose in between")
    durations = _durations(path, b.duration_s, seg.box)
    support = Support.of(seg.side) if seg.side else Support.DOUBLE
    vias = [Waypoint(f"{b.name}~via{k}", seg.servo(p)[0], d, 0.0, support)
            for k, (p, d) in enumerate(zip(path[1:-1], durations), start=1)]
    return vias + [replace(b, duration_s=durations[-1])], why


def route(waypoints: Sequence[Waypoint], spec: Spec, planner: PlannerName = "rrt", seed: int = 0,
          settings: RrtSettings = RrtSettings()) -> Routed:
    """``waypoints`` with every colliding segment planned around (``planner`` "rrt": ours, "ompl": OMPL's
    RRT-Connect), or as they are ("none")."""
    if planner not in PLANNERS:
        raise InputError(f"expected one of {', '.join(PLANNERS)}, got {planner!r}", "planner")
    out, notes = [waypoints[0]], list[str]()
    segments: list[int] = []
    vias: list[int] = []
    if planner == "none":
        return Routed(list(waypoints), notes, segments, vias)
    started = time.monotonic()
    for i, (a, b) in enumerate(zip(waypoints, waypoints[1:])):
        if time.monotonic() - started > MAX_ROUTE_S:
            raise CheckFailed(f"planning around collisions took over {MAX_ROUTE_S:g} s in all (at segment {i + 1} of "
                              f"{len(waypoints) - 1}): add poses that keep the links apart, or split the motion")
        pieces, why = route_segment(a, b, spec, seed * 1000 + i, settings, planner)
        if why is not None:
            first = len(out) - 1
            segments += list(range(first, first + len(pieces)))
            vias += list(range(first + 1, first + len(pieces)))
            notes.append(f"{a.name} -> {b.name}: {why}; planned around it through {len(pieces) - 1} via pose"
                         f"{'s' if len(pieces) != 2 else ''} ({SEARCH_NAMES[planner]} in joint space, seed {seed})")
        out += pieces
    return Routed(out, notes, segments, vias)


def with_stops(routed: Routed) -> list[Waypoint]:
    """The routed waypoints with the motion coming to rest at every via pose (each piece then a straight line
    in joint space)."""
    return [replace(w, stop=True) if k in routed.vias else w for k, w in enumerate(routed.waypoints)]


def routed_clearance(goals: np.ndarray, segment: np.ndarray, routed: Routed, spec: Spec) -> float:
    """The least clearance [m] between links on the rows (of goals (K, 20) [rad]) of the planned-around segments
    (+inf when none was)."""
    rows = np.flatnonzero(np.isin(segment, routed.segments))
    if rows.size == 0:
        return math.inf
    return float(clearance(goals[rows], spec)[0].min())
