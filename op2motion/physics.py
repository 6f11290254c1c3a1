"""PyBullet validation: does a pose stand on the real robot's masses, servos and feet?

A fresh DIRECT-mode simulation per call (so the same input gives the same verdict): a ground plane, the
generated URDF loaded with its own inertias (``URDF_USE_INERTIA_FROM_FILE``; otherwise PyBullet recomputes them
from the collision shapes) and self-collision between non-adjacent links; the pose set with the support sole(s)
flat on the ground and the robot placed so it touches without penetrating; every joint held by a position
controller limited to the MX-28's stall torque and speed; a few seconds simulated.

PyBullet traps handled here: ``loadURDF`` needs a file path (the URDF text goes to a temporary file that is
removed afterwards); a link without ``<inertial>`` would weigh 1 kg (the URDF gives every link one); and the base
position PyBullet reports and expects is that of the base's centre of mass, not of its link frame.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import sys
import tempfile
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Iterator

import numpy as np

from .errors import InputError
from .model.urdf import build_urdf, foot_link, sole_link
from .pose import check_pose_support
from .spec import SUPPORTS, Spec, feet_of

GRAVITY_M_S2 = 9.81
TIME_STEP_S = 1.0 / 240.0
GROUND_FRICTION = 1.0
PLACEMENT_CLEARANCE_M = 1e-4    # the lowest sole starts this far above the ground
POSITION_GAIN = 0.05            # PyBullet motor gains (dimensionless constraint gains). Soft enough that the two
VELOCITY_GAIN = 1.0             # feet of a double-support pose do not fight through the ground with the full
                                # stall torque (steady torques stay near pinocchio's static estimate), as the real
                                # servos' compliance and backlash allow; stiff enough to hold every stock pose.
TILT_LIMIT_DEG = 20.0           # torso tilt beyond this (from its initial attitude) is a fall
COM_DROP_LIMIT = 0.25           # losing this fraction of the CoM height is a fall
SLIP_LIMIT_M = 0.02             # a support foot sliding this far is not standing
TORQUE_MARGIN = 0.98            # steady torque above this fraction of stall means the servo is saturated
STEADY_WINDOW_S = 0.5           # torques are averaged over the last half second


@dataclass(frozen=True)
class Validation:
    """Verdict and measurements of one physics run."""

    stable: bool
    max_tilt_deg: float
    com_drift_m: float
    feet_slip_m: float
    self_collisions: list = field(default_factory=list)
    max_torque_nm: float = 0.0
    torque_ok: bool = True
    peak_torque_nm: float = 0.0
    worst_joint: str = ""
    ground_contacts: list = field(default_factory=list)
    reason: str = ""
    seconds: float = 0.0
    snapshot_png: bytes | None = field(default=None, repr=False, compare=False)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        out = asdict(self)
        del out["snapshot_png"]
        return out


@contextlib.contextmanager
def quiet_c_output() -> Iterator[None]:
    """Silence C-level writes to stdout and stderr (PyBullet prints a banner on import and on connect), so that
    JSON output stays clean and errors stay one line."""
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
        return client.loadURDF(path, basePosition=(0.0, 0.0, 1.0), flags=flags)
    finally:
        os.unlink(path)


class Sim:
    """One DIRECT-mode PyBullet world with the ground and the robot; use as a context manager."""

    def __init__(self, spec: Spec, use_inertia_from_file: bool = True):
        with quiet_c_output():  # PyBullet prints a banner on import and on connect
            import pybullet as pb
            from pybullet_utils import bullet_client

            self.client = bullet_client.BulletClient(connection_mode=pb.DIRECT)
        self.pb, self.spec = pb, spec
        c = self.client
        c.resetSimulation()
        c.setGravity(0.0, 0.0, -GRAVITY_M_S2)
        c.setTimeStep(TIME_STEP_S)
        c.setPhysicsEngineParameter(deterministicOverlappingPairs=1)
        self.plane = c.createMultiBody(0, c.createCollisionShape(pb.GEOM_PLANE))
        c.changeDynamics(self.plane, -1, lateralFriction=GROUND_FRICTION)
        flags = pb.URDF_USE_SELF_COLLISION | pb.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT
        if use_inertia_from_file:
            flags |= pb.URDF_USE_INERTIA_FROM_FILE
        self.robot = load_robot(c, build_urdf(spec), flags)
        self.link_index = {spec.root_link: -1}
        self.joint_index: dict[str, int] = {}
        for i in range(c.getNumJoints(self.robot)):
            info = c.getJointInfo(self.robot, i)
            self.link_index[info[12].decode()] = i
            self.joint_index[info[1].decode()] = i
        self.link_name = {i: n for n, i in self.link_index.items()}
        self.foot_links = tuple(foot_link(spec, side) for side in SUPPORTS)
        for foot in self.foot_links:
            c.changeDynamics(self.robot, self.link_index[foot], lateralFriction=GROUND_FRICTION)
        self.servo_joints = [self.joint_index[n] for n in spec.joint_names]

    def __enter__(self) -> "Sim":
        return self

    def __exit__(self, *exc: object) -> None:
        self.client.disconnect()

    def masses(self) -> dict[str, float]:
        """Mass [kg] PyBullet assigned to each link."""
        return {name: self.client.getDynamicsInfo(self.robot, i)[0] for name, i in self.link_index.items()}

    def set_joints(self, servo: np.ndarray) -> None:
        """Teleport the joints to servo angles (20,) [rad]."""
        for j, q in zip(self.servo_joints, servo):
            self.client.resetJointState(self.robot, j, float(q), 0.0)

    def link_frame(self, name: str) -> tuple[tuple, tuple]:
        """World pose of a link's URDF frame (not its centre of mass)."""
        c, i = self.client, self.link_index[name]
        if i == -1:
            return self.base_link_frame()
        state = c.getLinkState(self.robot, i, computeForwardKinematics=True)
        return state[4], state[5]

    def base_link_frame(self) -> tuple[tuple, tuple]:
        """World pose of the base's URDF frame: PyBullet reports the base's CoM frame, so undo the inertial offset."""
        c = self.client
        com_pos, com_orn = c.getBasePositionAndOrientation(self.robot)
        info = c.getDynamicsInfo(self.robot, -1)
        inv = c.invertTransform(info[3], info[4])
        return c.multiplyTransforms(com_pos, com_orn, inv[0], inv[1])

    def set_base_link_frame(self, pos: tuple, orn: tuple) -> None:
        """Put the base's URDF frame at (pos, orn): PyBullet wants the CoM frame, so apply the inertial offset."""
        c = self.client
        info = c.getDynamicsInfo(self.robot, -1)
        com = c.multiplyTransforms(pos, orn, info[3], info[4])
        c.resetBasePositionAndOrientation(self.robot, com[0], com[1])

    def place(self, support: str) -> None:
        """Support sole(s) flat on the ground (first sole at the origin), lowest sole just touching."""
        c = self.client
        soles = [sole_link(side) for side in feet_of(support)]
        first = soles[0]
        base = self.base_link_frame()
        sole = self.link_frame(first)
        inv_base = c.invertTransform(*base)
        sole_in_base = c.multiplyTransforms(inv_base[0], inv_base[1], sole[0], sole[1])
        self.set_base_link_frame(*c.invertTransform(*sole_in_base))
        lowest = min(self.link_frame(s)[0][2] for s in soles)
        pos, orn = self.base_link_frame()
        self.set_base_link_frame((pos[0], pos[1], pos[2] - lowest + PLACEMENT_CLEARANCE_M), orn)

    def hold(self, servo: np.ndarray) -> None:
        """Position control of every joint to ``servo`` with the MX-28 torque and speed limits."""
        s = self.spec.servo
        for j, q in zip(self.servo_joints, servo):
            self.client.setJointMotorControl2(self.robot, j, self.pb.POSITION_CONTROL, targetPosition=float(q),
                                              force=s.stall_torque_nm, maxVelocity=s.no_load_speed_rad_s,
                                              positionGain=POSITION_GAIN, velocityGain=VELOCITY_GAIN)

    def com(self) -> np.ndarray:
        """Whole-body centre of mass [m] from PyBullet's link masses and CoM positions."""
        c = self.client
        total, acc = 0.0, np.zeros(3)
        for name, i in self.link_index.items():
            mass = c.getDynamicsInfo(self.robot, i)[0]
            pos = c.getBasePositionAndOrientation(self.robot)[0] if i == -1 else c.getLinkState(self.robot, i)[0]
            acc += mass * np.asarray(pos)
            total += mass
        return acc / total

    def self_collision_pairs(self) -> set[tuple[str, str]]:
        """Link pairs of the robot in contact with each other (adjacent links are excluded by the load flags)."""
        pairs = set()
        for cp in self.client.getContactPoints(self.robot, self.robot):
            a, b = sorted((self.link_name[cp[3]], self.link_name[cp[4]]))
            if a != b:
                pairs.add((a, b))
        return pairs

    def ground_links(self) -> set[str]:
        """Links touching the ground plane."""
        return {self.link_name[cp[3]] for cp in self.client.getContactPoints(self.robot, self.plane)}

    def torques(self) -> np.ndarray:
        """Torques the motors applied in the last step [N·m], ID order."""
        return np.array([st[3] for st in self.client.getJointStates(self.robot, self.servo_joints)])

    def snapshot(self, width: int = 640, height: int = 480) -> bytes:
        """PNG bytes of the scene from the front left (TinyRenderer: works headless)."""
        import io

        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg

        c, pb = self.client, self.pb
        target = self.com()
        view = c.computeViewMatrix(cameraEyePosition=(target[0] + 0.55, target[1] + 0.45, 0.35),
                                   cameraTargetPosition=(target[0], target[1], 0.18), cameraUpVector=(0, 0, 1))
        proj = c.computeProjectionMatrixFOV(fov=50, aspect=width / height, nearVal=0.05, farVal=5.0)
        img = c.getCameraImage(width, height, view, proj, renderer=pb.ER_TINY_RENDERER)
        rgb = np.reshape(np.asarray(img[2], dtype=np.uint8), (height, width, 4))[:, :, :3]
        buf = io.BytesIO()
        mpimg.imsave(buf, rgb, format="png")
        return buf.getvalue()


