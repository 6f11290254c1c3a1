"""Pictures of paths in space: a routed motion beside the straight line that collided, and a hand's straight move.

* :func:`render_route`: the paths of the hands and elbows that move, in 3D (stance sole's frame, X forward, Y left,
  Z up [mm]) along the straight joint interpolation (dashed, red where links overlap) and along the planned path
  (solid), with the least clearance against the share of the way for both;
* :func:`render_line`: the hand's path in 3D beside the commanded line, its distance from the line [mm] and the CoM
  margin and least clearance [mm] against time.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from op2motion.figures.draw import _png, _pyplot
from op2motion.kinematics import forward
from op2motion.kinematics.points import row_of
from op2motion.motion.cartesian import LINE_TOL_M, LineMove
from op2motion.motion.checks import clearance
from op2motion.posture.cost import SELF_CLEARANCE_M
from op2motion.robot.joints import servo_to_book
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side

MOVING_MM = 10.0           # a point drawn when its path spans more than this [mm]
_TRACKED = (("right_hand", "tab:orange"), ("left_hand", "tab:blue"), ("r_el", "tab:red"), ("l_el", "tab:purple"))


def _points(rows: np.ndarray, spec: Spec, side: Side) -> dict[str, np.ndarray]:
    data = forward(servo_to_book(rows, side, spec), spec, "dh").data
    return {name: data[row_of(name)].T * 1000.0 for name, _ in _TRACKED}


def _equal_axes(ax: Any, pts: np.ndarray) -> None:
    centre, half = pts.mean(axis=0), max(float(np.ptp(pts, axis=0).max()) / 2.0, 30.0)
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        setter(c - half, c + half)
    ax.set_xlabel("X [mm]")
    ax.set_ylabel("Y [mm]")
    ax.set_zlabel("Z [mm]")
    ax.tick_params(labelsize=7)


def render_route(straight: np.ndarray, planned: np.ndarray, spec: Spec, title: str, side: Side = "left") -> bytes:
    """PNG: the straight rows (K1, 20) [rad] against the planned rows (K2, 20) [rad] (see the module docstring),
    both in the ``side`` sole's frame."""
    plt = _pyplot()
    fig = plt.figure(figsize=(12, 5.5))
    grid = fig.add_gridspec(1, 2, width_ratios=[1.1, 1], wspace=0.3)
    ax = fig.add_subplot(grid[0], projection="3d")
    before, after = _points(straight, spec, side), _points(planned, spec, side)
    gap_before, gap_after = clearance(straight, spec)[0], clearance(planned, spec)[0]
    moving = [(n, c) for n, c in _TRACKED
              if max(np.ptp(before[n], axis=0).max(), np.ptp(after[n], axis=0).max()) > MOVING_MM]
    for name, colour in moving:
        ax.plot(*after[name].T, color=colour, lw=1.8, label=f"{name} planned")
        ax.plot(*before[name].T, color=colour, lw=1.0, ls="--", alpha=0.7)
        hit = gap_before < 0.0
        if hit.any():
            ax.scatter(*before[name][hit].T, color="red", s=4)
    ax.plot([], [], color="0.4", ls="--", label="straight interpolation (red: links overlap)")
    _equal_axes(ax, np.vstack([before[n] for n, _ in moving] + [after[n] for n, _ in moving]))
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("the hands and elbows that move [mm]", fontsize=10)
    bx = fig.add_subplot(grid[1])
    bx.plot(np.linspace(0, 1, len(gap_before)), gap_before * 1000, "--", color="0.4", label="straight")
    bx.plot(np.linspace(0, 1, len(gap_after)), gap_after * 1000, color="tab:green", label="planned")
    bx.axhline(SELF_CLEARANCE_M * 1000, color="tab:red", lw=0.8, ls=":", label="required clearance")
    bx.axhline(0.0, color="k", lw=0.6)
    bx.set_xlabel("share of the way")
    bx.set_ylabel("least clearance between links [mm]")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.subplots_adjust(left=0.02, right=0.97, top=0.9, bottom=0.1)
    return _png(fig)


def render_line(move: LineMove, title: str, verdict: str = "not checked in physics") -> bytes:
    """PNG: the hand's straight move (see the module docstring)."""
    plt = _pyplot()
    fig = plt.figure(figsize=(12, 6))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.1, 1], wspace=0.3)
    ax = fig.add_subplot(grid[:, 0], projection="3d")
    path, ends = move.hand_path * 1000, np.array([move.start_m, move.end_m]) * 1000
    ax.plot(*ends.T, color="0.3", lw=3, alpha=0.4, label="commanded line")
    ax.plot(*path.T, color="tab:orange", lw=1.5, label=f"{move.hand} hand")
    ax.scatter(*ends[0], color="tab:green", s=20, label="start")
    _equal_axes(ax, np.vstack([path, ends]))
    ax.legend(fontsize=8, loc="upper left")
    t = move.times
    bx = fig.add_subplot(grid[0, 1])
    bx.plot(t, move.deviation_m * 1000, color="tab:orange")
    bx.axhline(LINE_TOL_M * 1000, color="tab:red", lw=0.8, ls=":", label="allowed")
    bx.set_ylabel("distance from the line [mm]")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8)
    cx = fig.add_subplot(grid[1, 1], sharex=bx)
    cx.plot(t, move.com_margin_m * 1000, color="tab:blue", label="CoM margin")
    cx.plot(t, move.clearance_m * 1000, color="tab:green", label="least clearance")
    cx.set_xlabel("time [s]")
    cx.set_ylabel("[mm]")
    cx.grid(alpha=0.3)
    cx.legend(fontsize=8)
    fig.suptitle(f"{title}\n{verdict}", fontsize=10)
    fig.subplots_adjust(left=0.02, right=0.97, top=0.88, bottom=0.09)
    return _png(fig)
