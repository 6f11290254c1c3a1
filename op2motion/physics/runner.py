"""The one physics entry: :func:`check` runs a controller in each engine asked for and returns a typed report.

Per engine: the main run, then (with :class:`Pushes`) one run per push direction with a push at the torso's centre
of mass, then (with :class:`Trials`) runs from randomly perturbed starts (seeded). Every run is a fresh world with
the same servo model (:class:`Setup`: the MX-28 at its P gains, scaled stiffness, a rated voltage), judged by
:mod:`.judge` against the controller's plan and measured by :mod:`.measure` (and by the plan's own hook,
:attr:`.plan.Plan.measure`, when it has one: a walk's measurements come from :mod:`op2motion.gait.measures`). The
engines *agree* when the same thing happened in each (:meth:`.report.CheckReport.agree`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.model.servo import ServoModel
from op2motion.physics.ball import Ball, BallWatch
from op2motion.physics.body import LYING, Body
from op2motion.physics.controller import Controller
from op2motion.physics.engine import ENGINES, make_engine, snapshot_png
from op2motion.physics.judge import TILT_LIMIT_DEG, judge
from op2motion.physics.loop import Push, RunSetup, simulate
from op2motion.physics.measure import RunSetupFacts, run_report
from op2motion.physics.plan import Plan
from op2motion.physics.report import PUSH_DIRECTIONS, CheckReport, EngineReport, PushResult, RunReport, TrialsResult
from op2motion.physics.scene import FLOOR_FRICTION, EngineName
from op2motion.physics.sensors import Sensors
from op2motion.robot.spec import Spec

MAX_PUSH_N = 100.0
MAX_FRICTION = 2.0
PUSH_DURATION_S = 0.1
MAX_TRIALS = 100
MAX_PERTURB_DEG = 5.0
MAX_SIMULATED_S = 7200.0   # one request simulates at most this long in all [s] (about an hour of computing)
Progress = Callable[[float, float], object]      # (simulated seconds done, in all) of the whole check


@dataclass(frozen=True)
class Setup:
    """What every run of a check shares: the servo model (Kp scaled by ``stiffness``, a rated supply ``voltage`` [V],
    None: the spec's), the floor's Coulomb ``friction``, the ``sensors``' latency and noise; ``snapshot`` keeps a
    picture of the main run's end (the first engine's), ``keep_track`` the samples of each main and pushed run
    (:class:`.track.Track`, e.g. to plot the joints); ``full_length`` plays every run for the plan's whole
    duration (by default a run ends once settled or fallen, :mod:`.stopping`); ``lying`` starts every run lying on
    the floor (``front``: face down, ``back``: face up, ``left`` or ``right``: on that side; the plan's first goals
    laid on the floor, :func:`.body.lying_placement`) instead of on the feet; ``ball`` lays a ball on the floor in
    every run (:mod:`.ball`: each run reports what it did to it)."""

    stiffness: float = 1.0
    voltage: float | None = None
    snapshot: bool = False
    keep_track: bool = False
    friction: float = FLOOR_FRICTION
    sensors: Sensors = Sensors()
    full_length: bool = False
    lying: str | None = None
    ball: Ball | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.friction) and 0.0 < self.friction <= MAX_FRICTION):
            raise InputError(f"expected a friction coefficient in (0, {MAX_FRICTION:g}], got {self.friction!r}",
                             "friction")
        if self.lying is not None and self.lying not in LYING:
            raise InputError(f"expected one of {', '.join(LYING)} (or none), got {self.lying!r}", "lying")


@dataclass(frozen=True)
class Pushes:
    """Pushes of ``force_n`` [N] for ``duration_s`` [s], one run per direction (the way the force points:
    ``forward``, ``backward``, ``left``, ``right``), at ``at_s`` [s] into the run (None: the plan's default, see
    :meth:`.plan.Plan.default_push_s`)."""

    force_n: float
    directions: tuple[str, ...] = tuple(PUSH_DIRECTIONS)
    at_s: float | None = None
    duration_s: float = PUSH_DURATION_S

    def __post_init__(self) -> None:
        if not (isinstance(self.force_n, (int, float)) and math.isfinite(self.force_n)
                and 0.0 <= self.force_n <= MAX_PUSH_N):
            raise InputError(f"expected a force from 0 to {MAX_PUSH_N:g} N, got {self.force_n!r}", "push")
        unknown = [d for d in self.directions if d not in PUSH_DIRECTIONS]
        if unknown:
            raise InputError(f"expected directions among {', '.join(PUSH_DIRECTIONS)}, got {unknown[0]!r}", "push")


@dataclass(frozen=True)
class Trials:
    """``runs`` more runs, each starting with every joint off the plan by a normal draw of ``perturb_deg`` [deg]
    (``seed``: the same offsets in every engine)."""

    runs: int
    perturb_deg: float = 0.5
    seed: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.runs, bool) or not isinstance(self.runs, int) or not 0 <= self.runs <= MAX_TRIALS:
            raise InputError(f"expected 0 to {MAX_TRIALS} runs, got {self.runs!r}", "trials")
        if not (math.isfinite(self.perturb_deg) and 0.0 <= self.perturb_deg <= MAX_PERTURB_DEG):
            raise InputError(f"expected 0 to {MAX_PERTURB_DEG:g}°, got {self.perturb_deg!r}", "perturb_deg")

    def offsets(self, joints: int) -> list[np.ndarray]:
        """The start offsets [rad], one (``joints``,) per run."""
        rng = np.random.default_rng(self.seed)
        return [np.radians(rng.normal(0.0, self.perturb_deg, joints)) for _ in range(self.runs)]


def sag_allowance_deg(plan: Plan, spec: Spec, servo: ServoModel) -> float:
    """For a motion with one-foot rows: the largest torso turn [deg] the compliance model predicts from the servos'
    sag on one leg (:mod:`op2motion.model.compliance`), by which a motion's tilt limit grows (its plan is rigid);
    0 for a held pose or a motion on two feet."""
    if not plan.is_motion:
        return 0.0
    from op2motion.kinematics import forward
    from op2motion.model.compliance import Compliance
    from op2motion.robot.joints import servo_to_book

    model, worst = Compliance(spec, servo), 0.0
    for side in ("left", "right"):
        rows = [k for k, s in enumerate(plan.supports) if s == side]
        if rows:
            points = forward(servo_to_book(plan.goals[rows], side, spec), spec, "dh", full_com=True)
            tilt = model.settle(points, points.full()).tilt
            worst = max(worst, float(np.degrees(np.max(np.where(np.isfinite(tilt), tilt, 0.0)))))
    return worst


class _Runner:
    """The runs of one check: one servo model, one body, one tilt limit; progress summed over every run."""

    def __init__(self, controller: Controller[Plan], spec: Spec, setup: Setup, runs: int, on_progress: Progress | None):
        self.controller, self.spec, self.setup = controller, spec, setup
        plan = controller.plan
        self.servo = ServoModel.of(spec, plan.p_gains[0], setup.stiffness, setup.voltage)
        self.servo_nominal = ServoModel.of(spec)
        self.body = Body(spec)
        self.tilt_limit = TILT_LIMIT_DEG + sag_allowance_deg(plan, spec, self.servo_nominal)
        self.total, self.done, self.on_progress = runs * plan.duration_s, 0.0, on_progress

    def _tick(self, t: float) -> None:
        if self.on_progress is not None:
            self.on_progress(self.done + t, self.total)

    def run(self, engine_name: EngineName, run: RunSetup = RunSetup(), snapshot: bool = False,
            keep_track: bool = False) -> RunReport:
        """One run in a fresh world, judged and measured."""
        engine = make_engine(engine_name, self.spec, self.servo, self.setup.friction, self.setup.ball)
        run = replace(run, sensors=self.setup.sensors, full_length=run.full_length or self.setup.full_length,
                      lying=self.setup.lying)
        plan = self.controller.plan
        watch = None if self.setup.ball is None else BallWatch(engine, self.setup.ball)

        def on_tick(t: float) -> None:
            self._tick(t)
            if watch is not None:
                watch.sample(t)

        try:
            track, start = simulate(engine, self.body, self.controller, self.servo, run, on_tick)
            judged = judge(track, start, plan, self.spec, self.tilt_limit)
            report = run_report(track, start, plan, self.spec, judged,
                                RunSetupFacts(engine_name, self.servo, engine.time_step))
            if plan.measure is not None:
                report = replace(report, walk=plan.measure(track, start, plan, self.spec))
            if watch is not None:
                report = replace(report, ball=watch.report())
            if snapshot:
                report = replace(report, snapshot_png=snapshot_png(engine, self.spec, self.servo))
            return replace(report, track=track) if keep_track else report
        finally:
            engine.close()
            self.done += plan.duration_s

    def pushed(self, engine_name: EngineName, pushes: Pushes) -> tuple[PushResult, ...]:
        """One run per push direction."""
        at = self.controller.plan.default_push_s() if pushes.at_s is None else pushes.at_s
        out = []
        for direction in pushes.directions:
            dx, dy = PUSH_DIRECTIONS[direction]
            push = Push(np.array([dx, dy, 0.0]) * pushes.force_n, at, pushes.duration_s)
            out.append(PushResult(direction, pushes.force_n, at, pushes.duration_s,
                                  self.run(engine_name, RunSetup(push=push), keep_track=self.setup.keep_track)))
        return tuple(out)


def runs_per_engine(pushes: Pushes | None, trials: Trials | None) -> int:
    """The runs one engine makes in a check: the main run, one per push direction, one per trial."""
    pushing = pushes is not None and pushes.force_n > 0.0
    return 1 + (len(pushes.directions) if pushes is not None and pushing else 0) + (trials.runs if trials else 0)


def check_runs(engines: int, pushes: Pushes | None, trials: Trials | None) -> int:
    """The runs a check makes in ``engines`` engines (see :func:`runs_per_engine`)."""
    return engines * runs_per_engine(pushes, trials)


def check_work(runs: int, seconds_each: float, counted: str | None = None) -> None:
    """Refuse more than :data:`MAX_SIMULATED_S` of simulated time in one request (runs x seconds), before any work:
    engines, bodies, pushes, trials and steps multiply. ``counted`` says how the runs came about."""
    total = runs * seconds_each
    if total > MAX_SIMULATED_S:
        raise InputError(f"expected at most {MAX_SIMULATED_S:g} s of simulated time in all, got {counted or runs} "
                         f"run(s) of {seconds_each:.1f} s = {total:.0f} s: ask for fewer steps or seconds, trials, "
                         f"pushes, bodies or engines")


def check(controller: Controller[Plan], spec: Spec, engines: Sequence[EngineName] = ("pybullet",),
          pushes: Pushes | None = None, trials: Trials | None = None, setup: Setup = Setup(),
          on_progress: Progress | None = None) -> CheckReport:
    """Run ``controller`` (a :class:`.controller.Controller`, e.g. a :class:`.controller.Schedule`) in each of
    ``engines`` (see the module docstring); ``on_progress(done, total)`` gets the simulated seconds [s]."""
    if not engines or any(e not in ENGINES for e in engines):
        raise InputError(f"expected engines among {', '.join(ENGINES)}, got {list(engines)!r}", "engine")
    if not isinstance(controller, Controller):
        raise InputError(f"expected a controller (plan, start, step, done), got {type(controller).__name__}",
                         "controller")
    pushing = pushes is not None and pushes.force_n > 0.0
    planned = check_runs(len(engines), pushes, trials)
    check_work(planned, controller.plan.duration_s)
    runner = _Runner(controller, spec, setup, planned, on_progress)
    reports: dict[str, EngineReport] = {}
    for k, name in enumerate(engines):
        main = runner.run(name, snapshot=setup.snapshot and k == 0, keep_track=setup.keep_track)
        pushed = runner.pushed(name, pushes) if pushes is not None and pushing else ()
        tried = None
        if trials is not None and trials.runs:
            runs = tuple(runner.run(name, RunSetup(start_offset=o)) for o in trials.offsets(len(spec.joints)))
            tried = TrialsResult(trials.perturb_deg, trials.seed, runs)
        reports[name] = EngineReport(name, main, pushed, tried)
    return CheckReport(reports)
