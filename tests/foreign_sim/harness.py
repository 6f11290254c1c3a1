"""A second, independent simulator for walk controllers: a MuJoCo loop written without any op2motion code.

What is independent here (written for this harness alone, sharing nothing with ``op2motion.physics``):

* the loop: a 1 kHz physics step (by default) and a control tick every :data:`CONTROL_PERIOD_S` of simulated time;
* the servo model (:class:`ServoModel`): a clipped torque-level PD with a DC motor's torque-speed line, applied as
  generalised forces (``qfrc_applied``) every physics step, with no reflected rotor inertia and no Coulomb
  friction. Its damping term is integrated implicitly: the same amount is given to MuJoCo as joint damping (which
  its Euler integrator treats implicitly) and added back to the applied force, so the torque is exactly the model's
  while the light links (a foot about its roll axis: 1e-4 kg·m²) stay stable at a 1 ms step;
* the IMU: the torso's angular velocity and specific force in the torso frame, the acceleration finite-differenced
  from the torso origin's world velocity over one tick, handed to the controller ``latency_ticks`` ticks late;
* the fall detection: the torso's z axis more than :data:`FALL_TILT_DEG` from vertical, or its origin lower than
  :data:`FALL_HEIGHT_M`;
* the floor: a MuJoCo plane with MuJoCo's default contact softness and the given sliding friction (also set on every
  robot geom, since MuJoCo combines two geoms' frictions by their maximum);
* the initial placement: the joints at the controller's first goals, the torso level (or, asked to start lying, turned
  a quarter turn face down, face up or onto a side: :data:`LYING_QUATERNIONS`), and the lowest point of any robot geom
  :data:`START_GAP_M` above the floor, everything at rest, gravity at full strength from the start.

What comes from outside: the URDF text (links, masses, inertias, joint axes and collision shapes) and the controller
(an object with ``start(positions)`` and ``step(t, gyro, accel, positions)`` returning ``{joint: goal [rad]}``).

Only the standard library, NumPy and MuJoCo are imported.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any, Mapping

import mujoco
import numpy as np

CONTROL_PERIOD_S = 0.008        # the controller is called this often [s] of simulated time
START_GAP_M = 0.0005            # the robot starts this far above the floor [m]
FALL_TILT_DEG = 50.0            # torso z axis further than this from vertical: fallen [deg]
FALL_HEIGHT_M = 0.15            # torso origin lower than this: fallen [m]
TORSO_LINK = "body_link"        # the torso link of the URDF (may be fused into its fixed parent on import)
FLOOR_NAME = "foreign_floor"
TORSIONAL_FRICTION = 0.005      # MuJoCo's default torsional and rolling friction coefficients
ROLLING_FRICTION = 0.0001
DEFAULT_STALL_NM = 2.5          # a 12 V MX-28 class servo: stall torque [N·m] ...
DEFAULT_NO_LOAD_RAD_S = 5.76    # ... and no-load speed [rad/s]
_HALF = math.sqrt(0.5)
#: The torso's orientation (w, x, y, z) for a start lying: face down (front: a quarter turn about y, the torso's front
#: to the floor), face up (back), on the left side (a quarter turn about -x) or the right one.
LYING_QUATERNIONS = {"front": (_HALF, 0.0, _HALF, 0.0), "back": (_HALF, 0.0, -_HALF, 0.0),
                     "left": (_HALF, -_HALF, 0.0, 0.0), "right": (_HALF, _HALF, 0.0, 0.0)}


@dataclass(frozen=True)
class ServoModel:
    """A position servo as a DC motor: ``tau = clip(kp (goal - q) - damping dq, ±tau_max(dq))`` where the limit is
    ``stall * max(0, 1 - |dq| / no_load)`` while the torque drives the motion and ``stall`` while it brakes it.

    The default damping is the slope of that same torque-speed line, ``stall / no_load`` (0.434 N·m·s/rad): a DC
    motor's back-EMF brakes it at every PWM duty, not only at full duty. A smaller value (say 0.1) leaves the servos
    of a light robot under-damped.

    Attributes:
        kp_nm_rad: Proportional stiffness [N·m/rad].
        stall_nm: Stall torque [N·m].
        no_load_rad_s: No-load speed [rad/s].
        damping_nm_s: Viscous damping [N·m·s/rad].
    """

    kp_nm_rad: float = 12.6
    stall_nm: float = DEFAULT_STALL_NM
    no_load_rad_s: float = DEFAULT_NO_LOAD_RAD_S
    damping_nm_s: float = DEFAULT_STALL_NM / DEFAULT_NO_LOAD_RAD_S

    def torque(self, goal: np.ndarray, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The joint torques [N·m] of servos holding ``goal`` at angles ``q`` [rad] and speeds ``dq`` [rad/s].

        Args:
            goal: Goal angles (n,) [rad].
            q: Joint angles (n,) [rad].
            dq: Joint speeds (n,) [rad/s].

        Returns:
            The clipped torques (n,) [N·m].
        """
        wanted = self.kp_nm_rad * (goal - q) - self.damping_nm_s * dq
        driving = wanted * dq > 0.0
        slowed = self.stall_nm * np.maximum(0.0, 1.0 - np.abs(dq) / self.no_load_rad_s)
        limit = np.where(driving, slowed, self.stall_nm)
        return np.clip(wanted, -limit, limit)


