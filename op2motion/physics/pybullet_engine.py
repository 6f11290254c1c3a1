"""PyBullet as a physics engine for the run loop (:mod:`.run`): the generated URDF on a floor, torque-controlled.

PyBullet traps handled here: ``loadURDF`` needs a file path (a temporary file, removed after loading); the URDF's
inertias are used only with ``URDF_USE_INERTIA_FROM_FILE`` (else they are recomputed from the collision shapes); a
link without ``<inertial>`` would weigh 1 kg (every generated link has one); the base position PyBullet reports
and expects is the base's centre of mass, not its link frame; the default velocity motors hold every joint unless
switched off; a C-level banner on stdout would spoil JSON output.

Servo losses: PyBullet integrates applied torques explicitly, so the servo's damping (0.44 N·m·s/rad on a foot of
4e-5 kg·m² would diverge at 1 kHz) and Coulomb friction act through each joint's velocity motor, which PyBullet
solves as a constraint: target velocity 0, force limit ``damping * |dq| + friction``. PyBullet has no rotor
inertia (armature); :mod:`.mujoco_engine` models it, and the two engines' verdicts are compared.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import sys
import tempfile
from typing import Any, Iterator

import numpy as np

from op2motion.kinematics.frames import quat_xyzw
from op2motion.model.servo import ServoModel
from op2motion.model.urdf import URDF_ROOT, build_urdf
from op2motion.physics.ball import Ball
from op2motion.physics.scene import FLOOR_FRICTION, Contact
from op2motion.robot.spec import GRAVITY_M_S2, Spec

SOLVER_ITERATIONS = 20   # PyBullet's default 50 gives the same verdicts and margins (within 0.4 mm), 25 % slower


@contextlib.contextmanager
def quiet_c_output() -> Iterator[None]:
    """Silence C-level writes to stdout and stderr (PyBullet prints a banner on import and on connect)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            os.dup2(devnull.fileno(), 2)
        yield
    finally:
        ctypes.CDLL(None).fflush(None)  # flush C stdio buffers into /dev/null before restoring the descriptors
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)


def load_robot(client: Any, urdf_text: str, flags: int) -> int:
    """``loadURDF`` from text: PyBullet only loads files, so write a temporary one and remove it after."""
    fd, path = tempfile.mkstemp(prefix="op2motion-", suffix=".urdf")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(urdf_text)
        body_id: int = client.loadURDF(path, basePosition=(0.0, 0.0, 1.0), flags=flags)
        return body_id
    finally:
        os.unlink(path)


class _Bound:
    """PyBullet's functions bound to one client once each (``bullet_client`` binds them anew on every call, which
    cost a tenth of a walk check)."""

    def __init__(self, pb: Any, client_id: int):
        self._pb, self._id = pb, client_id

    def __getattr__(self, name: str) -> Any:
        fn = functools.partial(getattr(self._pb, name), physicsClientId=self._id)
        setattr(self, name, fn)
        return fn


