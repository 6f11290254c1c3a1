"""Motions that go around: RRT-Connect (op2motion.motion.rrt) and the OP2's joint-space routing (motion.route):
pose pairs whose straight interpolation drives links through each other are planned around with clearance at every
row, deterministically; an impossible pair is refused; the CLI writes nothing then."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from helpers import DATA, POSES, pybullet_pair_distances, run_cli

from op2motion.errors import CheckFailed
from op2motion.formats.posefile import read_pose, write_pose
from op2motion.kinematics.dh import forward_dh_frames
from op2motion.kinematics.shapes import clearances, shape_set
from op2motion.motion.body_checks import PLAN_CLEARANCE_M, BodyChecks
from op2motion.motion.checks import check_trajectory, clearance, require_clear
from op2motion.motion.planner import trajectory_through
from op2motion.motion.route import route_segment
from op2motion.motion.rrt import Box, RrtSettings, edge_points, rrt_connect, shortcut
from op2motion.motion.trajectory import Trajectory
from op2motion.motion.waypoint import Waypoint
from op2motion.physics import check
from op2motion.posture.cost import SELF_CLEARANCE_M
from op2motion.robot.joints import servo_to_book
from op2motion.robot.pose import Pose
from op2motion.robot.specfile import default_spec
from op2motion.robot.support import Support

OBSTACLE_RADIUS = 0.3
DENSE_RAD = 0.005            # the routed edges are re-checked this finely [rad of the fastest joint]
MIN_MARGIN_M = 0.0           # the CoM never leaves the support along a routed path
NEAR_M = 0.025               # pairs compared with PyBullet where our clearance is below this
# ours against PyBullet's exact distances: segment-against-box sampling and PyBullet's box distances (1.3 mm
# seen), plus the cylinders' rims and caps (ShapeSet.approximation_m)
SAMPLING_M = 0.0015
ROWS_COMPARED = 40
END_TOL_RAD = 1e-3           # the planned rows start and end on the poses (the balance lean moves them < 0.06°)
# The colliding pairs (tests/data/route_pairs.json, which tools/route_compare.py reads too): joint -> (from, to) [deg].
ROUTE_PAIRS = json.loads((DATA / "route_pairs.json").read_text(encoding="utf-8"))["pairs"]
PAIRS = {name: {joint: tuple(v) for joint, v in p["joints_deg"].items()} for name, p in ROUTE_PAIRS.items()}
ONE_FOOT = {name: (p["base"], p["support"]) for name, p in ROUTE_PAIRS.items() if p["support"] != "double"}
ARM_THROUGH_TORSO, ARM_THROUGH_ARM = PAIRS["arm through torso"], PAIRS["arm through the other arm"]
#: The planned motions played in PyBullet as well as MuJoCo: one on both feet, the one on one foot.
BOTH_ENGINES_PAIRS = ("arm through torso", "crossed leg through the floor")


def _pair(spec, change: dict, duration_s: float = 2.0) -> tuple[Waypoint, Waypoint]:
    base, support = next((v for k, v in ONE_FOOT.items() if PAIRS[k] is change), ("init", "double"))
    start = read_pose(POSES / f"{base}.json", spec).servo
    a, b = start.copy(), start.copy()
    for joint, (x, y) in change.items():
        a[spec.joint_names.index(joint)], b[spec.joint_names.index(joint)] = np.radians(x), np.radians(y)
    return Waypoint("a", a, 0.0, 0.0, support), Waypoint("b", b, duration_s, 0.0, support)


@functools.lru_cache(maxsize=None)
def _planned(name: str) -> Trajectory:
    """The pair's motion as planned around (seed 0) with the shipped spec, once per test process: the tests of its
    rows' clearance, against PyBullet and in physics look at the one trajectory (the first test plans it twice
    more itself, to see that planning repeats)."""
    spec = default_spec()
    return trajectory_through(list(_pair(spec, PAIRS[name])), spec, seed=0)


def _disc_world(weights: tuple[float, float] = (1.0, 1.0)):
    """A unit square with a disc of :data:`OBSTACLE_RADIUS` in its middle, its metric weighted by ``weights``."""
    box = Box(np.zeros(2), np.ones(2), np.array(weights))

    def valid(p: np.ndarray) -> np.ndarray:
        return np.hypot(p[:, 0] - 0.5, p[:, 1] - 0.5) > OBSTACLE_RADIUS

    return box, valid


def test_rrt_connect_goes_around_an_obstacle_and_repeats_with_its_seed():
    box, valid = _disc_world()
    start, goal = np.array([0.1, 0.5]), np.array([0.9, 0.5])
    settings = RrtSettings(step=0.1, resolution=0.005)
    paths = [rrt_connect(start, goal, valid, box, np.random.default_rng(3), settings) for _ in range(2)]
    assert paths[0] is not None and len(paths[0]) > 2
    assert all(np.array_equal(p, q) for p, q in zip(*paths))
    short = shortcut(paths[0], valid, box, np.random.default_rng(3), settings)
    for path in (paths[0], short):
        assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal)
        assert all(valid(edge_points(a, b, box, 0.001)).all() for a, b in zip(path, path[1:]))
    length = lambda p: sum(float(box.distance(a, b)) for a, b in zip(p, p[1:]))  # noqa: E731
    assert length(short) <= length(paths[0]) + 1e-12
    assert length(short) < 1.2 * np.pi * OBSTACLE_RADIUS + 0.4      # about half round the disc, not a detour


def test_rrt_connect_gives_up_on_an_enclosed_goal():
    box, _ = _disc_world()

    def pocket(p: np.ndarray) -> np.ndarray:       # free inside r < 0.1 and outside r > 0.3: a closed ring between
        r = np.hypot(p[:, 0] - 0.5, p[:, 1] - 0.5)
        return (r < 0.1) | (r > OBSTACLE_RADIUS)

    path = rrt_connect(np.array([0.05, 0.05]), np.array([0.5, 0.5]), pocket, box, np.random.default_rng(0),
                       RrtSettings(max_samples=300, budget_s=2.0))
    assert path is None


@pytest.mark.parametrize("name", sorted(PAIRS))
def test_colliding_pairs_are_planned_around_with_clearance_at_every_row(spec, name):
    a, b = _pair(spec, PAIRS[name])
    one_foot = name in ONE_FOOT
    if not one_foot:
        with pytest.raises(CheckFailed, match="passes"):
            require_clear(trajectory_through([a, b], spec, planner="none"), spec)
    pieces, why = route_segment(a, b, spec, seed=0)
    assert why is not None and ("swing foot comes down" if one_foot else "overlap") in why and len(pieces) >= 2
    checks = BodyChecks(spec, "left" if one_foot else None)
    poses = [a.servo] + [p.servo for p in pieces]
    least = min(PLAN_CLEARANCE_M, checks.measure(np.array([a.servo, b.servo])).clearance.min())   # as the ends have
    for x, y in zip(poses, poses[1:]):
        n = int(np.ceil(np.abs(y - x).max() / DENSE_RAD)) + 1
        m = checks.measure(x + np.linspace(0.0, 1.0, n)[:, None] * (y - x))
        assert m.clearance.min() >= least - 1e-9 and m.margin.min() > MIN_MARGIN_M
        assert m.swing.min() >= 0.0                                  # on one foot, the other stays lifted
    traj = _planned(name)
    assert clearance(traj.goals, spec)[0].min() >= SELF_CLEARANCE_M
    assert check_trajectory(traj, spec).summary()["min_clearance_m"] >= SELF_CLEARANCE_M - 5e-6
    assert any("planned around" in n for n in traj.notes)
    again = trajectory_through([a, b], spec, seed=0)          # planned again here: the same rows
    assert np.array_equal(traj.goals, again.goals)
    ends = np.array([traj.goals[0] - a.servo, traj.goals[-1] - b.servo])
    assert np.abs(ends).max() < END_TOL_RAD               # on one foot the balance lean leaves the ends as they were


def test_a_goal_inside_the_body_has_no_path(spec):
    init = read_pose(POSES / "init.json", spec).servo
    inside = init.copy()
    for joint, deg in (("r_sho_pitch", -45.0), ("r_sho_roll", -90.0), ("r_el", 0.0)):
        inside[spec.joint_names.index(joint)] = np.radians(deg)
    with pytest.raises(CheckFailed, match="no path from init to arm_in: arm_in itself has links"):
        trajectory_through([Waypoint("init", init, 0.0, 0.0, "double"), Waypoint("arm_in", inside, 1.0, 0.0, "double")],
                           spec)


def _write_pair(tmp_path, spec, change: dict) -> list[str]:
    a, b = _pair(spec, change)
    paths = []
    for w in (a, b):
        write_pose(Pose(f"pair_{w.name}", Support.DOUBLE, w.servo), tmp_path / f"{w.name}.json", spec)
        paths.append(str(tmp_path / f"{w.name}.json"))
    return paths


def test_cli_plans_around_and_refuses_with_planner_none(tmp_path, spec, capsys):
    paths = _write_pair(tmp_path, spec, ARM_THROUGH_TORSO)
    out = tmp_path / "m.json"
    code, stdout, _ = run_cli(capsys, "motion", "plan", *paths, "--durations", "2", "--seed", "4", "--out", out,
                              "--json")
    result = json.loads(stdout)
    assert code == 0 and out.is_file()
    assert result["checks"]["min_clearance_m"] >= SELF_CLEARANCE_M and any("via pose" in n for n in result["notes"])
    refused = tmp_path / "refused.json"
    code, _, err = run_cli(capsys, "motion", "plan", *paths, "--durations", "2", "--planner", "none", "--out", refused)
    assert code == 1 and not refused.exists() and "passes" in err


def test_cli_refuses_a_pair_with_no_path_writing_nothing(tmp_path, spec, capsys):
    init = read_pose(POSES / "init.json", spec)
    inside = init.servo.copy()
    for joint, deg in (("r_sho_pitch", -45.0), ("r_sho_roll", -90.0), ("r_el", 0.0)):
        inside[spec.joint_names.index(joint)] = np.radians(deg)
    write_pose(Pose("arm_in", Support.DOUBLE, inside), tmp_path / "in.json", spec)
    out = tmp_path / "m.json"
    code, _, err = run_cli(capsys, "motion", "plan", POSES / "init.json", tmp_path / "in.json", "--durations", "1",
                           "--out", out, "--csv", tmp_path / "m.csv")
    assert code == 1 and not out.exists() and not (tmp_path / "m.csv").exists()
    assert err.count("\n") == 1 and "no path" in err and "Traceback" not in err


@pytest.mark.parametrize("name", sorted(PAIRS))
def test_planned_rows_clearance_agrees_with_pybullets_closest_points(spec, pybullet_robot, name):
    client, robot = pybullet_robot
    traj = _planned(name)
    rows = traj.goals[np.linspace(0, len(traj.goals) - 1, ROWS_COMPARED).astype(int)]
    shapes = shape_set(spec, "left")
    _, frames = forward_dh_frames(servo_to_book(rows, "left", spec), spec)
    ours = clearances(frames, shapes)
    names, (over, under) = shapes.pair_names(), shapes.approximation_m()
    near = [(k, p) for k in range(len(rows)) for p in range(len(names)) if ours[p, k] <= NEAR_M]
    exact = pybullet_pair_distances(client, robot, spec, rows, [(k, names[p]) for k, p in near], NEAR_M)
    assert len(near) > 10
    for (k, p), (_, a, b, d) in zip(near, exact):
        assert -SAMPLING_M - under[p] <= ours[p, k] - d <= SAMPLING_M + over[p], (k, a, b, ours[p, k], d)
        assert d >= SELF_CLEARANCE_M - SAMPLING_M - over[p]


@pytest.mark.physics
@pytest.mark.parametrize("name", sorted(PAIRS))
def test_planned_motions_stand(spec, name):
    """In MuJoCo, and in PyBullet too for :data:`BOTH_ENGINES_PAIRS` (PyBullet costs seven times MuJoCo's CPU per
    simulated second; each stood in both when measured)."""
    traj = _planned(name)
    engines = ("pybullet", "mujoco") if name in BOTH_ENGINES_PAIRS else ("mujoco",)
    report = check(traj.schedule(spec), spec, engines)
    assert report.agree and report.stable, [e.run.reasons for e in report.engines.values()]
