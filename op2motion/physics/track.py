"""What a run records: every :data:`SAMPLE_S` the torso, the centre of mass, the soles, the joints, the servo
torques, the contacts. :class:`Recorder` samples a live engine; :class:`Track` is the finished record (arrays along
the samples) that the judge (:mod:`.judge`) and the measurements (:mod:`.measure`, and a plan's own hook such as a
walk's, :mod:`op2motion.gait.measures`) read, so both can be tested on made-up tracks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from op2motion.model.servo import ServoModel
from op2motion.physics.body import Body, BodyState
from op2motion.physics.engine import Engine
from op2motion.physics.scene import Contact
from op2motion.robot.support import SIDES

SAMPLE_S = 0.01
CONTACT_FORCE_N = 0.5          # a contact pressing harder than this counts ("pressed on")
_LOAD_EPS_N = 1e-6

FootSample = dict[str, tuple[float, np.ndarray]]    # side -> (vertical load [N], that foot's own CoP (2,) [m])


@dataclass(frozen=True)
class Track:
    """A run's samples (n of them), world frame: time [s], the plan row the servos held, torso rotation (n, 3, 3),
    full-inertia CoM (n, 3) [m], sole positions {side: (n, 3)} [m], joint angles, goals sent (n, 20) [rad], servo
    torques (n, 20) [N·m, signed] and the torque available then (n, 20) [N·m], the centre of pressure (2,) [m] or
    None (off the floor), each foot's load and own CoP, the links pressing on the floor, the link pairs pressing on
    each other, the measured body states, and the torso link frame's position (n, 3) [m]."""

    times: np.ndarray
    rows: np.ndarray
    rot: np.ndarray
    com: np.ndarray
    soles: dict[str, np.ndarray]
    q: np.ndarray
    goals: np.ndarray
    torque: np.ndarray
    available: np.ndarray
    cop: tuple[np.ndarray | None, ...]
    feet: tuple[FootSample, ...]
    ground: tuple[frozenset[str], ...]
    self_pairs: tuple[frozenset[tuple[str, str]], ...]
    states: tuple[BodyState, ...] = field(repr=False)
    base_pos: np.ndarray | None = None


def _load_and_moment(contacts: list[Contact]) -> tuple[float, float, float]:
    """The contacts' summed vertical load [N] and its moments (x, y) [N·m] (load x point), summed in order as
    floats (a sample sums a few contacts: array sums cost more than the arithmetic)."""
    load = mx = my = 0.0
    for c in contacts:
        fz = float(c.force[2])
        load += fz
        mx += fz * float(c.point[0])
        my += fz * float(c.point[1])
    return load, mx, my


def centre_of_pressure(contacts: list[Contact]) -> np.ndarray | None:
    """The load-weighted mean of the contact points (2,) [m], or None without vertical load."""
    load, mx, my = _load_and_moment(contacts)
    return np.array([mx / load, my / load]) if load > _LOAD_EPS_N else None


def foot_loads(ground: list[Contact], foot_links: dict[str, str]) -> FootSample:
    """Each foot's vertical load [N] and own centre of pressure, for the feet that carry any."""
    out = {}
    for side, link in foot_links.items():
        load, mx, my = _load_and_moment([c for c in ground if c.link == link])
        if load > _LOAD_EPS_N:
            out[side] = (load, np.array([mx / load, my / load]))
    return out


def pressed(contacts: list[Contact]) -> tuple[frozenset[str], frozenset[tuple[str, str]]]:
    """The links pressing on the floor and the pairs of links pressing on each other (> :data:`CONTACT_FORCE_N`)."""
    floor: dict[str, float] = {}
    pairs: dict[tuple[str, str], float] = {}
    for c in contacts:
        if c.other is None:
            floor[c.link] = floor.get(c.link, 0.0) + c.normal_force
        else:
            a, b = sorted((c.link, c.other))
            pairs[(a, b)] = pairs.get((a, b), 0.0) + c.normal_force
    return (frozenset(link for link, f in floor.items() if f > CONTACT_FORCE_N),
            frozenset(p for p, f in pairs.items() if f > CONTACT_FORCE_N and p[0] != p[1]))


class Recorder:
    """Samples a live engine into the lists a :class:`Track` is made of."""

    def __init__(self, body: Body, servo: ServoModel):
        self.body, self.servo = body, servo
        self.lists: dict[str, list[Any]] = {name: [] for name in (
            "times", "rows", "rot", "com", "soles", "q", "goals", "torque", "available", "cop", "feet", "ground",
            "self_pairs", "states", "base_pos")}

    def sample(self, engine: Engine, t: float, row: int, goals: np.ndarray, kp: np.ndarray,
               limit: np.ndarray | None = None) -> None:
        """Record the engine's state at time ``t`` [s], the servos holding ``goals`` (20,) [rad] at stiffness
        ``kp`` (20,) [N·m/rad] (plan row ``row``) within a torque ``limit`` (20,) [N·m] if the controller set one."""
        q, dq = engine.state()
        pos, rot = engine.base()
        state = self.body.state(pos, rot, q)
        contacts = engine.contacts()
        ground = [c for c in contacts if c.other is None and c.normal_force > 0.0]
        floor, pairs = pressed([c for c in contacts if c.other is not None or c.normal_force > 0.0])
        torque = self.servo.motor_torque(goals, q, dq, kp, limit)
        values = {"times": t, "rows": row, "rot": rot, "com": state.com, "soles": state.soles, "q": q,
                  "goals": np.array(goals), "torque": torque, "available": self.servo.available(dq, torque),
                  "cop": centre_of_pressure(ground), "feet": foot_loads(ground, self.body.foot_links),
                  "ground": floor, "self_pairs": pairs, "states": state, "base_pos": pos}
        for name, value in values.items():
            self.lists[name].append(value)

    def track(self) -> Track:
        """The finished record."""
        s = self.lists
        soles = {side: np.array([p[side][0] for p in s["soles"]]) for side in SIDES}
        return Track(np.array(s["times"]), np.array(s["rows"], dtype=int), np.array(s["rot"]), np.array(s["com"]),
                     soles, np.array(s["q"]), np.array(s["goals"]), np.array(s["torque"]), np.array(s["available"]),
                     tuple(s["cop"]), tuple(s["feet"]), tuple(s["ground"]), tuple(s["self_pairs"]),
                     tuple(s["states"]), np.array(s["base_pos"]))
