"""Pictures of a motion: joint curves and the balance tracks.

:func:`render_motion` draws, top to bottom, every joint's goal angle q [deg], velocity q̇ [deg/s] and acceleration
q̈ [deg/s²] against time (one colour per joint, named in the legend; the derivatives of the goals smoothed over
40 ms; segments marked), then a top view of the support polygons with the planned CoM and ZMP tracks (and the
centre of pressure measured in physics when given), and the ZMP margin against time.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from op2motion.figures.draw import _pyplot, margin_panel_png
from op2motion.motion.checks import SMOOTH_ROWS, MotionChecks, smoothed
from op2motion.motion.trajectory import Trajectory
from op2motion.robot.spec import Spec

LEGEND_RIGHT = 0.87       # the panels keep this share of the width; the joints' legend takes the rest


def _joint_panel(ax: Any, t: np.ndarray, values: np.ndarray, spec: Spec, label: str) -> None:
    """One curve per joint, each its own colour (tab20 and a dash for the 20th), labelled by joint name."""
    import matplotlib

    colours = matplotlib.colormaps["tab20"](np.arange(20))
    for j, name in enumerate(spec.joint_names):
        ax.plot(t, values[:, j], color=colours[j % len(colours)], lw=0.9, ls="-" if j < len(colours) else "--",
                label=name)
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)


def render_motion(trajectory: Trajectory, checks: MotionChecks, spec: Spec, title: str,
                  cop: Sequence[Sequence[float]] | None = None, verdict: str = "not checked in physics") -> bytes:
    """The PNG (see the module docstring). ``cop``: rows of (time [s], x [m], y [m]) measured in physics, in the
    fixed foot's frame."""
    plt = _pyplot()
    fig = plt.figure(figsize=(11.5, 13))
    grid = fig.add_gridspec(5, 1, height_ratios=[1, 1, 1, 1.8, 0.8])
    t = trajectory.times
    # goals come in whole ticks (0.088°): their derivatives are drawn from the goals smoothed over SMOOTH_ROWS rows,
    # as the checks take them, or the tick steps would show as a sawtooth
    smooth = smoothed(trajectory.goals, SMOOTH_ROWS)
    velocity = np.gradient(smooth, trajectory.dt, axis=0) if len(t) > 1 else np.zeros_like(smooth)
    acceleration = np.gradient(velocity, trajectory.dt, axis=0) if len(t) > 1 else np.zeros_like(smooth)
    panels = [(np.degrees(trajectory.goals), "q [deg]"),
              (np.degrees(velocity), f"q̇ [deg/s] ({SMOOTH_ROWS * 8} ms average)"),
              (np.degrees(acceleration), "q̈ [deg/s²]")]
    starts = [t[np.flatnonzero(trajectory.segment == k)[0]] for k in range(len(trajectory.segment_names))
              if np.any(trajectory.segment == k)]
    for i, (values, label) in enumerate(panels):
        ax = fig.add_subplot(grid[i])
        _joint_panel(ax, t, values, spec, label)
        for s in starts:
            ax.axvline(s, color="0.6", lw=0.6, ls=":")
        if i == 0:
            ax.set_title(f"{title}\n{verdict}", fontsize=10)
            handles, labels = ax.get_legend_handles_labels()
            fig.legend(handles, labels, loc="upper right", fontsize=7, title="joint", title_fontsize=8)
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
    return margin_panel_png(fig, fig.add_subplot(grid[4]), t, checks.zmp_margin_m, "tab:red", right=LEGEND_RIGHT)

