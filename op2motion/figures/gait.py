"""Pictures of a gait: the walk from above, and the CoM and ZMP against time.

:func:`render_gait` draws a top view (X forward, Y left) of every footstep's sole (left blue, right red, numbered),
the ZMP reference, the planned multibody ZMP and the planned CoM, and the centre of pressure measured in physics
when given; below, x and y of the CoM, the ZMP reference and the planned ZMP against time, and the planned ZMP's
margin to the soles on the floor.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from op2motion.figures.draw import _pyplot, margin_panel_png
from op2motion.gait.footsteps import sole_rectangle
from op2motion.gait.generator import Gait
from op2motion.robot.spec import Spec

SIDE_COLOUR = {"left": "tab:blue", "right": "tab:red"}
PLOT_WIDTH_IN = 8.0        # the top view's drawing width [in] (of a 10 in figure)
TIME_PANELS_IN = 7.5       # the three time panels' height [in]


def _top_height_in(gait: Gait, spec: Spec) -> float:
    """Height [in] of the top view that shows the footprints at equal scale across :data:`PLOT_WIDTH_IN`, plus
    room for its legend and labels, within 2-7 in."""
    corners = np.vstack([sole_rectangle(spec, f) for f in (*gait.footsteps.start.values(), *gait.footsteps.steps)])
    span = np.ptp(corners, axis=0) + 0.02
    return float(np.clip(PLOT_WIDTH_IN * span[1] / max(span[0], 1e-3) + 1.2, 2.0, 7.0))


def render_gait(gait: Gait, spec: Spec, title: str, cop: Sequence[Sequence[float]] | None = None,
                cop_start_s: float = 0.0, verdict: str = "not checked in physics") -> bytes:
    """The PNG (see the module docstring). ``cop``: rows of (time [s], x [m], y [m]) measured in physics, the
    walk starting at ``cop_start_s`` [s] of that clock."""
    plt = _pyplot()
    top_in = _top_height_in(gait, spec)
    fig = plt.figure(figsize=(10, top_in + TIME_PANELS_IN))
    grid = fig.add_gridspec(4, 1, height_ratios=[top_in, 2.4, 2.4, 1.7])
    top = fig.add_subplot(grid[0])
    for side, foot in gait.footsteps.start.items():
        box = sole_rectangle(spec, foot)
        top.fill(box[:, 0], box[:, 1], fill=False, ls=":", color=SIDE_COLOUR[side], lw=1.0)
    for k, foot in enumerate(gait.footsteps.steps):
        box = sole_rectangle(spec, foot)
        top.fill(box[:, 0], box[:, 1], alpha=0.15, color=SIDE_COLOUR[foot.side])
        top.plot(*np.vstack([box, box[:1]]).T, color=SIDE_COLOUR[foot.side], lw=0.8)
        top.annotate(str(k + 1), (foot.x, foot.y), ha="center", va="center", fontsize=7)
    ref, zmp, com = gait.timeline.zmp_ref, gait.zmp, gait.com
    top.plot(ref[:, 0], ref[:, 1], "k--", lw=0.8, label="ZMP reference")
    top.plot(zmp[:, 0], zmp[:, 1], color="tab:green", lw=0.9, label="planned ZMP (multibody)")
    top.plot(com[:, 0], com[:, 1], color="tab:purple", lw=1.4, label="planned CoM")
    if cop:
        c = np.array([row for row in cop if row[0] >= cop_start_s])
        if len(c):
            top.plot(c[:, 1], c[:, 2], ".", color="tab:orange", ms=1.5, alpha=0.6, label="measured CoP")
    top.set_aspect("equal")
    top.set_xlabel("x [m] (forward)")
    top.set_ylabel("y [m] (left)")
    top.grid(alpha=0.3)
    top.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=4, fontsize=8)
    fig.suptitle(f"{title}\n{verdict}", fontsize=10)
    t = gait.times
    for row, (axis, name) in enumerate(((0, "x"), (1, "y"))):
        ax = fig.add_subplot(grid[1 + row])
        ax.plot(t, ref[:, axis], "k--", lw=0.8, label="ZMP reference")
        ax.plot(t, zmp[:, axis], color="tab:green", lw=0.9, label="planned ZMP")
        ax.plot(t, com[:, axis], color="tab:purple", lw=1.2, label="planned CoM")
        ax.set_ylabel(f"{name} [m]")
        ax.grid(alpha=0.3)
        if row == 0:
            ax.legend(loc="best", fontsize=8)
    return margin_panel_png(fig, fig.add_subplot(grid[3]), t, gait.zmp_margin, "tab:green")
