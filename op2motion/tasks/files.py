"""The file tasks: poses to a ROBOTIS action file, a Webots motion or CSV (``export``); an action page to a pose, or
the pages listed (``import-action``); a motion file to chained action pages, Webots or CSV (``motion export``); the
URDF (``urdf``). Each returns a :class:`~.result.TaskResult` whose output the caller writes; ``output`` paths are the
caller's, already checked (:class:`~op2motion.fileio.OutputSet`), and the lines say where they go.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from op2motion.errors import InputError
from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile, Page
    from op2motion.formats.motionfile import Motion, PlannerName
    from op2motion.robot.pose import Pose


@dataclass(frozen=True)
class PageWrite:
    """Where pages go in an action file: the ``base`` file (None: blank pages), the first ``page`` (None: the first
    run of empty pages of the base), ``force`` (overwrite pages that hold actions)."""

    base: ActionFile | None = None
    page: int | None = None
    force: bool = False

    def start(self) -> ActionFile:
        """The file the pages go into."""
        from op2motion.formats.action import ActionFile

        return self.base if self.base is not None else ActionFile.blank()


def cable_warnings(poses: Sequence[Pose], spec: Spec) -> list[str]:
    """Advice for poses with joints outside their cable-safe range (inside the mechanical range: still valid)."""
    from op2motion.robot.joints import limit_violations

    return [f"{pose.name}: {v.describe()} (the robot can do it, but the cable may be strained)"
            for pose in poses for v in limit_violations(pose.servo, spec, "cable-safe")]


def export_poses(poses: Sequence[Pose], spec: Spec, fmt: str, output: Path, seconds: float = 1.0,
                 pages: PageWrite = PageWrite()) -> TaskResult[str | bytes]:
    """``export``: ``poses`` to ``fmt`` (``action``: each pose a one-step page of ``seconds`` [s] in ``pages``;
    ``webots`` or ``csv``: a row per pose ``seconds`` apart) at ``output``."""
    from op2motion.formats.tables import csv_table, webots_motion, webots_warnings

    data: dict[str, Any] = {"path": str(output), "format": fmt, "poses": [p.name for p in poses]}
    if fmt == "action":
        done = pages.start().with_poses(poses, spec, pages.page, seconds, pages.force)
        content: str | bytes = done.action.data
        first = done.first
        text = f"{len(poses)} pose(s) in pages {first}..{first + len(poses) - 1}" if poses else "the base, unchanged"
        if poses:
            data["pages"] = list(range(first, first + len(poses)))
    else:
        if not poses:
            raise InputError(f"expected at least one pose file for the {fmt} format", "poses")
        content = (webots_motion if fmt == "webots" else csv_table)(poses, spec, seconds)
        text = f"{len(poses)} pose(s)"
    warnings = cable_warnings(poses, spec) + (webots_warnings(poses, spec) if fmt == "webots" else [])
    return TaskResult(True, None, tuple(warnings), {"output": Output(str(output), content)}, data,
                      (f"wrote {output}: {text}",), value=content)


def import_page(action: ActionFile, page: int, spec: Spec, name: str | None = None,
                output: Path | None = None, out_text: str | None = None) -> TaskResult[Pose]:
    """``import-action --page``: the page's last step as a pose (named ``name``, default the page's), written to
    ``output`` when given (``out_text``: the path as the user typed it, for the report)."""
    from op2motion.formats.posefile import pose_to_json

    pose = action.pose(page, spec, name).checked(spec, "page")
    text = pose_to_json(pose, spec)
    data = {"page": page, "pose": json.loads(text), "path": out_text}
    outputs = {"out": Output(str(output), text)} if output is not None else {}
    line = f"page {page} -> pose {pose.name!r}" + (f", wrote {out_text}" if output is not None else "")
    return TaskResult(True, None, tuple(cable_warnings([pose], spec)), outputs, data, (line,), value=pose)


def list_pages(action: ActionFile, spec: Spec) -> TaskResult[list[Page]]:
    """``import-action``: every page with its steps (goal ticks by servo ID, pause and time in the file's units)."""
    pages = action.pages(spec)
    data: JsonObject = {"pages": [{"index": p.index, "name": p.name, "repeat": p.repeat, "next": p.next,
                       "steps": [{"ticks": {str(k): v for k, v in s.ticks.items()}, "pause": s.pause, "time": s.time}
                                 for s in p.steps]} for p in pages]}
    text = "\n".join(f"{p.index:3d} {p.name:<14} {len(p.steps)} step(s)" + (f" -> page {p.next}" if p.next else "")
                     for p in pages)
    return TaskResult(True, None, None, {}, data, (text,), value=pages)


def export_motion(motion: Motion, spec: Spec, fmt: str, output: Path, pages: PageWrite = PageWrite(),
                  planner: PlannerName = "rrt", seed: int = 0) -> TaskResult[str | bytes]:
    """``motion export``: ``motion`` planned and written as chained action pages (``action``, into ``pages``), or
    its goals every 8 ms as Webots or CSV, at ``output``; the planner's notes as warnings."""
    from op2motion.formats.tables import goals_csv, webots_rows, webots_warnings
    from op2motion.motion.pipeline import motion_to_action, plan_motion

    data: dict[str, Any] = {"name": motion.name, "format": fmt}
    content: str | bytes
    if fmt == "action":
        done = motion_to_action(motion, spec, pages.start(), pages.page, pages.force, planner, seed)
        content, chain, notes = done.action.data, done.pages, list(done.notes)
        data["pages"] = list(chain)
        text = f"pages {chain[0]}..{chain[-1]} (play page {chain[0]})"
    else:
        trajectory = plan_motion(motion, spec, planner, seed)
        notes = list(trajectory.notes)
        if fmt == "csv":
            content = goals_csv(trajectory.times, trajectory.goals, trajectory.supports, spec)
        else:
            names = [f"t{k}" for k in range(len(trajectory.goals))]
            content = webots_rows(list(trajectory.times), trajectory.goals, spec, names)
            notes += webots_warnings([s.pose for s in motion.steps], spec)
        text = f"{len(trajectory.goals)} rows every {trajectory.dt * 1000:.0f} ms"
    data["path"] = str(output)
    return TaskResult(True, None, tuple(notes), {"output": Output(str(output), content)}, data,
                      (f"wrote {output}: {motion.name}, {text}",), value=content)


def urdf(spec: Spec, output: Path | None = None, as_json: bool = False) -> TaskResult[str]:
    """``urdf``: the URDF generated from ``spec``, to ``output`` (the report: where, joints, mass), or shown (its
    text; ``as_json``: in the report)."""
    from op2motion.model.urdf import build_urdf, total_mass

    text = build_urdf(spec)
    facts = {"joints": len(spec.joints), "mass_kg": total_mass(spec)}
    if output is not None:
        return TaskResult(True, None, None, {"output": Output(str(output), text)}, {"path": str(output), **facts},
                          (f"wrote {output}: {len(spec.joints)} joints, {total_mass(spec):.3f} kg",), value=text)
    shown = (text[:-1] if text.endswith("\n") else text,) if not as_json else ()
    return TaskResult(True, None, None, {}, {"urdf": text, **facts}, shown, value=text)
