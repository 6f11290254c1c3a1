"""A physics check ends when its verdict is known (op2motion.physics.stopping): a settled pose and a fallen one end
early with the verdict (and the first failure) of the run played to its full length. (The hardest cases, the lean
sweeps' last standing leans and first falls in both engines, are played both ways by tests/test_lean_sweeps.py,
whose sweeps have run them already.)"""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest
from helpers import same_verdict

from op2motion.formats.action import ActionFile
from op2motion.formats.posefile import read_pose
from op2motion.physics import Schedule
from op2motion.physics.loop import Push, RunSetup
from op2motion.physics.runner import Setup, _Runner
from op2motion.physics.stopping import FULL, SETTLED, EarlyStop

pytestmark = pytest.mark.physics
ROOT = os.path.join(os.path.dirname(__file__), "..")
SECONDS = 3.0
SAME_MARGIN_M = 5e-4           # a settled margin measured early agrees with the full run's to this
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


#: The committed poses, each with the engine it is held in: PyBullet (the default) and MuJoCo in turn (PyBullet costs
#: seven times MuJoCo's CPU per simulated second; every pose kept its verdict in both when measured).
COMMITTED = [(path, ("pybullet", "mujoco")[i % 2])
             for i, path in enumerate(sorted(glob.glob(os.path.join(ROOT, "poses", "*.json"))))]


@pytest.mark.parametrize("path, engine", COMMITTED, ids=lambda v: os.path.basename(v) if v.endswith(".json") else v)
def test_committed_poses_keep_their_verdict(spec, path, engine):
    pose = read_pose(path, spec)
    early, full = _both(Schedule.hold(pose.servo, pose.support, spec, SECONDS), spec, engine)
    same_verdict(early, full)
    assert early.support_margin_m == pytest.approx(full.support_margin_m, abs=SAME_MARGIN_M)


@pytest.mark.parametrize("page", STOCK_PAGES)
def test_stock_pages_keep_their_verdict(spec, page):
    from op2motion.motion.pipeline import play_page

    played = play_page(ActionFile.read(os.path.join(ROOT, "tests", "data", "motion_4096.bin")), page, spec)
    early, full = _both(played.trajectory.schedule(spec), spec, "mujoco")
    same_verdict(early, full)
    assert early.seconds <= full.seconds


def test_a_push_is_waited_out(spec):
    pose = read_pose(os.path.join(ROOT, "poses", "standing.json"), spec)
    push = Push(np.array([0.0, 8.0, 0.0]), 1.5, 0.1)
    early, full = _both(Schedule.hold(pose.servo, pose.support, spec, SECONDS), spec, "mujoco", RunSetup(push=push))
    same_verdict(early, full)
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
