"""``op2motion bench``'s figures timed from the shell: what a user waits for, start-up included.

Each command runs as its own process (this interpreter, ``-m op2motion``) in a scratch folder, ``runs`` times; the
median wall time is reported with a check that the run did its job (exit 0, its files written, its verdict).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Sequence

WALL_TIMEOUT_S = 600.0


def _timed(argv: list[str], cwd: Path) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "op2motion", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=WALL_TIMEOUT_S)
    return time.perf_counter() - t0, done


def _median(argv: list[str], runs: int) -> tuple[float, dict[str, Any], bool]:
    """Median wall time [s] of ``runs`` fresh runs, the last run's JSON and whether every run exited 0."""
    times, doc, ok = [], {}, True
    for _ in range(runs):
        with tempfile.TemporaryDirectory(prefix="op2motion-bench-") as tmp:
            seconds, done = _timed(argv, Path(tmp))
            times.append(seconds)
            ok = ok and done.returncode == 0
            if "--json" in argv and done.returncode == 0:
                doc = json.loads(done.stdout)
    return statistics.median(times), doc, ok


def wall_figures(runs: int = 3, library: bool = True, grid: Sequence[str] = ()) -> dict[str, Any]:
    """``help_wall_s``, ``optimize_wall_s``, ``optimize_validate_wall_s`` (default problem) and, with ``library``,
    ``library_poses_per_min`` (``--validate --workers 2`` on the default grid, or the ``grid`` flags given), each
    with its check."""
    help_s, _, help_ok = _median(["--help"], runs)
    opt_s, opt, opt_ok = _median(["optimize", "--json"], runs)
    val_s, val, val_ok = _median(["optimize", "--validate", "--json"], runs)
    out: dict[str, Any] = {
        "help_wall_s": round(help_s, 3), "optimize_wall_s": round(opt_s, 3),
        "optimize_validate_wall_s": round(val_s, 3), "wall_runs": runs, "check_help_ok": help_ok,
        "check_optimize_reached": bool(opt_ok and opt.get("reached")),
        "check_optimize_validate_stands": bool(val_ok and (val.get("validation") or {}).get("stable")),
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
