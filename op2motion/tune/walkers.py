"""What a tuning task walks, and how it is judged: op2motion's planned walk from a gait preset
(:class:`PresetWalker`, under :class:`~op2motion.gait.controller.WalkController`) or the stock Walking module from a
``[Walking Config]`` (:class:`StockWalker`, under :class:`~op2motion.gait.stock_controller.StockWalkController`).

Each says how a point of the search space becomes its settings, how the settings are planned and walked, how a run
is judged (:meth:`Walker.judge`: why it does not hold, and the share of its bounds it left), how hard the
verification pushes, and how the chosen settings are written. A run of op2motion's walk holds when
:func:`hold_problem` finds nothing: no fall (nor when pushed), drift and heading within the walk's bounds
(:mod:`op2motion.gait.robust`), the CoP inside the planned soles for at least :data:`MIN_COP_INSIDE` of the walk, and
some servo at its available torque for at most :data:`MAX_LIMITED_SHARE` of it; its margin is the smallest share of a
bound left (:func:`run_margin`). The stock module, which has no heading or line feedback, is judged as the acceptance
of its config states it: no fall on any body, the heading within 5° on the nominal one (:func:`stock_problem`; within
:data:`STOCK_OTHER_HEADING_DEG` on the others).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import TYPE_CHECKING, Any, Literal, Protocol

from op2motion.errors import InputError

if TYPE_CHECKING:
    from op2motion.gait.measures import WalkMeasures
    from op2motion.gait.params import GaitParams
    from op2motion.gait.stock_config import StockConfig
    from op2motion.physics import EngineReport
    from op2motion.robot.spec import Spec

MIN_COP_INSIDE = 0.8         # the CoP inside the planned soles for at least this share of the walk (docs/tuning.md)
MAX_LIMITED_SHARE = 0.25     # some servo at its available torque for at most this share of the walk (docs/tuning.md)
STOCK_OTHER_HEADING_DEG = 15.0   # the stock module's heading on the family's other bodies: at most this [deg]
VERIFY_PUSH_N = 2.0          # op2motion's walk is verified with side pushes of this much [N]
#: What a task tunes: op2motion's walk (a preset) or the stock Walking module (a config).
WalkerKind = Literal["walk", "stock"]


class Walker(Protocol):
    """What a tuning task walks (see the module docstring)."""

    @property
    def kind(self) -> WalkerKind:
        """``walk`` or ``stock``."""
        ...

    @property
    def verify_push_n(self) -> float:
        """The side pushes [N] of the verification (0: none)."""
        ...

    def base_values(self) -> dict[str, Any]:
        """The base settings' values (a preset's name aside), for the study's fingerprint."""
        ...

    def base_name(self) -> str:
        """Where the base settings come from, in words."""
        ...

    def settings(self, values: dict[str, Any], steps: int) -> Any:
        """The base settings with ``values``, walking ``steps`` steps where the settings count them."""
        ...

    def plan(self, settings: Any, spec: Spec) -> tuple[Any, str | None]:
        """What the controller walks (a gait within the servos' speed, or the settings as they are), or why there
        is none."""
        ...

    def controller(self, planned: Any, spec: Spec, steps: int) -> Any:
        """A fresh controller for one run of ``planned``."""
        ...

    def judge(self, report: EngineReport, member: str) -> tuple[str | None, float]:
        """Why a run on body ``member`` does not hold (None: it holds), and the share of its bounds it left."""
        ...

    def settings_text(self, settings: Any, name: str, header: list[str]) -> str:
        """The chosen settings as their file (named ``name``) with ``header`` lines."""
        ...


@dataclass(frozen=True)
class PresetWalker:
    """op2motion's planned walk from the gait preset ``base``."""

    base: GaitParams
    kind: WalkerKind = "walk"
    verify_push_n: float = VERIFY_PUSH_N

    def base_values(self) -> dict[str, Any]:
        return _values(self.base)

    def base_name(self) -> str:
        return f"preset {self.base.name}"

    def settings(self, values: dict[str, Any], steps: int) -> GaitParams:
        return replace(self.base, steps=steps, **values)

    def plan(self, settings: GaitParams, spec: Spec) -> tuple[Any, str | None]:
        from op2motion.gait.speeds import gait_within_speed

        try:
            return gait_within_speed(settings, spec), None
        except InputError as exc:
            return None, f"plan refused: {exc.message}"

    def controller(self, planned: Any, spec: Spec, steps: int) -> Any:
        from op2motion.gait.controller import WalkController

        return WalkController(planned, spec)

    def judge(self, report: EngineReport, member: str) -> tuple[str | None, float]:
        return hold_problem(report), run_margin(report)

    def settings_text(self, settings: GaitParams, name: str, header: list[str]) -> str:
        from op2motion.gait.params import preset_text

        return preset_text(replace(settings, name=name), header)


