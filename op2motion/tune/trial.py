"""One tuning trial: a point of the search space walked in physics on a set of bodies, judged and measured.

A :class:`Task` says what is tuned (its :class:`~.walkers.Walker`: a gait preset under
:class:`~op2motion.gait.controller.WalkController`, or a ``[Walking Config]`` under the stock Walking module's
emulation, :class:`~op2motion.gait.stock_controller.StockWalkController`), in which direction, on which robot (a
spec file, or the shipped OP2), on which bodies of its robustness family, in which engines, with which pushes.

:func:`evaluate` is the trial (a module-level function: it runs on worker processes and Ray). Runs go in order, the
nominal body first (its speed is the one that counts, the slowest engine's; a task of one body counts that body's),
then the hardest members; the first run that does not hold ends the trial (pruned: the rest would not change the
verdict). The walker judges each run (:meth:`~.walkers.Walker.judge`); the margin is the worst run's.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal

from op2motion.errors import InputError
from op2motion.jsonout import JsonObject
from op2motion.tune.study import TrialOutcome
from op2motion.tune.walkers import PresetWalker, StockWalker, WalkerKind

if TYPE_CHECKING:
    from op2motion.physics import EngineName
SEARCH_ENGINES: tuple[EngineName, ...] = ("mujoco", "pybullet")   # the search walks each body in both, the
                                                                    # faster first
#: Per direction: the shipped preset tuned from, and the measure that counts (speed along the walk [m/s], or turn
#: rate [rad/s]).
DIRECTIONS = {"forward": "forward", "backward": "backward", "sideways": "sideways", "turn": "turn_left"}
#: The way a tuned walk goes (a key of :data:`DIRECTIONS`).
Direction = Literal["forward", "backward", "sideways", "turn"]


@dataclass(frozen=True)
class Task:
    """What a trial walks (see the module docstring): the ``walker`` (op2motion's walk from a preset, or the stock
    module from a config) and the ``direction``; the robot's spec file (None: the shipped OP2); the members by name
    (None: the search's: the nominal body, then the family's four corners, heavy/soft/slippery and light/stiff/grippy
    with the torso CoM at both ends, then the torso CoM alone at both ends); engines (the search's: both, MuJoCo
    first: PyBullet's contacts fail walks MuJoCo passes); steps; the side pushes [N] (0: none)."""

    walker: PresetWalker | StockWalker
    direction: Direction
    spec_path: str | None = None
    members: tuple[str, ...] | None = None
    engines: tuple[EngineName, ...] = SEARCH_ENGINES
    steps: int = 20
    push_n: float = 0.0

    def __post_init__(self) -> None:
        if self.direction not in DIRECTIONS:
            raise InputError(f"expected one of {', '.join(DIRECTIONS)}, got {self.direction!r}", "direction")

    @property
    def kind(self) -> WalkerKind:
        """What is tuned: ``walk`` (op2motion's walk) or ``stock`` (the stock Walking module)."""
        return self.walker.kind


@lru_cache(maxsize=4)
def spec_of(path: str | None) -> Any:
    """The robot's spec (a file, or the shipped OP2), read once per process."""
    from op2motion.robot.specfile import default_spec, load_spec

    return default_spec() if path is None else load_spec(path)


def identity(task: Task) -> JsonObject:
    """What a study of ``task`` is for, recorded in its mark and compared when it is resumed
    (:func:`~op2motion.tune.study.study_mark`): the spec's fingerprint (SHA-256 of its file) and name, the task (kind
    and direction), its runs (steps, bodies, engines, pushes) and the base settings' fingerprint (SHA-256 of their
    values, the preset's name aside) and name."""
    spec = spec_of(task.spec_path)
    values = task.walker.base_values()
    base = hashlib.sha256(json.dumps(values, sort_keys=True, default=repr).encode("utf-8")).hexdigest()
    bodies = ", ".join(task.members) if task.members is not None else "the search's bodies"
    pushes = f", {task.push_n:g} N side pushes" if task.push_n else ""
    settings_from = task.walker.base_name()
    return {"spec": {"sha256": spec.sha256, "name": task.spec_path or "the shipped specs/op2.toml"},
            "task": f"{task.kind} {task.direction}",
            "runs": f"{task.steps} steps on {bodies} in {' and '.join(task.engines)}{pushes}",
            "base": {"sha256": base, "name": settings_from}}


def members_of(task: Task) -> list[Any]:
    """The family members a task walks, in order (the nominal body first)."""
    from op2motion.physics import family

    everyone = family(spec_of(task.spec_path))
    if task.members is None:
        return [everyone[0], *everyone[-4:], *everyone[1:3]]
    chosen = [m for m in everyone if m.name in task.members]
    if len(chosen) != len(task.members):
        known = ", ".join(m.name for m in everyone)
        raise InputError(f"expected members among {known}, got {', '.join(task.members)}", "members")
    return chosen


def settings(task: Task, point: dict[str, float]) -> Any:
    """The base settings with the point's values (whole numbers where the setting is one; others to 6 significant
    digits, as the written preset or config.ini keeps them, so that what was walked is what is written)."""
    values = {k: (int(round(v)) if k in ("p_gain",) else float(f"{v:.6g}")) for k, v in point.items()}
    return task.walker.settings(values, task.steps)


def measure(task: Task, walk: Any) -> float:
    """The measure that counts: speed along the walk [m/s], or the turn rate [rad/s]."""
    return math.radians(abs(walk.turn_rate_deg_s)) if task.direction == "turn" else float(walk.mean_speed_mps)


def evaluate(point: dict[str, float], task: Task) -> TrialOutcome:
    """One trial (see the module docstring)."""
    from op2motion.physics import check
    from op2motion.tune.study import timed

    def run() -> TrialOutcome:
        spec = spec_of(task.spec_path)
        members = members_of(task)
        planned = len(members) * len(task.engines)
        gait, problem = task.walker.plan(settings(task, point), spec)
        if problem is not None:
            return TrialOutcome(0.0, -1.0, False, 0, planned, problem, 0.0)
        pushes = None
        if task.push_n:
            from op2motion.gait import side_pushes

            pushes = side_pushes(task.push_n)
        speeds, margin, runs = [], math.inf, 0
        for member in members:
            body = member.body(spec)
            for engine in task.engines:
                report = check(task.walker.controller(gait, body, task.steps), body, (engine,), pushes,
                               setup=member.setup()).engines[engine]
                runs += 1
                problem, run_slack = task.walker.judge(report, member.name)
                margin = min(margin, run_slack)
                if report.run.walk is not None and (member.name == "nominal" or len(members) == 1):
                    speeds.append(measure(task, report.run.walk))
                if problem is not None:
                    return TrialOutcome(min(speeds, default=0.0), margin, False, runs, planned,
                                   f"{member.name}, {engine}: {problem}", 0.0)
        return TrialOutcome(min(speeds, default=0.0), margin, True, runs, planned, None, 0.0)

    return timed(run)
