"""Falls and getting up: the physics hooks (a run that starts lying, a per-tick torque limit), how the IMU says the
robot lies, GetUp from the front, the back and both sides in PyBullet and MuJoCo (the stock pages and op2motion's own
motions), the fall supervisor (a 30 N push mid-walk: detected, up again, walking on), and the kicks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import STOCK

from op2motion.gait import SteerableWalk, timeline_of
from op2motion.motion import GetUp, Supervisor
from op2motion.motion.lying import lying_side, tilt_deg
from op2motion.physics import LYING, Plan, Pushes, Setup, check
from op2motion.physics.body import Body, lowest_point, lying_placement
from op2motion.physics.controller import ControllerHooks
from op2motion.physics.runner import _Runner
from op2motion.robot.spec import GRAVITY_M_S2
from op2motion.robot.specfile import default_spec

UPRIGHT_TILT_DEG = 25.0     # standing again: the torso within 25° of vertical ...
UPRIGHT_HEIGHT_M = 0.25     # ... and its origin above 0.25 m
GETUP_WITHIN_S = 20.0       # ... within 20 s
FLOOR_TOL_M = 1e-6          # a lying start touches the floor to this
GIVE_FACTOR = 3.0           # limp servos lie at least this many times further from their goals than full ones


@pytest.fixture(scope="module")
def spec():
    return default_spec()


def _upright_at(track) -> float | None:
    """The first sample time [s] with the torso upright and high (None if never)."""
    for t, rot, pos in zip(track.times, track.rot, track.base_pos):
        if math.degrees(math.acos(np.clip(rot[2, 2], -1.0, 1.0))) < UPRIGHT_TILT_DEG and pos[2] > UPRIGHT_HEIGHT_M:
            return float(t)
    return None


# -- how it lies, without physics -------------------------------------------------------------------------------


@pytest.mark.parametrize("side", sorted(LYING))
def test_a_lying_start_touches_the_floor_with_that_side_down(spec, side):
    body = Body(spec)
    q = GetUp(spec).plan.goals[0]
    pos, rot = lying_placement(body, q, side)
    assert abs(lowest_point(body, pos, rot, q)) < FLOOR_TOL_M
    up_in_torso = rot.T @ np.array([0.0, 0.0, GRAVITY_M_S2])            # what a still accelerometer reads
    assert lying_side(up_in_torso) == side


def test_the_framework_fall_test_in_counts_and_the_tilt(spec):
    # the framework's test in the board's counts (the spec's [imu] mapping, as on the robot: robot.imu.FallWatch)
    from op2motion.robot.imu import FallWatch, encode_imu

    board = spec.imu
    for accel, verdict in (((-GRAVITY_M_S2, 0.0, 0.0), "front"), ((GRAVITY_M_S2, 0.0, 0.0), "back"),
                           ((0.0, 0.0, GRAVITY_M_S2), None)):
        watch = FallWatch(board)
        verdicts = [watch.add(encode_imu(board, np.zeros(3), np.array(accel))) for _ in range(board.fallen_window)]
        assert verdicts[-2] is None and verdicts[-1] == verdict
    assert tilt_deg(np.array([0.0, 0.0, GRAVITY_M_S2])) == pytest.approx(0.0)
    assert tilt_deg(np.array([GRAVITY_M_S2, 0.0, 0.0])) == pytest.approx(90.0)
    assert lying_side(np.array([0.0, 0.0, GRAVITY_M_S2])) == "upright"


# -- the physics hooks -------------------------------------------------------------------------------------------


class _Limp(ControllerHooks):
    """Holds a pose with the servos' torque limit at ``share`` of what they have."""

    torque_limits = None        # the hook, set per instance

    def __init__(self, spec, share: float):
        self.spec, self.share = spec, share
        self.plan = Plan.hold(GetUp(spec).plan.goals[0], "double", 2.5, np.full(20, 32.0))
        self.torque_limits = {n: share for n in spec.joint_names}

    def start(self, positions):
        return {n: float(v) for n, v in zip(self.spec.joint_names, self.plan.goals[0])}

    def step(self, t, gyro, accel, positions):
        return self.start(positions)

    @property
    def done(self):
        return False


def test_the_servo_models_torque_limit_caps_the_active_torque(spec):
    from op2motion.model.servo import ServoModel

    servo = ServoModel.of(spec)
    goal, q = np.full(20, 0.5), np.zeros(20)
    limit = np.full(20, 0.2)
    assert np.allclose(servo.active_torque(goal, q), servo.torque_max)
    assert np.allclose(servo.active_torque(goal, q, limit=limit), 0.2)
    assert np.allclose(servo.active_torque(-goal, q, limit=limit), -0.2)


