"""A ball on the floor in the physics check: the stock kick (page 12, the right foot, from walk-ready) sends a size-1
football forward in both engines, the robot standing; a ball out of reach changes nothing of the robot's run; the
ball's contacts are never the robot's; bad placements are refused."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from helpers import STOCK, run_cli

from op2motion.errors import InputError
from op2motion.formats.action import ActionFile
from op2motion.physics import BALL_MASS_KG, BALL_RADIUS_M, Ball, Setup, check
from op2motion.physics.ball import BallWatch

KICK_PAGE, READY_PAGE = 12, 9
IN_FRONT_OF_RIGHT_FOOT = (0.14, -0.086)   # [m]: 1 cm ahead of the right toe from walk-ready, on the foot's line
KICKED_MPS = 0.6                # the stock kick sends the ball at least this fast [m/s] (0.84-0.93 measured)
FORWARD_DEG = 30.0              # ... within this of straight ahead [deg]
ROLLED_M = 0.5                  # ... and it rolls at least this far by the run's end [m]
KICK_FROM_S = 2.0               # the kick's swing comes after this into the page [s] (the ball lies still before)
SAME_SPEED = 0.25               # the two engines' ball speeds agree to this share
SAME_RUN_M = 1e-6               # a ball out of reach leaves the robot's run as it was [m]


@functools.lru_cache(maxsize=None)
def _kick_of_the_shipped_spec():
    from op2motion.motion.pipeline import play_page
    from op2motion.robot.specfile import default_spec

    spec, action = default_spec(), ActionFile.read(STOCK)
    return play_page(action, KICK_PAGE, spec, action.pose(READY_PAGE, spec)).trajectory.schedule(spec)


def _kick(spec):
    """The stock kick from walk-ready as an open-loop schedule (planned once per test process)."""
    from op2motion.robot.specfile import default_spec

    assert spec is default_spec()
    return _kick_of_the_shipped_spec()


@pytest.mark.physics
@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_the_stock_kick_sends_the_ball_forward_and_the_robot_stands(spec, engine):
    report = check(_kick(spec), spec, (engine,), setup=Setup(ball=Ball(*IN_FRONT_OF_RIGHT_FOOT))).run
    ball = report.ball
    assert report.stable, report.reason
    assert ball is not None and ball.moved_at_s is not None and ball.moved_at_s > KICK_FROM_S
    assert ball.max_speed_mps >= KICKED_MPS and abs(ball.direction_deg) <= FORWARD_DEG, ball
    assert ball.travelled_m >= ROLLED_M, ball
    assert "ball" in report.as_dict() and report.as_dict()["ball"]["max_speed_mps"] == pytest.approx(ball.max_speed_mps)


@pytest.mark.physics
def test_both_engines_send_the_ball_alike(spec):
    both = check(_kick(spec), spec, ("mujoco", "pybullet"), setup=Setup(ball=Ball(*IN_FRONT_OF_RIGHT_FOOT)))
    speeds = [e.run.ball.max_speed_mps for e in both.engines.values() if e.run.ball is not None]
    assert len(speeds) == 2 and abs(speeds[0] - speeds[1]) <= SAME_SPEED * max(speeds), speeds


@pytest.mark.physics
def test_a_ball_out_of_reach_is_not_touched_and_changes_nothing_of_the_robots_run(spec):
    alone = check(_kick(spec), spec, ("mujoco",)).run
    beside = check(_kick(spec), spec, ("mujoco",), setup=Setup(ball=Ball(0.6, 0.6))).run
    assert beside.ball is not None and beside.ball.moved_at_s is None and beside.ball.travelled_m < 1e-3
    assert beside.reason == alone.reason and abs(beside.support_margin_m - alone.support_margin_m) <= SAME_RUN_M
    assert np.allclose(beside.com_settled, alone.com_settled, atol=SAME_RUN_M)
    assert "ball" not in alone.as_dict() and alone.ball is None


def test_a_ball_is_a_size_one_football_and_a_misplaced_one_is_refused():
    assert 0.46 <= 2 * np.pi * BALL_RADIUS_M <= 0.51 and 0.18 <= BALL_MASS_KG <= 0.25      # size 1: 46-51 cm, 180-250 g
    ball = Ball(0.1, 0.0)
    assert ball.centre[2] == pytest.approx(BALL_RADIUS_M)
    assert ball.inertia_kg_m2 == pytest.approx(2.0 / 3.0 * BALL_MASS_KG * BALL_RADIUS_M ** 2)   # a thin shell
    for bad in ((3.0, 0.0), (float("nan"), 0.0)):
        with pytest.raises(InputError, match="ball"):
            Ball(*bad)


class _Rolling:
    """Ball states as an engine reports them: still, then rolling at 1 m/s towards +Y (a recorded reading)."""

    def __init__(self) -> None:
        self.k = 0

    def ball_state(self):
        self.k += 1
        speed = 0.0 if self.k < 3 else 1.0
        return np.array([0.1, 0.008 * max(self.k - 3, 0), BALL_RADIUS_M]), np.array([0.0, speed, 0.0])


def test_the_watch_reports_the_fastest_speed_its_direction_and_when_it_moved():
    watch = BallWatch(_Rolling(), Ball(0.1, 0.0))
    for k in range(6):
        watch.sample(k * 0.008)
    report = watch.report()
    assert report.max_speed_mps == pytest.approx(1.0) and report.direction_deg == pytest.approx(90.0)
    assert report.moved_at_s == pytest.approx(0.016) and report.travelled_m == pytest.approx(0.024)
    assert "1.00 m/s towards +90°" in report.describe()


def test_the_command_line_takes_a_ball_only_with_the_physics_check(capsys):
    code, _, err = run_cli(capsys, "motion", "play", str(STOCK), "--page", "12", "--ball", "0.14", "-0.086")
    assert code == 2 and "--ball" in err and "--validate" in err and err.count("\n") == 1


@pytest.mark.physics
def test_the_command_line_reports_the_ball_per_engine(capsys):
    code, out, err = run_cli(capsys, "motion", "play", str(STOCK), "--page", "12", "--validate", "--engine", "mujoco",
                             "--ball", "0.14", "-0.086", "--json")
    assert code == 0, err
    ball = json.loads(out)["physics"]["engines"]["mujoco"]["ball"]
    assert set(ball) == {"max_speed_mps", "direction_deg", "moved_at_s", "travelled_m"} and ball["max_speed_mps"] > 0
