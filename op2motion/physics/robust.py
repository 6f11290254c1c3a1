"""Robustness as a check: the same controller over a family of bodies and floors drawn from what we do not know.

The family (:func:`family`) comes from the spec's uncertainty: the torso's centre of mass (the figure that matters
most; its box in ``specs/op2.toml`` is ±20 mm fore–aft and ±10 mm sideways) and mass (±15 %) (a spec that states
none gets those, :data:`UNSTATED_TORSO`), plus what no spec
knows: the servos' stiffness (Kp ×0.6 to ×1.6, :data:`STIFFNESS_RANGE`), the floor's friction (0.5 to 1.0,
:data:`FRICTION_RANGE`) and the IMU's latency (16 ms in every member, :data:`LATENCY_S`). Its members: the nominal
body, each factor alone at each end of its range, and four corners that pair the torso CoM's ends with the worst
combinations seen (heavy torso on soft servos and a slippery floor; light torso on stiff servos and a grippy floor).

:func:`robust_check` runs one fresh controller per member and engine through :func:`~.runner.check` and returns a
:class:`RobustReport`: per run the verdict and the one phrase that says why not; the pass rate, the worst case, the
reasons counted, and whether the engines agree member by member (the same outcome for the same reasons).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any, Callable, Iterable

from op2motion.physics.controller import Controller
from op2motion.physics.plan import Plan
from op2motion.physics.report import EngineReport
from op2motion.physics.runner import Pushes, Setup, check, check_runs, check_work, runs_per_engine
from op2motion.physics.scene import EngineName
from op2motion.physics.sensors import Sensors
from op2motion.robot.spec import Spec, Uncertainty
from op2motion.robot.variant import spec_variant

STIFFNESS_RANGE = (0.6, 1.6)      # servo Kp factor: the MX-28's P law and load vary from servo to servo
FRICTION_RANGE = (0.5, 1.0)       # floor Coulomb friction: carpet to wood
LATENCY_S = 0.016                 # IMU reading to goal: two 8 ms control periods
#: The torso's uncertainty when a spec states none: ±15 % mass, CoM ±20 mm fore-aft, ±10 mm sideways, ±8 mm up.
UNSTATED_TORSO = Uncertainty(0.15, ((-0.02, 0.02), (-0.01, 0.01), (-0.008, 0.008)))


@dataclass(frozen=True)
class Member:
    """One body and floor of the family: the torso CoM moved by ``com_shift_m`` (x, y, z) [m] (torso frame), its
    mass scaled by ``mass_scale``, the servos' Kp by ``stiffness``, the floor's ``friction``."""

    name: str
    com_shift_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mass_scale: float = 1.0
    stiffness: float = 1.0
    friction: float = 0.8

    def body(self, spec: Spec) -> Spec:
        """The spec of this member's body."""
        return spec_variant(spec, self.com_shift_m, self.mass_scale)

    def setup(self) -> Setup:
        """The check setup of this member's servos, floor and sensors."""
        return Setup(stiffness=self.stiffness, friction=self.friction, sensors=Sensors(latency_s=LATENCY_S))


def family(spec: Spec) -> tuple[Member, ...]:
    """The robustness family of ``spec`` (see the module docstring)."""
    torso = spec.inertial(spec.root_link).uncertainty or UNSTATED_TORSO
    (x_lo, x_hi), (y_lo, y_hi), _ = torso.com_m
    m_lo, m_hi = 1.0 - torso.mass_fraction, 1.0 + torso.mass_fraction
    s_lo, s_hi = STIFFNESS_RANGE
    f_lo, f_hi = FRICTION_RANGE

    def mm(v: float) -> str:
        return f"{v * 1000:+.0f}"

    return (Member("nominal"),
            *(Member(f"torso CoM x {mm(x)} mm", (x, 0.0, 0.0)) for x in (x_hi, x_lo)),
            *(Member(f"torso CoM y {mm(y)} mm", (0.0, y, 0.0)) for y in (y_hi, y_lo)),
            Member(f"torso mass ×{m_hi:.2f}", mass_scale=m_hi), Member(f"torso mass ×{m_lo:.2f}", mass_scale=m_lo),
            Member(f"stiffness ×{s_lo:g}", stiffness=s_lo), Member(f"stiffness ×{s_hi:g}", stiffness=s_hi),
            Member(f"friction {f_lo:g}", friction=f_lo), Member(f"friction {f_hi:g}", friction=f_hi),
            *(Member(f"x {mm(x)} mm, mass ×{m_hi:.2f}, stiffness ×{s_lo:g}, friction {f_lo:g}", (x, 0.0, 0.0),
                     m_hi, s_lo, f_lo) for x in (x_hi, x_lo)),
            *(Member(f"x {mm(x)} mm, mass ×{m_lo:.2f}, stiffness ×{s_hi:g}, friction {f_hi:g}", (x, 0.0, 0.0),
                     m_lo, s_hi, f_hi) for x in (x_hi, x_lo)))


