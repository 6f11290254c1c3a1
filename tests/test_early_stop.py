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
from op2motion.physics.stopping import FELL, FULL, SETTLED, EarlyStop
from op2motion.physics.sweeps import leaned, sweep_base

pytestmark = pytest.mark.physics
ROOT = os.path.join(os.path.dirname(__file__), "..")
SECONDS = 3.0
# The lean sweeps' last standing lean and first fall in either engine (README, Lean sweeps): (support, kind, deg).
SWEEP_EDGES = [("left", "pitch", 7.5), ("left", "pitch", 8.5), ("left", "pitch", -6.0), ("left", "pitch", -7.0),
               ("left", "roll", 6.5), ("left", "roll", 7.0), ("double", "pitch", 11.5), ("double", "pitch", 12.0),
               ("double", "pitch", -10.5), ("double", "pitch", -11.0), ("double", "roll", 22.5),
               ("double", "roll", 23.0)]
STOCK_PAGES = [15, 16]            # sit down, stand up (from the init pose)


def _both(schedule: Schedule, spec, engine: str, setup: RunSetup = RunSetup()):
    runner = _Runner(schedule, spec, Setup(), 2, None)
    early = runner.run(engine, setup)
    full = runner.run(engine, RunSetup(push=setup.push, full_length=True))
    return early, full


def _same_verdict(early, full) -> None:
    assert full.ended == FULL and full.seconds == pytest.approx(full.planned_seconds)
    assert early.stable == full.stable, (early.reasons, full.reasons)
    if not full.stable:
        assert early.reasons[0] == full.reasons[0]
        assert set(early.reasons) <= set(full.reasons)


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
@pytest.mark.parametrize("support, kind, degrees", SWEEP_EDGES, ids=[f"{s}-{k}{d:+g}" for s, k, d in SWEEP_EDGES])
def test_lean_sweep_edges_keep_their_verdict(spec, engine, support, kind, degrees):
    pose = leaned(spec, sweep_base(spec, support), support, kind, degrees)
    early, full = _both(Schedule.hold(pose, support, spec, SECONDS), spec, engine)
    _same_verdict(early, full)
    assert early.ended == (SETTLED if early.stable else FELL) and early.seconds < SECONDS
    if early.stable:   # the same still robot measured
        assert early.support_margin_m == pytest.approx(full.support_margin_m, abs=5e-4)


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(ROOT, "poses", "*.json"))),
                         ids=lambda p: os.path.basename(p))
def test_committed_poses_keep_their_verdict(spec, path):
    pose = read_pose(path, spec)
    early, full = _both(Schedule.hold(pose.servo, pose.support, spec, SECONDS), spec, "pybullet")
    _same_verdict(early, full)


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
    still = EarlyStop(hold, ramped=False)
    quiet, zero = np.zeros(20), np.zeros(3)
    assert not any(still.tick(t, quiet, zero, zero) for t in np.arange(0.008, 1.0, 0.008))
    assert still.tick(1.0, quiet, zero, zero) and still.ended == SETTLED
    moving = EarlyStop(hold, ramped=False)
    assert not any(moving.tick(t, quiet, zero, np.array([0.01, 0.0, 0.0])) for t in np.arange(0.008, 3.0, 0.008))
    assert EarlyStop(hold, ramped=False, enabled=False).sample(0.0, 0.2) is False
