"""One tuning trial: a point of the search space walked in physics on a set of bodies, judged and measured.

A :class:`Task` says what is tuned (``walk``: a gait preset under :class:`~op2motion.gait.controller.WalkController`;
``stock``: a ``[Walking Config]`` under the stock Walking module's emulation,
:class:`~op2motion.gait.stock_controller.StockWalkController`), in which direction, on which robot (a spec file, or
the shipped OP2), on which bodies of its robustness family, in which engines, with which pushes.

:func:`evaluate` is the trial (a module-level function: it runs on worker processes and Ray). Runs go in order, the
nominal body first (its speed is the one that counts, the slowest engine's; a task of one body counts that body's),
then the hardest members; the first run that does not hold ends the trial (pruned: the rest would not change the
verdict). A run holds when :func:`hold_problem` finds nothing: no fall (nor when pushed), drift and heading within
the walk's bounds (:mod:`op2motion.gait.robust`), the CoP inside the planned soles for at least
:data:`MIN_COP_INSIDE` of the walk, and some servo at its available torque for at most :data:`MAX_LIMITED_SHARE` of
it. The margin is the worst run's smallest share of a bound left (:func:`run_margin`). The stock module, which has
no heading or line feedback, is judged as the acceptance of its config states it: no fall on any body, the heading
within 5° on the nominal one (:func:`stock_problem`; within :data:`STOCK_OTHER_HEADING_DEG` on the others).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, replace
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal

from op2motion.errors import InputError
from op2motion.jsonout import JsonObject
from op2motion.tune.study import TrialOutcome

if TYPE_CHECKING:
    from op2motion.gait.measures import WalkMeasures
    from op2motion.physics import EngineName

MIN_COP_INSIDE = 0.8         # the CoP inside the planned soles for at least this share of the walk (the shipped
                             # forward walk: 88 % at worst, light, stiff, grippy corner with the CoM forward, PyBullet)
MAX_LIMITED_SHARE = 0.25     # some servo at its available torque for at most this share of the walk (the shipped
                             # forward walk, which holds on the whole family: 18 % on its heavy, soft corner)
STOCK_OTHER_HEADING_DEG = 15.0   # the stock module's heading on the family's other bodies: at most this [deg]
SEARCH_ENGINES: tuple[EngineName, ...] = ("mujoco", "pybullet")   # the search walks each body in both, the
                                                                    # faster first
#: Per direction: the shipped preset tuned from, and the measure that counts (speed along the walk [m/s], or turn
#: rate [rad/s]).
DIRECTIONS = {"forward": "forward", "backward": "backward", "sideways": "sideways", "turn": "turn_left"}
#: The way a tuned walk goes (a key of :data:`DIRECTIONS`).
Direction = Literal["forward", "backward", "sideways", "turn"]


@dataclass(frozen=True)
class Task:
    """What a trial walks (see the module docstring): ``kind`` ``walk`` or ``stock``; the base settings (a gait
    preset's :class:`~op2motion.gait.params.GaitParams`, or a :class:`~op2motion.gait.stock_config.StockConfig`);
    the robot's spec file (None: the shipped OP2); the members by name (None: the search's: the nominal body, then the
    family's four corners, heavy/soft/slippery and light/stiff/grippy with the torso CoM at both ends, then the torso
    CoM alone at both ends); engines (the search's: both, MuJoCo first: PyBullet's contacts fail walks MuJoCo
    passes);
    steps; the side pushes [N] (0: none)."""

    kind: str
    direction: Direction
    base: Any
    spec_path: str | None = None
    members: tuple[str, ...] | None = None
    engines: tuple[EngineName, ...] = SEARCH_ENGINES
    steps: int = 20
    push_n: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("walk", "stock"):
            raise InputError(f"expected walk or stock, got {self.kind!r}", "kind")
        if self.direction not in DIRECTIONS:
            raise InputError(f"expected one of {', '.join(DIRECTIONS)}, got {self.direction!r}", "direction")


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
    values = {k: v for k, v in asdict(task.base).items() if k != "name"}
    base = hashlib.sha256(json.dumps(values, sort_keys=True, default=repr).encode("utf-8")).hexdigest()
    bodies = ", ".join(task.members) if task.members is not None else "the search's bodies"
    pushes = f", {task.push_n:g} N side pushes" if task.push_n else ""
    settings_from = f"preset {task.base.name}" if task.kind == "walk" else "the stock Walking config"
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
    if task.kind == "walk":
        return replace(task.base, steps=task.steps, **values)
    return task.base.with_values(**values)


def controller_of(task: Task, chosen: Any, spec: Any) -> Any:
    """A fresh controller for one run (a walk's plan is made once per trial and shared)."""
    if task.kind == "walk":
        from op2motion.gait.controller import WalkController

        return WalkController(chosen, spec)
    from op2motion.gait.stock_controller import StockWalkController

    return StockWalkController(chosen, spec, task.steps)


def measure(task: Task, walk: Any) -> float:
    """The measure that counts: speed along the walk [m/s], or the turn rate [rad/s]."""
    return math.radians(abs(walk.turn_rate_deg_s)) if task.direction == "turn" else float(walk.mean_speed_mps)


def stock_heading_bound(member: str) -> float:
    """The stock module's heading bound [deg] on a body: :data:`~op2motion.gait.robust.MAX_HEADING_DEG` on the
    nominal one, :data:`STOCK_OTHER_HEADING_DEG` on the others (it has no heading feedback: a body it was not tuned
    on turns it)."""
    from op2motion.gait.robust import MAX_HEADING_DEG

    return MAX_HEADING_DEG if member == "nominal" else STOCK_OTHER_HEADING_DEG


def stock_problem(report: Any, member: str) -> str | None:
    """Why a run of the stock module does not hold: a fall, or its heading past :func:`stock_heading_bound`."""
    if report.run.fell or report.run.walk is None:
        return report.run.reason if report.run.fell else "no walk measured"
    heading = report.run.walk.heading_error_deg
    bound = stock_heading_bound(member)
    return f"heading off by {heading:+.1f}° (at most {bound:g}°)" if abs(heading) > bound else None


def stock_margin(report: Any, member: str) -> float:
    """The stock run's share of its heading bound left (-1 for a fall)."""
    if report.run.fell or report.run.walk is None:
        return -1.0
    return 1.0 - abs(float(report.run.walk.heading_error_deg)) / stock_heading_bound(member)


def hold_problem(report: Any) -> str | None:
    """Why a run does not hold (None: it holds; see the module docstring)."""
    from op2motion.gait.robust import walk_judge

    problem = walk_judge(report)
    if problem is not None:
        return problem
    walk = report.run.walk
    if walk.cop_inside_fraction < MIN_COP_INSIDE:
        return f"CoP inside the soles {walk.cop_inside_fraction:.0%} of the walk"
    limited = walk.worst_torque.limited_share or 0.0
    if limited > MAX_LIMITED_SHARE:
        return f"{walk.worst_torque.joint} at its available torque {limited:.0%} of the walk"
    return None


def run_margin(report: Any) -> float:
    """The smallest share of a bound a run left (1: none used; 0: on a bound; negative: past it)."""
    from op2motion.gait.robust import MAX_DRIFT_SHARE, MAX_HEADING_DEG, MIN_DISTANCE_M

    walk: WalkMeasures | None = report.run.walk
    if report.run.fell or walk is None or any(p.fell for p in report.pushes):
        return -1.0
    distance = max(walk.distance_m, MIN_DISTANCE_M)
    return min(1.0 - walk.lateral_drift_m / (MAX_DRIFT_SHARE * distance),
               1.0 - abs(walk.heading_error_deg) / MAX_HEADING_DEG,
               (walk.cop_inside_fraction - MIN_COP_INSIDE) / (1.0 - MIN_COP_INSIDE),
               1.0 - (walk.worst_torque.limited_share or 0.0) / MAX_LIMITED_SHARE)


def plan_problem(task: Task, chosen: Any, spec: Any) -> tuple[Any, str | None]:
    """A walk's plan within its servos' speed and ranges (the trial's gait), or why there is none."""
    if task.kind == "stock":
        return chosen, None
    from op2motion.gait.speeds import gait_within_speed

    try:
        return gait_within_speed(chosen, spec), None
    except InputError as exc:
        return None, f"plan refused: {exc.message}"


def evaluate(point: dict[str, float], task: Task) -> TrialOutcome:
    """One trial (see the module docstring)."""
    from op2motion.physics import check
    from op2motion.tune.study import timed

    def run() -> TrialOutcome:
        spec = spec_of(task.spec_path)
        members = members_of(task)
        planned = len(members) * len(task.engines)
        gait, problem = plan_problem(task, settings(task, point), spec)
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
                report = check(controller_of(task, gait, body), body, (engine,), pushes,
                               setup=member.setup()).engines[engine]
                runs += 1
                if task.kind == "stock":
                    problem, run_slack = stock_problem(report, member.name), stock_margin(report, member.name)
                else:
                    problem, run_slack = hold_problem(report), run_margin(report)
                margin = min(margin, run_slack)
                if report.run.walk is not None and (member.name == "nominal" or len(members) == 1):
                    speeds.append(measure(task, report.run.walk))
                if problem is not None:
                    return TrialOutcome(min(speeds, default=0.0), margin, False, runs, planned,
                                   f"{member.name}, {engine}: {problem}", 0.0)
        return TrialOutcome(min(speeds, default=0.0), margin, True, runs, planned, None, 0.0)

    return timed(run)
