"""The forward walk under WalkController across a representative subset of the robustness family, in both engines
(the whole family's table is in the README, from ``op2motion walk --validate --robust --engine both``)."""

from __future__ import annotations

import pytest

from op2motion.gait import load_preset
from op2motion.gait.controller import WalkController
from op2motion.gait.robust import MAX_DRIFT_SHARE, MAX_HEADING_DEG, walk_judge
from op2motion.gait.speeds import plan_within_speed
from op2motion.physics import family, robust_check
from op2motion.robot.specfile import default_spec

pytestmark = pytest.mark.physics

MIN_SPEED_MPS = 0.22        # the issue: the forward walk at 0.22 m/s or more (steady window)
#: Servos 0.6 times as stiff as the model: without the swing leg's learnt feed-forward the last steps land short and
#: turned (heading -9°, 0.16 m/s in both engines); with it the walk passes (0.24 m/s).
SOFT = "stiffness ×0.6"
#: The torso CoM 20 mm forward leans the body: before the swing foot settled over its place (``swing_settle``) it
#: touched down early and short, 0.19-0.20 m/s.
FORWARD_COM = "torso CoM x +20 mm"
SUBSET = ("nominal", FORWARD_COM, "torso CoM x -20 mm", "torso CoM y -10 mm", "torso mass ×1.15", SOFT,
          "friction 0.5")


@pytest.fixture(scope="module")
def report():
    spec = default_spec()
    gait = plan_within_speed(load_preset("forward"), spec)
    members = [m for m in family(spec) if m.name in SUBSET]
    assert len(members) == len(SUBSET)
    return robust_check(lambda: WalkController(gait, spec), spec, ("pybullet", "mujoco"), walk_judge,
                        members=members)


def test_the_forward_walk_passes_the_subset_in_both_engines(report):
    for run in (r for r in report.runs if r.member.name in SUBSET):
        walk = run.report.run.walk
        assert run.passed, (run.member.name, run.engine, run.problem)
        assert walk.lateral_drift_m <= MAX_DRIFT_SHARE * walk.distance_m and abs(walk.heading_error_deg) <= (
            MAX_HEADING_DEG), (run.member.name, run.engine)
        assert walk.mean_speed_mps >= MIN_SPEED_MPS, (run.member.name, run.engine, walk.mean_speed_mps)
    assert report.pass_rate == 1.0 and not report.disagreements

