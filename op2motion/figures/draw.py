"""PNG figures: whole-body stick figures (front, side, top, 3D; book figs. 2.31/2.32, 2.44-2.47) and PSO cost curves.

A pose figure has a title block (the pose, its support, the key numbers and the physics verdict, coloured), one row
per kinematic model, and one legend for the whole figure. Left limbs are blue and right limbs red, as in the book,
so the support and swing legs always differ; the support foot is shaded. Both centres of mass are drawn with
their ground projections: the book's lumped CoM (green square) and the full-inertia CoM (purple diamond) that
physics acts on, against the br-shrunk support rectangle (dashed green). Every render returns the PNG bytes and a
report of what was drawn (for ``--json`` and tests).
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from op2motion.kinematics.points import BodyPoints
from op2motion.robot.balance import COM_MODEL_FULL, support_polygon
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Side, Support, as_side

if TYPE_CHECKING:
    from matplotlib.artist import Artist

LEFT_COLOUR, RIGHT_COLOUR, BODY_COLOUR = "tab:blue", "tab:red", "black"
SIDE_COLOURS: tuple[tuple[Side, str], ...] = (("left", LEFT_COLOUR), ("right", RIGHT_COLOUR))
LUMPED_COLOUR, FULL_COLOUR, TARGET_COLOUR = "green", "tab:purple", "gold"
OK_COLOUR, BAD_COLOUR, UNKNOWN_COLOUR = "#1b7a1b", "#b3261e", "#555555"
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
_VIEWS = (("front (looking along -X)", 1, 2, ("Y left [m]", "Z up [m]")),
          ("side (looking along +Y)", 0, 2, ("X forward [m]", "Z up [m]")),
          ("top (looking down)", 0, 1, ("X forward [m]", "Y left [m]")))
DPI = 90
ROW_HEIGHT_IN = 5.2   # height of one row of views [in]


@dataclass(frozen=True)
class PoseFigure:
    """One row of a pose figure: body points (pose 0 is drawn), both CoMs [m], what to mark, and a note."""

    points: BodyPoints
    label: str
    com_lumped: np.ndarray
    com_full: np.ndarray | None = None
    br: float = 1.0
    target: Sequence[float] | None = None
    ghost: BodyPoints | None = None   # an earlier pose drawn in grey (e.g. before an arm IK step)
    note: str = ""
    double: bool = False              # double support: the support polygon is the hull of both soles


@dataclass(frozen=True)
class TitleBlock:
    """The text above a pose figure: a title, key numbers, and the physics verdict (``ok`` None: not checked)."""

    title: str
    lines: Sequence[str] = ()
    verdict: str = "not checked in physics"
    ok: bool | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def _pyplot() -> ModuleType:
    """matplotlib's pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(fig: Any) -> bytes:
    """The figure as PNG bytes; the figure is closed."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    _pyplot().close(fig)
    return buf.getvalue()


def _draw(ax: Any, xyz: dict[str, np.ndarray], fig: PoseFigure, spec: Spec, h: int | None, v: int | None) -> None:
    """The pose on ``ax`` (a matplotlib Axes: 3D when ``h`` is None, else the plane of axes ``h``, ``v``)."""
    def line(pts: np.ndarray, **kw: Any) -> None:
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
    for side, colour in SIDE_COLOURS:
        corners = fig.points.foot_corners(side)[0]
        ring = np.vstack([corners, corners[:1]])
        line(ring, color=colour, linewidth=1.5)
        if side == fig.points.support and (h, v) == (0, 1):
            ax.fill(ring[:, 0], ring[:, 1], color=colour, alpha=0.15)
    sp = fig.points.point(f"{fig.points.support}_sole")[0]
    if fig.double:      # the hull of both real soles
        polys = [(Support.DOUBLE.polygon({s: fig.points.foot_corners(s)[0] for s in SIDES}), FULL_COLOUR)]
    else:               # the book's rectangle (lumped CoM) and the real sole (full-inertia CoM), both shrunk by br
        foot = as_side(fig.points.support, "support")
        polys = [(support_polygon(spec, foot, fig.br, (sp[0], sp[1])), LUMPED_COLOUR),
                 (support_polygon(spec, foot, fig.br, (sp[0], sp[1]), com_model=COM_MODEL_FULL), FULL_COLOUR)]
    for poly, colour in polys:
        ring = np.vstack([poly, poly[:1]])
        line(np.column_stack([ring, np.full(len(ring), sp[2])]), color=colour, linestyle="--", linewidth=1)
    for com, colour, marker in ((fig.com_lumped, LUMPED_COLOUR, "s"), (fig.com_full, FULL_COLOUR, "D")):
        if com is None:
            continue
        com = np.asarray(com, dtype=float)
        line(np.array([com, [com[0], com[1], sp[2]]]), color=colour, linestyle=":", linewidth=1)
        line(com[None, :], color=colour, marker=marker, markersize=7, linestyle="none")
        line(np.array([[com[0], com[1], sp[2]]]), color=colour, marker="x", markersize=7, linestyle="none")
    if fig.target is not None:
        line(np.asarray(fig.target, dtype=float)[None, :], color=TARGET_COLOUR, marker="*", markersize=14,
             markeredgecolor="black", linestyle="none")


def _legend_handles(figures: Sequence[PoseFigure]) -> list[Artist]:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Line2D([], [], color=LEFT_COLOUR, lw=2, marker="o", ms=3, label="left limbs"),
               Line2D([], [], color=RIGHT_COLOUR, lw=2, marker="o", ms=3, label="right limbs"),
               Line2D([], [], color=BODY_COLOUR, lw=2, label="torso, pelvis, head"),
               Patch(color="grey", alpha=0.3, label="support foot")]
    if not all(f.double for f in figures):
        handles += [Line2D([], [], color=LUMPED_COLOUR, ls="--", label="book's foot rectangle (shrunk by br)"),
                    Line2D([], [], color=FULL_COLOUR, ls="--", label="real sole (shrunk by br)")]
    if any(f.double for f in figures):
        handles.append(Line2D([], [], color=FULL_COLOUR, ls="--", label="support polygon (both soles)"))
    handles.append(Line2D([], [], color=LUMPED_COLOUR, marker="s", ls="none", label="CoM, lumped (book masses)"))
    if any(f.com_full is not None for f in figures):
        handles.append(Line2D([], [], color=FULL_COLOUR, marker="D", ls="none", label="CoM, full inertia (physics)"))
    handles.append(Line2D([], [], color="grey", marker="x", ls="none", label="CoM ground projection"))
    if any(f.target is not None for f in figures):
        handles.append(Line2D([], [], color=TARGET_COLOUR, marker="*", ms=12, mec="black", ls="none", label="target"))
    if any(f.ghost is not None for f in figures):
        handles.append(Line2D([], [], color="grey", ls="--", label="initial pose"))
    return handles


def _row_views(fig: Any, grid: Any, r: int, pf: PoseFigure, spec: Spec, rows: int) -> None:
    """Row ``r`` of a pose figure: the front, side and top views and the 3D view of ``pf``."""
    xyz = {name: np.array(val) for name, val in pf.points.as_dict(0).items()}
    for c, (view, h, v, labels) in enumerate(_VIEWS):
        ax = fig.add_subplot(grid[r, c])
        _draw(ax, xyz, pf, spec, h, v)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        ax.grid(True, alpha=0.3)
        ax.set_title(f"{pf.label}: {view}" if c == 0 and rows > 1 else view, fontsize=10)
    ax3 = fig.add_subplot(grid[r, 3], projection="3d")
    _draw(ax3, xyz, pf, spec, None, None)
    pts = np.array(list(xyz.values()))
    centre, half = (pts.max(0) + pts.min(0)) / 2, (pts.max(0) - pts.min(0)).max() / 2 + 0.02
    for setter, k in ((ax3.set_xlim, 0), (ax3.set_ylim, 1), (ax3.set_zlim, 2)):
        setter(centre[k] - half, centre[k] + half)
    ax3.set_box_aspect((1, 1, 1))
    ax3.view_init(elev=18, azim=-135)
    ticks = np.array([-0.6, 0.0, 0.6]) * half     # away from the box's corners, where two axes' labels meet
    ax3.set_xticks(np.round(centre[0] + ticks, 2))
    ax3.set_yticks(np.round(centre[1] + ticks, 2))
    ax3.set_zticks(np.round(centre[2] + ticks, 2))
    ax3.tick_params(labelsize=8)
    ax3.set_xlabel("X forward [m]", labelpad=6)
    ax3.set_ylabel("Y left [m]", labelpad=6)
    ax3.zaxis.set_rotate_label(False)
    ax3.set_zlabel("Z up [m]", labelpad=8, rotation=90)
    ax3.set_title("3D" + (f" — {pf.note}" if pf.note else ""), fontsize=10)


class PoseCanvas:
    """A pose figure (see :func:`render_poses`) drawn in two steps: everything but the physics verdict when made,
    the verdict (top right, where nothing else is drawn) and the PNG in :meth:`finish`, so that a figure can be
    drawn while the pose's physics check runs. The bytes are those of drawing it in one go."""

    def __init__(self, figures: Sequence[PoseFigure], spec: Spec, block: TitleBlock):
        plt = _pyplot()
        self.figures, self.block = figures, block
        rows = len(figures)
        header = 0.75 + 0.2 * len(block.lines) + 0.35        # title, number lines, panel titles [in]
        footer = 1.25                                         # axis labels and the legend [in]
        self.height = height = ROW_HEIGHT_IN * rows + header + footer
        self.fig = fig = plt.figure(figsize=(19, height), dpi=DPI)
        grid = fig.add_gridspec(rows, 4, width_ratios=(1, 1, 1, 1.45), left=0.045, right=0.99,
                                top=1 - header / height, bottom=footer / height, wspace=0.28, hspace=0.35)
        for r, pf in enumerate(figures):
            _row_views(fig, grid, r, pf, spec, rows)
        top = 1 - 0.2 / height
        fig.text(0.045, top, block.title, fontsize=15, weight="bold", va="top")
        fig.text(0.045, top - 0.5 / height, "\n".join(block.lines), fontsize=10, va="top", family="monospace")
        self.handles = _legend_handles(figures)
        fig.legend(handles=self.handles, loc="lower center", ncol=min(len(self.handles), 6), fontsize=9,
                   frameon=False, bbox_to_anchor=(0.5, 0.02 / height))
        fig.canvas.draw()

    def finish(self, verdict: str, ok: bool | None) -> tuple[bytes, dict[str, Any]]:
        """Draw the physics ``verdict`` (``ok`` None: not checked) and return the PNG bytes and the report."""
        import matplotlib.image

        colour = UNKNOWN_COLOUR if ok is None else OK_COLOUR if ok else BAD_COLOUR
        fig, block = self.fig, self.block
        text = fig.text(0.99, 1 - 0.2 / self.height, verdict, fontsize=13, weight="bold", color=colour, va="top",
                        ha="right")
        fig.draw_artist(text)
        buf = io.BytesIO()       # as savefig writes it (it would draw the whole figure again first)
        matplotlib.image.imsave(buf, fig.canvas.buffer_rgba(), format="png", origin="upper", dpi=fig.dpi)
        self.close()
        report = {"title": block.title, "verdict": verdict, "stable": ok, "lines": list(block.lines),
                  "legend": [h.get_label() for h in self.handles],
                  "rows": [{"model": f.label, "note": f.note, "com_lumped": [float(x) for x in f.com_lumped],
                            "com_full": None if f.com_full is None else [float(x) for x in f.com_full],
                            "target": None if f.target is None else [float(x) for x in f.target],
                            "initial_pose": f.ghost is not None} for f in self.figures], **block.extra}
        return buf.getvalue(), report

    def close(self) -> None:
        """Let the figure go (after :meth:`finish`, or when it will not be finished)."""
        _pyplot().close(self.fig)


