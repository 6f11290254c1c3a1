"""RRT-Connect from OMPL (the Open Motion Planning Library, its ``ompl`` Python bindings) in the same box, the same
metric and with the same checks as :func:`.rrt.rrt_connect`, so that :mod:`.route` can call either.

OMPL searches; op2motion judges. OMPL's space is the box scaled by the metric's weights (its Euclidean distance is
then exactly :meth:`.rrt.Box.distance`, so :attr:`~.rrt.RrtSettings.step` is OMPL's range); a state is valid when
the validity function passed in says so, and an edge (OMPL's motion check) when :func:`.rrt.edge_valid` does: the
same points, :attr:`~.rrt.RrtSettings.resolution` apart, checked in one batch. OMPL's own interpolation and path
simplifier are not used: :mod:`.route` shortens the path with :func:`.rrt.shortcut`, as it does ours.

The caps are ours: :attr:`~.rrt.RrtSettings.budget_s` of wall time, and :attr:`~.rrt.RrtSettings.max_samples`
rounds of the planner's loop (each draws one sample; counted as the loop asks whether to stop). The seed: OMPL's
random numbers come from one process-wide seed generator, :func:`ompl.util.RNG.setSeed`, set from the ``numpy``
generator passed in before OMPL makes any of its generators for this search, so one seed plans one path. (OMPL
logs an error when the seed changes after its first generator; its log is silenced while it plans, since OMPL
writes to stdout, where ``--json`` wants nothing else.)

``ompl`` is imported when a search runs, not before: it is the ``ompl`` extra (``pip install op2motion[ompl]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from op2motion.errors import InputError
from op2motion.motion.rrt import Box, RrtSettings, Validity, edge_valid

_SEED_SPAN = 2 ** 31 - 1          # OMPL seeds are positive 32-bit numbers


def _ompl_util() -> Any:
    """OMPL's ``util`` module, or an :class:`InputError` saying how to install OMPL."""
    try:
        import ompl.util as ou
    except ImportError as exc:
        raise InputError(f"expected the OMPL Python bindings (pip install 'op2motion[ompl]'), got {exc}",
                         "planner") from exc
    return ou


def ompl_rrt_connect(start: np.ndarray, goal: np.ndarray, valid: Validity, box: Box, rng: np.random.Generator,
                     settings: RrtSettings = RrtSettings()) -> list[np.ndarray] | None:
    """A valid piecewise-straight path [start, ..., goal] (states (d,)) found by OMPL's RRT-Connect, or None when
    the samples or the time budget run out first; ``start`` and ``goal`` must be valid. One number drawn from
    ``rng`` seeds OMPL."""
    if edge_valid(start, goal, valid, box, settings.resolution):
        return [start.copy(), goal.copy()]
    ou = _ompl_util()
    seed = int(rng.integers(1, _SEED_SPAN))
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    try:
        return _search(start, goal, valid, box, seed, settings)
    finally:
        ou.setLogLevel(level)


def _search(start: np.ndarray, goal: np.ndarray, valid: Validity, box: Box, seed: int,
            settings: RrtSettings) -> list[np.ndarray] | None:
    """One OMPL RRT-Connect search (OMPL importable, its log already silenced)."""
    import ompl.base as ob
    import ompl.geometric as og
    import ompl.util as ou
    dim, weight = len(start), np.asarray(box.weight, dtype=float)
    ou.RNG.setSeed(seed)                           # before the space, sampler and neighbour structures exist
    space = ob.RealVectorStateSpace(dim)
    bounds = ob.RealVectorBounds(dim)
    for i, (lo, hi) in enumerate(zip(box.lower * weight, box.upper * weight)):
        bounds.setLow(i, float(lo))
        bounds.setHigh(i, float(hi))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)

    def state_of(s: Any) -> np.ndarray:            # an OMPL state (scaled) -> ours
        state: np.ndarray = np.array([s[i] for i in range(dim)]) / weight
        return state

    # OMPL ships no type information: its bases are Any, which only --strict (disallow_subclassing_any) rejects
    class Valid(ob.StateValidityChecker):          # type: ignore[misc, unused-ignore]
        def isValid(self, s: Any) -> bool:   # OMPL's name
            return bool(valid(state_of(s)[None])[0])

    class Edge(ob.MotionValidator):                # type: ignore[misc, unused-ignore]  # as Valid
        def checkMotion(self, a: Any, b: Any) -> bool:   # OMPL's name
            return edge_valid(state_of(a), state_of(b), valid, box, settings.resolution)

    checker, motions = Valid(si), Edge(si)         # kept referenced while OMPL holds them
    si.setStateValidityChecker(checker)
    si.setMotionValidator(motions)
    si.setup()
    ends = []
    for point in (start, goal):
        s = si.allocState()
        for i, x in enumerate(point * weight):
            s[i] = float(x)
        ends.append(s)
    problem = ob.ProblemDefinition(si)
    problem.setStartAndGoalStates(ends[0], ends[1])
    planner = og.RRTConnect(si)
    planner.setRange(settings.step)
    planner.setProblemDefinition(problem)
    planner.setup()
    rounds = [0]

    def out_of_samples() -> bool:
        rounds[0] += 1
        return rounds[0] > settings.max_samples

    stop = ob.plannerOrTerminationCondition(ob.timedPlannerTerminationCondition(settings.budget_s),
                                            ob.PlannerTerminationCondition(out_of_samples))
    planner.solve(stop)
    if not problem.hasExactSolution():
        return None
    found = problem.getSolutionPath()
    path = [state_of(found.getState(i)) for i in range(found.getStateCount())]
    path[0], path[-1] = start.copy(), goal.copy()  # the ends exactly, not scaled there and back
    return path