@dataclass
class _Robot:
    """The compiled model with the addresses the loop needs."""

    model: Any
    data: Any
    names: list[str]
    qadr: np.ndarray
    dadr: np.ndarray
    torso: int
    free_qadr: int


def _top_body(ms: Any) -> Any:
    """The one body hanging from the world in a freshly imported spec."""
    tops = [b for b in ms.bodies if b.parent is not None and b.parent.name == ms.worldbody.name and b.name != "world"]
    if len(tops) != 1:
        raise ValueError(f"expected one top-level body in the URDF, got {[b.name for b in tops]}")
    return tops[0]


def _build(urdf_text: str, friction: float, time_step_s: float) -> _Robot:
    """Compile the URDF with a free-floating root and a floor.

    Args:
        urdf_text: The robot's URDF.
        friction: Sliding friction coefficient of the floor and of every robot geom.
        time_step_s: Physics time step [s].

    Returns:
        The compiled robot.
    """
    ms = mujoco.MjSpec.from_string(urdf_text)
    root = _top_body(ms)
    root.add_freejoint(name="foreign_free")
    ms.option.timestep = time_step_s
    ms.option.integrator = mujoco.mjtIntegrator.mjINT_EULER       # semi-implicit Euler, implicit in joint damping
    coefficients = [friction, TORSIONAL_FRICTION, ROLLING_FRICTION]
    for geom in ms.geoms:
        geom.friction = coefficients
    ms.worldbody.add_geom(name=FLOOR_NAME, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 1.0],
                          friction=coefficients)
    model = ms.compile()
    data = mujoco.MjData(model)
    hinges = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    names = [model.joint(j).name for j in hinges]
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    torso_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, TORSO_LINK)
    if torso_id < 0:                     # fused into the free-floating root: the torso frame is the root's
        torso_id = int(model.jnt_bodyid[free[0]])
    return _Robot(model, data, names, np.array([model.jnt_qposadr[j] for j in hinges]),
                  np.array([model.jnt_dofadr[j] for j in hinges]), torso_id, int(model.jnt_qposadr[free[0]]))