class PyBulletEngine:
    """One DIRECT-mode PyBullet world with the floor and the robot."""

    name = "pybullet"

    def __init__(self, spec: Spec, servo: ServoModel, time_step: float, use_inertia_from_file: bool = True,
                 friction: float = FLOOR_FRICTION, ball: Ball | None = None):
        with quiet_c_output():
            import pybullet as pb
            from pybullet_utils import bullet_client

            self._bullet = bullet_client.BulletClient(connection_mode=pb.DIRECT)
        self.client = _Bound(pb, self._bullet._client)
        self.pb, self.spec, self.servo, self.time_step = pb, spec, servo, time_step
        c = self.client
        c.resetSimulation()
        c.setGravity(0.0, 0.0, -GRAVITY_M_S2)
        c.setTimeStep(time_step)
        c.setPhysicsEngineParameter(deterministicOverlappingPairs=1, numSolverIterations=SOLVER_ITERATIONS)
        self.plane = c.createMultiBody(0, c.createCollisionShape(pb.GEOM_PLANE))
        c.changeDynamics(self.plane, -1, lateralFriction=1.0)     # PyBullet multiplies the two frictions
        flags = pb.URDF_USE_SELF_COLLISION | pb.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT
        if use_inertia_from_file:
            flags |= pb.URDF_USE_INERTIA_FROM_FILE
        self.robot = load_robot(c, build_urdf(spec), flags)
        self.link_index = {URDF_ROOT: -1}
        self.joint_index: dict[str, int] = {}
        for i in range(c.getNumJoints(self.robot)):
            info = c.getJointInfo(self.robot, i)
            self.link_index[info[12].decode()] = i
            self.joint_index[info[1].decode()] = i
        self.link_name = {i: n for n, i in self.link_index.items()}
        for i in self.link_index.values():
            c.changeDynamics(self.robot, i, lateralFriction=friction)
        self.joints = [self.joint_index[n] for n in spec.joint_names]
        c.setJointMotorControlArray(self.robot, self.joints, pb.VELOCITY_CONTROL, forces=[0.0] * len(self.joints))
        info = c.getDynamicsInfo(self.robot, -1)
        self._inertial = (info[3], info[4])      # base CoM frame in the base link frame
        self._link_in_com = c.invertTransform(*self._inertial)
        self.torso = self.link_index[spec.root_link]
        self._dq = np.zeros(len(self.joints))
        self._zero = [0.0] * len(self.joints)
        self.ball_spec, self.ball = ball, None
        if ball is not None:
            sphere = c.createCollisionShape(pb.GEOM_SPHERE, radius=ball.radius_m)
            self.ball = c.createMultiBody(ball.mass_kg, sphere, -1, ball.centre.tolist())
            c.changeDynamics(self.ball, -1, lateralFriction=friction, localInertiaDiagonal=[ball.inertia_kg_m2] * 3)

    def close(self) -> None:
        """Disconnect."""
        self._bullet.disconnect()

    def masses(self) -> dict[str, float]:
        """Mass [kg] PyBullet assigned to each link."""
        return {name: self.client.getDynamicsInfo(self.robot, i)[0] for name, i in self.link_index.items()}

    def reset(self, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> None:
        """Teleport: torso link frame at (``base_pos``, ``base_rot``), joints at ``q`` [rad], all at rest."""
        c = self.client
        for j, angle in zip(self.joints, q):
            c.resetJointState(self.robot, j, float(angle), 0.0)
        orn = quat_xyzw(base_rot)
        com = c.multiplyTransforms(tuple(base_pos), orn, *self._inertial)
        c.resetBasePositionAndOrientation(self.robot, com[0], com[1])
        c.resetBaseVelocity(self.robot, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        if self.ball is not None and self.ball_spec is not None:
            c.resetBasePositionAndOrientation(self.ball, self.ball_spec.centre.tolist(), (0.0, 0.0, 0.0, 1.0))
            c.resetBaseVelocity(self.ball, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        self._dq[:] = 0.0

    def set_gravity(self, scale: float) -> None:
        """Gravity at ``scale`` of its full strength."""
        self.client.setGravity(0.0, 0.0, -GRAVITY_M_S2 * scale)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles and velocities (20,) [rad, rad/s]."""
        states = self.client.getJointStates(self.robot, self.joints)
        self._dq = np.array([s[1] for s in states])
        return np.array([s[0] for s in states]), self._dq

    def step(self, torque: np.ndarray, push: np.ndarray | None = None) -> None:
        """One time step with the servos' active ``torque`` (20,) [N·m] and an optional ``push`` (3,) [N] at the
        torso's centre of mass."""
        c, pb = self.client, self.pb
        losses = (self.servo.damping * np.abs(self._dq) + self.servo.friction).tolist()
        c.setJointMotorControlArray(self.robot, self.joints, pb.VELOCITY_CONTROL, targetVelocities=self._zero,
                                    forces=losses)
        c.setJointMotorControlArray(self.robot, self.joints, pb.TORQUE_CONTROL, forces=torque.tolist())
        if push is not None:
            com = c.getLinkState(self.robot, self.torso)[0]                # the torso's centre of mass
            c.applyExternalForce(self.robot, self.torso, push.tolist(), com, pb.WORLD_FRAME)
        c.stepSimulation()

    def base(self) -> tuple[np.ndarray, np.ndarray]:
        """Torso link frame (= the URDF root's): position [m] and rotation (3, 3)."""
        c = self.client
        pos, orn = c.multiplyTransforms(*c.getBasePositionAndOrientation(self.robot), *self._link_in_com)
        return np.asarray(pos), np.asarray(c.getMatrixFromQuaternion(orn)).reshape(3, 3)

    def base_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Velocity of the torso link frame's origin: linear [m/s] and angular [rad/s], world frame (PyBullet
        reports the base's centre of mass: v_origin = v_com + w x (p_origin - p_com))."""
        c = self.client
        (vx, vy, vz), (wx, wy, wz) = c.getBaseVelocity(self.robot)
        com, orn = c.getBasePositionAndOrientation(self.robot)
        origin = c.multiplyTransforms(com, orn, *self._link_in_com)[0]
        rx, ry, rz = (o - p for o, p in zip(origin, com))
        return (np.array([vx + wy * rz - wz * ry, vy + wz * rx - wx * rz, vz + wx * ry - wy * rx]),
                np.array([wx, wy, wz]))

    def ball_state(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The ball's centre (3,) [m] and velocity (3,) [m/s], world frame (None: no ball)."""
        if self.ball is None:
            return None
        c = self.client
        return np.array(c.getBasePositionAndOrientation(self.ball)[0]), np.array(c.getBaseVelocity(self.ball)[0])

    def contacts(self) -> list[Contact]:
        """Contacts of the robot with the floor (``other`` None) and with itself (the ball's are not the robot's)."""
        points = self.client.getContactPoints(self.robot)
        if self.ball is not None:
            points = [cp for cp in points if cp[2] != self.ball]
        if not points:
            return []
        # all contacts at once: (normal force, friction 1, friction 2) and their directions (the normal on B,
        # pointing towards A); per contact, seven small arrays cost more than the arithmetic
        size = np.array([(cp[9], cp[10], cp[12]) for cp in points])
        normal, lateral1, lateral2 = (np.array([cp[i] for cp in points]) for i in (7, 11, 13))
        force = size[:, :1] * normal + size[:, 1:2] * lateral1 + size[:, 2:] * lateral2
        where = np.array([cp[5] for cp in points])
        return [Contact(self.link_name[cp[3]], None if cp[2] == self.plane else self.link_name[cp[4]], float(cp[9]),
                        force[i], where[i]) for i, cp in enumerate(points)]

    def snapshot(self, width: int = 640, height: int = 480) -> bytes:
        """PNG bytes of the scene from the front left (TinyRenderer: works headless)."""
        return render_png(self.client, self.pb, self.base()[0], width, height)


def render_png(client: Any, pb: Any, centre: np.ndarray, width: int, height: int) -> bytes:
    """A TinyRenderer picture of a PyBullet scene looking at ``centre`` [m] from the front left."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg

    view = client.computeViewMatrix(cameraEyePosition=(centre[0] + 0.55, centre[1] + 0.45, 0.35),
                                    cameraTargetPosition=(centre[0], centre[1], 0.18), cameraUpVector=(0, 0, 1))
    proj = client.computeProjectionMatrixFOV(fov=50, aspect=width / height, nearVal=0.05, farVal=5.0)
    img = client.getCameraImage(width, height, view, proj, renderer=pb.ER_TINY_RENDERER)
    rgb = np.reshape(np.asarray(img[2], dtype=np.uint8), (height, width, 4))[:, :, :3]
    buf = io.BytesIO()
    mpimg.imsave(buf, rgb, format="png")
    return buf.getvalue()
