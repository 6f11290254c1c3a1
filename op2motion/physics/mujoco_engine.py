"""MuJoCo as a physics engine for the run loop (:mod:`.run`): the same generated URDF, compiled with ``MjSpec``.

The URDF is loaded into an ``MjSpec``; the torso gets a free joint (without it MuJoCo would weld the torso to the
world), the named frame links become sites, inertias are taken from the URDF only, and a floor plane is added.
Each of the 20 joints gets a torque motor and the servo's losses as joint properties, which MuJoCo integrates
implicitly (``implicitfast``): damping (back-EMF and viscous), Coulomb friction (``frictionloss``) and the rotor
inertia reflected through the gearbox (``armature``). Contacts: elliptic friction cones, friction
:data:`FLOOR_FRICTION`, a 5 ms critically damped contact time constant (about 0.02 mm of penetration).
"""

from __future__ import annotations

import numpy as np

from op2motion.model.servo import ServoModel
from op2motion.model.urdf import URDF_ROOT, build_urdf, frame_points
from op2motion.physics.ball import Ball
from op2motion.physics.scene import BALL_NAME, FLOOR_FRICTION, Contact
from op2motion.robot.spec import GRAVITY_M_S2, Spec

SOLREF = (0.005, 1.0)                    # contact time constant [s] and damping ratio
SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)   # contact impedance: stiff, little penetration
IMPRATIO = 10.0                          # friction-to-normal impedance ratio (MuJoCo's advice for legged robots)