@dataclass(frozen=True)
class StockWalker:
    """The stock Walking module from the config ``base``."""

    base: StockConfig
    kind: WalkerKind = "stock"
    verify_push_n: float = 0.0

    def base_values(self) -> dict[str, Any]:
        return _values(self.base)

    def base_name(self) -> str:
        return "the stock Walking config"

    def settings(self, values: dict[str, Any], steps: int) -> StockConfig:
        return self.base.with_values(**values)

    def plan(self, settings: StockConfig, spec: Spec) -> tuple[Any, str | None]:
        return settings, None

    def controller(self, planned: StockConfig, spec: Spec, steps: int) -> Any:
        from op2motion.gait.stock_controller import StockWalkController

        return StockWalkController(planned, spec, steps)

    def judge(self, report: EngineReport, member: str) -> tuple[str | None, float]:
        return stock_problem(report, member), stock_margin(report, member)

    def settings_text(self, settings: StockConfig, name: str, header: list[str]) -> str:
        from op2motion.gait.stock_config import stock_config_text

        return stock_config_text(settings, "\n".join(header))


def stock_heading_bound(member: str) -> float:
    """The stock module's heading bound [deg] on a body: :data:`~op2motion.gait.robust.MAX_HEADING_DEG` on the
    nominal one, :data:`STOCK_OTHER_HEADING_DEG` on the others (it has no heading feedback: a body it was not tuned
    on turns it)."""
    from op2motion.gait.robust import MAX_HEADING_DEG

    return MAX_HEADING_DEG if member == "nominal" else STOCK_OTHER_HEADING_DEG


def stock_problem(report: EngineReport, member: str) -> str | None:
    """Why a run of the stock module does not hold: a fall, or its heading past :func:`stock_heading_bound`."""
    walk = _walk(report)
    if report.run.fell or walk is None:
        return report.run.reason if report.run.fell else "no walk measured"
    bound = stock_heading_bound(member)
    heading = walk.heading_error_deg
    return f"heading off by {heading:+.1f}° (at most {bound:g}°)" if abs(heading) > bound else None


def stock_margin(report: EngineReport, member: str) -> float:
    """The stock run's share of its heading bound left (-1 for a fall)."""
    walk = _walk(report)
    if report.run.fell or walk is None:
        return -1.0
    return 1.0 - abs(walk.heading_error_deg) / stock_heading_bound(member)


def hold_problem(report: EngineReport) -> str | None:
    """Why a run of op2motion's walk does not hold (None: it holds; see the module docstring)."""
    from op2motion.gait.robust import walk_judge

    problem = walk_judge(report)
    walk = _walk(report)
    if problem is not None or walk is None:
        return problem or "no walk measured"
    if walk.cop_inside_fraction < MIN_COP_INSIDE:
        return f"CoP inside the soles {walk.cop_inside_fraction:.0%} of the walk"
    limited = walk.worst_torque.limited_share or 0.0
    if limited > MAX_LIMITED_SHARE:
        return f"{walk.worst_torque.joint} at its available torque {limited:.0%} of the walk"
    return None


def run_margin(report: EngineReport) -> float:
    """The smallest share of a bound a run left (1: none used; 0: on a bound; negative: past it)."""
    from op2motion.gait.robust import MAX_DRIFT_SHARE, MAX_HEADING_DEG, MIN_DISTANCE_M

    walk = _walk(report)
    if report.run.fell or walk is None or any(p.fell for p in report.pushes):
        return -1.0
    distance = max(walk.distance_m, MIN_DISTANCE_M)
    return min(1.0 - walk.lateral_drift_m / (MAX_DRIFT_SHARE * distance),
               1.0 - abs(walk.heading_error_deg) / MAX_HEADING_DEG,
               (walk.cop_inside_fraction - MIN_COP_INSIDE) / (1.0 - MIN_COP_INSIDE),
               1.0 - (walk.worst_torque.limited_share or 0.0) / MAX_LIMITED_SHARE)


def _values(settings: GaitParams | StockConfig) -> dict[str, Any]:
    """The settings' values, a name aside (a preset renamed is the same base)."""
    return {k: v for k, v in asdict(settings).items() if k != "name"}


def _walk(report: EngineReport) -> WalkMeasures | None:
    """The run's walking measurements (None: it measured none)."""
    from op2motion.gait.measures import WalkMeasures

    walk = report.run.walk
    return walk if isinstance(walk, WalkMeasures) else None
