"""``op2motion library build``: solve a grid of reach targets (hands x supports x br x targets) in parallel.

Each target is one posture solve in a worker process; reached poses are written as pose files (atomically) and
every target, reached or not, gets a row in ``index.json`` and ``index.csv`` (rewritten atomically after each
result). A build that is interrupted and run again skips the targets its index already holds, and pose files that
were written just before the interruption; nothing is ever half-written.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import InputError, PoseFileError
from ..export.library import read_pose, write_pose
from ..fileio import write_atomic
from ..spec import Spec, load_spec
from .cost import PostureProblem
from .pso import PSOSettings
from .solve import optimize_posture

INDEX_FIELDS = ("name", "hand", "support", "br", "x", "y", "z", "reached", "hand_error_m", "stability_margin_m",
                "validated", "stable", "seconds", "message", "file")


@dataclass(frozen=True)
class Job:
    """One grid point."""

    hand: str
    support: str
    br: float
    target: tuple[float, float, float]

    @property
    def problem(self) -> PostureProblem:
        """The posture problem of this grid point."""
        return PostureProblem(self.support, self.hand, self.target, self.br)

    @property
    def name(self) -> str:
        """Pose name of this grid point, e.g. ``reach-ll-100-50-70-br70``."""
        return self.problem.name


def axis(start: float, stop: float, count: float, name: str) -> list[float]:
    """``count`` evenly spaced values from ``start`` to ``stop`` [m]."""
    if not (np.isfinite(start) and np.isfinite(stop) and float(count).is_integer() and count >= 1):
        raise InputError(f"{name}: expected START STOP COUNT with COUNT >= 1, got {start} {stop} {count}")
    return [float(v) for v in np.linspace(start, stop, int(count))]


def grid_jobs(hands: Sequence[str], supports: Sequence[str], brs: Sequence[float], xs: Sequence[float],
              ys: Sequence[float], zs: Sequence[float]) -> list[Job]:
    """All combinations, validated."""
    jobs = [Job(h, s, float(b), (float(x), float(y), float(z)))
            for h, s, b, x, y, z in itertools.product(hands, supports, brs, xs, ys, zs)]
    for job in jobs:
        job.problem.validated()
    return jobs


def _solve(job: Job, spec_path: str | None, settings: PSOSettings, validate: bool, out_dir: str) -> dict[str, Any]:
    """Worker: solve one job, write its pose file if reached, return its index row."""
    spec = load_spec(spec_path)
    t0 = time.perf_counter()
    res = optimize_posture(job.problem, spec, settings, restarts=1)
    row: dict[str, Any] = {"name": job.name, "hand": job.hand, "support": job.support, "br": job.br,
                           "x": job.target[0], "y": job.target[1], "z": job.target[2], "reached": res.reached,
                           "hand_error_m": round(float(res.terms.hand_error[0]), 6),
                           "stability_margin_m": round(float(res.terms.margin[0]), 6), "validated": False,
                           "stable": None, "message": res.message, "file": ""}
    if res.reached:
        pose = res.pose(job.name, spec, {"command": "op2motion library build"})
        if validate:
            from ..physics import validate_servo

            v = validate_servo(pose.servo, pose.support, spec, 2.0)
            row["validated"], row["stable"] = True, v.stable
        path = Path(out_dir) / f"{job.name}.json"
        write_pose(pose, path, spec)
        row["file"] = path.name
    row["seconds"] = round(time.perf_counter() - t0, 3)
    return row


def _write_index(out_dir: Path, rows: dict[str, dict[str, Any]]) -> None:
    ordered = [rows[k] for k in sorted(rows)]
    write_atomic(out_dir / "index.json", json.dumps(ordered, indent=1) + "\n")
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=INDEX_FIELDS, extrasaction="ignore")
    writer.writeheader()
    writer.writerows(ordered)
    write_atomic(out_dir / "index.csv", buf.getvalue())


def _existing(out_dir: Path, spec: Spec) -> dict[str, dict[str, Any]]:
    for stale in out_dir.glob(".*.tmp"):  # temp files of writes that a kill interrupted (never renamed into place)
        stale.unlink(missing_ok=True)
    rows: dict[str, dict[str, Any]] = {}
    index = out_dir / "index.json"
    if index.is_file():
        try:
            for row in json.loads(index.read_text(encoding="utf-8")):
                rows[row["name"]] = row
        except (json.JSONDecodeError, KeyError, TypeError) as exc:
            raise InputError(f"{index}: not a library index ({exc}); move it away to rebuild") from None
    for path in out_dir.glob("reach-*.json"):  # poses written just before an interruption
        if path.stem not in rows:
            try:
                pose = read_pose(path, spec)
            except PoseFileError:
                continue
            m = pose.metrics
            rows[path.stem] = {"name": path.stem, "reached": True, "file": path.name, "validated": False,
                               "stable": None, "hand_error_m": m.get("hand_error_m"),
                               "stability_margin_m": m.get("stability_margin_m"), "message": "recovered"}
    return rows


def build_library(jobs: Sequence[Job], spec: Spec, out_dir: str | Path, settings: PSOSettings = PSOSettings(),
                  workers: int = 0, validate: bool = False, spec_path: str | None = None,
                  on_done: Callable[[dict[str, Any]], Any] | None = None) -> dict[str, Any]:
    """Solve every job not already in ``out_dir``'s index; returns the build summary."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = _existing(out, spec)
    todo = [j for j in jobs if j.name not in rows]
    t0 = time.perf_counter()
    workers = workers or max(1, os.cpu_count() or 1)
    if todo:
        ctx = multiprocessing.get_context("spawn")  # fresh interpreters: no inherited threads or pyswarms state
        with ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx) as pool:
            futures = [pool.submit(_solve, j, spec_path, settings, validate, str(out)) for j in todo]
            for future in as_completed(futures):
                row = future.result()
                rows[row["name"]] = row
                _write_index(out, rows)
                if on_done is not None:
                    on_done(row)
    elif not (out / "index.json").is_file():
        _write_index(out, rows)
    wanted = {j.name for j in jobs}
    done = [rows[n] for n in wanted if n in rows]
    return {"solved": sum(1 for r in done if r.get("reached")), "failed": sum(1 for r in done if not r.get("reached")),
            "skipped": len(jobs) - len(todo), "targets": len(jobs), "seconds": round(time.perf_counter() - t0, 2),
            "index": str(out / "index.json")}