@pytest.mark.physics
def test_a_controllers_torque_limit_lets_the_servos_give(spec):
    """Lying face down on servos at 10 % of their torque, the joints give under the body's weight: at the end they
    lie far further from their goals than at full torque."""
    setup = Setup(lying="front", keep_track=True, full_length=True)
    limited = check(_Limp(spec, 0.1), spec, ("mujoco",), setup=setup).run.track
    full = check(_Limp(spec, 1.0), spec, ("mujoco",), setup=setup).run.track
    given = np.abs(limited.q[-1] - limited.goals[-1]).max()
    held = np.abs(full.q[-1] - full.goals[-1]).max()
    assert given > GIVE_FACTOR * held, (given, held)


# -- getting up --------------------------------------------------------------------------------------------------


GETUP_CHECK_S = 12.0        # a get-up run this long (every way up here stands within 10.5 s; README table)


@pytest.mark.physics
@pytest.mark.parametrize("engine, lying", [("pybullet", "front"), ("mujoco", "front"), ("mujoco", "back"),
                                           ("mujoco", "left"), ("mujoco", "right")])   # every member, both engines:
                                                                                        # tools/getup_table.py
def test_getup_stands_up_from_lying(spec, engine, lying):
    getup = GetUp(seconds=GETUP_CHECK_S)
    track = check(getup, spec, (engine,), setup=Setup(lying=lying, keep_track=True, full_length=True)).run.track
    up = _upright_at(track)
    assert getup.stood and up is not None and up < GETUP_WITHIN_S, getup.events
    assert any("plays" in what for _, what in getup.events)


@pytest.mark.physics
def test_getup_plays_the_stock_page_when_the_action_file_has_it(spec):
    getup = GetUp(spec, STOCK, seconds=GETUP_CHECK_S)
    track = check(getup, spec, ("mujoco",), setup=Setup(lying="back", keep_track=True, full_length=True)).run.track
    assert any("stock page 11" in what for _, what in getup.events), getup.events
    assert getup.stood and _upright_at(track) is not None


# -- the supervisor ----------------------------------------------------------------------------------------------

PUSH_N = 30.0               # the acceptance's push
PUSH_AT_S = 2.8             # as the first step begins [s]
WALK = [(0.0, 0.0, 0.0, 0.0), (1.0, 0.15, 0.0, 0.0), (24.0, "stop")]   # the supervisor's clock: a fall, a wait
                                                                    # and a get-up take up to ~14 s of it
WALKED_ON_M = 0.15          # after resuming, the torso gets at least this far [m]


@pytest.mark.physics
@pytest.mark.parametrize("engine", ["mujoco"])      # PyBullet and every push direction: tools/getup_table.py falls
def test_a_pushed_walk_falls_is_caught_gets_up_and_walks_on(spec, engine):
    walk = SteerableWalk.make(spec, commands=timeline_of(WALK))
    supervisor = Supervisor(walk, spec=spec, extra_s=0.0)
    # the pushed run alone, as check() plays it after its main run (the unpushed 27-s walk, which nothing here
    # looks at: half the test's time)
    runner = _Runner(supervisor, spec, Setup(keep_track=True, full_length=True), 1, None)
    pushed = runner.pushed(engine, Pushes(PUSH_N, ("forward",), at_s=PUSH_AT_S))
    events = [what for _, what in supervisor.events]
    assert events[:4] == ["fall detected" + events[0][len("fall detected"):], "still; getting up",
                          "standing again", "resumed"], supervisor.events
    detected = supervisor.events[0][0]
    assert PUSH_AT_S <= detected < PUSH_AT_S + 1.0
    track = pushed[0].run.track
    resumed = supervisor.events[3][0]
    at = int(np.searchsorted(track.times, resumed))
    assert track.base_pos[-1][2] > UPRIGHT_HEIGHT_M                        # up at the end ...
    assert np.hypot(*(track.base_pos[-1][:2] - track.base_pos[at][:2])) > WALKED_ON_M   # ... having walked on


# -- kicks -------------------------------------------------------------------------------------------------------

MIN_KICK_FOOT_M_S = 0.3     # the kicking foot's peak speed (ball-less): at least this [m/s]


@pytest.mark.physics
def test_op2motions_own_kick_stands_and_swings_the_foot(spec):
    from op2motion.formats.motionfile import read_motion
    from op2motion.motion.getup_ways import motion_path
    from op2motion.motion.pipeline import plan_motion

    trajectory = plan_motion(read_motion(motion_path("kick_right"), spec), spec)
    run = check(trajectory.schedule(spec), spec, ("mujoco",), setup=Setup(keep_track=True)).run
    assert run.stable, run.reasons
    sole = run.track.soles["right"]
    speed = np.linalg.norm(np.diff(sole, axis=0), axis=1) / np.diff(run.track.times)
    assert speed.max() > MIN_KICK_FOOT_M_S
