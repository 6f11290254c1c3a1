"""Checks along a trajectory before any physics: links apart, the ZMP over the feet, torques within the servos.

* **Self-clearance**: the spec's collision shapes on the D-H chain (:mod:`op2motion.kinematics.shapes`) at every
  row; :func:`require_clear` refuses a trajectory whose links overlap by more than :data:`OVERLAP_TOL_M` (the shapes'
  approximation error) and names the segment, the time and the two links.
* **Centre of mass and ZMP** with pinocchio on the generated URDF: the fixed foot (the one that stays down
  throughout) is laid level at the origin, velocities and accelerations are differences of the 8 ms rows, and the
  zero-moment point of the whole body is

      p = c_xy - c_z c''_xy / (g + c''_z) + (-L'_y, L'_x) / (m (g + c''_z))

  with L the centroidal angular momentum (pinocchio's ``computeCentroidalMomentum``); its margin to the support
  polygon of the row (the real sole box, or the hull of both soles) is reported.
* **Torques** from RNEA with those velocities and accelerations, the contact wrench on the supporting sole(s)
  taken out through the floating base's six rows (least norm over both soles in double support), against the
  MX-28's available torque at the joint speed (:mod:`op2motion.model.servo`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from op2motion.errors import CheckFailed
from op2motion.jsonout import JsonObject, json_object
from op2motion.kinematics import forward
from op2motion.kinematics.dh import MATRIX_BELOW, forward_dh_frames
from op2motion.kinematics.shapes import self_clearance, shape_set
from op2motion.model.dynamics import dynamics_for
from op2motion.model.servo import ServoModel
from op2motion.model.urdf import foot_box_corners, foot_link
from op2motion.motion.trajectory import Trajectory
from op2motion.robot.balance import polygon_margin
from op2motion.robot.joints import servo_to_book
from op2motion.robot.spec import GRAVITY_M_S2, Spec
from op2motion.robot.support import Side, Support, SupportName, fixed_foot

MAX_RATIO = 99.0          # a torque ratio is reported up to this (a goal faster than the no-load speed has none)
SMOOTH_ROWS = 5           # 40 ms: the goals' derivatives are taken after this moving average
OVERLAP_TOL_M = 0.003     # the shapes on the chain match the engines' to 2.8 mm: deeper overlaps are real


@dataclass(frozen=True)
class ChecksWorst:
    """The worst row of each check along a trajectory: the least clearance [m] between ``min_clearance_links``, the
    least ZMP margin [m] and the share of rows with the ZMP inside, the largest torque ratio and torque [N·m] at
    ``torque_joint``; the foot that stays on the floor (the checks' frame)."""

    min_clearance_m: float
    min_clearance_links: tuple[str, str]
    zmp_margin_min_m: float
    zmp_inside_fraction: float
    torque_ratio_max: float
    torque_max_nm: float
    torque_joint: str
    fixed_foot: str


@dataclass(frozen=True)
class MotionChecks:
    """Per row: least self-clearance [m] and its links, CoM (K, 3) and ZMP (K, 2) [m] in the fixed-foot frame,
    the ZMP's margin to the row's support polygon [m] (negative outside), and the worst joint's torque ratio
    (needed / available) with its torque [N·m]."""

    fixed_foot: Side
    clearance_m: np.ndarray
    clearance_links: tuple[tuple[str, str], ...]
    com: np.ndarray
    zmp: np.ndarray
    zmp_margin_m: np.ndarray
    polygons: tuple[np.ndarray, ...]
    torque_ratio: np.ndarray
    torque_nm: np.ndarray
    torque_joint: tuple[str, ...]

    def worst(self) -> ChecksWorst:
        """The worst of each check."""
        c, z, t = int(np.argmin(self.clearance_m)), int(np.argmin(self.zmp_margin_m)), int(np.argmax(self.torque_ratio))
        return ChecksWorst(float(self.clearance_m[c]), self.clearance_links[c], float(self.zmp_margin_m[z]),
                           float(np.mean(self.zmp_margin_m >= 0.0)), float(self.torque_ratio[t]),
                           float(self.torque_nm[t]), self.torque_joint[t], self.fixed_foot)

    def summary(self) -> JsonObject:
        """The worst of each check, for reports (:meth:`worst` as JSON)."""
        return json_object(self.worst())


def clearance(goals: np.ndarray, spec: Spec, side: Support | Side = "left") -> tuple[np.ndarray, list[tuple[str, str]]]:
    """Least clearance [m] (K,) between the spec's collision shapes for each row of goals (K, 20) [rad], and the
    links of the closest pair."""
    shapes = shape_set(spec, side)
    names = shapes.pair_names()
    values, links = [], []
    for start in range(0, len(goals), MATRIX_BELOW - 1):
        _, frames = forward_dh_frames(servo_to_book(goals[start:start + MATRIX_BELOW - 1], side, spec), spec)
        least, pair = self_clearance(frames, shapes)
        values.append(least)
        links += [names[p] for p in pair]
    return np.concatenate(values), links


def require_clear(trajectory: Trajectory, spec: Spec) -> None:
    """Refuse a trajectory whose links pass through each other, naming the segment, time and links."""
    least, links = clearance(trajectory.goals, spec)
    bad = np.flatnonzero(least < -OVERLAP_TOL_M)
    if bad.size:
        k = int(bad[0])
        deepest = int(bad[np.argmin(least[bad])])
        raise CheckFailed(f"segment {trajectory.segment_of(k)} passes {links[deepest][0]} through "
                          f"{links[deepest][1]} from {k * trajectory.dt:.2f} s (overlap {-least[deepest] * 1000:.0f} "
                          f"mm): add a pose in between that keeps them apart, or change the order of the moves")


def _polygon(dyn: Any, data: Any, support: Support, spec: Spec) -> np.ndarray:
    """The support polygon of the soles (foot boxes) of ``support`` in pinocchio's current frame placements."""
    corners = {}
    for side in support.feet:
        foot = data.oMf[dyn.model.getFrameId(foot_link(spec, side))]
        corners[side] = foot_box_corners(spec, side) @ foot.rotation.T + foot.translation
    return support.polygon(corners)


def smoothed(values: np.ndarray, width: int) -> np.ndarray:
    """A centred moving average over ``width`` rows (ends held), per column."""
    if len(values) < width or width < 2:
        return values
    pad = np.concatenate([np.repeat(values[:1], width // 2, axis=0), values,
                          np.repeat(values[-1:], width - 1 - width // 2, axis=0)])
    kernel = np.ones(width) / width
    return np.apply_along_axis(lambda c: np.convolve(c, kernel, mode="valid"), 0, pad)


@dataclass(frozen=True)
class ZmpTrack:
    """A motion's whole-body centre of mass ``com`` (K, 3) [m] and ZMP ``zmp`` (K, 2) [m] (world frame, floor at
    z = 0), and the velocities ``v`` and accelerations ``a`` (K, nv) of its configurations, taken by differences."""

    com: np.ndarray
    zmp: np.ndarray
    v: np.ndarray
    a: np.ndarray


def multibody_zmp(dyn: Any, configs: np.ndarray, dt: float) -> ZmpTrack:
    """The :class:`ZmpTrack` of pinocchio configurations (K, nq) one ``dt`` [s] apart: the ZMP from the CoM's
    acceleration and the rate of the centroidal angular momentum."""
    pin, model, data = dyn.pin, dyn.model, dyn.data
    k = len(configs)
    v = np.zeros((k, model.nv))
    if k > 1:
        steps = np.array([pin.difference(model, configs[i], configs[i + 1]) / dt for i in range(k - 1)])
        v[1:-1] = 0.5 * (steps[1:] + steps[:-1])
        v[0], v[-1] = steps[0], steps[-1]
    a = np.gradient(v, dt, axis=0) if k > 1 else np.zeros_like(v)
    com: np.ndarray = np.zeros((k, 3))
    momentum: np.ndarray = np.zeros((k, 3))
    for i in range(k):
        com[i] = pin.centerOfMass(model, data, configs[i])
        momentum[i] = np.asarray(pin.computeCentroidalMomentum(model, data, configs[i], v[i]).angular)
    ddc = np.gradient(np.gradient(com, dt, axis=0), dt, axis=0) if k > 2 else np.zeros_like(com)
    dl = np.gradient(momentum, dt, axis=0) if k > 2 else np.zeros_like(momentum)
    vertical = GRAVITY_M_S2 + ddc[:, 2]
    mass = dyn.total_mass
    zmp = com[:, :2] - com[:, 2:3] / vertical[:, None] * ddc[:, :2] + np.column_stack([-dl[:, 1], dl[:, 0]]) / (
        mass * vertical[:, None])
    return ZmpTrack(com, zmp, v, a)


def contact_torques(dyn: Any, configs: np.ndarray, v: np.ndarray, a: np.ndarray,
                    supports: tuple[Support | SupportName, ...]) -> np.ndarray:
    """Joint torques (K, 20) [N·m] about the spec's joint axes that move pinocchio configurations (K, nq) with
    velocities and accelerations (K, nv) while the soles of each row's support carry the robot: inverse dynamics
    (RNEA) less the contact wrenches, the smallest (least-squares) wrenches at the soles that balance the floating
    base."""
    pin, model, data = dyn.pin, dyn.model, dyn.data
    out = np.empty((len(configs), len(dyn.v_index)))
    for i, q in enumerate(configs):
        tau = pin.rnea(model, data, q, v[i], a[i])
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        jac = np.vstack([pin.getFrameJacobian(model, data, dyn.sole_ids[s], pin.ReferenceFrame.LOCAL)
                         for s in Support.of(supports[i]).feet])
        wrench = np.linalg.lstsq(jac[:, :6].T, tau[:6], rcond=None)[0]
        out[i] = (tau - jac.T @ wrench)[dyn.v_index]
    return out


def check_trajectory(trajectory: Trajectory, spec: Spec, servo: ServoModel | None = None,
                     foot: Side | None = None) -> MotionChecks:
    """All checks of the module docstring on every row of ``trajectory``. ``foot`` picks the frame of the report:
    that sole where it stood at the start, as the physics world has it (default: the fixed foot's). Velocities and
    accelerations are taken from the goals smoothed over :data:`SMOOTH_ROWS` rows: goals come in whole ticks
    (0.088°), and the servos follow them through their own lag, so raw second differences would be noise."""
    dyn = dynamics_for(spec)
    pin, model, data = dyn.pin, dyn.model, dyn.data
    servo = servo or ServoModel.of(spec)
    dt, goals = trajectory.dt, trajectory.goals
    side: Side = fixed_foot(trajectory.supports)
    smooth = smoothed(goals, SMOOTH_ROWS)
    configs = np.array([dyn.level_configuration(g, side) for g in smooth])
    k = len(goals)
    track = multibody_zmp(dyn, configs, dt)
    com, zmp, v, a = track.com, track.zmp, track.v, track.a
    polygons: list[np.ndarray] = []
    joint_speed = np.gradient(smooth, dt, axis=0) if k > 1 else np.zeros_like(goals)
    torques = contact_torques(dyn, configs, v, a, trajectory.supports)
    available = servo.available(joint_speed, torques)
    for i in range(k):
        pin.framesForwardKinematics(model, data, configs[i])
        polygons.append(_polygon(dyn, data, Support.of(trajectory.supports[i]), spec))
    share = np.minimum(np.abs(torques) / np.maximum(available, 1e-9), MAX_RATIO)
    worst = np.argmax(share, axis=1)
    ratio, torque = share[np.arange(k), worst], np.abs(torques)[np.arange(k), worst]
    joint = [spec.joint_names[w] for w in worst]
    if foot is not None and foot != side:     # report in the ``foot`` sole's frame (where it stood at the start)
        pin.framesForwardKinematics(model, data, configs[0])
        rel = data.oMf[dyn.sole_ids[foot]].inverse() * data.oMf[dyn.sole_ids[side]]
        yaw = np.arctan2(rel.rotation[1, 0], rel.rotation[0, 0])
        turn = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
        shift = rel.translation[:2]
        zmp = zmp @ turn.T + shift
        com[:, :2] = com[:, :2] @ turn.T + shift
        polygons = [p @ turn.T + shift for p in polygons]
        side = foot
    margin = np.array([polygon_margin(zmp[i], polygons[i])[0] for i in range(k)])
    least, links = clearance(goals, spec)
    return MotionChecks(side, least, tuple(links), com, zmp, margin, tuple(polygons), ratio, torque, tuple(joint))


def in_sole_frame(track: Sequence[Sequence[float]], start: np.ndarray, measured: Side, wanted: Side,
                  spec: Spec) -> list[tuple[float, float, float]]:
    """Rows (time [s], x [m], y [m]) measured in the ``measured`` sole's frame, in the ``wanted`` sole's frame
    instead, the two soles placed as the start pose ``start`` (20,) [rad] has them (D-H chain)."""
    if measured == wanted:
        return [tuple(row) for row in track]                  # type: ignore[misc]
    corners = forward(servo_to_book(np.atleast_2d(start), wanted, spec), spec, "dh").foot_corners(measured)[0]
    centre = corners[:, :2].mean(axis=0)
    forward_edge = (corners[0, :2] + corners[1, :2]) / 2 - (corners[2, :2] + corners[3, :2]) / 2
    yaw = float(np.arctan2(forward_edge[1], forward_edge[0]))
    turn = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    return [(float(t), *(turn @ np.array([x, y]) + centre)) for t, x, y in track]
