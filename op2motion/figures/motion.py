"""Pictures of a motion: joint curves and the balance tracks.

:func:`render_motion` draws, top to bottom, every joint's goal angle q [deg], velocity q̇ [deg/s] and acceleration
q̈ [deg/s²] against time (the legs, arms and head in separate colours; segments marked), then a top view of the
support polygons with the planned CoM and ZMP tracks (and the centre of pressure measured in physics when given),
and the ZMP margin against time.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from op2motion.figures.draw import _pyplot, margin_panel_png
from op2motion.motion.checks import MotionChecks
from op2motion.motion.trajectory import Trajectory
from op2motion.robot.spec import Spec


def _joint_panel(ax: Any, t: np.ndarray, values: np.ndarray, spec: Spec, label: str) -> None:
    for j, name in enumerate(spec.joint_names):
        colour = "tab:blue" if any(k in name for k in ("hip", "knee", "ank")) else (
            "tab:orange" if any(k in name for k in ("sho", "el")) else "tab:green")
        ax.plot(t, values[:, j], color=colour, lw=0.8, alpha=0.8)
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)


def render_motion(trajectory: Trajectory, checks: MotionChecks, spec: Spec, title: str,
                  cop: Sequence[Sequence[float]] | None = None, verdict: str = "not checked in physics") -> bytes:
    """The PNG (see the module docstring). ``cop``: rows of (time [s], x [m], y [m]) measured in physics, in the
    fixed foot's frame."""
    plt = _pyplot()
    fig = plt.figure(figsize=(10, 13))
    grid = fig.add_gridspec(5, 1, height_ratios=[1, 1, 1, 1.8, 0.8])
    t = trajectory.times
    panels = [(np.degrees(trajectory.goals), "q [deg]"), (np.degrees(trajectory.velocity()), "q̇ [deg/s]"),
              (np.degrees(trajectory.acceleration()), "q̈ [deg/s²]")]
    starts = [t[np.flatnonzero(trajectory.segment == k)[0]] for k in range(len(trajectory.segment_names))
              if np.any(trajectory.segment == k)]
    for i, (values, label) in enumerate(panels):
        ax = fig.add_subplot(grid[i])
        _joint_panel(ax, t, values, spec, label)
        for s in starts:
            ax.axvline(s, color="0.6", lw=0.6, ls=":")
        if i == 0:
            ax.set_title(f"{title}\n{verdict}", fontsize=10)
            ax.plot([], [], color="tab:blue", label="legs")
            ax.plot([], [], color="tab:orange", label="arms")
            ax.plot([], [], color="tab:green", label="head")
            ax.legend(loc="upper right", fontsize=8)
    ax = fig.add_subplot(grid[3])
    seen = set()
    for poly in checks.polygons:
        key = tuple(np.round(poly, 4).ravel())
        if key in seen:
            continue
        seen.add(key)
        closed = np.vstack([poly, poly[:1]])
        ax.plot(closed[:, 0] * 1000, closed[:, 1] * 1000, color="0.5", lw=0.8)
    ax.plot(checks.com[:, 0] * 1000, checks.com[:, 1] * 1000, color="tab:blue", lw=1.2, label="CoM (planned)")
    ax.plot(checks.zmp[:, 0] * 1000, checks.zmp[:, 1] * 1000, color="tab:red", lw=1.0, label="ZMP (planned)")
    if cop:
        xy = np.array([[c[1], c[2]] for c in cop])
        ax.plot(xy[:, 0] * 1000, xy[:, 1] * 1000, color="tab:green", lw=0.8, alpha=0.8, label="CoP (physics)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x [mm] ({checks.fixed_foot} sole frame, forward)")
    ax.set_ylabel("y [mm] (left)")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    return margin_panel_png(fig, fig.add_subplot(grid[4]), t, checks.zmp_margin_m, "tab:red")

