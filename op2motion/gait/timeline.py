"""The gait's clock: phases, the ZMP reference and both feet's trajectories, one row per 8 ms control tick.

A walk is :data:`LEAD_S` standing still, ``start_s`` on both feet (the ZMP reference moves from between the feet
onto the first support foot), then the steps, each a single-support phase (the swing foot travels) and a
double-support phase (the reference moves onto the foot that just landed; after the last step, back to between the
feet), then ``end_s`` on both feet.

The swing foot's x, y and yaw follow a cruise blend (zero velocity and acceleration at lift-off and landing); its
height is ``h·64 s³(1-s)³`` of the phase ``s``, which starts and ends with zero velocity and acceleration, so the
foot lands flat (its sole stays parallel to the floor throughout) and at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from op2motion.gait.footsteps import Footstep, Footsteps
from op2motion.gait.params import GaitParams
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.support import LIFTED_M, SupportName, other_side

LEAD_S = 0.5             # standing still before the start ramp: the preview moves the CoM ahead of the reference


def quintic_blend(s: np.ndarray) -> np.ndarray:
    """0 -> 1 with zero first and second derivatives at both ends, for ``s`` in [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    blend: np.ndarray = s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)
    return blend


def cruise_blend(s: np.ndarray, ramp: float) -> np.ndarray:
    """0 -> 1 over ``s`` in [0, 1] at a constant speed between two ramps of ``ramp`` of the phase each, whose
    speed rises and falls as a half cosine: zero velocity and acceleration at both ends, a peak speed of
    1 / (1 - ramp) times the mean (the quintic's is 1.875), so the swing leg's servos stay further from their
    no-load speed."""
    s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
    peak = 1.0 / (1.0 - ramp)

    def rising(u: np.ndarray) -> np.ndarray:
        return peak * 0.5 * (u - ramp / np.pi * np.sin(np.pi * u / ramp))

    middle = peak * (0.5 * ramp + (s - ramp))
    return np.where(s < ramp, rising(s), np.where(s > 1.0 - ramp, 1.0 - rising(1.0 - s), middle))


def lift_profile(s: np.ndarray) -> np.ndarray:
    """0 -> 1 -> 0 over ``s`` in [0, 1] with zero first and second derivatives at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return 64.0 * s ** 3 * (1.0 - s) ** 3


@dataclass(frozen=True)
class Timeline:
    """Per row (K,): time [s], step index (-1 before the first step, len(steps) after the last), whether the row
    is in single support, the planned contact ("left", "right", "double") and the physics support (a swing foot
    below :data:`LIFTED_M` counts as standing); the ZMP reference (K, 2) [m]; each foot's sole pose
    (K, 4): x, y, z [m], yaw [rad]."""

    times: np.ndarray
    step: np.ndarray
    contact: tuple[SupportName, ...]
    supports: tuple[SupportName, ...]
    zmp_ref: np.ndarray
    feet: dict[str, np.ndarray]

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return CONTROL_PERIOD_S


def zmp_point(step: Footstep, params: GaitParams) -> np.ndarray:
    """Where the ZMP reference sits under a support foot [m]: its sole centre moved by the preset's offsets
    (forward, and towards the other foot)."""
    inward = -params.zmp_offset_y_m if step.side == "left" else params.zmp_offset_y_m
    c, s = math.cos(step.yaw), math.sin(step.yaw)
    return np.array([step.x + c * params.zmp_offset_x_m - s * inward, step.y + s * params.zmp_offset_x_m + c * inward])


def ticks(seconds: float) -> int:
    """Whole control ticks in ``seconds`` [s] (at least one)."""
    return max(1, int(round(seconds / CONTROL_PERIOD_S)))


def landing(start: np.ndarray, step: Footstep) -> np.ndarray:
    """Where a foot standing at ``start`` (x, y, z [m], yaw [rad]) lands for ``step``: on the floor, its yaw
    reached the short way round from the start's (so a walk's yaw stays continuous)."""
    goal = np.array([step.x, step.y, 0.0, step.yaw])
    goal[3] = start[3] + math.remainder(goal[3] - start[3], 2.0 * math.pi)
    return goal


def swing_path(params: GaitParams, start: np.ndarray, step: Footstep) -> np.ndarray:
    """The swing foot's sole (x, y, z [m], yaw [rad]) at each single-support row (n, 4) from ``start`` (4,) to
    ``step``: the cruise blend on x, y and yaw (completed ``swing_settle`` before landing, the yaw the short way
    round), the lift profile on z."""
    n_single = ticks(params.single_s)
    s = np.arange(1, n_single + 1) / n_single
    blend = cruise_blend(s / (1.0 - params.swing_settle), params.swing_ramp)[:, None]
    goal = landing(start, step)
    path: np.ndarray = start + blend * (goal - start)
    path[:, 2] = params.step_height_m * lift_profile(s)
    return path


def build_timeline(params: GaitParams, footsteps: Footsteps) -> Timeline:
    """Rows every :data:`CONTROL_PERIOD_S` for the whole walk (see the module docstring)."""
    n_start, n_single, n_double, n_end = (ticks(params.start_s), ticks(params.single_s), ticks(params.double_s),
                                          ticks(params.end_s))
    where = {side: np.array([f.x, f.y, 0.0, f.yaw]) for side, f in footsteps.start.items()}
    middle = 0.5 * (where["left"][:2] + where["right"][:2])
    rows_step, refs = [], []
    rows_contact: list[SupportName] = []
    feet: dict[str, list[np.ndarray]] = {side: [] for side in ("left", "right")}

    def hold(n: int, step: int, ref: np.ndarray) -> None:
        for side in feet:
            feet[side].append(np.repeat(where[side][None], n, axis=0))
        rows_step.append(np.full(n, step))
        rows_contact.extend(["double"] * n)
        refs.append(ref)

    first_support = footsteps.stance_before(0)[0]
    n_lead = ticks(LEAD_S)
    hold(n_lead, -1, np.repeat(middle[None], n_lead, axis=0))
    ramp = quintic_blend(np.arange(1, n_start + 1) / n_start)[:, None]
    hold(n_start, -1, middle + ramp * (zmp_point(first_support, params) - middle))
    for k, step in enumerate(footsteps.steps):
        stand, before = footsteps.stance_before(k)
        feet[step.side].append(swing_path(params, where[step.side], step))
        goal = landing(where[step.side], step)
        feet[stand.side].append(np.repeat(where[stand.side][None], n_single, axis=0))
        rows_step.append(np.full(n_single, k))
        rows_contact.extend([stand.side] * n_single)
        refs.append(np.repeat(zmp_point(stand, params)[None], n_single, axis=0))
        where[step.side] = goal
        last = k == len(footsteps.steps) - 1
        after = 0.5 * (where["left"][:2] + where["right"][:2]) if last else zmp_point(step, params)
        ramp = (np.arange(1, n_double + 1) / n_double)[:, None]
        hold(n_double, k, zmp_point(stand, params) + ramp * (after - zmp_point(stand, params)))
    hold(n_end, len(footsteps.steps), np.repeat(refs[-1][-1:], n_end, axis=0))
    feet_rows = {side: np.vstack(v) for side, v in feet.items()}
    contact = tuple(rows_contact)
    supports = tuple(c if c == "double" or feet_rows[other_side(c)][i, 2] >= LIFTED_M
                     else "double" for i, c in enumerate(contact))
    k_rows = len(contact)
    return Timeline(np.arange(k_rows) * CONTROL_PERIOD_S, np.concatenate(rows_step), contact, supports,
                    np.vstack(refs), feet_rows)