def render_poses(figures: Sequence[PoseFigure], spec: Spec, block: TitleBlock) -> tuple[bytes, dict[str, Any]]:
    """Each pose as a row of front, side, top and 3D views under a title block; returns (PNG bytes, report)."""
    return PoseCanvas(figures, spec, block).finish(block.verdict, block.ok)


def render_cost_curve(attempts: Sequence[Sequence[float] | np.ndarray],
                      hand_errors: Sequence[Sequence[float] | np.ndarray], threshold_m: float, title: str,
                      chosen: int, final: tuple[float, float, str] | None = None) -> bytes:
    """The PSO's best cost after each iteration for every attempt (book fig. 2.43), log scale, with the hand
    error of the best particle and the reach threshold; ``chosen`` marks the attempt that was kept; ``final``
    (cost, hand error [m], method) is the result after the refinement, drawn one step after the last iteration."""
    plt = _pyplot()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 4.6))
    for k, (history, errors) in enumerate(zip(attempts, hand_errors)):
        it = np.arange(1, len(history) + 1)
        style = dict(lw=2.2 if k == chosen else 1.2, alpha=1.0 if k == chosen else 0.6)
        label = f"attempt {k + 1}" + (" (kept)" if k == chosen else "")
        ax.semilogy(it, np.maximum(np.asarray(history, dtype=float), 1e-9), label=label, **style)
        ax2.semilogy(np.arange(1, len(errors) + 1), np.maximum(np.asarray(errors, dtype=float) * 1000, 1e-6),
                     label=label, **style)
    if final is not None and attempts:
        after = len(attempts[chosen]) + 1
        label = f"after refinement ({final[2]})"
        ax.semilogy([after], [max(final[0], 1e-9)], marker="*", ms=12, color="k", ls="none", label=label)
        ax2.semilogy([after], [max(final[1] * 1000, 1e-6)], marker="*", ms=12, color="k", ls="none", label=label)
    ax.axhline(100, color="grey", ls=":", lw=1)
    ax.text(1, 100, " a penalty (100) is active above this line", va="bottom", fontsize=8, color="grey")
    ax.set_xlabel("iteration")
    ax.set_ylabel("best cost (log)")
    ax.set_title("cost = 100·[swing foot too low] + 100·[CoM outside the sole or torso sags too far]\n"
                 "+ 100·[links too close] + |hand − target| [m] + 10·violation + small tie-breakers", fontsize=9)
    ax2.axhline(threshold_m * 1000, color=BAD_COLOUR, ls="--", lw=1.2,
                label=f"reach threshold {threshold_m * 1000:g} mm")
    ax2.set_xlabel("iteration")
    ax2.set_ylabel("hand distance to target of the best particle [mm] (log)")
    ax2.set_title("hand error (the refinement then brings it within 1 mm)", fontsize=9)
    for a in (ax, ax2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(title)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.11, top=0.8, wspace=0.22)   # fixed: tight_layout took 0.3 s
    return _png(fig)


def margin_panel_png(fig: Any, ax: Any, t: np.ndarray, margin_m: np.ndarray, colour: str,
                     right: float | None = None) -> bytes:
    """Draw the ZMP margin [m] against time [s] (in mm) on ``ax`` as the last panel, and the figure's PNG
    (``right``: the share of the width the panels keep, leaving the rest for a legend beside them)."""
    ax.plot(t, margin_m * 1000, color=colour, lw=1.0)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("ZMP margin [mm]")
    ax.grid(alpha=0.3)
    fig.tight_layout(rect=(0.0, 0.0, right or 1.0, 1.0))
    return _png(fig)
