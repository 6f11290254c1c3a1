"""The gait generator: footsteps -> ZMP reference -> preview-controlled CoM -> torso -> leg IK -> joint goals.

1. :func:`.footsteps.place_footsteps` places the feet, :func:`.timeline.build_timeline` clocks them (8 ms rows):
   ZMP reference and both soles' trajectories.
2. The cart-table preview controller (:mod:`.preview`) turns the ZMP reference into a CoM path at the pendulum
   height ``z_c``: the CoM height of the gait's standing pose (hips :attr:`~.GaitParams.hip_lower_m` below their
   straight-leg height), from pinocchio on the full model, unless the preset fixes it.
3. The torso keeps a constant height, the preset's lean and the mean heading of the feet; its horizontal position
   is found so that the whole body's CoM (pinocchio, legs from the closed-form IK, arms swinging) lies on the
   planned path (a few fixed-point passes: the legs are 19 % of the mass each and move the CoM by themselves).
4. Second stage: the multibody ZMP of the resulting motion (CoM acceleration and centroidal angular momentum rate,
   :func:`op2motion.motion.checks.multibody_zmp`) differs from the cart's; the difference, fed through the same
   preview controller, moves the CoM path (Kajita's two-stage preview), :attr:`~.GaitParams.zmp_passes` times.

The result holds the planned ZMP's margin to the sole(s) on the floor at every row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.gait.footsteps import Footsteps, place_footsteps, zmp_margins
from op2motion.gait.params import GaitParams
from op2motion.gait.preview import CartTrack, preview_gains, track_reference
from op2motion.gait.timeline import Timeline, build_timeline
from op2motion.kinematics.frames import eigen_quaternions
from op2motion.kinematics.leg_ik import leg_ik, leg_of, rot_y, rot_z, within_reach
from op2motion.model.dynamics import dynamics_for
from op2motion.model.servo import ServoModel
from op2motion.motion.checks import SMOOTH_ROWS, contact_torques, multibody_zmp, smoothed
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import SupportName

FRICTION_SMOOTH_RAD_S = 0.05   # the friction feed-forward's sign is smoothed over this speed
REST_PAD = 4            # rows of rest around the walk when differentiating (the robot stands before and after)
COM_PASSES = 3          # fixed-point passes placing the torso under the planned CoM (residual < 0.1 mm)
#: The arms during a walk [deg]: the stock walk-ready page (motion_4096.bin page 9), left and right made symmetric.
ARM_POSE_DEG = {"r_sho_pitch": -45.0, "l_sho_pitch": 45.0, "r_sho_roll": -17.7, "l_sho_roll": 17.7,
                "r_el": 29.4, "l_el": -29.4}


@dataclass(frozen=True)
class Gait:
    """A planned walk. Per row (K,) every :attr:`dt`: torso position (K, 3) [m] and rotation (K, 3, 3), the
    planned joint angles (K, 20) [rad], the goals sent to the servos (K, 20) [rad] (the joint angles led by the
    servo model's inverse, :attr:`~.GaitParams.servo_feedforward`) with P gains (K, 20),
    the whole-body CoM (K, 3) [m], the cart's CoM (K, 2) [m], the
    multibody ZMP (K, 2) [m] and its margin to the soles on the floor (K,) [m] (negative: outside); the preview
    controller's state of the CoM path the body was fitted to (:func:`cart_states`, the sum of the pendulum's and
    each correction's) and the reference's corrections, from which a walk stopped early is planned on
    (:mod:`.planned_stop`); world frame of the start (X forward, Y left, floor at Z = 0)."""

    params: GaitParams
    footsteps: Footsteps
    timeline: Timeline
    com_height: float
    torso_pos: np.ndarray
    torso_rot: np.ndarray
    joints: np.ndarray
    goals: np.ndarray
    p_gains: np.ndarray
    com: np.ndarray
    cart_com: np.ndarray
    zmp: np.ndarray
    zmp_margin: np.ndarray
    cart_states: np.ndarray | None = None        # the CoM path's preview state before each row (K, 4, 2)
    zmp_correction: np.ndarray | None = None     # the multibody corrections added to the ZMP reference (K, 2) [m]

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return CONTROL_PERIOD_S

    @property
    def times(self) -> np.ndarray:
        """Row times [s]."""
        return self.timeline.times

    @property
    def supports(self) -> tuple[SupportName, ...]:
        """The physics support of every row."""
        return self.timeline.supports

    @property
    def duration_s(self) -> float:
        """From the first row to the last [s]."""
        return float(self.times[-1])

    @property
    def walking_s(self) -> float:
        """Time spent stepping: from the first lift-off to the last touchdown and its double support [s]."""
        return len(self.footsteps.steps) * self.params.step_s

    @property
    def steady_window(self) -> tuple[float, float]:
        """(start, end) [s] of steady walking: from the second step's touchdown to the last advancing step's
        (the whole stepping time for walks of three steps or fewer)."""
        step, t = self.timeline.step, self.times
        n = len(self.footsteps.steps)
        if n <= 3:
            rows = np.flatnonzero((step >= 0) & (step < n))
            return float(t[rows[0]]), float(t[rows[-1]])
        return float(t[np.flatnonzero(step == 1)[-1]]), float(t[np.flatnonzero(step == n - 2)[-1]])

    def end_pose(self) -> np.ndarray:
        """Planned (x, y, yaw) [m, m, rad] of the body at the end: between the feet, their mean heading."""
        left, right = self.timeline.feet["left"][-1], self.timeline.feet["right"][-1]
        yaw = left[3] + 0.5 * math.remainder(right[3] - left[3], 2.0 * math.pi)
        return np.array([0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]), yaw])


def arm_rows(params: GaitParams, timeline: Timeline, spec: Spec, torso_rot: np.ndarray,
             torso_pos: np.ndarray) -> np.ndarray:
    """Servo rows (K, 20) [rad] with the arm pose and its swing, zero elsewhere: each shoulder pitches forward as
    the opposite foot leads, by :attr:`~.GaitParams.arm_swing_deg` at the largest split of the feet."""
    rows = np.zeros((len(timeline.times), len(spec.joints)))
    for name, deg in ARM_POSE_DEG.items():
        rows[:, spec.joint_names.index(name)] = math.radians(deg)
    stride = 2.0 * abs(params.step_length_m)
    if params.arm_swing_deg > 0.0 and stride > 0.0:
        ahead = {side: np.einsum("kj,kj->k", torso_rot[:, :, 0], timeline.feet[side][:, :3] - torso_pos)
                 for side in ("left", "right")}
        split = np.clip((ahead["right"] - ahead["left"]) / stride, -1.0, 1.0)
        swing = math.radians(params.arm_swing_deg) * split           # left arm forward when the right foot leads
        for name in ("l_sho_pitch", "r_sho_pitch"):
            j = spec.joint(name)
            forward = -1.0 if j.axis[1] > 0 else 1.0                  # servo sign that brings the hand forward
            rows[:, spec.joint_names.index(name)] += forward * (swing if name[0] == "l" else -swing)
    return rows


class _Body:
    """The torso-to-goals step: IK of both legs for torso poses, and the whole-body CoM and ZMP of the result."""

    def __init__(self, spec: Spec, timeline: Timeline):
        self.spec, self.timeline = spec, timeline
        self.dyn = dynamics_for(spec)
        self.legs = {side: leg_of(spec, side) for side in ("left", "right")}
        self.sole_rot = {side: rot_z(timeline.feet[side][:, 3]) for side in ("left", "right")}

    def goals(self, arms: np.ndarray, pos: np.ndarray, rot: np.ndarray, reach: float | None = None) -> np.ndarray:
        """Servo rows (K, 20) [rad]: ``arms`` with both legs by IK for the torso poses; a leg asked beyond its
        length is an error, or (``reach``: a share of its length) stretched only that far towards the sole."""
        out = arms.copy()
        for side, leg in self.legs.items():
            sole = np.einsum("kji,kj->ki", rot, self.timeline.feet[side][:, :3] - pos)
            sole_rot = np.transpose(rot, (0, 2, 1)) @ self.sole_rot[side]
            if reach is not None:
                sole, sole_rot = within_reach(leg, sole, sole_rot, reach)
            try:
                out[:, list(leg.index)] = leg_ik(leg, sole, sole_rot)
            except InputError as e:                # a preset whose values are in range but not together
                raise InputError(f"expected a gait the legs can reach; the {side} leg cannot: {e.message} (lower "
                                 f"the hips more, shorten the steps or lift the swing foot less)", "preset") from None
        return out

    def configs(self, goals: np.ndarray, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        out = np.repeat(self.dyn.configuration(goals[0])[None], len(goals), axis=0)
        out[:, self.dyn.q_index] = goals
        out[:, :3] = pos
        out[:, 3:7] = eigen_quaternions(rot)
        return out

    def zmp(self, configs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """CoM (K, 3) and multibody ZMP (K, 2) [m]; the robot rests before the first row and after the last (the
        rows are padded with copies for the differences)."""
        pad = np.vstack([np.repeat(configs[:1], REST_PAD, axis=0), configs, np.repeat(configs[-1:], REST_PAD, axis=0)])
        track = multibody_zmp(self.dyn, pad, CONTROL_PERIOD_S)
        com, zmp, v, a = track.com, track.zmp, track.v, track.a
        inner = slice(REST_PAD, -REST_PAD)
        self.last_motion = (configs, v[inner], a[inner])
        return com[inner], zmp[inner]

    def feedforward(self, p_gains: np.ndarray) -> np.ndarray:
        """Goal offsets (K, 20) [rad] that make the servo model drive the last planned motion
        (:func:`servo_feedforward`)."""
        configs, v, a = self.last_motion
        return servo_feedforward(self.spec, configs, v, a, self.timeline.contact, p_gains[0])

    def com(self, configs: np.ndarray) -> np.ndarray:
        pin, model, data = self.dyn.pin, self.dyn.model, self.dyn.data
        return np.array([pin.centerOfMass(model, data, c) for c in configs])


def servo_feedforward(spec: Spec, configs: np.ndarray, v: np.ndarray, a: np.ndarray, contact: tuple[SupportName, ...],
                      p_gains: np.ndarray) -> np.ndarray:
    """Goal offsets (K, 20) [rad] that make the servo model (:mod:`op2motion.model.servo`) at P gains (20,) drive a
    planned motion (pinocchio configurations (K, nq), velocities and accelerations (K, nv), each row on its planned
    ``contact``): the joint torque it needs (inverse dynamics with the plan's contacts) plus the servo's own losses
    and rotor inertia (damping x speed, armature x acceleration, friction), over Kp; smoothed over
    :data:`SMOOTH_ROWS` rows and clipped to the servo's linear range (its largest torque over Kp: 11° at P = 32; the
    PWM saturates beyond)."""
    dyn = dynamics_for(spec)
    torques = contact_torques(dyn, configs, v, a, contact)
    servo = ServoModel.of(spec, p_gains)
    dq, ddq = v[:, dyn.v_index], a[:, dyn.v_index]
    torques += servo.damping * dq + servo.armature * ddq + servo.friction * np.tanh(dq / FRICTION_SMOOTH_RAD_S)
    linear = servo.torque_max / servo.kp
    sag: np.ndarray = np.clip(smoothed(torques / servo.kp, SMOOTH_ROWS), -linear, linear)
    return sag


def torso_rotations(feet: dict[str, np.ndarray], params: GaitParams) -> np.ndarray:
    """The torso's rotation (K, 3, 3) at each row of the soles (K, 4): the feet's mean heading, the preset's lean."""
    yaw = feet["left"][:, 3] + 0.5 * np.remainder(feet["right"][:, 3] - feet["left"][:, 3] + np.pi, 2 * np.pi) - (
        0.5 * np.pi)
    rotations: np.ndarray = rot_z(yaw) @ rot_y(math.radians(params.torso_pitch_deg))
    return rotations


def standing_height(params: GaitParams, spec: Spec) -> float:
    """Torso origin height [m] that puts the hip centres :attr:`~.GaitParams.hip_lower_m` below their height on
    straight legs, with the torso leaning :attr:`~.GaitParams.torso_pitch_deg`."""
    leg = leg_of(spec, "left")
    straight = leg.ankle_to_sole + leg.thigh + leg.calf
    hip = rot_y(math.radians(params.torso_pitch_deg)) @ leg.hip
    return straight - params.hip_lower_m - float(hip[2])


def generate_gait(params: GaitParams, spec: Spec, target: tuple[float, float, float] | None = None,
              on_progress: Callable[[float, float], Any] | None = None, footsteps: Footsteps | None = None) -> Gait:
    """Plan a walk (see the module docstring); ``target`` (x [m], y [m], yaw [rad]) walks there instead of
    ``params.steps`` steps, ``footsteps`` walks those (e.g. one step closing feet that stand apart);
    ``on_progress(done, total)`` gets the planning passes done."""
    footsteps = footsteps or place_footsteps(params, spec, target)
    timeline = build_timeline(params, footsteps)
    body = _Body(spec, timeline)
    feet = timeline.feet
    rot = torso_rotations(feet, params)
    k = len(timeline.times)
    pos = np.zeros((k, 3))
    pos[:, 2] = standing_height(params, spec)
    pos[:, :2] = 0.5 * (feet["left"][:, :2] + feet["right"][:, :2])
    arms = arm_rows(params, timeline, spec, rot, pos)
    goals = body.goals(arms, pos, rot)
    com = body.com(body.configs(goals, pos, rot))
    com_height = params.com_height_m or float(com[0, 2])
    gains = preview_gains(CONTROL_PERIOD_S, com_height, params.preview_s, params.zmp_weight, params.jerk_weight)
    cart = track_reference(gains, timeline.zmp_ref)
    target_com = cart.com.copy()
    states = cart_states(cart, timeline.zmp_ref)
    correction = np.zeros_like(timeline.zmp_ref)
    for p in range(params.zmp_passes + 1):
        for _ in range(COM_PASSES):
            pos[:, :2] += target_com - com[:, :2]
            goals = body.goals(arm_rows(params, timeline, spec, rot, pos), pos, rot)
            com = body.com(body.configs(goals, pos, rot))
        com, zmp = body.zmp(body.configs(goals, pos, rot))
        if on_progress is not None:
            on_progress(p + 1, params.zmp_passes + 1)
        if p < params.zmp_passes:
            fix_ref = timeline.zmp_ref - zmp
            fix = track_reference(gains, fix_ref, start=np.zeros(2))
            target_com = target_com + fix.com
            states += cart_states(fix, fix_ref)
            correction += fix_ref
    margin = zmp_margins(zmp, timeline.contact, timeline.feet, spec)
    p_gains = np.full_like(goals, float(params.p_gain))
    servo_goals = goals + body.feedforward(p_gains) if params.servo_feedforward else goals
    return Gait(params, footsteps, timeline, com_height, pos, rot, goals, servo_goals, p_gains, com, cart.com, zmp,
                margin, states, correction)


def cart_states(track: CartTrack, ref: np.ndarray) -> np.ndarray:
    """The preview controller's state before each row (K, 4, 2): the cart's position [m], velocity [m/s] and
    acceleration [m/s²], and the ZMP error summed over the rows before (the integral action's) [m], of a run from
    rest along ``ref`` (K, 2) [m] (the controller is linear: the states of runs whose references add up add up)."""
    summed = np.vstack([np.zeros((1, 2)), np.cumsum(track.zmp - ref, axis=0)[:-1]])
    return np.stack([track.com, track.vel, track.acc, summed], axis=1)