class MuJoCoEngine:
    """One MuJoCo world with the floor and the robot."""

    name = "mujoco"

    def __init__(self, spec: Spec, servo: ServoModel, time_step: float, friction: float = FLOOR_FRICTION,
                 ball: Ball | None = None):
        import mujoco

        self.mj, self.spec, self.servo, self.time_step = mujoco, spec, servo, time_step
        ms = mujoco.MjSpec.from_string(build_urdf(spec))
        c = ms.compiler
        c.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        c.balanceinertia, c.boundmass, c.boundinertia, c.discardvisual = False, 0.0, 0.0, True
        for link, _, _ in frame_points(spec).values():
            ms.body(link).add_site(name=link)
        ms.body(spec.root_link).fuse = False      # keep the torso a body of its own, under the URDF root
        o = ms.option
        o.timestep, o.gravity = time_step, [0.0, 0.0, -GRAVITY_M_S2]
        o.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        o.cone, o.impratio = mujoco.mjtCone.mjCONE_ELLIPTIC, IMPRATIO
        coefficients = [friction, 0.005, 0.0001]
        ms.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], friction=coefficients,
                              solref=list(SOLREF), solimp=list(SOLIMP), condim=3)
        for g in ms.geoms:
            if g.name != "floor":
                g.friction, g.solref, g.solimp, g.condim = coefficients, list(SOLREF), list(SOLIMP), 3
        ms.body(URDF_ROOT).add_freejoint(name="root")
        if ball is not None:
            sphere = ms.worldbody.add_body(name=BALL_NAME, pos=ball.centre.tolist(), mass=ball.mass_kg,
                                           ipos=[0.0, 0.0, 0.0], inertia=[ball.inertia_kg_m2] * 3,
                                           explicitinertial=True)      # its centre of mass at its centre
            sphere.add_freejoint(name=BALL_NAME)
            sphere.add_geom(name=BALL_NAME, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[ball.radius_m, 0, 0],
                            friction=coefficients, solref=list(SOLREF), solimp=list(SOLIMP),
                            condim=3)
        limit = servo.torque_max
        for j in ms.joints:
            if j.type != mujoco.mjtJoint.mjJNT_HINGE:
                continue
            j.armature, j.damping, j.frictionloss = servo.armature, [servo.damping, 0.0, 0.0], servo.friction
            a = ms.add_actuator(name=j.name, target=j.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            a.set_to_motor()
            a.ctrllimited, a.ctrlrange = mujoco.mjtLimited.mjLIMITED_TRUE, [-limit, limit]
        self.model = ms.compile()
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.actuator = np.array([m.actuator(n).id for n in spec.joint_names])
        self.qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in spec.joint_names])
        self.dadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in spec.joint_names])
        self.root = m.body(spec.root_link).id
        self.root_qadr = int(m.jnt_qposadr[m.joint("root").id])     # the torso's free joint (a ball has one too)
        self.floor = m.geom("floor").id
        self.body_name = {i: m.body(i).name for i in range(m.nbody)}
        self.geom_body = [self.body_name[int(b)] for b in m.geom_bodyid]      # each geom's body, by geom id
        self.ball = m.body(BALL_NAME).id if ball is not None else None
        self.ball_qadr = int(m.jnt_qposadr[m.joint(BALL_NAME).id]) if ball is not None else -1
        self.ball_dof = int(m.jnt_dofadr[m.joint(BALL_NAME).id]) if ball is not None else -1
        self.ball_geom = m.geom(BALL_NAME).id if ball is not None else -1

    def close(self) -> None:
        """Nothing to release."""

    def total_mass(self) -> float:
        """Mass of the compiled model [kg]."""
        return float(self.mj.mj_getTotalmass(self.model))

    def reset(self, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> None:
        """Teleport: torso link frame at (``base_pos``, ``base_rot``), joints at ``q`` [rad], all at rest."""
        mj, d = self.mj, self.data
        mj.mj_resetData(self.model, d)
        quat = np.zeros(4)
        mj.mju_mat2Quat(quat, np.asarray(base_rot, dtype=float).reshape(-1))
        r = self.root_qadr
        d.qpos[r:r + 3], d.qpos[r + 3:r + 7] = base_pos, quat
        d.qpos[self.qadr] = q
        mj.mj_forward(self.model, d)

    def set_gravity(self, scale: float) -> None:
        """Gravity at ``scale`` of its full strength."""
        self.model.opt.gravity[2] = -GRAVITY_M_S2 * scale

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles and velocities (20,) [rad, rad/s] (copies: indexing by an array copies)."""
        return self.data.qpos[self.qadr], self.data.qvel[self.dadr]

    def step(self, torque: np.ndarray, push: np.ndarray | None = None) -> None:
        """One time step with the servos' active ``torque`` (20,) [N·m] and an optional ``push`` (3,) [N] at the
        torso's centre of mass."""
        d = self.data
        d.ctrl[self.actuator] = torque
        d.xfrc_applied[self.root, :3] = 0.0 if push is None else push
        self.mj.mj_step(self.model, d)

    def base(self) -> tuple[np.ndarray, np.ndarray]:
        """Torso link frame: position [m] and rotation (3, 3), at the current state."""
        d = self.data
        self.mj.mj_kinematics(self.model, d)
        return d.xpos[self.root].copy(), d.xmat[self.root].reshape(3, 3).copy()

    def base_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Velocity of the torso link frame's origin: linear [m/s] and angular [rad/s], world frame."""
        twist = np.zeros(6)                       # MuJoCo: (angular, linear) at the body's frame origin
        self.mj.mj_objectVelocity(self.model, self.data, self.mj.mjtObj.mjOBJ_BODY, self.root, twist, 0)
        return twist[3:].copy(), twist[:3].copy()

    def ball_state(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The ball's centre (3,) [m] and velocity (3,) [m/s], world frame (None: no ball)."""
        if self.ball is None:
            return None
        q, v = self.ball_qadr, self.ball_dof             # a free joint: position, then linear velocity (world)
        return self.data.qpos[q:q + 3].copy(), self.data.qvel[v:v + 3].copy()

    def contacts(self) -> list[Contact]:
        """Contacts of the robot with the floor (``other`` None) and with itself, at the current state."""
        mj, m, d = self.mj, self.model, self.data
        mj.mj_forward(m, d)
        n = d.ncon
        if not n:
            return []
        con = d.contact                                             # every contact's fields as arrays (n, ...)
        wrench, local = np.zeros(6), np.empty((n, 3))
        for i in range(n):
            mj.mj_contactForce(m, d, i, wrench)
            local[i] = wrench[:3]                                   # normal, then the two tangents (contact frame)
        on_g1 = np.einsum("nji,nj->ni", con.frame.reshape(n, 3, 3), local)   # force on geom[1] from geom[0], world
        points, normal = con.pos.copy(), local[:, 0].tolist()
        out = []
        for i, (g0, g1) in enumerate(con.geom.tolist()):
            if self.ball_geom in (g0, g1):                          # the ball's contacts are not the robot's
                continue
            if self.floor in (g0, g1):
                robot, force = (g1, on_g1[i]) if g0 == self.floor else (g0, -on_g1[i])
                out.append(Contact(self.geom_body[robot], None, normal[i], force, points[i]))
            else:
                out.append(Contact(self.geom_body[g0], self.geom_body[g1], normal[i], -on_g1[i], points[i]))
        return out
