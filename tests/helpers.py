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
    from op2motion.joints import BookAngles, book_to_servo

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
