"""CLI commands of the physics layer: urdf, validate."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..physics import DEFAULT_SECONDS, MAX_SECONDS, MIN_SECONDS
from ..spec import Spec
from .common import add_command, emit, number, output_path, progress_enabled


def register(sub: Any) -> None:
    """Add urdf and validate."""
    p = add_command(sub, "urdf", cmd_urdf, "the URDF generated from the spec (stdout, or -o FILE)")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE", help="write the URDF here (atomically)")

    p = add_command(sub, "validate", cmd_validate, "physics check: does a pose stand?")
    p.add_argument("pose", metavar="POSE", help="pose file (schema op2motion.pose/1)")
    p.add_argument("--seconds", type=number(MIN_SECONDS, MAX_SECONDS, "s"), default=DEFAULT_SECONDS,
                   help=f"simulated time [s] (default {DEFAULT_SECONDS:g})")
    p.add_argument("--gui-png", type=output_path, metavar="PNG", help="snapshot of the final state (TinyRenderer)")


def cmd_urdf(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion urdf``."""
    from ..fileio import OutputSet
    from ..model.urdf import build_urdf, total_mass

    text = build_urdf(spec)
    facts = {"joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}
    if args.output:
        outputs = OutputSet({"output": args.output})
        outputs.put("output", text)
        out = outputs.commit()["output"]
        emit(args, {"path": str(out), **facts}, f"wrote {out}: {len(spec.joints)} joints, {total_mass(spec):.3f} kg")
    elif args.json:
        emit(args, {"urdf": text, **facts}, "")
    else:
        sys.stdout.write(text)
    return 0


def cmd_validate(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion validate``."""
    from tqdm import tqdm

    from ..errors import CheckFailed
    from ..export.posefile import read_pose
    from ..fileio import OutputSet
    from ..kinematics import forward
    from ..model.dynamics import dynamics_for
    from ..physics import steps_for, validate_servo

    outputs = OutputSet({"gui_png": args.gui_png} if args.gui_png else {})
    pose = read_pose(args.pose, spec)
    with tqdm(total=steps_for(args.seconds), desc="physics", unit="step", leave=False,
              disable=not progress_enabled(args)) as bar:
        v = validate_servo(pose.servo, pose.support, spec, args.seconds, bool(args.gui_png), on_step=bar.update)
    dyn = dynamics_for(spec)
    static = dyn.static_torques(pose.servo, pose.support)
    lumped = forward(pose.book(spec), spec).com[:, 0]
    result = {**v.as_dict(), "pose": pose.name, "support": pose.support,
              "static_torque_nm": {n: float(x) for n, x in zip(spec.joint_names, static.torques)},
              "static_worst_joint": static.worst_joint, "static_worst_ratio": round(static.worst_ratio, 4),
              "com_full": [float(x) for x in dyn.com(pose.servo, pose.stance)],
              "com_lumped": [float(x) for x in lumped]}
    if args.gui_png and v.snapshot_png is not None:
        outputs.put("gui_png", v.snapshot_png)
        result["png"] = str(outputs.commit()["gui_png"])
    text = (f"{pose.name} ({pose.support} support), {args.seconds:g} s of PyBullet: "
            f"{'STABLE' if v.stable else 'NOT STABLE'} ({v.reason})\n"
            f"  torso tilt max {v.max_tilt_deg:.2f}°, CoM drift {v.com_drift_m * 1000:.1f} mm, "
            f"feet slip {v.feet_slip_m * 1000:.1f} mm\n"
            f"  servo torque (steady) max {v.max_torque_nm:.2f} N·m at {v.worst_joint} "
            f"({'ok' if v.torque_ok else 'SATURATED'}; stall {spec.servo.stall_torque_nm} N·m); static model: "
            f"{abs(static.worst_torque_nm):.2f} N·m at {static.worst_joint}\n"
            f"  self-collisions: {', '.join('-'.join(p) for p in v.self_collisions) or 'none'}")
    emit(args, result, text)
    if not v.stable:
        raise CheckFailed(f"{pose.name} does not stand: {v.reason}")
    return 0
