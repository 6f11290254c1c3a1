"""``op2motion bench``'s figures timed from the shell: what a user waits for, start-up included.

Each command runs as the user runs it: the ``op2motion`` program installed beside this interpreter (else
``python -m op2motion``), in a fresh process, in a scratch folder, ``runs`` times, with this process's op2motion
first on its path (so the code timed is the code running the bench). A run is timed from its start until it has
exited (every file it names is written by then, and the check says so), and until the first line of its answer
(``optimize`` prints its result while its figures are still being drawn). The best of the runs is the figure (on a
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

from op2motion.errors import Op2MotionError
from op2motion.jsonout import JsonObject

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


def _timed(argv: list[str], cwd: Path) -> tuple[float, subprocess.CompletedProcess[str]]:
    t0 = time.perf_counter()
    done = subprocess.run([*program(), *argv], cwd=cwd, capture_output=True, text=True, timeout=WALL_TIMEOUT_S,
                          env=_environment())
    return time.perf_counter() - t0, done


def _run(argv: list[str], cwd: Path) -> tuple[float, float, int, str]:
    """One run of ``op2motion ARGV`` in ``cwd``: the seconds until its first line of output and until it exited,
    its exit code and its output."""
    with tempfile.TemporaryFile() as errors:
        t0 = time.perf_counter()
        proc = subprocess.Popen([*program(), *argv], cwd=cwd, stdout=subprocess.PIPE, stderr=errors, text=True,
                                env=_environment())
        if proc.stdout is None:                      # asked for a pipe: never the case, but a typed way to say so
            raise Op2MotionError("expected the program's output on a pipe")
        with proc.stdout:
            first = proc.stdout.readline()
            answer = time.perf_counter() - t0
            rest = proc.stdout.read()                # through the same buffer as the first line (errors: a file)
        code = proc.wait(timeout=WALL_TIMEOUT_S)
        return answer, time.perf_counter() - t0, code, first + rest


def files_written(text: str, cwd: Path) -> bool:
    """Does every file the output's ``wrote`` line names exist, and is it not empty, in ``cwd``?"""
    named = [line.strip().removeprefix("wrote ").split(", ") for line in text.splitlines()
             if line.strip().startswith("wrote ")]
    return bool(named) and all((cwd / path).is_file() and (cwd / path).stat().st_size > 0 for path in named[-1])


@dataclass
class Runs:
    """Fresh runs of one command: the seconds until each printed its first line (``answers``) and exited
    (``seconds``), the last run's output, whether every run exited 0, and whether every run had written every file
    it named by the time it exited."""

    seconds: list[float] = field(default_factory=list)
    answers: list[float] = field(default_factory=list)
    text: str = ""
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


def shell_runs(argv: list[str], runs: int, files: bool = False, folders: Sequence[str] = ()) -> Runs:
    """``runs`` fresh runs of ``op2motion ARGV`` (see the module docstring), each in its own scratch folder with
    the sub-folders ``folders`` made; ``files``: check the files its output names."""
    out = Runs()
    for _ in range(runs):
        with tempfile.TemporaryDirectory(prefix="op2motion-bench-") as tmp:
            for folder in folders:
                (Path(tmp) / folder).mkdir(parents=True)
            answer, seconds, code, out.text = _run(argv, Path(tmp))
            out.answers.append(answer)
            out.seconds.append(seconds)
            out.ok = out.ok and code == 0
            out.files_ok = out.files_ok and (not files or files_written(out.text, Path(tmp)))
    return out


def wall_figures(runs: int = 3, library: bool = True, grid: Sequence[str] = ()) -> JsonObject:
    """``cli_start_s`` (``--help``), ``main_job_s`` (``optimize``, the default problem, its figures written) and
    ``main_job_validate_s`` (``optimize --validate``), each the best of ``runs`` to the command's exit, beside the
    median and the best time to the first line of the answer (``*_answer_s``: the result is printed while the
    figures are drawn), with their checks; the medians also under the older names ``help_wall_s``,
    ``optimize_wall_s``, ``optimize_validate_wall_s``. With ``library``: ``library_poses_per_min``
    (``--validate --workers 2`` on the default grid, or the ``grid`` flags given)."""
    start = shell_runs(["--help"], runs)
    # in a folder that has its poses/ (as after a first run): optimize answers there before its figures are drawn
    job = shell_runs(["optimize"], runs, files=True, folders=["poses"])
    validated = shell_runs(["optimize", "--validate"], runs, files=True, folders=["poses"])
    out: dict[str, Any] = {
        "cli_start_s": round(start.best, 3), "main_job_s": round(job.best, 3),
        "main_job_validate_s": round(validated.best, 3), "main_job_answer_s": round(min(job.answers), 3),
        "main_job_validate_answer_s": round(min(validated.answers), 3), "cli_start_median_s": round(start.median, 3),
        "main_job_median_s": round(job.median, 3), "main_job_validate_median_s": round(validated.median, 3),
        "help_wall_s": round(start.median, 3), "optimize_wall_s": round(job.median, 3),
        "optimize_validate_wall_s": round(validated.median, 3), "wall_runs": runs,
        "wall_program": " ".join(Path(p).name for p in program()), "check_help_ok": start.ok,
        "check_optimize_reached": job.ok and ": reached: " in job.text,
        "check_optimize_validate_stands": validated.ok and "): STABLE" in validated.text,
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
