"""A kick inside a steered walk: stop, kick, walk on.

:meth:`.steer.SteerableWalk.kick` asks for it; the rolling planner (:mod:`.rolling`) closes the feet as for a stop,
stands, and then plays a kick phase (:func:`kick_chunk`): a quintic from the walk's standing goals to the kick's
first pose, the kick, a quintic back (:func:`op2motion.motion.planner.blend`), after which the walk goes on with
the command in force. The kick is the stock page 12 (right) or 13 (left) of the action file given when it has them,
played as the robot's framework plays them (:mod:`op2motion.motion.player`) from walk-ready, or op2motion's own
``kick_right`` / ``kick_left`` (``poses/motions/``, planned like every motion: weight shift, lift, routes around
the floor). Its rows are played open loop (the walk's feedback assumes soles where its own plan puts them); their
torso poses, for the judge and the attitude estimate, stand on the foot that does not kick, where the walk left it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.formats.action import ActionFile
from op2motion.gait.phases import WalkState
from op2motion.kinematics.leg_ik import Leg, leg_fk, rot_z
from op2motion.model.dynamics import dynamics_for
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, SupportName, other_side

STOCK_KICKS = {"right": 12, "left": 13}     # the stock action file's kick pages (framework demos)
OWN_KICKS = {"right": "kick_right", "left": "kick_left"}
WALK_READY_PAGE = 9                         # the stock kicks start from walk-ready (the stock page 9's pose)
BLEND_S = 0.8                               # the quintics into and out of the kick take at least this [s]


@dataclass(frozen=True)
class KickMotion:
    """A kick as rows every 8 ms: the goals (K, 20) [rad], the P gains (K, 20), the support of each row, and the
    kick's name (the stock page, or op2motion's own motion)."""

    goals: np.ndarray
    p_gains: np.ndarray
    supports: tuple[Support | SupportName, ...]
    name: str


@dataclass(frozen=True)
class KickRows:
    """A kick phase's rows (K of them): the joints (= the goals: played open loop) (K, 20) [rad], the P gains
    (K, 20), the torso's positions (K, 3) [m] and rotations (K, 3, 3) and the whole-body CoM (K, 3) [m] in the world
    (the start's support-foot frame), each sole's pose by side (K, 4: x, y, z [m], yaw [rad]) and each row's
    contact."""

    goals: np.ndarray
    p_gains: np.ndarray
    torso_pos: np.ndarray
    torso_rot: np.ndarray
    com: np.ndarray
    feet: dict[str, np.ndarray]
    contact: tuple[SupportName, ...]


_CACHE: dict[tuple[str, str, bytes | None], KickMotion] = {}


def kick_motion(spec: Spec, side: Side, action: ActionFile | None = None) -> KickMotion:
    """The kick with the ``side`` foot (planned once per spec, side and action file)."""
    key = (spec.sha256, side, None if action is None else bytes(action.data))
    if key not in _CACHE:
        page = STOCK_KICKS[side]
        if action is not None and action.raw(page).playable and action.raw(WALK_READY_PAGE).playable:
            from op2motion.motion.pipeline import play_page

            played = play_page(action, page, spec, action.pose(WALK_READY_PAGE, spec))
            trajectory, name = played.trajectory, f"stock page {page}"
        else:
            from op2motion.formats.motionfile import read_motion
            from op2motion.motion.getup_ways import motion_path
            from op2motion.motion.pipeline import plan_motion

            trajectory = plan_motion(read_motion(motion_path(OWN_KICKS[side]), spec), spec)
            name = OWN_KICKS[side]
        _CACHE[key] = KickMotion(trajectory.goals, trajectory.p_gains, trajectory.supports, name)
    return _CACHE[key]


def kick_chunk(spec: Spec, legs: dict[str, Leg], state: WalkState, stand_goals: np.ndarray, p_gain: float,
               side: Side, action: ActionFile | None = None) -> KickRows:
    """The rows of a kick phase from a robot standing at ``stand_goals`` (20,) [rad] on the feet of ``state``."""
    from op2motion.motion.planner import blend

    kick = kick_motion(spec, side, action)
    goals, gains, supports = kick.goals, kick.p_gains, kick.supports
    into = blend(stand_goals, goals[0], spec, BLEND_S)
    back = blend(goals[-1], stand_goals, spec, BLEND_S)
    rows = np.vstack([into, goals, back])
    p_gains = np.vstack([np.full((len(into), len(stand_goals)), p_gain), gains,
                         np.full((len(back), len(stand_goals)), p_gain)])
    both: tuple[SupportName, ...] = ("double",)
    contact = both * len(into) + tuple(Support.of(s).value for s in supports) + both * len(back)
    anchor = other_side(side)
    foot = state.foot(anchor)
    world_rot, world_pos = rot_z(foot.yaw), np.array([foot.x, foot.y, 0.0])
    leg = legs[anchor]
    sole, sole_rot = leg_fk(leg, rows[:, list(leg.index)])
    rot = world_rot @ np.swapaxes(sole_rot, 1, 2)                               # torso rotation (K, 3, 3)
    pos = world_pos - np.einsum("kij,kj->ki", rot, sole)
    feet: dict[str, np.ndarray] = {anchor: np.repeat(np.array([[foot.x, foot.y, 0.0, foot.yaw]]), len(rows), axis=0)}
    other = legs[side]
    p_other, r_other = leg_fk(other, rows[:, list(other.index)])
    world_other = pos + np.einsum("kij,kj->ki", rot, p_other)
    yaw_other = np.arctan2((rot @ r_other)[:, 1, 0], (rot @ r_other)[:, 0, 0])
    feet[side] = np.column_stack([world_other, np.unwrap(yaw_other)])
    com = _coms(spec, rows, pos, rot)
    return KickRows(rows, p_gains, pos, rot, com, feet, contact)


def _coms(spec: Spec, rows: np.ndarray, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """The whole-body CoM (K, 3) [m] of joint rows at torso poses (pinocchio)."""
    dyn = dynamics_for(spec)
    pin = dyn.pin
    out = np.empty((len(rows), 3))
    for i, (q, p, r) in enumerate(zip(rows, pos, rot)):
        config = dyn.configuration(q)
        config[:3] = p
        config[3:7] = pin.Quaternion(r).coeffs()
        out[i] = pin.centerOfMass(dyn.model, dyn.data, config)
    return out
