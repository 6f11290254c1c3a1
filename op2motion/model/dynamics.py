"""Rigid-body dynamics of the generated URDF with pinocchio: placements, full-inertia CoM, Jacobians, and the
static joint torques that hold a pose on its support foot (or feet), compared with the MX-28 stall torque.

The model has a free-flyer root (the torso floats), so one model serves either support foot: results are
expressed in the support sole frame, the same world frame as the kinematic models (X forward, Y left, Z up).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from op2motion.errors import InputError
from op2motion.model.urdf import build_urdf, frame_link, frame_points, sole_link
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Support, SupportName


@dataclass(frozen=True)
class TorqueReport:
    """Static joint torques [N·m] (ID order) holding a pose, and the worst joint against the stall torque."""

    torques: np.ndarray
    worst_joint: str
    worst_torque_nm: float
    stall_torque_nm: float

    @property
    def worst_ratio(self) -> float:
        """|worst torque| / stall torque."""
        return abs(self.worst_torque_nm) / self.stall_torque_nm


class Dynamics:
    """A pinocchio model of the robot built from the generated URDF string."""

    def __init__(self, spec: Spec):
        import pinocchio as pin

        self.pin, self.spec = pin, spec
        self.model = pin.buildModelFromXML(build_urdf(spec), pin.JointModelFreeFlyer())
        self.data = self.model.createData()
        self._neutral = pin.neutral(self.model)          # copied by every configuration (a physics run: thousands)
        self.q_index = np.array([self.model.joints[self.model.getJointId(n)].idx_q for n in spec.joint_names])
        self.v_index = np.array([self.model.joints[self.model.getJointId(n)].idx_v for n in spec.joint_names])
        self.joint_ids = [self.model.getJointId(n) for n in spec.joint_names]
        self.sole_ids = {side: self.model.getFrameId(sole_link(side)) for side in SIDES}

    @property
    def total_mass(self) -> float:
        """Total mass of the model [kg]."""
        return float(sum(inertia.mass for inertia in self.model.inertias))

    def configuration(self, servo: np.ndarray) -> np.ndarray:
        """Pinocchio configuration: free flyer at identity, joints from servo angles (20,) [rad] in ID order."""
        servo = np.asarray(servo, dtype=float).reshape(-1)
        if servo.size != len(self.spec.joints) or not np.isfinite(servo).all():
            raise InputError(f"expected {len(self.spec.joints)} finite values, got {servo.size}", "servo angles")
        q: np.ndarray = self._neutral.copy()
        q[self.q_index] = servo
        return q

    def level_configuration(self, servo: np.ndarray, support: Support | SupportName) -> np.ndarray:
        """Configuration whose free flyer puts the support sole at the world origin, level: gravity (world -Z)
        then acts as it does on the robot standing on that foot."""
        q = self.configuration(servo)
        q[:7] = self.pin.SE3ToXYZQUAT(self._sole_frame(q, support).inverse())
        return q

    def _sole_frame(self, q: np.ndarray, support: Support | SupportName) -> Any:
        self.pin.framesForwardKinematics(self.model, self.data, q)
        return self.data.oMf[self.sole_ids[Support.of(support).stance]]

    def joint_centres(self, servo: np.ndarray, support: Support | SupportName) -> dict[str, np.ndarray]:
        """Joint origins and named frames [m] in the support sole frame."""
        q = self.configuration(servo)
        inv = self._sole_frame(q, support).inverse()
        out = {n: (inv * self.data.oMi[i]).translation.copy() for n, i in zip(self.spec.joint_names, self.joint_ids)}
        for name, (link, _, _) in frame_points(self.spec).items():
            out[name] = (inv * self.data.oMf[self.model.getFrameId(link)]).translation.copy()
        return out

    def frame_jacobian(self, servo: np.ndarray, frame: str, support: Support | SupportName) -> np.ndarray:
        """Jacobian (6, 20) of a named frame (e.g. ``left_hand``) w.r.t. the servo angles, with the support sole
        fixed and level: rows are linear [m/rad] then angular [rad/rad] velocity in the support sole frame."""
        pin = self.pin
        q = self.level_configuration(servo, support)
        pin.computeJointJacobians(self.model, self.data, q)
        pin.framesForwardKinematics(self.model, self.data, q)
        fid = self.model.getFrameId(frame_link(self.spec, frame))
        if fid >= len(self.model.frames):
            raise InputError(f"unknown frame {frame!r}", "frame")
        world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        jac = pin.getFrameJacobian(self.model, self.data, fid, world)
        sole = pin.getFrameJacobian(self.model, self.data, self.sole_ids[Support.of(support).stance], world)
        # Hold the sole still: the free-flyer velocity is whatever cancels the sole's motion (J_sole v = 0).
        base = -np.linalg.solve(sole[:, :6], sole[:, 6:])
        joints: np.ndarray = (jac[:, 6:] + jac[:, :6] @ base)[:, self.v_index - 6]
        return joints

    def com(self, servo: np.ndarray, support: Support | SupportName) -> np.ndarray:
        """Full-inertia centre of mass [m] in the support sole frame."""
        q = self.configuration(servo)
        c = self.pin.centerOfMass(self.model, self.data, q)
        com: np.ndarray = self._sole_frame(q, support).inverse().act(c)
        return com

    def static_torques(self, servo: np.ndarray, support: Support | SupportName) -> TorqueReport:
        """Joint torques [N·m] that hold the pose still on ``support`` ("left", "right" or "double").

        Generalised gravity from RNEA at rest, balanced by a contact wrench at the support sole(s): the torso's six
        free-flyer rows fix the wrench (least norm over both soles for double support), the joint rows give the
        torques the servos must supply.
        """
        pin = self.pin
        q = self.level_configuration(servo, support)
        zero = np.zeros(self.model.nv)
        gravity = pin.rnea(self.model, self.data, q, zero, zero)
        pin.computeJointJacobians(self.model, self.data, q)
        pin.framesForwardKinematics(self.model, self.data, q)
        jac = np.vstack([pin.getFrameJacobian(self.model, self.data, self.sole_ids[s], pin.ReferenceFrame.LOCAL)
                         for s in Support.of(support).feet])
        wrench = np.linalg.lstsq(jac[:, :6].T, gravity[:6], rcond=None)[0]
        torques = (gravity - jac.T @ wrench)[self.v_index]
        worst = int(np.argmax(np.abs(torques)))
        return TorqueReport(torques, self.spec.joint_names[worst], float(torques[worst]),
                            self.spec.servo.stall_torque_nm)

    def com_loop(self, servo_batch: np.ndarray) -> np.ndarray:
        """pinocchio ``centerOfMass`` called once per configuration (the baseline of ``op2motion bench``)."""
        out = np.empty((len(servo_batch), 3))
        q = self.pin.neutral(self.model)
        for k, servo in enumerate(servo_batch):
            q[self.q_index] = servo
            out[k] = self.pin.centerOfMass(self.model, self.data, q)
        return out


_CACHE: dict[str, Dynamics] = {}


def dynamics_for(spec: Spec) -> Dynamics:
    """A :class:`Dynamics` for ``spec``, built once per spec file content."""
    if spec.sha256 not in _CACHE:
        _CACHE[spec.sha256] = Dynamics(spec)
    return _CACHE[spec.sha256]
