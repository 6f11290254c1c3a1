"""A controller of your own in the physics loop: every 8 ms it reads the simulated IMU (gyro and accelerometer in
the torso frame, as the CM-730 board measures them) and sets goals by joint name. This one levels a torso that leans
forward: it estimates the torso's pitch from gravity's direction and turns both ankles back until it is upright.

    python examples/closed_loop_controller.py
"""

import math

import numpy as np

import op2motion as op2
from op2motion.physics.sweeps import centred, leaned, servo_pose
from op2motion.robot.framework import CONTROL_PERIOD_S

GAIN = 0.5          # ankle pitch rate [rad/s] per radian of torso pitch (the OP2 on compliant servos rocks at 1 Hz)


class LevelTheTorso:
    """Holds a pose, and integrates the torso's pitch into both ankle pitches."""

    def __init__(self, schedule: op2.Schedule, spec):
        self.inner, self.plan, self.spec = schedule, schedule.plan, spec
        self.correction = 0.0

    def start(self, joint_positions):
        self.correction = 0.0
        return self.inner.start(joint_positions)

    def step(self, t_s, gyro_rad_s, accel_m_s2, joint_positions):
        pitch = math.atan2(-accel_m_s2[0], accel_m_s2[2])        # the torso leaning forward: positive
        self.correction += GAIN * pitch * CONTROL_PERIOD_S
        goals = dict(self.inner.step(t_s, gyro_rad_s, accel_m_s2, joint_positions))
        for side in ("l", "r"):
            goals[f"{side}_ank_pitch"] += self.correction * self.spec.joint(f"{side}_ank_pitch").axis[1]
        return goals

    @property
    def done(self):
        return False


def upright_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(rotation[2, 2], -1.0, 1.0))))


def main() -> None:
    spec = op2.load_spec()
    leaning = leaned(spec, centred(spec, servo_pose(spec)), "double", "pitch", 8.0)   # 8° forward at the ankles
    schedule = op2.Schedule.hold(leaning, "double", spec, seconds=4.0)
    keep = op2.Setup(keep_track=True)
    open_loop = op2.check(schedule, spec, setup=keep).run
    closed_loop = op2.check(LevelTheTorso(schedule, spec), spec, setup=keep).run
    print(f"open loop: the torso ends {upright_deg(open_loop.track.rot[-1]):.1f}° from upright")
    print(f"closed loop on the accelerometer: {upright_deg(closed_loop.track.rot[-1]):.1f}° from upright")


if __name__ == "__main__":
    main()
