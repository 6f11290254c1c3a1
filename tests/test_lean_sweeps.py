"""Lean sweeps: a pose leaned at the support ankle(s) until it falls, in both engines: 4° steps from upright, then
each engine's switch halved down to 0.5° and two leans past it.

The verdict must be monotonic (once a pose falls, every further lean falls too), the two engines must agree on every
pose whose margin is beyond ±5 mm, and the verdict must switch where the pose runs out of support: where the settled
full-inertia CoM reaches the edge of the support polygon, within 5 mm. The switch is measured as the margin halfway
between the last standing pose and the next step (the last standing margin less half the margin lost per step).

One sweep runs out of support before its CoM reaches that edge, for a reason the engines agree on and the README
explains: on two legs leaning sideways as a parallelogram, the compliant legs (P = 32) shear, the unloaded foot
rolls onto its inner edge from about 10° of lean (the statically sagged solution with both soles flat would need
its centre of pressure beyond that edge) and the loaded foot tips over its outer edge while the other still carries
12 % of the weight, so the CoM is 10 mm inside the hull of both soles: there the switch is measured on the loaded
foot's own centre of pressure, which reaches its edge within 5 mm.

Each engine's last standing lean and first fall are the hardest cases for a check that ends once its verdict is
known (op2motion.physics.stopping, tests/test_early_stop.py): there MuJoCo's run of every sweep, and PyBullet's of
one, is played to its full length as well and must end with the same verdict and first failures. (Each engine at its
own edges: the other engine's edges are other leans of the sweep, none closer to this engine's switch than its own
edges.)
"""

from __future__ import annotations

import functools
import multiprocessing
import os

import pytest
from helpers import same_verdict

from op2motion.physics.stopping import EDGE_BAND_M, FELL, FULL, SETTLED
from op2motion.physics.sweeps import sweep_outcome, sweep_run

STEP_DEG = 0.5                 # the fine step: each engine's last standing lean and first fall lie this far apart
COARSE_DEG = 4.0               # the step from the upright start until a pose falls
SECONDS = 3.0
FALLS_PAST_SWITCH = 2          # steps leaned on after the first fall, to see that nothing stands again
MAX_DEG = 35.0
AGREE_BEYOND_M = 0.005         # the engines agree wherever the margin is beyond this
SAME_MARGIN_M = 5e-4           # a settled margin measured early agrees with the full run's to this
ENGINES = ("mujoco", "pybullet")
SWITCH_TOL_M = 0.005           # the switch lies this close to the edge
#: The sweep whose edges are played to their full length in PyBullet too (MuJoCo plays every sweep's; PyBullet costs
#: seven times its CPU per simulated second, and the full-length replays were a fifth of this module's).
REPLAYED_IN_BOTH = ("left", "pitch", 1)
pytestmark = pytest.mark.physics

#: Leaned towards the toe and the side on one foot; towards the toe, the heel and the side on two (the heel on one foot
#: runs out at the same edge of the same sole as on two).
SWEEPS = [  # support, kind, direction, what runs out (the CoM's polygon or a loaded foot's own sole)
    ("left", "pitch", 1, "com"), ("left", "roll", 1, "com"),
    ("double", "pitch", 1, "com"), ("double", "pitch", -1, "com"), ("double", "roll", 1, "foot"),
]


def _sweep(pool, support: str, kind: str, direction: int) -> tuple[list[float], dict[str, list], list[tuple]]:
    """One sweep in both engines: leaned in :data:`COARSE_DEG` steps from upright until a pose falls in either
    engine; then the gap between each engine's last standing lean and its first fall halved until it is
    :data:`STEP_DEG`, and leaned on until at least :data:`FALLS_PAST_SWITCH` leans lie past each first fall (an
    engine that has not fallen yet leans on in coarse steps); every lean runs in both engines. (Halving finds the
    switch to the same 0.5° as stepping 0.5° across it did, in fewer leans: 54 instead of 70 for six sweeps.)
    Returns the leans (signed), each engine's :func:`sweep_outcome` per lean, and :func:`_edges`."""
    verdicts: dict[float, dict[str, tuple]] = {}
    reports: dict[tuple[float, str], object] = {}

    def run(degrees: set[float]) -> None:
        todo = sorted({round(d, 6) for d in degrees if d <= MAX_DEG} - set(verdicts))
        tasks = [(support, kind, direction * d, e, SECONDS) for d in todo for e in ENGINES]
        for (_, _, deg, engine, _), report in zip(tasks, pool.map(sweep_run, tasks)):
            verdicts.setdefault(abs(deg), {})[engine] = sweep_outcome(report)
            reports[abs(deg), engine] = report

    def next_leans(engine: str) -> set[float]:
        falls = sorted(d for d, v in verdicts.items() if not v[engine].stable)
        if not falls:                                       # not fallen yet in this engine: lean on
            return {max(verdicts) + COARSE_DEG}
        below = max((d for d in verdicts if d < falls[0]), default=falls[0])
        if falls[0] - below > STEP_DEG + 1e-9:              # halve the gap (on the fine step's grid)
            return {round((below + falls[0]) / 2 / STEP_DEG) * STEP_DEG}
        past = sum(d > falls[0] for d in verdicts)
        return {max(verdicts) + STEP_DEG * k for k in range(1, FALLS_PAST_SWITCH - past + 1)}

    coarse = 0.0
    while coarse <= MAX_DEG and all(v.stable for d in verdicts.values() for v in d.values()):
        run({coarse})
        coarse += COARSE_DEG
    while True:
        todo = {round(d, 6) for e in ENGINES for d in next_leans(e) if d <= MAX_DEG} - set(verdicts)
        if not todo:
            break
        run(todo)
    angles = sorted(verdicts)
    replay = ENGINES if (support, kind, direction) == REPLAYED_IN_BOTH else ("mujoco",)
    return ([direction * a for a in angles], {e: [verdicts[a][e] for a in angles] for e in ENGINES},
            _edges(pool, (support, kind, direction), verdicts, reports, replay))


