"""PNG figures: whole-body stick figures in front, side, top and 3D views (book figs. 2.31/2.32, 2.44-2.47).

Left limbs are blue and right limbs red, as in the book, so the support and swing legs always differ in colour;
the support foot is shaded. Each figure shows the centre of mass (square, with its ground projection), the
br-shrunk support rectangle (dashed) and an optional target (star).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .balance import support_polygon
from .kinematics.points import BodyPoints
from .spec import Spec

LEFT_COLOUR, RIGHT_COLOUR, BODY_COLOUR = "tab:blue", "tab:red", "black"
_CHAINS = (
    (("left_sole", "l_ank_roll", "l_knee", "l_hip_pitch", "l_hip_yaw"), LEFT_COLOUR),
    (("right_sole", "r_ank_roll", "r_knee", "r_hip_pitch", "r_hip_yaw"), RIGHT_COLOUR),
    (("l_sho_pitch", "l_sho_roll", "l_el", "left_hand"), LEFT_COLOUR),
    (("r_sho_pitch", "r_sho_roll", "r_el", "right_hand"), RIGHT_COLOUR),
    (("l_hip_yaw", "pelvis", "r_hip_yaw"), BODY_COLOUR),
    (("pelvis", "neck", "head_pan", "head_tilt", "head_top"), BODY_COLOUR),
    (("l_sho_pitch", "neck", "r_sho_pitch"), BODY_COLOUR),
)
# (title, horizontal axis index, vertical axis index, axis labels)
_VIEWS = (("front", 1, 2, ("Y left [m]", "Z [m]")), ("side", 0, 2, ("X forward [m]", "Z [m]")),
          ("top", 0, 1, ("X forward [m]", "Y left [m]")))


@dataclass(frozen=True)
class PoseFigure:
    """One pose to draw: its body points (pose 0 is drawn), CoM [m], label, and what to mark."""

    points: BodyPoints
    com: np.ndarray
    label: str
    br: float = 1.0
    target: Sequence[float] | None = None
    ghost: BodyPoints | None = None  # an earlier pose drawn in grey (e.g. before an arm IK step)


def _draw(ax, xyz: dict[str, np.ndarray], fig: PoseFigure, spec: Spec, h: int | None, v: int | None) -> None:
    def line(pts: np.ndarray, **kw) -> None:
        if h is None:
            ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], **kw)
        else:
            ax.plot(pts[:, h], pts[:, v], **kw)

    if fig.ghost is not None:
        ghost = {name: np.array(val) for name, val in fig.ghost.as_dict(0).items()}
        for names, _ in _CHAINS:
            line(np.array([ghost[n] for n in names]), color="grey", linestyle="--", linewidth=1, alpha=0.7)
    for names, colour in _CHAINS:
        line(np.array([xyz[n] for n in names]), color=colour, marker="o", markersize=3, linewidth=2)
    for side, colour in (("left", LEFT_COLOUR), ("right", RIGHT_COLOUR)):
        corners = fig.points.foot_corners(side)[0]
        ring = np.vstack([corners, corners[:1]])
        line(ring, color=colour, linewidth=1.5)
        if side == fig.points.support and h is not None and (h, v) == (0, 1):
            ax.fill(ring[:, 0], ring[:, 1], color=colour, alpha=0.15)
    sp = fig.points.point(f"{fig.points.support}_sole")[0]
    poly = support_polygon(spec, fig.points.support, fig.br, (sp[0], sp[1]))
    ring = np.vstack([poly, poly[:1]])
    ring3 = np.column_stack([ring, np.full(len(ring), sp[2])])
    line(ring3, color="green", linestyle="--", linewidth=1)
    com = np.asarray(fig.com, dtype=float)
    drop = np.array([com, [com[0], com[1], sp[2]]])
    line(drop, color="green", linestyle=":", linewidth=1)
    line(com[None, :], color="green", marker="s", markersize=7, linestyle="none")
    if fig.target is not None:
        line(np.asarray(fig.target, dtype=float)[None, :], color="gold", marker="*", markersize=14,
             markeredgecolor="black", linestyle="none")


def _pyplot():
    """matplotlib's pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(fig) -> bytes:  # type: ignore[no-untyped-def]
    """The figure as PNG bytes; the figure is closed."""
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    _pyplot().close(fig)
    return buf.getvalue()


def render_poses(figures: Sequence[PoseFigure], spec: Spec, title: str | None = None) -> bytes:
    """Each pose as a row of front, side, top and 3D views; returns the PNG bytes."""
    plt = _pyplot()

    rows = len(figures)
    fig = plt.figure(figsize=(16, 4.2 * rows))
    for r, pf in enumerate(figures):
        xyz = {name: np.array(val) for name, val in pf.points.as_dict(0).items()}
        for c, (view, h, v, labels) in enumerate(_VIEWS):
            ax = fig.add_subplot(rows, 4, r * 4 + c + 1)
            _draw(ax, xyz, pf, spec, h, v)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel(labels[0])
            ax.set_ylabel(labels[1])
            ax.grid(True, alpha=0.3)
            ax.set_title(f"{pf.label}: {view}")
        ax3 = fig.add_subplot(rows, 4, r * 4 + 4, projection="3d")
        _draw(ax3, xyz, pf, spec, None, None)
        allpts = np.array(list(xyz.values()))
        centre = (allpts.max(0) + allpts.min(0)) / 2
        half = (allpts.max(0) - allpts.min(0)).max() / 2 + 0.02
        ax3.set_xlim(centre[0] - half, centre[0] + half)
        ax3.set_ylim(centre[1] - half, centre[1] + half)
        ax3.set_zlim(max(0.0, centre[2] - half) if centre[2] - half > -0.05 else centre[2] - half, centre[2] + half)
        ax3.set_box_aspect((1, 1, 1))
        ax3.view_init(elev=20, azim=-135)
        ax3.set_xlabel("X [m]")
        ax3.set_ylabel("Y [m]")
        ax3.set_zlabel("Z [m]")
        ax3.set_title(f"{pf.label}: 3D")
    if title:
        fig.suptitle(title)
    fig.text(0.01, 0.005, "blue: left limbs, red: right limbs, shaded: support foot; green square: CoM, "
             "dashed green: support rectangle (br); star: target; grey dashed: initial pose", fontsize=8)
    fig.tight_layout(rect=(0, 0.02, 1, 0.97 if title else 1))
    return _png(fig)


def render_cost_curve(history: Sequence[float], title: str = "PSO cost") -> bytes:
    """Best cost after each PSO iteration (book fig. 2.43), log scale; returns the PNG bytes."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.semilogy(np.arange(1, len(history) + 1), np.maximum(np.asarray(history, dtype=float), 1e-9), color="tab:blue")
    ax.set_xlabel("iteration")
    ax.set_ylabel("best cost (log)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return _png(fig)
