"""OMPL's RRT-Connect as the route planner (op2motion.motion.rrt_ompl, ``planner="ompl"``): it goes around with
op2motion's own checks accepting every edge, one seed plans one path, and an unknown planner is refused naming
the parameter. Skipped where the ompl extra is not installed (the test extra installs it)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import run_cli
from test_route import ARM_THROUGH_ARM, _pair, _write_pair
from test_route import _disc_world as disc_world

from op2motion.errors import InputError
from op2motion.motion.body_checks import PLAN_CLEARANCE_M, BodyChecks
from op2motion.motion.route import route, route_segment
from op2motion.motion.rrt import RrtSettings, edge_points, edge_valid

pytest.importorskip("ompl")

from op2motion.motion.rrt_ompl import ompl_rrt_connect  # noqa: E402 (after the skip: it needs no ompl, its use does)

OBSTACLE_RADIUS = 0.3
DENSE_RAD = 0.005            # the routed edges are re-checked this finely [rad of the fastest joint]
FINE = 0.001                 # the disc world's edges are re-checked this finely [metric units]


def _disc_world():
    return disc_world((1.0, 2.0))                               # a weighted metric, as a route's progress has


def test_ompl_goes_around_an_obstacle_every_edge_checked_by_ours_and_repeats_with_its_seed():
    box, valid = _disc_world()
    start, goal = np.array([0.1, 0.5]), np.array([0.9, 0.5])
    settings = RrtSettings(step=0.1, resolution=0.005)
    paths = [ompl_rrt_connect(start, goal, valid, box, np.random.default_rng(3), settings) for _ in range(2)]
    other = ompl_rrt_connect(start, goal, valid, box, np.random.default_rng(4), settings)
    assert paths[0] is not None and paths[1] is not None and other is not None and len(paths[0]) > 2
    assert np.array_equal(paths[0][0], start) and np.array_equal(paths[0][-1], goal)
    assert all(edge_valid(a, b, valid, box, settings.resolution) for a, b in zip(paths[0], paths[0][1:]))
    assert all(valid(edge_points(a, b, box, FINE)).all() for a, b in zip(paths[0], paths[0][1:]))
    assert len(paths[0]) == len(paths[1]) and all(np.array_equal(p, q) for p, q in zip(*paths))
    assert len(other) != len(paths[0]) or not all(np.array_equal(p, q) for p, q in zip(paths[0], other))
    steps = [float(box.distance(a, b)) for a, b in zip(paths[0], paths[0][1:])]
    assert max(steps) <= settings.step + 1e-9                         # OMPL's range is our step, in our metric


def test_ompl_gives_up_on_an_enclosed_goal_within_the_sample_cap():
    box, _ = _disc_world()

    def pocket(p: np.ndarray) -> np.ndarray:
        r = np.hypot(p[:, 0] - 0.5, p[:, 1] - 0.5)
        return (r < 0.1) | (r > OBSTACLE_RADIUS)

    path = ompl_rrt_connect(np.array([0.05, 0.05]), np.array([0.5, 0.5]), pocket, box, np.random.default_rng(0),
                            RrtSettings(max_samples=300, budget_s=2.0))
    assert path is None


def test_ompl_plans_an_op2_pair_around_with_clearance_at_every_edge_and_repeats(spec):
    a, b = _pair(spec, ARM_THROUGH_ARM)
    pieces, why = route_segment(a, b, spec, seed=0, planner="ompl")
    assert why is not None and "overlap" in why and len(pieces) >= 2
    checks = BodyChecks(spec, None)
    poses = [a.servo] + [p.servo for p in pieces]
    least = min(PLAN_CLEARANCE_M, checks.measure(np.array([a.servo, b.servo])).clearance.min())
    for x, y in zip(poses, poses[1:]):
        n = int(np.ceil(np.abs(y - x).max() / DENSE_RAD)) + 1
        m = checks.measure(x + np.linspace(0.0, 1.0, n)[:, None] * (y - x))
        assert m.clearance.min() >= least - 1e-9 and checks.within_joint_limits(np.array([x, y])).all()
    again, _ = route_segment(a, b, spec, seed=0, planner="ompl")
    assert len(again) == len(pieces) and all(np.array_equal(p.servo, q.servo) for p, q in zip(pieces, again))


def test_an_unknown_planner_is_refused_naming_it(spec):
    a, b = _pair(spec, ARM_THROUGH_ARM)
    for call in (lambda: route([a, b], spec, planner="prm"), lambda: route_segment(a, b, spec, 0, planner="prm")):
        with pytest.raises(InputError, match="rrt, ompl") as err:
            call()
        assert err.value.param == "planner"


def test_cli_plans_with_ompl_and_refuses_an_unknown_planner(tmp_path, spec, capsys):
    paths = _write_pair(tmp_path, spec, ARM_THROUGH_ARM)
    code, stdout, _ = run_cli(capsys, "motion", "plan", *paths, "--durations", "2", "--planner", "ompl", "--json")
    result = json.loads(stdout)
    assert code == 0 and any("OMPL's RRT-Connect" in n for n in result["notes"])
    out = tmp_path / "m.json"
    code, _, err = run_cli(capsys, "motion", "plan", *paths, "--durations", "2", "--planner", "prm", "--out", out)
    assert code == 2 and not out.exists() and "--planner" in err and "Traceback" not in err
