"""How a hand line's rows are found: three ways, tried in turn by :func:`.cartesian.line_move`.

* ``forward``: every 8 ms row from the last, starting at the pose (the whole-body IK of :mod:`.whole_body`, knees
  that start straight held straight);
* ``crouching``: the same, the body free to sink on bending knees (a hand below what straight legs allow);
* ``from the end``: where the start is a singular arm (a forearm hanging straight down cannot start upwards
  without first folding the elbow the wrong way, into its stop), the arm configurations that hold the hand at the
  line's end are found from a few seeds (:data:`END_SEEDS_RAD`); from each the line is followed backwards (the
  torso keeping its speed from row to row, :data:`~.whole_body.W_SMOOTH`), which may arrive at the start point on
  the arm's other branch. The move then begins with the body changing to that branch
  while the hand stays at the start (a reconfiguration, the joints on a minimum-jerk straight line in the IK's
  unknowns, as fast as :data:`RECONFIGURE_SPEED_RAD_S` and :data:`RECONFIGURE_ACCEL_M_S2` allow); it is measured
  like every other row.

Each way returns :class:`Rows`; the caller checks them (on the line, balanced, apart, within the servos' speed).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from op2motion.motion.whole_body import WholeBodyIk
from op2motion.robot.framework import CONTROL_PERIOD_S

END_SEEDS_RAD = ((0.0, 0.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (-1.0, -1.0),
                 (1.0, 1.0))                # (shoulder pitch, elbow) added to the start's arm
END_TOL_M = 1e-3            # an end configuration holds the hand this close to the line's end
SAME_END_RAD = 0.05         # end configurations closer than this (each arm joint) are one
SAME_START_RAD = 0.01       # a backward solve that arrives this close to the start needs no reconfiguration
RECONFIGURE_SPEED_RAD_S = 1.4   # the fastest joint while the body changes branch (a quarter of no-load speed)
WATCH_EVERY = 6             # a forward way asks every this many rows (48 ms) whether the robot would tip
RECONFIGURE_ACCEL_M_S2 = 0.5    # ... and the CoM's largest acceleration (its ZMP moves about 12 mm)


@dataclass(frozen=True)
class Rows:
    """One way through the line: the goals (K, 20) [rad] every 8 ms, the hand's target (K, 3) [m] and the forearm's
    (K, 3) (None: free) per row, ``how`` it was found, and how many rows at the start (and, going back, at the end)
    only reconfigure the body with the hand held at the start."""

    goals: np.ndarray
    targets: np.ndarray
    points: np.ndarray | None
    how: str
    reconfigure_rows: int = 0

    @property
    def reconfigure_s(self) -> float:
        """How long the body reconfigures at the start [s]."""
        return self.reconfigure_rows * CONTROL_PERIOD_S


def _there_and_back(rows: np.ndarray, back: bool) -> np.ndarray:
    return np.concatenate([rows, rows[-2::-1]]) if back else rows


def sweep_forward(ik: WholeBodyIk, targets: np.ndarray, points: np.ndarray | None, give_up_m: float,
                  tips: Callable[[np.ndarray], bool] | None = None) -> np.ndarray:
    """Goals (k <= K, 20) [rad]: each row solved from the one before, from the start pose, up to the first row
    whose hand is more than ``give_up_m`` [m] from its target or, looked at every :data:`WATCH_EVERY` rows, whose
    goals (20,) ``tips`` says the robot would tip over (that way has failed)."""
    x, rows = ik.x0.copy(), [ik.start.copy()]
    for i in range(1, len(targets)):
        x, error = ik.solve(x, targets[i], None if points is None else points[i])
        rows.append(ik.servo(x[None])[0])
        if error > give_up_m or (tips is not None and i % WATCH_EVERY == 0 and tips(rows[-1])):
            break
    return np.array(rows)


def _backward(ik: WholeBodyIk, x_end: np.ndarray, targets: np.ndarray, points: np.ndarray | None,
              give_up_m: float) -> np.ndarray | None:
    """Unknowns (K, 9): each row solved from the one after, from ``x_end`` at the last, the torso keeping its speed
    from row to row (this way is the careful one: it is tried last); None where a row's hand ends more than
    ``give_up_m`` [m] from its target."""
    x, rows = x_end, [x_end]
    before = x
    for i in range(len(targets) - 2, -1, -1):
        (x, error), before = ik.solve(x, targets[i], None if points is None else points[i], before=before), x
        if error > give_up_m:
            return None
        rows.append(x)
    return np.array(rows[::-1])


def _reconfiguration(ik: WholeBodyIk, x_to: np.ndarray) -> np.ndarray:
    """Unknowns (R, 9) from the start's to ``x_to`` on a minimum-jerk straight line, as many rows as the fastest
    joint needs at :data:`RECONFIGURE_SPEED_RAD_S` (a minimum-jerk move peaks at 15/8 of its mean speed) and the
    CoM at :data:`RECONFIGURE_ACCEL_M_S2` (its acceleration peaks at 10/sqrt(3) of the distance over the time
    squared)."""
    ends = np.array([ik.x0, x_to])
    turn = float(np.abs(ik.servo(ends[1:])[0] - ik.start).max())
    com = ik.features(ik.servo(ends))["com"]
    shift = float(np.linalg.norm(com[1] - com[0]))
    seconds = max(15 / 8 * turn / RECONFIGURE_SPEED_RAD_S,
                  math.sqrt(10 / math.sqrt(3) * shift / RECONFIGURE_ACCEL_M_S2))
    count = max(2, int(math.ceil(seconds / CONTROL_PERIOD_S)) + 1)
    tau = np.linspace(0.0, 1.0, count)
    s = 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5
    states: np.ndarray = ik.x0 + s[:, None] * (x_to - ik.x0)
    return states


@dataclass
class EndSearch:
    """What the search for end configurations found so far: how many, and the hand's least distance from the
    line's end [m]."""

    found: int = 0
    closest_m: float = math.inf