#: What a run must do to pass: None, or the phrase that says why it does not (default: stand, see ``problem``).
Judge = Callable[[EngineReport], "str | None"]


def stands(report: EngineReport) -> str | None:
    """The default judge: the run and every push stable."""
    if not report.run.stable:
        return report.run.reason
    fallen = [p.direction for p in report.pushes if not p.stable]
    return f"fell when pushed {', '.join(fallen)}" if fallen else None


@dataclass(frozen=True)
class RunOutcome:
    """What happened in a run, for comparing engines: it ``passed`` the judge, it ``fell``, and the ``kind`` of
    failure (None when it passed)."""

    passed: bool
    fell: bool
    kind: str | None


@dataclass(frozen=True)
class RobustRun:
    """One member in one engine: ``problem`` None when it passed."""

    member: Member
    engine: EngineName
    report: EngineReport
    problem: str | None

    @property
    def passed(self) -> bool:
        """The run did what the judge asks."""
        return self.problem is None

    @property
    def kind(self) -> str | None:
        """The failure in one word (a fall's reason, ``drifted``, ``heading``, ...), None when it passed."""
        return None if self.problem is None else self.problem.split()[0].rstrip(":")

    @property
    def outcome(self) -> RunOutcome:
        """What happened, for comparing engines."""
        return RunOutcome(self.passed, self.report.run.fell, self.kind)


@dataclass(frozen=True)
class RobustReport:
    """Every run of the family (member-major, then engine)."""

    runs: tuple[RobustRun, ...]

    @property
    def pass_rate(self) -> float:
        """Share of the runs that passed."""
        return sum(r.passed for r in self.runs) / len(self.runs) if self.runs else 0.0

    @property
    def passed(self) -> bool:
        """Every run passed."""
        return all(r.passed for r in self.runs)

    @property
    def failures(self) -> Counter[str]:
        """How many runs failed, by the kind of failure."""
        return Counter(r.kind for r in self.runs if r.kind is not None)

    @property
    def disagreements(self) -> list[str]:
        """The members on which the engines did not do the same thing for the same reason (both passed, or both
        failed the same way: fell for the same first reason, or drifted, or turned)."""
        out: dict[str, set[Any]] = {}
        for r in self.runs:
            out.setdefault(r.member.name, set()).add(r.outcome)
        return [name for name, outcomes in out.items() if len(outcomes) > 1]

    def worst(self, score: Callable[[RobustRun], float]) -> RobustRun:
        """The run with the highest ``score`` (the caller's measure of how bad a run went)."""
        return max(self.runs, key=score)


def robust_runs(members: int, engines: int, pushes: Pushes | None) -> int:
    """The runs a robustness check makes: every member in every engine, each with its pushes."""
    return members * check_runs(engines, pushes, None)


def robust_check(make_controller: Callable[[], Controller[Plan]], spec: Spec, engines: Iterable[EngineName],
                 judge: Judge = stands, pushes: Pushes | None = None, members: Iterable[Member] | None = None,
                 on_progress: Callable[[float, float], Any] | None = None) -> RobustReport:
    """Run a fresh controller from ``make_controller()`` on every member (default :func:`family`) in every engine;
    each run judged by ``judge``; ``on_progress(done, total)`` counts runs."""
    chosen = tuple(family(spec) if members is None else members)
    names = tuple(engines)
    per = runs_per_engine(pushes, None)
    check_work(robust_runs(len(chosen), len(names), pushes), make_controller().plan.duration_s,
               f"{len(chosen)} bodies x {len(names)} engine(s) x {per}")
    runs = []
    total = len(chosen) * len(names)
    for i, member in enumerate(chosen):
        body = member.body(spec)
        for j, engine in enumerate(names):
            report = check(make_controller(), body, (engine,), pushes, setup=member.setup()).engines[engine]
            runs.append(RobustRun(member, engine, report, judge(report)))
            if on_progress is not None:
                on_progress(i * len(names) + j + 1, total)
    return RobustReport(tuple(runs))
