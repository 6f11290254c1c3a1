"""What a physics check reports: typed results, per run, per engine and for the whole check.

Reasons (a fixed vocabulary; a run is ``stable`` only when there is none), listed in the order they first happened;
:mod:`.judge` decides each:

* ``tilt``: the torso turned more than the tilt limit from its loaded attitude (a fall), or more than the loading
  limit while gravity ramped in;
* ``com_drop``: the centre of mass sank below three quarters of its planned height;
* ``ground_contact``: a link other than a foot pressed on the floor;
* ``swing_foot_contact``: a foot that should be lifted pressed on the floor;
* ``self_collision``: two links that are not parent and child pressed on each other;
* ``torque_saturation``: over the steady window a servo was at its available torque for most of the time;
* ``joint_limit``: a joint lay on its mechanical stop, away from its goal;
* ``slip``: a supporting sole slid over the floor while it carried load.

A run *fell* when it tilted, dropped its centre of mass or touched the floor with a link other than a foot
(:data:`FALL_REASONS`); two engines *agree* when the same thing happened in both (:meth:`RunReport.outcome`): both
stood, both fell, or both failed for the same reasons without falling.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

from op2motion.jsonout import JsonObject, json_object
from op2motion.physics.ball import BallReport
from op2motion.physics.scene import EngineName
from op2motion.robot.sides import Side

REASONS = ("tilt", "com_drop", "ground_contact", "swing_foot_contact", "self_collision", "torque_saturation",
           "joint_limit", "slip")
FALL_REASONS = ("tilt", "com_drop", "ground_contact")
PUSH_DIRECTIONS = {"forward": (1.0, 0.0), "backward": (-1.0, 0.0), "left": (0.0, 1.0), "right": (0.0, -1.0)}
OPPOSITE = {"forward": "backward", "backward": "forward", "left": "right", "right": "left"}


def _r(value: float, digits: int = 5) -> float:
    return round(float(value), digits)


@dataclass(frozen=True)
class Failure:
    """One reason, when it first happened [s] after the start of the run, and what was seen."""

    reason: str
    time_s: float
    detail: str


@dataclass(frozen=True)
class FootLoad:
    """One foot on the floor over the steady window: its share of the load, its own centre of pressure (world xy
    [m]) and that CoP's margin to the foot's sole [m] (a foot tips when its own CoP reaches its edge)."""

    load_share: float
    cop_xy: tuple[float, float]
    cop_margin_m: float


@dataclass(frozen=True)
class WorstTorque:
    """The largest servo torque [N·m] of a stretch of a run, at ``joint`` and ``time_s`` [s], against
    ``available_nm`` [N·m] (what the servo could deliver at that moment, its speed and the torque's direction; a
    walk reports the sample nearest the limit, a motion its largest torque);
    ``limited_share``: the share of samples with some servo at its limit (walks)."""

    joint: str
    torque_nm: float
    available_nm: float
    time_s: float
    limited_share: float | None = None

    @property
    def ratio(self) -> float:
        """Torque over available torque."""
        return self.torque_nm / max(self.available_nm, 1e-9)

    def as_dict(self) -> JsonObject:
        """JSON-ready."""
        out: JsonObject = {"joint": self.joint, "torque_nm": self.torque_nm, "available_nm": self.available_nm,
                           "ratio": self.ratio, "time_s": self.time_s}
        if self.limited_share is not None:
            out["limited_share"] = self.limited_share
        return out


@dataclass(frozen=True)
class MotionMeasures:
    """A motion's extras: tracking error per joint [deg] (max and RMS) while it plays and half a second after, the
    worst torque against what was available then, and the centre-of-pressure track ((t [s], x [m], y [m]), ...)."""

    tracking_max_deg: dict[str, float]
    tracking_rms_deg: dict[str, float]
    worst_torque: WorstTorque
    cop_track: tuple[tuple[float, float, float], ...] = field(repr=False)


class RunMeasures(Protocol):
    """What physics reads of a wing's own measurements of a run (:attr:`RunReport.walk`, made by the plan's hook
    :attr:`.plan.Plan.measure`, e.g. a walk's :class:`op2motion.gait.measures.WalkMeasures`): only its columns in
    the robustness family's JSON (:func:`.robust_table.robust_summary`)."""

    def robust_row(self) -> JsonObject:
        """JSON-ready columns for the family's rows."""
        ...


