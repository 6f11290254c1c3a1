"""The steered walk in physics: a command sequence (standing, forward, forward while turning, sideways, backward,
stop) walked in PyBullet and MuJoCo without a fall and ending done, near where it was planned; a kick inside a walk
keeps the robot up."""

from __future__ import annotations

import math

import pytest

from op2motion.gait import SteerableWalk, timeline_of
from op2motion.gait.robust import MAX_COMMANDED_HEADING_DEG
from op2motion.physics import check
from op2motion.robot.specfile import default_spec

pytestmark = pytest.mark.physics

#: Standing, forward, forward while turning left, sideways to the left, backward, stop (times [s] on the walk's clock).
SEQUENCE = [(0.0, 0.0, 0.0, 0.0), (1.5, 0.15, 0.0, 0.0), (4.0, 0.1, 0.0, 0.4), (6.5, 0.0, 0.05, 0.0),
            (8.5, -0.08, 0.0, 0.0), (10.5, "stop")]
END_TOL_M = 0.1             # the torso ends within this of its planned end [m]
#: Stop, kick with the right foot, walk on.
KICK = [(0.0, 0.0, 0.0, 0.0), (1.5, 0.12, 0.0, 0.0), (3.0, "kick_right"), (20.0, "stop")]


@pytest.fixture(scope="module")
def spec():
    return default_spec()


@pytest.fixture(scope="module")
def plan(spec):
    """The sequence's plan, made once (a dry run)."""
    return SteerableWalk.make(spec, commands=timeline_of(SEQUENCE)).plan


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_a_command_sequence_walks_without_a_fall_and_ends_done(spec, plan, engine):
    walk = SteerableWalk.make(spec, commands=timeline_of(SEQUENCE))
    walk._plan = plan
    run = check(walk, spec, (engine,)).run
    assert not run.fell, run.reasons
    assert walk.done                                   # stopped and still: the loop stopped calling it
    pos, rot = plan.base
    planned_yaw = math.degrees(math.atan2(rot[-1][1, 0], rot[-1][0, 0]))
    assert planned_yaw > 30.0                          # the turn was planned ...
    assert abs(run.walk.heading_error_deg) < MAX_COMMANDED_HEADING_DEG          # ... and walked
    assert run.walk.distance_m > 0.5 * math.hypot(*pos[-1][:2])
    assert run.walk.lateral_drift_m < END_TOL_M


@pytest.fixture(scope="module")
def kick_walk(spec):
    """The kick sequence's walk, planned once."""
    walk = SteerableWalk.make(spec, commands=timeline_of(KICK))
    walk.plan
    return walk


@pytest.mark.parametrize("engine", ["mujoco"])      # both engines, every kick: tools/kick_table.py
def test_a_kick_inside_a_walk_keeps_the_robot_up_and_it_walks_on(spec, kick_walk, engine):
    plan = kick_walk.plan
    kinds = [p.kind for _, p in kick_walk.dry.planner.phases]
    kick = kinds.index("kick")
    assert "step" in kinds[kick:]                      # walks on after the kick
    walk = SteerableWalk.make(spec, commands=timeline_of(KICK))
    walk._plan = plan
    run = check(walk, spec, (engine,)).run
    assert not run.fell, run.reasons
    assert run.walk.distance_m > 0.25 and plan.duration_s > 18.0
