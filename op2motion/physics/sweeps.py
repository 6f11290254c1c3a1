"""Lean sweeps: a stance leaned step by step at its support ankle(s) until it falls, to see where physics says
the support runs out (docs/model.md, Lean sweeps; ``tests/test_lean_sweeps.py``, ``tools/lean_sweeps.py``).

The stances: on the left foot, the swing leg folded and the arms forward, balanced so the full-inertia CoM stands
11 mm inward of the sole centre (:data:`ARMS_FORWARD`, :data:`FOLDED_SWING`); or on both feet, the standing pose
with the arms forward, centred over the soles. A lean turns the support ankle(s) in pitch (forward positive) or
roll (outward for the left foot; on two feet the legs lean as a parallelogram, the torso level).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from op2motion.model.dynamics import dynamics_for
from op2motion.physics.controller import Schedule
from op2motion.physics.report import RunReport
from op2motion.physics.runner import Setup, check
from op2motion.robot.joints import BookAngles, book_to_servo, hip_roll_sign
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, SupportName

if TYPE_CHECKING:
    from op2motion.physics.scene import EngineName

ARMS_FORWARD = {"r_sho_pitch": -90.0, "l_sho_pitch": 90.0}
FOLDED_SWING = {"r_hip_roll": 25.0, "r_ank_roll": 25.0, "r_hip_pitch": -90.0, "r_knee": 140.0, "r_ank_pitch": 50.0}
ONE_LEG_COM_XY_M = (0.0, 0.011)    # the one-leg stance's CoM over the sole: 11 mm inward of its centre
LEAN_TOL_M = 1e-5
LEAN_STEP_RAD = 1e-4


def servo_pose(spec: Spec, support: Support | SupportName = "left", **degrees: float) -> np.ndarray:
    """Servo angles (20,) [rad]: the book's standing pose with some joints set to ``degrees``."""
    servo: np.ndarray = book_to_servo(BookAngles.standing("left" if support == "double" else support), spec)[0]
    for name, value in degrees.items():
        servo[spec.joint_names.index(name)] = np.radians(value)
    return servo


def balanced_pose(spec: Spec, servo: np.ndarray, support: Support | Side, target_xy: Sequence[float] = (0.0, 0.0),
             iterations: int = 20) -> np.ndarray:
    """The pose with its full-inertia CoM over ``target_xy`` [m] of the support sole frame: the support ankle's
    roll and pitch tilt the whole body, the support hip roll turns back by the same roll (torso level)."""
    dyn = dynamics_for(spec)
    s = support[0]
    ankle_roll, ankle_pitch, hip_roll = (spec.joint_names.index(f"{s}_{j}") for j in ("ank_roll", "ank_pitch",
                                                                                       "hip_roll"))
    out = np.array(servo, dtype=float)

    def com_xy(v: np.ndarray) -> np.ndarray:
        return dyn.com(v, support)[:2]

    def with_lean(v: np.ndarray, roll: float, pitch: float) -> np.ndarray:
        w = v.copy()
        w[ankle_roll] += roll
        w[hip_roll] += roll * hip_roll_sign(spec, s)
        w[ankle_pitch] += pitch
        return w

    lean = np.zeros(2)
    for _ in range(iterations):
        current = com_xy(with_lean(out, *lean))
        err = np.asarray(target_xy) - current
        if np.linalg.norm(err) < LEAN_TOL_M:
            break
        h = LEAN_STEP_RAD
        jac = np.column_stack([(com_xy(with_lean(out, lean[0] + h, lean[1])) - current) / h,
                               (com_xy(with_lean(out, lean[0], lean[1] + h)) - current) / h])
        lean += np.linalg.lstsq(jac, err, rcond=None)[0]
    return with_lean(out, *lean)