@dataclass(frozen=True)
class RunReport:
    """Verdict and measurements of one physics run (lengths [m], angles [deg], torques [N·m], world frame: the floor,
    the start's flat sole at the origin)."""

    engine: EngineName
    servo: str
    time_step_s: float
    seconds: float
    failures: tuple[Failure, ...]
    support_margin_m: float          # settled full-inertia CoM to the edge of the real support polygon (+ inside)
    margin_at_load_m: float          # the same when gravity has just reached full strength
    cop_xy: tuple[float, float] | None   # measured centre of pressure (steady window)
    com_settled: tuple[float, float, float]
    com_start: tuple[float, float, float]
    max_tilt_deg: float              # largest turn of the torso after loading (from the start if it fell loading)
    settled_tilt_deg: float          # the torso's turn from the start to the end, loading included
    load_tilt_deg: float             # the torso's turn while the pose took its weight (servo sag)
    com_drift_m: float
    feet_slip_m: float
    start_gap_m: float               # double support: height of the other foot's lowest corner at the start
    flat_foot: Side
    self_collisions: tuple[tuple[str, str], ...]
    ground_contacts: tuple[str, ...]
    max_torque_nm: float             # steady window, worst joint
    torque_ratio: float              # max_torque_nm / its available torque
    worst_joint: str
    peak_torque_nm: float
    sag_deg: dict[str, float]        # steady-window joint angle minus goal
    swing_foot_min_z_m: float | None = None         # one-foot support: the swing foot's lowest corner at the end
    planned_seconds: float = 0.0     # the plan's duration; ``seconds`` is what was simulated
    ended: str = "full"              # why the run ended: full (its duration), settled or fell (physics.stopping)
    feet: dict[str, FootLoad] = field(default_factory=dict)
    motion: MotionMeasures | None = None
    walk: Any = None                 # the plan's own measurements (:attr:`.plan.Plan.measure`; a walk's), if any
    ball: BallReport | None = None   # what the run did to a ball on the floor (:mod:`.ball`), if one lay there
    snapshot_png: bytes | None = field(default=None, repr=False, compare=False)
    track: Any = field(default=None, repr=False, compare=False)     # the samples (:class:`.track.Track`), if kept

    @property
    def reasons(self) -> list[str]:
        """The reasons, each once, in the order they first happened."""
        return list(dict.fromkeys(f.reason for f in self.failures))

    @property
    def stable(self) -> bool:
        """No failure at all."""
        return not self.failures

    @property
    def fell(self) -> bool:
        """It tilted over, sank, or touched the floor with a link other than a foot."""
        return bool(set(self.reasons) & set(FALL_REASONS))

    @property
    def torque_ok(self) -> bool:
        """No servo saturated."""
        return "torque_saturation" not in self.reasons

    @property
    def reason(self) -> str:
        """The first failure in words, or ``stands``."""
        if not self.failures:
            return "stands"
        return f"{self.failures[0].reason}: {self.failures[0].detail}"

    def outcome(self) -> str:
        """What happened, for comparing engines: ``stands``, ``falls``, or the reasons it failed without falling."""
        if self.stable:
            return "stands"
        return "falls" if self.fell else ", ".join(sorted(self.reasons))

    def as_dict(self) -> JsonObject:
        """JSON-ready (without the snapshot and the plan's own (a walk's) measurements)."""
        out = asdict(self)
        for key in ("snapshot_png", "motion", "walk", "track", "ball"):
            del out[key]
        if self.ball is not None:                  # a key only where a ball lay (the reports without one unchanged)
            out["ball"] = json_object(self.ball)
        out.update(stable=self.stable, reasons=self.reasons, torque_ok=self.torque_ok, reason=self.reason)
        m = self.motion
        out.update(tracking_max_deg=m.tracking_max_deg if m else {}, tracking_rms_deg=m.tracking_rms_deg if m else {},
                   motion_worst_torque=m.worst_torque.as_dict() if m else {},
                   cop_track=[list(row) for row in m.cop_track] if m else [])
        return out

    def summary(self) -> str:
        """Two or three lines for people."""
        verdict = "STABLE" if self.stable else "NOT STABLE (" + ", ".join(self.reasons) + ")"
        feet = "; ".join(f"{side} {f.load_share * 100:.0f} % of the load, its CoP {f.cop_margin_m * 1000:+.1f} mm "
                         f"from its edge" for side, f in self.feet.items())
        early = "" if self.ended == "full" else f" ({self.ended}: ended early, of {self.planned_seconds:g} s)"
        return (f"{self.engine}, {self.seconds:g} s at {1 / self.time_step_s:.0f} Hz{early}: {verdict}\n"
                f"  margin {self.support_margin_m * 1000:+.1f} mm (settled full-inertia CoM to the support polygon's "
                f"edge), tilt max {self.max_tilt_deg:.1f}°, torque {self.max_torque_nm:.2f} N·m at "
                f"{self.worst_joint} ({self.torque_ratio * 100:.0f} % of available)"
                + (f"\n  feet: {feet}" if len(self.feet) > 1 else ""))


