"""A physics check ends when its verdict is known (op2motion.physics.stopping): a settled pose and a fallen one end
early with the verdict (and the first failure) of the run played to its full length."""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest

from op2motion.formats.action import ActionFile
from op2motion.formats.posefile import read_pose
from op2motion.physics import Schedule
from op2motion.physics.loop import Push, RunSetup
from op2motion.physics.runner import Setup, _Runner
from op2motion.physics.stopping import EDGE_BAND_M, FELL, FULL, SETTLED, EarlyStop
from op2motion.physics.sweeps import leaned, sweep_base

pytestmark = pytest.mark.physics
ROOT = os.path.join(os.path.dirname(__file__), "..")
SECONDS = 3.0
SAME_MARGIN_M = 5e-4           # a settled margin measured early agrees with the full run's to this
# The lean sweeps' last standing lean and first fall in either engine (README, Lean sweeps; -5.5°, -9.5° and +10°
# stand in MuJoCo and fall in PyBullet): (support, kind, deg).
SWEEP_EDGES = [("left", "pitch", 6.0), ("left", "pitch", 6.5), ("left", "pitch", -5.0), ("left", "pitch", -5.5),
               ("left", "pitch", -6.0), ("left", "roll", 6.5), ("left", "roll", 7.0), ("double", "pitch", 9.5),
               ("double", "pitch", 10.0), ("double", "pitch", 10.5), ("double", "pitch", -9.0),
               ("double", "pitch", -9.5), ("double", "pitch", -10.0), ("double", "roll", 22.5),
               ("double", "roll", 23.0)]
STOCK_PAGES = [15, 16]            # sit down, stand up (from the init pose)


def _both(schedule: Schedule, spec, engine: str, setup: RunSetup = RunSetup()):
    """The run with early stopping and the one played full length (the same run where the first played the whole
    plan: near its edge a pose does, and the engines are deterministic)."""
    runner = _Runner(schedule, spec, Setup(), 2, None)
    early = runner.run(engine, setup)
    if early.ended == FULL:
        return early, early
    full = runner.run(engine, RunSetup(push=setup.push, full_length=True))
    return early, full


def _same_verdict(early, full) -> None:
    """The same verdict, and every failure of the full run up to where the early one stopped, in the same order
    (the causes of a fall too: saturation, joint limits, collisions), at the same times."""
    assert full.ended == FULL and full.seconds == pytest.approx(full.planned_seconds)
    assert early.stable == full.stable, (early.reasons, full.reasons)
    until = [(f.reason, f.time_s) for f in full.failures if f.time_s <= early.seconds + 1e-9]
    assert [(f.reason, f.time_s) for f in early.failures] == until, (early.failures, full.failures)


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
@pytest.mark.parametrize("support, kind, degrees", SWEEP_EDGES, ids=[f"{s}-{k}{d:+g}" for s, k, d in SWEEP_EDGES])
def test_lean_sweep_edges_keep_their_verdict(spec, engine, support, kind, degrees):
    pose = leaned(spec, sweep_base(spec, support), support, kind, degrees)
    early, full = _both(Schedule.hold(pose, support, spec, SECONDS), spec, engine)
    _same_verdict(early, full)
    if early.stable:   # near its edge a pose plays the whole plan; clear of it, it ends once settled
        assert early.ended == FULL or (early.ended == SETTLED and early.support_margin_m > EDGE_BAND_M)
    else:
        assert early.ended == FELL and early.seconds < SECONDS
    if early.stable:   # the same still robot measured
        assert early.support_margin_m == pytest.approx(full.support_margin_m, abs=SAME_MARGIN_M)


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(ROOT, "poses", "*.json"))),
                         ids=lambda p: os.path.basename(p))
def test_committed_poses_keep_their_verdict(spec, path):
    pose = read_pose(path, spec)
    early, full = _both(Schedule.hold(pose.servo, pose.support, spec, SECONDS), spec, "pybullet")
    _same_verdict(early, full)
    assert early.support_margin_m == pytest.approx(full.support_margin_m, abs=SAME_MARGIN_M)


@pytest.mark.parametrize("page", STOCK_PAGES)
def test_stock_pages_keep_their_verdict(spec, page):
    from op2motion.motion.pipeline import play_page

    played = play_page(ActionFile.read(os.path.join(ROOT, "tests", "data", "motion_4096.bin")), page, spec)
    early, full = _both(played.trajectory.schedule(spec), spec, "mujoco")
    _same_verdict(early, full)
    assert early.seconds <= full.seconds


def test_a_push_is_waited_out(spec):
    pose = read_pose(os.path.join(ROOT, "poses", "standing.json"), spec)
    push = Push(np.array([0.0, 8.0, 0.0]), 1.5, 0.1)
    early, full = _both(Schedule.hold(pose.servo, pose.support, spec, SECONDS), spec, "mujoco", RunSetup(push=push))
    _same_verdict(early, full)
    assert early.seconds >= 1.6 + 1.0 - 1e-9       # the steady window lies wholly after the push


def test_the_earliest_end_waits_for_every_event(spec):
    hold = Schedule.hold(np.zeros(len(spec.joints)), "double", spec, SECONDS).plan
    assert EarlyStop(hold, ramped=False).earliest_s == pytest.approx(1.0)
    assert EarlyStop(hold, ramped=True).earliest_s == pytest.approx(2.0)
    assert EarlyStop(hold, ramped=False, push_end_s=1.6).earliest_s == pytest.approx(2.6)
    quiet, zero = np.zeros(20), np.zeros(3)

    def run(stop: EarlyStop, margin, until: float = SECONDS, speed=zero) -> float | None:
        """Feed a still robot with the CoM at ``margin(t)`` [m]; when the stop ends it [s], or None."""
        for t in np.arange(0.008, until, 0.008):
            stop.sample(t, 0.2, 0.2, margin(t))
            if stop.tick(t, quiet, zero, speed):
                return float(t)
        return None

    still = EarlyStop(hold, ramped=False)
    assert run(still, lambda t: 0.03) == pytest.approx(1.0, abs=0.01) and still.ended == SETTLED
    assert run(EarlyStop(hold, ramped=False), lambda t: 0.03, speed=np.array([0.01, 0.0, 0.0])) is None  # moving
    assert run(EarlyStop(hold, ramped=False), lambda t: 0.004) is None              # on the edge: the whole plan
    creeping = EarlyStop(hold, ramped=False)                                        # 8 mm in, creeping 3 mm/s
    assert run(creeping, lambda t: 0.008 - 0.003 * t) is None
    assert EarlyStop(hold, ramped=False, enabled=False).sample(0.0, 0.0, 0.2, 0.03) is False
