"""One library target solved by a worker (a process of the pool, or a Ray task), and the driver's record of it.

:func:`solve_job` runs the posture workflow (:func:`op2motion.workflow.solve`) on one target and returns its index
row and, when reached, the pose file's text; :class:`JobRecorder` is the only writer (pose files atomically, then the
index). Shared by the process pool (:mod:`.build`) and Ray (:mod:`.cluster`).
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

from op2motion.errors import Op2MotionError
from op2motion.fileio import write_atomic
from op2motion.formats.posefile import pose_to_json
from op2motion.library.grid import Job
from op2motion.library.index import IndexRow, write_index
from op2motion.posture.pso import PSOSettings
from op2motion.robot.spec import Spec
from op2motion.robot.specfile import load_spec, parse_spec
from op2motion.workflow import DEFAULT_RESTARTS, Validate, solve


@dataclass(frozen=True)
class BuildSettings:
    """How each target is solved: PSO settings, restarts, the physics check of each reached pose (None: none) and
    whether a pose that stands is also held on every member of the robustness family (``robust``, in the check's
    engine)."""

    pso: PSOSettings = PSOSettings()
    restarts: int = DEFAULT_RESTARTS
    validate: Validate | None = None
    robust: bool = False


def _row(job: Job, reached: bool, message: str, **extra: Any) -> IndexRow:
    x, y, z = job.target
    return IndexRow(job.name, job.hand, job.support, job.br, x, y, z, reached, message=message, **extra)


def solve_job(task: tuple[Job, str | None, str, BuildSettings, str | None]) -> tuple[IndexRow, str | None]:
    """Worker: solve one target; returns its index row and, when reached, the pose file text. The task names the
    spec by its file (same machine) or carries its text (another machine), with its SHA-256."""
    job, spec_path, sha, settings, text = task
    t0 = time.perf_counter()
    try:
        spec = _worker_spec(text) if text is not None else load_spec(spec_path)
        if spec.sha256 != sha:
            return _row(job, False, "error: the spec file changed during the build"), None
        out = solve(job.problem, spec, settings.pso, restarts=settings.restarts, validate=settings.validate)
    except Op2MotionError as exc:
        return _row(job, False, f"error: {exc}"), None
    r, v = out.result, out.validation
    seconds = round(time.perf_counter() - t0, 3)
    row = _row(job, out.ok, out.message, validated=v is not None, stable=None if v is None else v.stable,
               hand_error_m=round(r.hand_error_m, 6), stability_margin_m=round(r.margin_lumped_m, 6),
               stability_margin_full_m=round(r.margin_full_m, 6), seed=r.settings.seed, attempts=r.attempts,
               seconds=seconds, file=f"{job.name}.json" if out.ok else "")
    if not out.ok:
        return row, None
    pose = out.pose(job.name, spec, {"command": "op2motion library build", "seconds": seconds})
    if settings.robust and settings.validate is not None:
        row = _robust_row(row, pose.servo, job, spec, settings.validate)
    return row, pose_to_json(pose, spec)


@functools.lru_cache(maxsize=4)
def _worker_spec(text: str) -> Spec:
    return parse_spec(text)


def _robust_row(row: IndexRow, servo: Any, job: Job, spec: Spec, validate: Validate) -> IndexRow:
    """``row`` with the pose held on every member of the robustness family: runs passed, runs, the worst one."""
    from op2motion.physics import Schedule, robust_check

    report = robust_check(lambda: Schedule.hold(servo, job.support, spec, validate.seconds), spec,
                          (validate.engine,))
    failed = [r for r in report.runs if not r.passed]
    worst = f"{failed[0].member.name}: {failed[0].problem}" if failed else ""
    return replace(row, robust_passed=len(report.runs) - len(failed), robust_runs=len(report.runs),
                   robust_worst=worst)


class JobRecorder:
    """The driver's side of a build: each finished target's pose file (atomically), then the index."""

    def __init__(self, out: Path, rows: dict[str, IndexRow], on_done: Callable[[IndexRow], Any] | None):
        self.out, self.rows, self.on_done = out, rows, on_done

    def __call__(self, row: IndexRow, pose_text: str | None) -> None:
        if pose_text is not None:
            write_atomic(self.out / row.file, pose_text)
        self.rows[row.name] = row
        write_index(self.out, self.rows)
        if self.on_done is not None:
            self.on_done(row)