def _tilt_deg(q0: tuple, q1: tuple, client: Any) -> float:
    """Angle [deg] between two orientations' z axes (how far the torso tipped)."""
    z0 = np.asarray(client.getMatrixFromQuaternion(q0)).reshape(3, 3)[:, 2]
    z1 = np.asarray(client.getMatrixFromQuaternion(q1)).reshape(3, 3)[:, 2]
    return math.degrees(math.acos(float(np.clip(np.dot(z0, z1), -1.0, 1.0))))


MIN_SECONDS, MAX_SECONDS = 0.1, 60.0
DEFAULT_SECONDS = 3.0


def steps_for(seconds: float) -> int:
    """Simulation steps in ``seconds`` (0.1 to 60 s, else :class:`InputError`)."""
    if not (math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
        raise InputError(f"expected {MIN_SECONDS:g} to {MAX_SECONDS:g} s, got {seconds!r}", "seconds")
    return int(round(seconds / TIME_STEP_S))


def validate_servo(servo: np.ndarray, support: str, spec: Spec, seconds: float = DEFAULT_SECONDS,
                   snapshot: bool = False, on_step: Callable[[], Any] | None = None) -> Validation:
    """Simulate a pose held by the servos for ``seconds`` and judge whether it stands (see module docstring)."""
    check_pose_support(support)
    steps = steps_for(seconds)
    servo = np.asarray(servo, dtype=float)
    with Sim(spec) as sim:
        c = sim.client
        sim.set_joints(servo)
        sim.place(support)
        sim.hold(servo)
        sole_names = [sole_link(side) for side in feet_of(support)]
        start_soles = {s: np.asarray(sim.link_frame(s)[0]) for s in sole_names}
        start_orn = sim.base_link_frame()[1]
        com0 = sim.com()
        window = max(1, int(round(STEADY_WINDOW_S / TIME_STEP_S)))
        tilt = drift = slip = peak = 0.0
        collisions: set[tuple[str, str]] = set()
        grounded: set[str] = set()
        torque_sum = np.zeros(len(servo))
        reason = ""
        for k in range(steps):
            c.stepSimulation()
            if k % 4 == 3 or k == steps - 1:  # sample at 60 Hz
                tilt = max(tilt, _tilt_deg(start_orn, sim.base_link_frame()[1], c))
                com = sim.com()
                drift = max(drift, float(np.hypot(*(com - com0)[:2])))
                slip = max(slip, max(float(np.hypot(*(np.asarray(sim.link_frame(s)[0]) - p)[:2]))
                                     for s, p in start_soles.items()))
                collisions |= sim.self_collision_pairs()
                grounded |= sim.ground_links() - set(sim.foot_links)
            tau = sim.torques()
            peak = max(peak, float(np.max(np.abs(tau))))
            if k >= steps - window:
                torque_sum += np.abs(tau)
            if on_step is not None:
                on_step()
        steady = torque_sum / min(window, steps)
        worst = int(np.argmax(steady))
        com_end = sim.com()
        dropped = com_end[2] < (1.0 - COM_DROP_LIMIT) * com0[2]
        if tilt > TILT_LIMIT_DEG:
            reason = f"torso tipped {tilt:.0f}°"
        elif grounded:
            reason = f"{', '.join(sorted(grounded))} touched the ground"
        elif dropped:
            reason = f"centre of mass fell from {com0[2]:.3f} m to {com_end[2]:.3f} m"
        elif slip > SLIP_LIMIT_M:
            reason = f"support foot slid {slip * 1000:.0f} mm"
        png = sim.snapshot() if snapshot else None
        max_torque = float(steady[worst])
        return Validation(stable=not reason, max_tilt_deg=round(tilt, 3), com_drift_m=round(drift, 5),
                          feet_slip_m=round(slip, 5), self_collisions=sorted(list(p) for p in collisions),
                          max_torque_nm=round(max_torque, 4),
                          torque_ok=max_torque < TORQUE_MARGIN * spec.servo.stall_torque_nm,
                          peak_torque_nm=round(peak, 4), worst_joint=spec.joint_names[worst],
                          ground_contacts=sorted(grounded), reason=reason or "stands", seconds=seconds,
                          snapshot_png=png)