def _edges(pool, sweep: tuple[str, str, int], verdicts: dict, reports: dict, replay: tuple[str, ...]) -> list[tuple]:
    """Each engine's last standing lean and first fall, in that engine: (lean [deg], engine, the sweep's run (ended
    once its verdict was known), the same run played to its full length, in the engines of ``replay``; None in the
    others); a run that played its whole hold is its own full-length run."""
    support, kind, direction = sweep
    early = {}
    for engine in ENGINES:
        fall = min(d for d, v in verdicts.items() if not v[engine].stable)
        for d in sorted({fall, max((d for d in verdicts if d < fall), default=fall)}):
            early[d, engine] = reports[d, engine]
    again = [key for key, report in early.items() if report.ended != FULL and key[1] in replay]
    tasks = [(support, kind, direction * d, e, SECONDS) for d, e in again]
    full = dict(zip(again, pool.map(functools.partial(sweep_run, full_length=True), tasks)))
    return [(direction * d, e, report, full.get((d, e), report if report.ended == FULL else None))
            for (d, e), report in early.items()]


class _Here:
    """A pool's ``map`` in this process."""

    @staticmethod
    def map(fn, tasks: list) -> list:
        return [fn(task) for task in tasks]


@pytest.fixture(scope="module")
def sweeps():
    """Every sweep, every lean in both engines: in two processes, or in this one where it is one of a test run's
    processes (pytest-xdist's), which keep the cores busy already (two more processes would each import the package
    and both engines again)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return {(s, k, d): _sweep(_Here(), s, k, d) for s, k, d, _ in SWEEPS}
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(2) as pool:
        return {(s, k, d): _sweep(pool, s, k, d) for s, k, d, _ in SWEEPS}


def _switch_margin(angles: list[float], verdicts: list, field: str = "margin_m") -> float:
    """The margin halfway between the last standing lean and the next :data:`STEP_DEG` (the margin lost per step
    taken from the last standing lean and the one before it)."""
    stable = [v.stable for v in verdicts]
    last = stable.index(False) - 1
    assert last >= 1, "the sweep must start standing"
    assert abs(angles[last + 1] - angles[last]) <= STEP_DEG + 1e-9, "the switch must be bracketed by a fine step"
    margin = [getattr(v, field) for v in verdicts]
    per_step = (margin[last - 1] - margin[last]) * STEP_DEG / abs(angles[last] - angles[last - 1])
    return margin[last] - 0.5 * per_step


@pytest.mark.parametrize("support, kind, direction, criterion", SWEEPS,
                         ids=[f"{s}-{k}-{d:+d}" for s, k, d, _ in SWEEPS])
def test_lean_sweep(sweeps, support, kind, direction, criterion):
    angles, by_engine, _ = sweeps[(support, kind, direction)]
    assert any(not v.stable for v in by_engine["mujoco"]), "the sweep never fell"
    for engine, verdicts in by_engine.items():
        stable = [v.stable for v in verdicts]
        first_fall = stable.index(False)
        assert not any(stable[first_fall:]), f"{engine}: stands again after falling at {angles[first_fall]}°"
        switch = _switch_margin(angles, verdicts, "margin_m" if criterion == "com" else "foot_margin_m")
        assert abs(switch) <= SWITCH_TOL_M, (engine, criterion, switch)
    for deg, mj, pb in zip(angles, by_engine["mujoco"], by_engine["pybullet"]):
        if min(abs(mj.margin_m), abs(pb.margin_m)) > AGREE_BEYOND_M:
            assert mj.stable == pb.stable, f"{deg}°: MuJoCo {mj}, PyBullet {pb}"


@pytest.mark.parametrize("support, kind, direction", [s[:3] for s in SWEEPS],
                         ids=[f"{s}-{k}-{d:+d}" for s, k, d, _ in SWEEPS])
def test_the_edges_end_early_with_the_verdict_of_the_full_run(sweeps, support, kind, direction):
    """At each engine's last standing lean and first fall, the check that ended once its verdict was known has the
    verdict and the first failures of the same run played to its end: near its edge a pose plays the whole hold,
    clear of it it ends once settled (with the same margin), and a fall ends early."""
    edges = sweeps[(support, kind, direction)][2]
    assert sorted(e for _, e, *_ in edges) == sorted(ENGINES * 2)             # two edges per engine
    assert all({early.stable for _, e, early, _ in edges if e == engine} == {True, False} for engine in ENGINES)
    assert all(full is not None for _, engine, _, full in edges if engine == "mujoco")
    for deg, engine, early, full in edges:
        if full is not None:
            same_verdict(early, full)
        if early.stable:
            assert early.ended == FULL or (early.ended == SETTLED and early.support_margin_m > EDGE_BAND_M), (
                deg, engine, early.ended)
            if full is not None:
                assert early.support_margin_m == pytest.approx(full.support_margin_m, abs=SAME_MARGIN_M), (deg, engine)
        else:
            assert early.ended == FELL and early.seconds < SECONDS, (deg, engine, early.ended)
