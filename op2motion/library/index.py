"""The library index: one row per target (reached or not, with its reason), as ``index.json`` and ``index.csv``.

Both files are rewritten atomically after every result and on every exit path, so the index always describes the
pose files present. A pose file written just before a kill has no row yet; :func:`load_index` rebuilds its row
from the file's provenance (hand, support, br, target, seconds), so a resumed build's index is complete.
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from op2motion.errors import InputError, Op2MotionError
from op2motion.fileio import write_atomic
from op2motion.formats.posefile import read_pose
from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

INDEX_JSON, INDEX_CSV = "index.json", "index.csv"
POSE_GLOB = "reach-*.json"


@dataclass(frozen=True)
class IndexRow:
    """One target of the library: what was asked, what came out, and the pose file (empty when none)."""

    name: str
    hand: str
    support: Support | Side
    br: float
    x: float
    y: float
    z: float
    reached: bool
    validated: bool = False
    stable: bool | None = None
    hand_error_m: float | None = None
    stability_margin_m: float | None = None
    stability_margin_full_m: float | None = None
    seed: int | None = None
    attempts: int | None = None
    seconds: float | None = None
    message: str = ""
    file: str = ""
    robust_passed: int | None = None
    robust_runs: int | None = None
    robust_worst: str = ""

    def as_dict(self) -> JsonObject:
        """JSON-ready dict."""
        return asdict(self)

    @classmethod
    def from_dict(cls, doc: Any) -> "IndexRow":
        """A row from its JSON form; unknown keys are ignored, missing required ones are an error."""
        if not isinstance(doc, dict):
            raise TypeError(f"expected an object, got {type(doc).__name__}")
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in doc.items() if k in known})


FIELDS = tuple(f.name for f in fields(IndexRow))


def write_index(out_dir: Path, rows: dict[str, IndexRow]) -> None:
    """Rewrite ``index.json`` and ``index.csv`` (rows sorted by name) atomically."""
    ordered = [rows[k].as_dict() for k in sorted(rows)]
    write_atomic(out_dir / INDEX_JSON, json.dumps(ordered, indent=1) + "\n")
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=FIELDS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(ordered)
    write_atomic(out_dir / INDEX_CSV, buf.getvalue())


def _row_from_pose(path: Path, spec: Spec) -> IndexRow | None:
    """The index row of a pose file, rebuilt from its provenance and metrics (None if unreadable)."""
    try:
        pose = read_pose(path, spec)
        prov, metrics = dict(pose.provenance), dict(pose.metrics)
        x, y, z = (float(v) for v in prov["target_m"])
        return IndexRow(pose.name, str(prov["hand"]), pose.support, float(prov["br"]), x, y, z, True,
                        bool(metrics.get("validated", False)), metrics.get("stable"), metrics.get("hand_error_m"),
                        metrics.get("stability_margin_m"), metrics.get("stability_margin_full_m"), prov.get("seed"),
                        metrics.get("attempts"), prov.get("seconds"), "recovered from the pose file", path.name)
    except (Op2MotionError, KeyError, TypeError, ValueError):
        return None


def reconcile(out_dir: Path, rows: dict[str, IndexRow], spec: Spec) -> dict[str, IndexRow]:
    """``rows`` made to describe the pose files present: rows whose file is gone are dropped, files without a row
    get one rebuilt from their provenance."""
    rows = {name: row for name, row in rows.items() if not row.file or (out_dir / row.file).is_file()}
    for path in sorted(out_dir.glob(POSE_GLOB)):
        if path.stem not in rows or rows[path.stem].file != path.name:
            row = _row_from_pose(path, spec)
            if row is not None:
                rows[row.name] = row
    return rows


def load_index(out_dir: Path, spec: Spec) -> dict[str, IndexRow]:
    """The rows of an existing library folder: its index, reconciled with the pose files present (see
    :func:`reconcile`). Leftover temp files of interrupted writes are removed."""
    for stale in out_dir.glob(".*.tmp"):  # temp files of writes that a kill interrupted (never renamed into place)
        stale.unlink(missing_ok=True)
    rows: dict[str, IndexRow] = {}
    index = out_dir / INDEX_JSON
    if index.is_file():
        try:
            for doc in json.loads(index.read_text(encoding="utf-8")):
                row = IndexRow.from_dict(doc)
                rows[row.name] = row
        except (json.JSONDecodeError, UnicodeDecodeError, TypeError, ValueError) as exc:
            raise InputError(f"not a library index ({exc}); move it away to rebuild", str(index)) from None
    return reconcile(out_dir, rows, spec)