def _geom_bottom(model: Any, data: Any, g: int) -> float:
    """The lowest world z [m] of geom ``g`` at the current kinematics (planes: +inf)."""
    kind, size = model.geom_type[g], model.geom_size[g]
    centre, rot = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3)
    axis_z = abs(float(rot[2, 2]))                                  # vertical share of the geom's local z axis
    if kind == mujoco.mjtGeom.mjGEOM_PLANE:
        return math.inf
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return float(centre[2] - size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return float(centre[2] - size[1] * axis_z - size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return float(centre[2] - size[1] * axis_z - size[0] * math.sqrt(max(0.0, 1.0 - axis_z ** 2)))
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        half = size
        local_centre = np.zeros(3)
    else:                                                           # anything else: its local bounding box
        local_centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    corners = centre + (local_centre + signs * half) @ rot.T
    return float(corners[:, 2].min())


def _place(robot: _Robot, goals: Mapping[str, float], lying: str | None = None) -> None:
    """Joints at ``goals``, torso level (or lying as :data:`LYING_QUATERNIONS` says), at rest, the lowest robot point
    :data:`START_GAP_M` above the floor."""
    m, d = robot.model, robot.data
    mujoco.mj_resetData(m, d)
    for name, adr in zip(robot.names, robot.qadr):
        d.qpos[adr] = goals.get(name, 0.0)
    a = robot.free_qadr
    d.qpos[a:a + 3] = (0.0, 0.0, 1.0)
    d.qpos[a + 3:a + 7] = (1.0, 0.0, 0.0, 0.0) if lying is None else LYING_QUATERNIONS[lying]
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    bottom = min(_geom_bottom(m, d, g) for g in range(m.ngeom) if m.geom_bodyid[g] != 0)
    d.qpos[a + 2] += START_GAP_M - bottom
    mujoco.mj_forward(m, d)


class _Imu:
    """Gyro and accelerometer of the torso (torso frame), delivered ``latency`` ticks late."""

    def __init__(self, robot: _Robot, latency_ticks: int, tick_s: float):
        self.robot, self.latency, self.tick_s = robot, latency_ticks, tick_s
        self.last_velocity: np.ndarray | None = None
        self.queue: deque[tuple[np.ndarray, np.ndarray, dict[str, float]]] = deque()

    def measure(self) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
        """This tick's reading: gyro [rad/s], specific force [m/s²], joint angles {name: rad}."""
        m, d, torso = self.robot.model, self.robot.data, self.robot.torso
        rot = d.xmat[torso].reshape(3, 3)
        local, world = np.zeros(6), np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, torso, local, 1)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, torso, world, 0)
        velocity = world[3:].copy()
        accel = np.zeros(3) if self.last_velocity is None else (velocity - self.last_velocity) / self.tick_s
        self.last_velocity = velocity
        specific = rot.T @ (accel - m.opt.gravity)
        positions = {n: float(d.qpos[a]) for n, a in zip(self.robot.names, self.robot.qadr)}
        return local[:3].copy(), specific, positions

    def read(self) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
        """Measure now; hand out the reading from ``latency`` ticks ago (the oldest one at first)."""
        self.queue.append(self.measure())
        while len(self.queue) > self.latency + 1:
            self.queue.popleft()
        return self.queue[0]


def _torso_pose(robot: _Robot) -> tuple[np.ndarray, float, float]:
    """Torso origin (3,) [m], tilt of its z axis from vertical [deg] and heading [deg]."""
    d = robot.data
    rot = d.xmat[robot.torso].reshape(3, 3)
    tilt = math.degrees(math.acos(float(np.clip(rot[2, 2], -1.0, 1.0))))
    return d.xpos[robot.torso].copy(), tilt, math.degrees(math.atan2(rot[1, 0], rot[0, 0]))


def _apply(goal: np.ndarray, index: dict[str, int], goals: Mapping[str, float]) -> None:
    """Copy the controller's ``goals`` {name: rad} into the goal vector; joints left out keep theirs."""
    for name, value in goals.items():
        if name not in index:
            raise KeyError(f"the controller named an unknown joint {name!r}")
        goal[index[name]] = float(value)


