"""The forward walk under WalkController across a representative subset of the robustness family, in MuJoCo, and its
nominal body and corners in PyBullet too (the whole family's table in both engines is in the README, from
``op2motion walk --validate --robust --engine both``).

The forward walk takes :data:`FORWARD_STEPS` steps here, not the preset's 20: its steady window (the walk's middle)
lies after the start's transients either way, and the figures below were measured on the preset's 20 steps (at 12
the six bodies walk 0.23-0.27 m/s, drift at most 18 mm, heading within 1.2°, in both engines). The side steps keep
the preset's 20: their drift is judged against the judge's least distance (0.5 m) at any length, and without the
leg odometry it grew with the steps (47-65 mm after 20), so 20 steps keep that failure clear of the 25 mm allowed."""

from __future__ import annotations

from dataclasses import replace

import pytest

from op2motion.gait import load_preset
from op2motion.gait.controller import WalkController
from op2motion.gait.robust import MAX_DRIFT_SHARE, MAX_HEADING_DEG, walk_judge
from op2motion.gait.speeds import gait_within_speed
from op2motion.physics import family, robust_check
from op2motion.robot.specfile import default_spec

pytestmark = pytest.mark.physics

MIN_SPEED_MPS = 0.22        # the issue: the forward walk at 0.22 m/s or more (steady window)
FORWARD_STEPS = 12          # [steps] (see the module docstring)
#: Servos 0.6 times as stiff as the model: without the swing leg's learnt feed-forward the last steps land short and
#: turned (heading -9°, 0.16 m/s in both engines); with it the walk passes (0.24 m/s).
SOFT = "stiffness ×0.6"
#: The torso CoM 20 mm forward leans the body: before the swing foot settled over its place (``swing_settle``) it
#: touched down early and short, 0.19-0.20 m/s.
FORWARD_COM = "torso CoM x +20 mm"
#: The heavy, soft, slippery corner with the CoM back rocked backwards and fell without the attitude P that the
#: measured softness switches on; the light, stiff, grippy one with the CoM back ended 7° turned as its closing
#: foot landed short and the legs pulled it into the planned stance.
HEAVY_SOFT = "x -20 mm, mass ×1.15, stiffness ×0.6, friction 0.5"
LIGHT_STIFF = "x -20 mm, mass ×0.85, stiffness ×1.6, friction 1"
#: The single factors "torso CoM x -20 mm", "torso mass ×1.15" and "friction 0.5" are in the corners together (and in
#: the README's whole-family table, one at a time): the corners stand for them here.
SUBSET = ("nominal", FORWARD_COM, "torso CoM y -10 mm", SOFT, HEAVY_SOFT, LIGHT_STIFF)
#: The members walked in PyBullet as well (and the two engines compared on them): the nominal body and both corners.
#: PyBullet costs seven times MuJoCo's CPU per simulated second; each single factor passed in both when measured.
BOTH_ENGINES = ("nominal", HEAVY_SOFT, LIGHT_STIFF)
#: Side steps on these drifted 47-65 mm (9-13 %) along the walk's fore-aft line before the leg odometry kept it.
SIDEWAYS_SUBSET = ("torso CoM x +20 mm", "stiffness ×1.6")


@pytest.fixture(scope="module")
def report():
    spec = default_spec()
    gait = gait_within_speed(replace(load_preset("forward"), steps=FORWARD_STEPS), spec)
    members = [m for m in family(spec) if m.name in SUBSET]
    assert len(members) == len(SUBSET)
    both = [m for m in members if m.name in BOTH_ENGINES]
    return [robust_check(lambda: WalkController(gait, spec), spec, engines, walk_judge, members=some)
            for engines, some in ((("pybullet", "mujoco"), both), (("mujoco",), [m for m in members if m not in both]))]


def test_the_forward_walk_passes_the_subset(report):
    """Every member of :data:`SUBSET` in MuJoCo, :data:`BOTH_ENGINES` in PyBullet too."""
    runs = [r for part in report for r in part.runs]
    assert sorted((r.member.name, r.engine) for r in runs) == sorted(
        [(m, "mujoco") for m in SUBSET] + [(m, "pybullet") for m in BOTH_ENGINES])
    for run in runs:
        walk = run.report.run.walk
        assert run.passed, (run.member.name, run.engine, run.problem)
        assert walk.lateral_drift_m <= MAX_DRIFT_SHARE * walk.distance_m and abs(walk.heading_error_deg) <= (
            MAX_HEADING_DEG), (run.member.name, run.engine)
        assert walk.mean_speed_mps >= MIN_SPEED_MPS, (run.member.name, run.engine, walk.mean_speed_mps)
    assert all(part.pass_rate == 1.0 and not part.disagreements for part in report)



def test_side_steps_keep_their_line_by_leg_odometry():
    spec = default_spec()
    gait = gait_within_speed(load_preset("sideways"), spec)
    members = [m for m in family(spec) if m.name in SIDEWAYS_SUBSET]
    assert len(members) == len(SIDEWAYS_SUBSET)
    runs = [run for engines, some in ((("pybullet", "mujoco"), members[:1]), (("mujoco",), members[1:]))
            for run in robust_check(lambda: WalkController(gait, spec), spec, engines, walk_judge, members=some).runs]
    assert len(runs) == len(SIDEWAYS_SUBSET) + 1                   # the first member in PyBullet too
    for run in runs:
        assert run.passed, (run.member.name, run.engine, run.problem)