def _ends(ik: WholeBodyIk, end: np.ndarray, point: np.ndarray | None, search: EndSearch) -> Iterator[np.ndarray]:
    """Distinct arm configurations (unknowns (9,)) that hold the hand at ``end`` (3,) [m], from the seeds, as they
    are found (counted in ``search``)."""
    found: list[np.ndarray] = []
    for d_pitch, d_elbow in END_SEEDS_RAD:
        seed = ik.x0.copy()
        seed[6] += d_pitch
        seed[8] += d_elbow
        seed[6:] = np.clip(seed[6:], ik.lower[:3], ik.upper[:3])
        x, error = ik.settle(seed, end, point, lambda x: any(np.abs(x[6:] - f[6:]).max() <= SAME_END_RAD
                                                             for f in found))
        search.closest_m = min(search.closest_m, error)
        if error < END_TOL_M and all(np.abs(x[6:] - f[6:]).max() > SAME_END_RAD for f in found):
            found.append(x)
            search.found += 1
            yield x


def from_the_end(ik: WholeBodyIk, targets: np.ndarray, points: np.ndarray | None, back: bool,
                 search: EndSearch, give_up_m: float) -> Iterator[Rows]:
    """Rows (see the module docstring) for each end configuration from which the line can be followed back
    (within ``give_up_m`` [m] at every row), one way ``targets`` (K, 3) [m]."""
    for x_end in _ends(ik, targets[-1], None if points is None else points[-1], search):
        way = _backward(ik, x_end, targets, points, give_up_m)
        if way is None:
            continue
        lead = np.zeros((0, 9))
        if np.abs(way[0] - ik.x0).max() > SAME_START_RAD:
            lead = _reconfiguration(ik, way[0])[:-1]
        xs = np.concatenate([lead, way])
        held_t = np.repeat(targets[:1], len(lead), axis=0)
        row_targets = np.concatenate([held_t, targets])
        row_points = None if points is None else np.concatenate([np.repeat(points[:1], len(lead), axis=0), points])
        yield Rows(_there_and_back(ik.servo(xs), back), _there_and_back(row_targets, back),
                   None if row_points is None else _there_and_back(row_points, back), "from the end", len(lead))


def ways(ik: WholeBodyIk, crouching: WholeBodyIk, targets: np.ndarray, points: np.ndarray | None,
         back: bool, give_up_m: float, search: EndSearch,
         tips: Callable[[np.ndarray], bool] | None = None) -> Iterator[Rows]:
    """The ways in the order to try them, lazily (the later ones cost more); ``targets`` and ``points`` one way; a
    forward way stops at the first row more than ``give_up_m`` [m] off or where ``tips`` (see :func:`sweep_forward`)
    (its rows end there); ``search`` counts the end configurations tried."""
    all_targets, all_points = _there_and_back(targets, back), None if points is None else _there_and_back(points, back)
    for solver, how in ((ik, "forward"), (crouching, "crouching")):
        goals = sweep_forward(solver, all_targets, all_points, give_up_m, tips)
        k = len(goals)
        yield Rows(goals, all_targets[:k], None if all_points is None else all_points[:k], how)
    yield from from_the_end(ik, targets, points, back, search, give_up_m)
