"""Helpers shared by the tests: paths of the committed data and one way to run the CLI in-process."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from op2motion.cli import main

ROOT = Path(__file__).resolve().parents[1]
POSES = ROOT / "poses"
DATA = Path(__file__).parent / "data"
STOCK = DATA / "motion_4096.bin"
SEED = 20261121


def pose_path(name: str) -> str:
    """Path of a committed pose file."""
    return str(POSES / f"{name}.json")


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """Run ``op2motion ARGV`` in-process; returns (exit code, stdout, stderr)."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def page_last_step_ticks(data: bytes, page: int) -> np.ndarray:
    """Goal ticks of joints 1..20 in the last used step of a page (layout: ROBOTIS framework Action.h)."""
    base = page * 512
    steps = data[base + 20]  # stepnum
    step = base + 64 + 64 * (steps - 1)
    words = np.frombuffer(data[step:step + 62], dtype="<u2")
    return words[1:21].astype(int)


def servo_pose(spec, support: str = "left", **degrees: float) -> np.ndarray:
    """Servo angles (20,) [rad]: the book's standing pose with some joints set to ``degrees``."""
    from op2motion.robot.joints import BookAngles, book_to_servo

    servo = book_to_servo(BookAngles.standing("left" if support == "double" else support), spec)[0]
    for name, value in degrees.items():
        servo[spec.joint_names.index(name)] = np.radians(value)
    return servo


def balanced(spec, servo: np.ndarray, support: str, target_xy=(0.0, 0.0), iterations: int = 20) -> np.ndarray:
    """The pose with its full-inertia CoM over ``target_xy`` [m] of the support sole frame: the support ankle's
    roll and pitch tilt the whole body, the support hip roll turns back by the same roll (torso level)."""
    from op2motion.model.dynamics import dynamics_for

    dyn = dynamics_for(spec)
    s = support[0]
    ankle_roll, ankle_pitch, hip_roll = (spec.joint_names.index(f"{s}_{j}") for j in ("ank_roll", "ank_pitch",
                                                                                       "hip_roll"))
    # servo directions: +1 if a positive angle moves the CoM towards +y (roll) or +x (pitch) for this leg
    out = np.array(servo, dtype=float)

    def com_xy(v: np.ndarray) -> np.ndarray:
        return dyn.com(v, support)[:2]

    def with_lean(v: np.ndarray, roll: float, pitch: float) -> np.ndarray:
        w = v.copy()
        w[ankle_roll] += roll
        w[hip_roll] += roll * _hip_roll_sign(spec, s)
        w[ankle_pitch] += pitch
        return w

    lean = np.zeros(2)
    for _ in range(iterations):
        current = com_xy(with_lean(out, *lean))
        err = np.asarray(target_xy) - current
        if np.linalg.norm(err) < 1e-5:
            break
        h = 1e-4
        jac = np.column_stack([(com_xy(with_lean(out, lean[0] + h, lean[1])) - current) / h,
                               (com_xy(with_lean(out, lean[0], lean[1] + h)) - current) / h])
        lean += np.linalg.lstsq(jac, err, rcond=None)[0]
    return with_lean(out, *lean)


def _hip_roll_sign(spec, side: str) -> float:
    """Sign that makes a hip-roll change undo an ankle-roll change, so the torso stays level: with the pitch joints
    cancelling, the roll from torso to foot is a_hip q_hip + a_ankle q_ankle (a: the axes' x components)."""
    return -spec.joint(f"{side}_ank_roll").axis[0] / spec.joint(f"{side}_hip_roll").axis[0]


def centred(spec, servo: np.ndarray, x: float = 0.0, iterations: int = 20) -> np.ndarray:
    """A double-support pose leaned at both ankles (the feet stay flat) until its full-inertia CoM is ``x`` [m]
    ahead of the soles' centres."""
    from op2motion.model.dynamics import dynamics_for

    dyn = dynamics_for(spec)
    left, right = spec.joint_names.index("l_ank_pitch"), spec.joint_names.index("r_ank_pitch")
    sign = spec.joint("l_ank_pitch").axis[1] / spec.joint("r_ank_pitch").axis[1]   # the same lean on both legs
    out = np.array(servo, dtype=float)

    def com_x(v: np.ndarray) -> float:
        return float(dyn.com(v, "double")[0])

    for _ in range(iterations):
        err = x - com_x(out)
        if abs(err) < 1e-6:
            break
        probe = out.copy()
        probe[left] += 1e-4
        probe[right] += 1e-4 * sign
        step = err / ((com_x(probe) - com_x(out)) / 1e-4)
        out[left] += step
        out[right] += step * sign
    return out