@dataclass(frozen=True)
class PushResult:
    """A push of ``force_n`` [N] in ``direction`` (the way the force points) for ``duration_s`` [s] from
    ``start_s`` [s] into the run, and how the run it was in ended."""

    direction: str
    force_n: float
    start_s: float
    duration_s: float
    run: RunReport = field(repr=False)

    @property
    def stable(self) -> bool:
        """The run had no failure."""
        return self.run.stable

    @property
    def fell(self) -> bool:
        """The run fell (:data:`FALL_REASONS`)."""
        return self.run.fell

    @property
    def reasons(self) -> list[str]:
        """The run's reasons."""
        return self.run.reasons

    def as_dict(self) -> JsonObject:
        """JSON-ready."""
        return {"direction": self.direction, "force_n": self.force_n, "start_s": _r(self.start_s, 3),
                "duration_s": self.duration_s, "stable": self.stable, "reasons": self.reasons}


@dataclass(frozen=True)
class TrialsResult:
    """Runs from perturbed starts: every joint off its first goal by a normal draw of ``perturb_deg`` [deg]
    (``seed``)."""

    perturb_deg: float
    seed: int
    runs: tuple[RunReport, ...] = field(repr=False)

    @property
    def survived(self) -> int:
        """How many runs did not fall."""
        return sum(not r.fell for r in self.runs)

    @property
    def stood(self) -> int:
        """How many runs had no failure."""
        return sum(r.stable for r in self.runs)


@dataclass(frozen=True)
class EngineReport:
    """One engine's part of a check: the main run, the pushed runs and the perturbed runs."""

    engine: EngineName
    run: RunReport
    pushes: tuple[PushResult, ...] = ()
    trials: TrialsResult | None = None

    def as_dict(self) -> JsonObject:
        """The run's JSON with its pushes."""
        return {**self.run.as_dict(), "pushes": [p.as_dict() for p in self.pushes]}


@dataclass(frozen=True)
class CheckReport:
    """A whole check: one :class:`EngineReport` per engine, in the order they ran."""

    engines: dict[str, EngineReport]

    @property
    def first(self) -> EngineReport:
        """The first engine's report."""
        return next(iter(self.engines.values()))

    @property
    def run(self) -> RunReport:
        """The first engine's main run."""
        return self.first.run

    @property
    def agree(self) -> bool:
        """The same thing happened in every engine (:meth:`RunReport.outcome`)."""
        return len({e.run.outcome() for e in self.engines.values()}) == 1

    @property
    def stable(self) -> bool:
        """Every engine's main run stood (and they agree)."""
        return all(e.run.stable for e in self.engines.values())

    @property
    def fell(self) -> bool:
        """Some engine's main run fell."""
        return any(e.run.fell for e in self.engines.values())

    @property
    def pushes_stood(self) -> bool:
        """Every pushed run had no failure."""
        return all(p.stable for e in self.engines.values() for p in e.pushes)

    @property
    def pushes_survived(self) -> bool:
        """No pushed run fell."""
        return all(not p.fell for e in self.engines.values() for p in e.pushes)

    def problem(self, failed: str = "does not stand", fall_only: bool = False) -> str | None:
        """Why the check fails, in one phrase, or None: the engines disagree (what happened in each), an engine's
        main run failed (with ``fall_only``: fell) -- ``failed`` says so --, or a push made a run fail (fall)."""
        if not self.agree:
            return f"the engines disagree ({self.outcomes()})"
        for name, e in self.engines.items():
            if e.run.fell if fall_only else not e.run.stable:
                return f"{failed}: {e.run.reason}" + (f" ({name})" if len(self.engines) > 1 else "")
        for e in self.engines.values():
            for p in e.pushes:
                if p.fell if fall_only else not p.stable:
                    return (f"{'falls' if fall_only else 'fails'} when pushed {p.force_n:g} N {p.direction} "
                            f"({', '.join(p.reasons)}, {e.engine})")
        return None

    def outcomes(self) -> str:
        """Each engine's outcome in words: ``pybullet: stands, mujoco: tilt: ...``."""
        return ", ".join(f"{name}: {e.run.reason}" for name, e in self.engines.items())