def simulate(urdf_text: str, controller: Any, seconds: float, friction: float = 0.8, time_step_s: float = 0.001,
             servo: ServoModel = ServoModel(), latency_ticks: int = 1, lying: str | None = None,
             until: Any = None) -> dict[str, Any]:
    """Run ``controller`` on the robot of ``urdf_text`` standing on a flat floor for ``seconds`` of simulated time.

    Args:
        urdf_text: The robot's URDF (root link with a fixed joint to the torso ``body_link``).
        controller: Has ``start(positions)`` and ``step(t, gyro, accel, positions)``, both returning goals
            {joint name: rad}.
        seconds: Simulated time [s].
        friction: Sliding friction coefficient of the floor and the robot.
        time_step_s: Physics time step [s] (a divisor of :data:`CONTROL_PERIOD_S`).
        servo: The servo model of every joint.
        latency_ticks: How many control ticks late the readings reach the controller.
        lying: Start lying (a key of :data:`LYING_QUATERNIONS`) instead of standing; then a fall is not looked for.
        until: Called with the time [s] after every control tick; the run ends when it returns True.

    Returns:
        ``fell``, ``fall_time_s`` (None if it did not fall), ``start_xy`` and ``end_xy`` (torso origin [m]),
        ``end_yaw_deg`` (torso heading), ``distance_m`` (forward, along x), ``lateral_m`` (along y), ``seconds``
        (simulated, up to the fall), ``end_tilt_deg`` and ``max_tilt_deg`` (torso z axis from vertical, the latter
        over the control ticks), ``last_gyro`` [rad/s] and ``last_accel`` [m/s²] (the last reading the controller
        got), ``trace``: per control tick (time [s], torso origin height [m], torso tilt [deg], heading [deg], x [m],
        y [m]).
    """
    if not (time_step_s > 0.0 and seconds >= 0.0 and latency_ticks >= 0):
        raise ValueError(f"expected a positive time step, seconds >= 0 and latency >= 0, got {time_step_s!r}, "
                         f"{seconds!r} and {latency_ticks!r}")
    robot = _build(urdf_text, friction, time_step_s)
    m, d = robot.model, robot.data
    m.dof_damping[robot.dadr] = servo.damping_nm_s         # integrated implicitly, added back below (module docstring)
    index = {n: i for i, n in enumerate(robot.names)}
    goal = np.zeros(len(robot.names))
    _apply(goal, index, controller.start({n: 0.0 for n in robot.names}))
    _place(robot, dict(zip(robot.names, goal.tolist())), lying)
    per_tick = max(1, int(round(CONTROL_PERIOD_S / time_step_s)))
    imu, start = _Imu(robot, latency_ticks, per_tick * time_step_s), _torso_pose(robot)[0]
    reading = imu.read()                                   # the reading at t = 0 (for the first acceleration)
    fall_time, max_tilt, steps = None, 0.0, int(round(seconds / time_step_s))
    trace: list[tuple[float, float, float, float, float, float]] = []
    for k in range(steps):
        if k and k % per_tick == 0:
            mujoco.mj_forward(m, d)                        # kinematics and velocities of the current state
            reading = imu.read()
            _apply(goal, index, controller.step(k * time_step_s, reading[0].copy(), reading[1].copy(), reading[2]))
            pos, tilt, heading = _torso_pose(robot)
            trace.append((k * time_step_s, float(pos[2]), tilt, heading, float(pos[0]), float(pos[1])))
            max_tilt = max(max_tilt, tilt)
            if lying is None and (tilt > FALL_TILT_DEG or pos[2] < FALL_HEIGHT_M):
                fall_time = k * time_step_s
                break
            if until is not None and until(k * time_step_s):
                steps = k
                break
        dq = d.qvel[robot.dadr]
        d.qfrc_applied[robot.dadr] = servo.torque(goal, d.qpos[robot.qadr], dq) + servo.damping_nm_s * dq
        mujoco.mj_step(m, d)
    mujoco.mj_forward(m, d)
    end, tilt, yaw = _torso_pose(robot)
    elapsed = fall_time if fall_time is not None else steps * time_step_s
    return {"fell": fall_time is not None, "fall_time_s": fall_time, "start_xy": (float(start[0]), float(start[1])),
            "end_xy": (float(end[0]), float(end[1])), "end_yaw_deg": yaw, "distance_m": float(end[0] - start[0]),
            "lateral_m": float(end[1] - start[1]), "seconds": elapsed,
            "end_tilt_deg": tilt, "max_tilt_deg": max_tilt, "last_gyro": reading[0], "last_accel": reading[1],
            "trace": trace}
