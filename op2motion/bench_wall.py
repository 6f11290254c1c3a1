"""``op2motion bench``'s figures timed from the shell: what a user waits for, start-up included.

Each command runs as the user runs it: the ``op2motion`` program installed beside this interpreter (else
``python -m op2motion``), in a fresh process, in a scratch folder, ``runs`` times, with this process's op2motion
first on its path (so the code timed is the code running the bench). A run is timed from its start until it has
exited: every file it names is written by then, and the check says so. The best of the runs is the figure (on a
shared machine other work only ever adds time) and the median is reported beside it.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

WALL_TIMEOUT_S = 600.0


def program() -> list[str]:
    """The command a user types to start op2motion: the console script beside this interpreter, or ``python -m
    op2motion`` where there is none (a source checkout run without installing)."""
    script = Path(sys.executable).with_name("op2motion")
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, "-m", "op2motion"]


def _environment() -> dict[str, str]:
    """This environment with the folder this op2motion was imported from first on the path."""
    here = str(Path(__file__).resolve().parents[1])
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": here + (os.pathsep + path if path else "")}


def _timed(argv: list[str], cwd: Path) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    done = subprocess.run([*program(), *argv], cwd=cwd, capture_output=True, text=True, timeout=WALL_TIMEOUT_S,
                          env=_environment())
    return time.perf_counter() - t0, done


def files_written(doc: dict[str, Any], cwd: Path) -> bool:
    """Does every file a result names (its ``files``) exist, and is it not empty, in ``cwd``?"""
    files = doc.get("files") or {}
    return bool(files) and all((cwd / path).is_file() and (cwd / path).stat().st_size > 0 for path in files.values())


@dataclass
class Runs:
    """Wall times [s] of fresh runs of one command, the last run's JSON (``--json`` runs), whether every run exited
    0 and whether every run had written every file it named by the time it exited."""

    seconds: list[float] = field(default_factory=list)
    doc: dict[str, Any] = field(default_factory=dict)
    ok: bool = True
    files_ok: bool = True

    @property
    def best(self) -> float:
        """The quickest run [s]."""
        return min(self.seconds)

    @property
    def median(self) -> float:
        """The median run [s]."""
        return statistics.median(self.seconds)


def shell_runs(argv: list[str], runs: int) -> Runs:
    """``runs`` fresh runs of ``op2motion ARGV`` (see the module docstring), each in its own scratch folder."""
    out = Runs()
    for _ in range(runs):
        with tempfile.TemporaryDirectory(prefix="op2motion-bench-") as tmp:
            seconds, done = _timed(argv, Path(tmp))
            out.seconds.append(seconds)
            out.ok = out.ok and done.returncode == 0
            if "--json" in argv and done.returncode == 0:
                out.doc = json.loads(done.stdout)
                out.files_ok = out.files_ok and files_written(out.doc, Path(tmp))
    return out


def wall_figures(runs: int = 3, library: bool = True, grid: Sequence[str] = ()) -> dict[str, Any]:
    """``cli_start_s`` (``--help``), ``main_job_s`` (``optimize``, the default problem, figures written) and
    ``main_job_validate_s`` (``optimize --validate``): the best of ``runs``, with their medians (also under the
    older names ``help_wall_s``, ``optimize_wall_s``, ``optimize_validate_wall_s``) and checks; with ``library``,
    ``library_poses_per_min`` (``--validate --workers 2`` on the default grid, or the ``grid`` flags given)."""
    start, job, validated = (shell_runs(["--help"], runs), shell_runs(["optimize", "--json"], runs),
                             shell_runs(["optimize", "--validate", "--json"], runs))
    out: dict[str, Any] = {
        "cli_start_s": round(start.best, 3), "main_job_s": round(job.best, 3),
        "main_job_validate_s": round(validated.best, 3), "cli_start_median_s": round(start.median, 3),
        "main_job_median_s": round(job.median, 3), "main_job_validate_median_s": round(validated.median, 3),
        "help_wall_s": round(start.median, 3), "optimize_wall_s": round(job.median, 3),
        "optimize_validate_wall_s": round(validated.median, 3), "wall_runs": runs,
        "wall_program": " ".join(Path(p).name for p in program()), "check_help_ok": start.ok,
        "check_optimize_reached": bool(job.ok and job.doc.get("reached")),
        "check_optimize_validate_stands": bool(validated.ok and (validated.doc.get("validation") or {}).get("stable")),
        "check_main_job_files_written": job.files_ok and validated.files_ok,
    }
    if library:
        with tempfile.TemporaryDirectory(prefix="op2motion-bench-") as tmp:
            seconds, done = _timed(["library", "build", *grid, "--validate", "--workers", "2", "--out", "lib",
                                    "--json"], Path(tmp))
        summary = json.loads(done.stdout) if done.returncode == 0 else {}
        solved = int(summary.get("solved", 0))
        out.update(library_poses_per_min=round(60.0 * solved / seconds, 1), library_wall_s=round(seconds, 1),
                   check_library_standing_poses=solved, check_library_targets=int(summary.get("targets", 0)))
    return out
