"""The physics loop with a controller of one's own: called every 8 ms with sensors that read what an IMU on the
torso would (checked at rest in both engines, and by closing a loop on them), goals by joint name."""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest
from helpers import ROOT

from op2motion.errors import InputError
from op2motion.physics import ENGINES, Plan, Schedule, Sensors, Setup, check
from op2motion.physics.controller import ControllerHooks
from op2motion.physics.sweeps import centred, leaned, servo_pose
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import GRAVITY_M_S2

pytestmark = pytest.mark.physics

HOLD_S = 2.5
GRAVITY_TOL_M_S2 = 0.3         # at rest the accelerometer reads gravity's reaction within this (contact jitter)
GYRO_TOL_RAD_S = 0.05
LEAN_DEG = 8.0                 # a forward lean the robot stands in on both feet (it tips at about 12°)
LEVELLED_DEG = 2.0             # the closed loop brings the torso this close to upright


class Recorder:
    """Holds a schedule's goals and records every call: times, gyro, accelerometer, the joint positions."""

    def __init__(self, schedule: Schedule):
        self.inner, self.plan = schedule, schedule.plan
        self.calls: list[tuple[float, np.ndarray, np.ndarray]] = []
        self.starts = 0

    def start(self, joint_positions):
        self.starts += 1
        self.calls = []
        return self.inner.start(joint_positions)

    def step(self, t_s, gyro_rad_s, accel_m_s2, joint_positions):
        assert set(joint_positions) == set(self.inner.joint_names)
        self.calls.append((t_s, np.array(gyro_rad_s), np.array(accel_m_s2)))
        return self.inner.step(t_s, gyro_rad_s, accel_m_s2, joint_positions)

    @property
    def done(self):
        return False                          # a held pose's schedule is done at once; keep being called


def _example(name: str):
    """A module of examples/ (its script part runs only as __main__)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _upright_deg(rot: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(rot[2, 2], -1.0, 1.0))))


@pytest.mark.parametrize("engine", ENGINES)
def test_the_controller_is_called_every_8_ms_with_an_imu_at_rest(spec, engine):
    recorder = Recorder(Schedule.hold(servo_pose(spec), "double", spec, HOLD_S))
    run = check(recorder, spec, (engine,), setup=Setup(full_length=True)).run
    assert run.stable and recorder.starts == 1
    times = np.array([c[0] for c in recorder.calls])
    assert times[0] == pytest.approx(CONTROL_PERIOD_S) and np.diff(times) == pytest.approx(CONTROL_PERIOD_S)
    assert len(times) == math.ceil(HOLD_S / CONTROL_PERIOD_S) - 1          # every tick after the start
    settled = [c for c in recorder.calls if c[0] > HOLD_S - 1.0]
    for _, gyro, accel in settled:
        assert np.linalg.norm(gyro) < GYRO_TOL_RAD_S
        assert abs(np.linalg.norm(accel) - GRAVITY_M_S2) < GRAVITY_TOL_M_S2
        assert accel[2] > 0.95 * GRAVITY_M_S2                 # the torso stands: gravity's reaction points up in it


def test_a_closed_loop_on_the_accelerometer_levels_a_leaning_torso(spec):
    """Open loop the robot stands leaning forward; closing a loop on the simulated accelerometer (the controller of
    examples/closed_loop_controller.py) brings the torso upright: the sensor's sign and frame are the robot's."""
    pose = leaned(spec, centred(spec, servo_pose(spec)), "double", "pitch", LEAN_DEG)
    schedule = Schedule.hold(pose, "double", spec, 4.0)
    keep = Setup(keep_track=True)
    # (in MuJoCo: the sensors sit in the engine-independent loop, each engine's readings are checked above)
    open_loop = check(schedule, spec, ("mujoco",), setup=keep).run
    closed = check(_example("closed_loop_controller").LevelTheTorso(schedule, spec), spec, ("mujoco",), setup=keep).run
    assert open_loop.stable and _upright_deg(open_loop.track.rot[-1]) > LEAN_DEG - 1.0
    assert _upright_deg(closed.track.rot[-1]) < LEVELLED_DEG
    assert not closed.fell or closed.reasons == ["tilt"]     # judged against the plan: levelling turns away from it


def test_goals_name_official_joints_and_unknown_ones_are_refused(spec):
    class Bad(Recorder):
        def step(self, t_s, gyro_rad_s, accel_m_s2, joint_positions):
            return {"left_knee": 0.0}

    with pytest.raises(InputError, match="official joint name"):
        check(Bad(Schedule.hold(servo_pose(spec), "double", spec, HOLD_S)), spec)
    with pytest.raises(InputError, match="controller"):
        check(object(), spec)                                                    # type: ignore[arg-type]


def test_a_plan_checks_its_rows(spec):
    with pytest.raises(InputError, match="one length"):
        Plan("motion", np.zeros((3, 20)), np.zeros((2, 20)), ("left",) * 3, 0.008, 1.5, 3.0)
    with pytest.raises(InputError, match="support"):
        Plan("motion", np.zeros((2, 20)), np.zeros((2, 20)), ("left", "both"), 0.008, 1.5, 3.0)


def test_a_controller_that_asks_gets_the_soles_loads(spec):
    """A controller that declares ``takes_foot_forces`` gets each sole's vertical load [N] in ``step``: at rest on
    two feet they carry the robot's weight between them."""
    weight_n = sum(i.mass for i in spec.inertials) * GRAVITY_M_S2

    class Loads(Recorder, ControllerHooks):
        takes_foot_forces = True

        def step(self, t_s, gyro_rad_s, accel_m_s2, joint_positions, foot_forces_n=None):
            self.loads = foot_forces_n
            return super().step(t_s, gyro_rad_s, accel_m_s2, joint_positions)

    recorder = Loads(Schedule.hold(servo_pose(spec), "double", spec, HOLD_S))
    assert check(recorder, spec).run.stable
    assert set(recorder.loads) == {"left", "right"}
    assert sum(recorder.loads.values()) == pytest.approx(weight_n, rel=0.05)


def test_sensor_latency_delays_every_reading_by_whole_periods(spec):
    """The same run read with 16 ms of latency sees exactly what the run without it saw two ticks earlier."""
    seen = {}
    for latency in (0.0, 0.016):
        recorder = Recorder(Schedule.hold(servo_pose(spec), "double", spec, HOLD_S))
        check(recorder, spec, ("mujoco",), setup=Setup(sensors=Sensors(latency_s=latency), full_length=True))
        seen[latency] = np.array([np.concatenate([g, a]) for _, g, a in recorder.calls])
    assert np.array_equal(seen[0.016][2:], seen[0.0][:-2])


def test_sensor_noise_is_seeded_and_of_its_size(spec):
    gyro_noise = 0.02
    runs = []
    for seed in (1, 1, 2):
        recorder = Recorder(Schedule.hold(servo_pose(spec), "double", spec, HOLD_S))
        check(recorder, spec, ("mujoco",),     # the sensors sit in the engine-independent loop: the cheaper engine
              setup=Setup(sensors=Sensors(gyro_noise_rad_s=gyro_noise, seed=seed), full_length=True))
        runs.append(np.array([g for t, g, _ in recorder.calls if t > HOLD_S - 1.0]))
    assert np.array_equal(runs[0], runs[1]) and not np.array_equal(runs[0], runs[2])
    assert np.std(runs[0]) == pytest.approx(gyro_noise, rel=0.2)        # the robot itself is still