ARMS_FORWARD = dict(r_sho_pitch=-90, l_sho_pitch=90)
FOLDED_SWING = dict(r_hip_roll=25, r_ank_roll=25, r_hip_pitch=-90, r_knee=140, r_ank_pitch=50)


def sweep_base(spec, support: str) -> np.ndarray:
    """The start of a lean sweep: a balanced one-leg stance on the left foot (swing leg folded, arms forward), or
    the standing pose with arms forward centred over the soles."""
    if support == "double":
        return centred(spec, servo_pose(spec, **ARMS_FORWARD))
    return balanced(spec, servo_pose(spec, "left", **ARMS_FORWARD, **FOLDED_SWING), "left", (0.0, 0.011))


def leaned(spec, base: np.ndarray, support: str, kind: str, degrees: float) -> np.ndarray:
    """``base`` leaned by ``degrees`` at the support ankle(s): ``pitch`` (positive forward) or ``roll`` (positive
    to the left, outward for the left foot; in double support the legs lean as a parallelogram, torso level)."""
    out = np.array(base, dtype=float)
    angle = np.radians(degrees)
    sides = ("l", "r") if support == "double" else ("l",)
    for s in sides:
        if kind == "pitch":                   # forward: the shank turns about +Y relative to the foot
            out[spec.joint_names.index(f"{s}_ank_pitch")] -= angle * spec.joint(f"{s}_ank_pitch").axis[1]
        else:
            out[spec.joint_names.index(f"{s}_ank_roll")] += angle
            out[spec.joint_names.index(f"{s}_hip_roll")] += angle * _hip_roll_sign(spec, s)
    return out


def sweep_verdict(task: tuple) -> tuple[bool, float, list, float]:
    """Worker of the lean sweeps: (support, kind, degrees, engine, seconds) -> (stable, margin [m], reasons, foot
    margin [m]); the margin is the settled one for a standing pose, the one when gravity reached full strength for a
    falling one; the foot margin is the least margin of a foot's own CoP to its sole among the feet carrying at least
    a tenth of the load (NaN for a falling pose)."""
    from op2motion.physics import validate
    from op2motion.robot.specfile import default_spec

    support, kind, degrees, engine, seconds = task
    spec = default_spec()
    v = validate(leaned(spec, sweep_base(spec, support), support, kind, degrees), support, spec, seconds, engine)
    feet = [f["cop_margin_m"] for f in v.feet.values() if f["load_share"] >= 0.1]
    foot = min(feet) if v.stable and feet else float("nan")
    return v.stable, (v.support_margin_m if v.stable else v.margin_at_load_m), v.reasons, foot


STATIC_TORQUE_CASES = (("init", "double"), ("walkready", "double"), ("sit_down", "double"), ("stand_up", "double"),
                       ("walkready", "left"), ("sit_down", "left"))


def static_torque_rows(spec=None) -> list[tuple[str, str, str, float, float]]:
    """The README's static torque table: (pose, support, worst joint, |torque| [N·m], share of stall) of the stock
    poses held still (pinocchio), on both feet as recorded and on the left foot alone."""
    from op2motion.formats.posefile import read_pose
    from op2motion.model.dynamics import dynamics_for
    from op2motion.robot.specfile import default_spec

    spec = spec or default_spec()
    rows = []
    for name, support in STATIC_TORQUE_CASES:
        report = dynamics_for(spec).static_torques(read_pose(POSES / f"{name}.json", spec).servo, support)
        rows.append((name, support, report.worst_joint, abs(report.worst_torque_nm), report.worst_ratio))
    return rows
