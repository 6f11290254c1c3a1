"""The Pareto figure of a tuning study (``op2motion tune ... --plot``): every finished trial by speed and margin."""

from __future__ import annotations

from typing import Any, Sequence

from op2motion.figures.draw import _png, _pyplot


def render_pareto(result: Any, front_rows: Sequence[Any], min_margin: float, unit: str) -> bytes:
    """PNG bytes: the trials that held on the search's bodies (blue), those that did not (grey: a fall or a bound
    ended them, plotted at their margin then), the Pareto front (``front_rows``, a line), the least margin a chosen
    point needs (dotted) and the point chosen after verification (star); ``result`` is a
    :class:`~op2motion.tune.run.TuneResult`."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    held = [r for r in result.table if r.outcome is not None and r.outcome.passed]
    failed = [r for r in result.table if r.outcome is not None and not r.outcome.passed]
    ax.scatter([r.outcome.speed for r in failed], [max(r.outcome.margin, -1.0) for r in failed], s=12,
               color="0.7", label=f"did not hold ({len(failed)})")
    ax.scatter([r.outcome.speed for r in held], [r.outcome.margin for r in held], s=16, color="tab:blue",
               label=f"held on the search's bodies ({len(held)})")
    front = sorted((r.outcome for r in front_rows if r.outcome is not None), key=lambda o: o.speed)
    if front:
        ax.plot([o.speed for o in front], [o.margin for o in front], "-", color="tab:blue", lw=1.0,
                label="Pareto front")
    ax.axhline(min_margin, color="k", lw=0.6, ls=":", label=f"least margin chosen from ({min_margin:g})")
    for number, _ in result.rejected:
        row = next(r for r in result.table if r.number == number)
        ax.scatter([row.outcome.speed], [row.outcome.margin], marker="x", s=60, color="tab:red")
    if result.chosen is not None and result.chosen.outcome is not None:
        ax.scatter([result.chosen.outcome.speed], [result.chosen.outcome.margin], marker="*", s=220,
                   color="tab:orange", zorder=5, label=f"chosen (verified: {result.verified_speed:.3f} {unit})")
    ax.set_xlabel(f"nominal speed [{unit}] (the slower engine)")
    ax.set_ylabel("margin: least share of a bound left")
    ax.set_ylim(-1.05, 1.05)
    ax.set_title(f"tune {result.kind} {result.direction}: {len(result.table)} trials"
                 + (f", {len(result.rejected)} rejected in verification (x)" if result.rejected else ""))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return _png(fig)
