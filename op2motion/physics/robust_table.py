"""The robustness family's runs as people read them (a Markdown table and a summary line) and as JSON."""

from __future__ import annotations

from typing import Any, Callable

from op2motion.jsonout import JsonObject
from op2motion.physics.report import RunMeasures
from op2motion.physics.robust import RobustReport, RobustRun


def robust_markdown(report: RobustReport, head: list[str], cells: Callable[[RobustRun], list[str]],
           badness: Callable[[RobustRun], float]) -> str:
    """The family's runs as a Markdown table (member, engine, the ``head`` columns from ``cells(run)``, verdict)
    and a summary line: runs passed, the worst by ``badness``, the failures by kind, the engines' agreement."""
    lines = ["| member | engine | " + " | ".join(head) + " | verdict |", "|---" * (len(head) + 3) + "|"]
    for run in report.runs:
        verdict = "passes" if run.passed else f"**fails**: {run.problem}"
        lines.append(f"| {run.member.name} | {run.engine} | " + " | ".join(cells(run)) + f" | {verdict} |")
    worst = report.worst(badness)
    reasons = ", ".join(f"{reason} ×{n}" for reason, n in report.failures.most_common()) or "none"
    agree = "the engines agree on every member" if not report.disagreements else (
        "the engines differ on " + "; ".join(report.disagreements))
    lines += ["", f"Passed {sum(r.passed for r in report.runs)}/{len(report.runs)} runs ({report.pass_rate:.0%}); "
                  f"worst: {worst.member.name} in {worst.engine} ({worst.problem or 'passed'}); failures: "
                  f"{reasons}; {agree}."]
    return "\n".join(lines)


def pose_robust_table(report: RobustReport) -> str:
    """A held pose's family as Markdown: support margin, sag, pushes, verdict per run; the summary line."""
    def cells(run: RobustRun) -> list[str]:
        r = run.report
        pushes = f"{sum(p.stable for p in r.pushes)}/{len(r.pushes)}" if r.pushes else "–"
        return [f"{r.run.support_margin_m * 1000:.0f} mm", f"{r.run.load_tilt_deg:.1f}°", pushes]

    return robust_markdown(report, ["margin", "sag", "pushes survived"], cells,
                  lambda run: -run.report.run.support_margin_m + (1.0 if not run.passed else 0.0))


def robust_summary(report: RobustReport) -> JsonObject:
    """The family's JSON: ``pass_rate``, ``passed``, ``failures`` {reason: runs}, ``disagreements`` [member] and
    ``runs`` [{``member``, ``engine``, ``passed``, ``problem``, ``reasons``, ``support_margin_m``, plus the plan's own
    measures' columns (:meth:`.report.RunMeasures.robust_row`; a walk's: speed, drift, heading, distance)}]."""
    runs = []
    for run in report.runs:
        row: dict[str, Any] = {"member": run.member.name, "engine": run.engine, "passed": run.passed,
                               "problem": run.problem, "reasons": run.report.run.reasons,
                               "support_margin_m": round(run.report.run.support_margin_m, 5)}
        measures: RunMeasures | None = run.report.run.walk
        if measures is not None:
            row.update(measures.robust_row())
        runs.append(row)
    return {"pass_rate": round(report.pass_rate, 4), "passed": report.passed, "failures": dict(report.failures),
            "disagreements": report.disagreements, "runs": runs}
