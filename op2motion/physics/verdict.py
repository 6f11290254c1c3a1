"""What a physics check reports: a verdict with named reasons, the numbers behind it, and its setup.

Reasons (a fixed vocabulary; ``stable`` is true only when there is none), listed in the order they first happened:

* ``tilt``: the torso turned more than :data:`TILT_LIMIT_DEG` from its loaded attitude (when gravity reached full
  strength: the servos' sag while the pose takes its weight is reported as ``load_tilt_deg``, not counted), or more
  than :data:`LOADING_TILT_LIMIT_DEG` from the start while gravity ramped in (a fall during loading); in a motion,
  turns are measured against the planned attitude of that moment, counted afresh :data:`SUPPORT_SETTLE_S` after
  each change of support (a foot taking or giving up the load changes the servos' sag by several degrees; a fall
  keeps turning); the limit of a motion that stands on one foot grows by the largest torso turn the compliance
  model predicts for its single-support rows (the plan is rigid; the servos sag).
* ``com_drop``: the centre of mass sank below (1 - :data:`COM_DROP_FRACTION`) of its planned height.
* ``ground_contact``: a link other than a supporting foot pressed on the floor.
* ``swing_foot_contact``: in a single-support pose, the swing foot pressed on the floor (the robot is then on two
  feet: the pose did not hold as a one-legged pose).
* ``self_collision``: two links that are not parent and child pressed on each other.
* ``torque_saturation``: over the steady window (the last second, the pose held), a servo delivered at least
  :data:`SATURATION_FRACTION` of its available torque in at least :data:`SATURATION_SHARE` of the samples: it
  cannot hold the pose. (While a motion plays, a servo at its limit only lags: that is the tracking error.)
* ``joint_limit``: a joint lay on its mechanical stop, away from its goal, for :data:`LIMIT_HOLD_S` or more.
* ``slip``: a supporting sole slid more than :data:`SLIP_LIMIT_M` over the floor while it carried at least
  :data:`SLIP_LOAD_SHARE` of the load (a foot sliding as it unloads before lifting, or after touching down, only
  scuffs).

"Pressed" means a contact force above :data:`CONTACT_FORCE_N` [N].
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

REASONS = ("tilt", "com_drop", "ground_contact", "swing_foot_contact", "self_collision", "torque_saturation",
           "joint_limit", "slip")
TILT_LIMIT_DEG = 10.0
LOADING_TILT_LIMIT_DEG = 20.0   # while gravity ramps in, a turn this large from the start is a fall
COM_DROP_FRACTION = 0.25
CONTACT_FORCE_N = 0.5
SATURATION_FRACTION = 0.95
SATURATION_SHARE = 0.5
LIMIT_AT_RAD = 0.0175           # 1°: a joint this close to its stop lies on it
LIMIT_AWAY_RAD = 0.035          # 2°: ...and is held there away from its goal
LIMIT_HOLD_S = 0.2
SLIP_LIMIT_M = 0.01
SLIP_LOAD_SHARE = 0.2
SUPPORT_SETTLE_S = 0.3
PUSH_DIRECTIONS = {"forward": (1.0, 0.0), "backward": (-1.0, 0.0), "left": (0.0, 1.0), "right": (0.0, -1.0)}


@dataclass(frozen=True)
class Failure:
    """One reason, when it first happened [s] after the start, and what was seen."""

    reason: str
    time_s: float
    detail: str


@dataclass(frozen=True)
class PushResult:
    """A push of ``force_n`` [N] for ``duration_s`` [s] at the torso's centre of mass, after settling."""

    direction: str
    force_n: float
    start_s: float
    duration_s: float
    stable: bool
    reasons: list[str]


@dataclass(frozen=True)
class Validation:
    """Verdict and measurements of one physics check of a pose (lengths [m], angles [deg], torques [N·m])."""

    engine: str
    servo: str
    time_step_s: float
    seconds: float
    stable: bool
    reasons: list[str]
    failures: list[Failure]
    support_margin_m: float          # settled full-inertia CoM to the edge of the real support polygon (+ inside)
    margin_at_load_m: float          # the same when gravity has just reached full strength
    cop_xy: list[float] | None       # measured centre of pressure (steady window), world frame
    com_settled: list[float]
    com_start: list[float]
    max_tilt_deg: float              # largest turn of the torso after loading (from the start if it fell loading)
    settled_tilt_deg: float          # the torso's turn from the start to the end, loading included
    load_tilt_deg: float             # the torso's turn while the pose took its weight (servo sag)
    com_drift_m: float
    feet_slip_m: float
    start_gap_m: float               # double support: height of the other foot's lowest corner at the start
    flat_foot: str
    self_collisions: list[list[str]]
    ground_contacts: list[str]
    max_torque_nm: float             # steady window, worst joint
    torque_ratio: float              # max_torque_nm / its available torque
    worst_joint: str
    peak_torque_nm: float
    sag_deg: dict[str, float]        # steady-window joint angle minus goal
    swing_foot_min_z_m: float | None = None   # single support: the swing foot's lowest corner at the end [m]
    feet: dict[str, dict[str, Any]] = field(default_factory=dict)   # per foot on the floor: load share, own CoP
    # a motion's extras (empty for a held pose): tracking error per joint [deg] while it plays, the worst torque
    # against what was available, the centre-of-pressure track [[t s, x m, y m], ...]
    tracking_max_deg: dict[str, float] = field(default_factory=dict)
    tracking_rms_deg: dict[str, float] = field(default_factory=dict)
    motion_worst_torque: dict[str, Any] = field(default_factory=dict)
    cop_track: list[list[float]] = field(default_factory=list, repr=False)
    pushes: list[PushResult] = field(default_factory=list)
    snapshot_png: bytes | None = field(default=None, repr=False, compare=False)

    @property
    def torque_ok(self) -> bool:
        """No servo saturated."""
        return "torque_saturation" not in self.reasons

    @property
    def reason(self) -> str:
        """The first failure in words, or ``stands``."""
        if not self.failures:
            return "stands"
        first = self.failures[0]
        return f"{first.reason}: {first.detail}"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict (without the snapshot)."""
        out = asdict(self)
        del out["snapshot_png"]
        out["torque_ok"], out["reason"] = self.torque_ok, self.reason
        return out

    def summary(self) -> str:
        """Two lines for people."""
        verdict = "STABLE" if self.stable else "NOT STABLE (" + ", ".join(self.reasons) + ")"
        pushes = "; ".join(f"{p.force_n:g} N {p.direction}: {'ok' if p.stable else ', '.join(p.reasons)}"
                           for p in self.pushes)
        feet = "; ".join(f"{side} {f['load_share'] * 100:.0f} % of the load, its CoP "
                         f"{f['cop_margin_m'] * 1000:+.1f} mm from its edge" for side, f in self.feet.items())
        return (f"{self.engine}, {self.seconds:g} s at {1 / self.time_step_s:.0f} Hz: {verdict}\n"
                f"  margin {self.support_margin_m * 1000:+.1f} mm "
                f"(settled full-inertia CoM to the support polygon's edge), "
                f"tilt max {self.max_tilt_deg:.1f}°, torque {self.max_torque_nm:.2f} N·m at {self.worst_joint} "
                f"({self.torque_ratio * 100:.0f} % of available)" + (f"\n  pushes: {pushes}" if pushes else "")
                + (f"\n  feet: {feet}" if len(self.feet) > 1 else ""))
