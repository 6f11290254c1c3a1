"""The picture of a steered walk: the path the commands asked for, the path planned, and the paths walked in physics.

:func:`render_steered` draws them from above (X forward, Y left; the commanded path integrates the commands from the
start, the planned one is the torso's, the walked ones the torso's in each engine, these averaged over a stride so
the sway from foot to foot does not hide the way), with the heading of each against time below. Kicks and stops
pause the robot; a kick does not pause the commanded path.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from op2motion.figures.draw import _png, _pyplot

ENGINE_COLOUR = {"pybullet": "tab:orange", "mujoco": "tab:green"}
STRIDE_S = 0.64             # the planned and walked paths are averaged over this long (a stride: the sway left out)


def _strides(t: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """``xy`` (K, 2) averaged over :data:`STRIDE_S` around each sample (the ends held)."""
    if len(t) < 3:
        return xy
    width = max(1, int(round(STRIDE_S / max(float(np.median(np.diff(t))), 1e-6))))
    if width < 2 or len(xy) < width:
        return xy
    pad = np.vstack([np.repeat(xy[:1], width // 2, 0), xy, np.repeat(xy[-1:], width - 1 - width // 2, 0)])
    kernel = np.ones(width) / width
    return np.column_stack([np.convolve(pad[:, i], kernel, mode="valid") for i in range(2)])


def render_steered(commanded: np.ndarray, commanded_t: np.ndarray, planned: np.ndarray, planned_t: np.ndarray,
                   walked: Mapping[str, tuple[np.ndarray, np.ndarray]], title: str) -> bytes:
    """The PNG. ``commanded`` and ``planned``: poses (N, 3) (x [m], y [m], yaw [rad]) at times (N,) [s];
    ``walked``: per engine, (times (K,) [s], poses (K, 3)), on one clock."""
    plt = _pyplot()
    fig = plt.figure(figsize=(9, 9))
    grid = fig.add_gridspec(2, 1, height_ratios=[3.0, 1.2])
    top, low = fig.add_subplot(grid[0]), fig.add_subplot(grid[1])
    top.plot(commanded[:, 0], commanded[:, 1], "k--", lw=1.2, label="commanded")
    planned_xy = _strides(planned_t, planned[:, :2])
    top.plot(planned_xy[:, 0], planned_xy[:, 1], color="tab:purple", lw=1.4, label="planned (torso, per stride)")
    low.plot(commanded_t, np.degrees(commanded[:, 2]), "k--", lw=1.2, label="commanded")
    low.plot(planned_t, np.degrees(planned[:, 2]), color="tab:purple", lw=1.4, label="planned")
    for engine, (t, poses) in walked.items():
        colour = ENGINE_COLOUR.get(engine, "tab:blue")
        xy = _strides(t, poses[:, :2])
        top.plot(xy[:, 0], xy[:, 1], color=colour, lw=1.0, label=f"walked in {engine}")
        low.plot(t, np.degrees(poses[:, 2]), color=colour, lw=1.0, label=engine)
    for xy, colour in ((commanded, "k"), (planned_xy, "tab:purple")):
        top.plot(xy[-1, 0], xy[-1, 1], "o", ms=4, color=colour)
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("x [m] (forward at the start)")
    top.set_ylabel("y [m] (left)")
    top.grid(alpha=0.3)
    top.legend(loc="best", fontsize=8)
    top.set_title(title, fontsize=10)
    low.set_xlabel("time [s]")
    low.set_ylabel("heading [deg]")
    low.grid(alpha=0.3)
    low.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return _png(fig)