def centred(spec: Spec, servo: np.ndarray, x: float = 0.0, iterations: int = 20) -> np.ndarray:
    """A double-support pose leaned at both ankles (the feet stay flat) until its full-inertia CoM is ``x`` [m]
    ahead of the soles' centres."""
    dyn = dynamics_for(spec)
    left, right = spec.joint_names.index("l_ank_pitch"), spec.joint_names.index("r_ank_pitch")
    sign = spec.joint("l_ank_pitch").axis[1] / spec.joint("r_ank_pitch").axis[1]   # the same lean on both legs
    out = np.array(servo, dtype=float)

    def com_x(v: np.ndarray) -> float:
        return float(dyn.com(v, "double")[0])

    for _ in range(iterations):
        err = x - com_x(out)
        if abs(err) < LEAN_TOL_M / 10:
            break
        probe = out.copy()
        probe[left] += LEAN_STEP_RAD
        probe[right] += LEAN_STEP_RAD * sign
        step = err / ((com_x(probe) - com_x(out)) / LEAN_STEP_RAD)
        out[left] += step
        out[right] += step * sign
    return out


def sweep_base(spec: Spec, support: Support | SupportName) -> np.ndarray:
    """The start of a lean sweep (see the module docstring) on ``left`` or ``double`` support."""
    if support == "double":
        return centred(spec, servo_pose(spec, "double", **ARMS_FORWARD))
    return balanced_pose(spec, servo_pose(spec, "left", **ARMS_FORWARD, **FOLDED_SWING), "left", ONE_LEG_COM_XY_M)


def leaned(spec: Spec, base: np.ndarray, support: Support | SupportName, kind: str, degrees: float) -> np.ndarray:
    """``base`` leaned by ``degrees`` at the support ankle(s): ``pitch`` (positive forward) or ``roll`` (positive
    to the left, outward for the left foot; in double support the legs lean as a parallelogram, torso level)."""
    out = np.array(base, dtype=float)
    angle = np.radians(degrees)
    for s in (("l", "r") if support == "double" else ("l",)):
        if kind == "pitch":                   # forward: the shank turns about +Y relative to the foot
            out[spec.joint_names.index(f"{s}_ank_pitch")] -= angle * spec.joint(f"{s}_ank_pitch").axis[1]
        else:
            out[spec.joint_names.index(f"{s}_ank_roll")] += angle
            out[spec.joint_names.index(f"{s}_hip_roll")] += angle * hip_roll_sign(spec, s)
    return out


SweepTask = tuple[SupportName, str, float, "EngineName", float]    # support, kind, degrees, engine, seconds


def sweep_run(task: SweepTask, full_length: bool = False) -> RunReport:
    """One pose of a sweep, (support, kind, degrees, engine, seconds), held in that engine (the shipped spec): the
    run's report; ``full_length`` plays the whole hold (a check ends once its verdict is known). A worker for process
    pools."""
    from op2motion.robot.specfile import default_spec

    support, kind, degrees, engine, seconds = task
    spec = default_spec()
    pose = leaned(spec, sweep_base(spec, support), support, kind, degrees)
    return check(Schedule.hold(pose, support, spec, seconds), spec, (engine,),
                 setup=Setup(full_length=full_length)).run


@dataclass(frozen=True)
class SweepOutcome:
    """A sweep's pose in one engine: whether it stood, its margin [m] (the settled one for a standing pose, the one
    when gravity reached full strength for a falling one), the run's reasons, and the loaded feet's own CoP margin
    [m] (the least margin of a foot's CoP to its sole among the feet carrying at least a tenth of the load; NaN for
    a falling pose)."""

    stable: bool
    margin_m: float
    reasons: list[str]
    foot_margin_m: float


def sweep_outcome(v: RunReport) -> SweepOutcome:
    """The :class:`SweepOutcome` of a sweep's run."""
    feet = [f.cop_margin_m for f in v.feet.values() if f.load_share >= 0.1]
    foot = min(feet) if v.stable and feet else float("nan")
    return SweepOutcome(v.stable, v.support_margin_m if v.stable else v.margin_at_load_m, list(v.reasons), foot)


def sweep_verdict(task: SweepTask) -> SweepOutcome:
    """One pose of a sweep, (support, kind, degrees, engine, seconds) -> :func:`sweep_outcome` of its run. A worker
    for process pools (the shipped spec)."""
    return sweep_outcome(sweep_run(task))
