"""CLI commands of the physics layer: urdf, validate."""

from __future__ import annotations

import argparse
import sys


from ..cli import emit
from ..spec import Spec


def cmd_urdf(args: argparse.Namespace, spec: Spec) -> int:
    from ..fileio import write_atomic
    from ..model.urdf import build_urdf, total_mass

    text = build_urdf(spec)
    if args.output:
        write_atomic(args.output, text)
        result = {"path": args.output, "joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}
        emit(args, result, f"wrote {args.output}: {len(spec.joints)} joints, {total_mass(spec):.3f} kg")
    elif args.json:
        emit(args, {"urdf": text, "joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}, "")
    else:
        sys.stdout.write(text)
    return 0


def cmd_validate(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from ..errors import CheckFailed
    from ..export.library import read_pose
    from ..model.dynamics import COM_MODEL_FULL, dynamics_for
    from ..physics import steps_for, validate_servo
    from ..kinematics import forward

    pose = read_pose(args.pose, spec)
    with tqdm(total=steps_for(args.seconds), desc="physics", unit="step", disable=not sys.stderr.isatty(),
              leave=False) as bar:
        v = validate_servo(pose.servo, pose.support, spec, args.seconds, args.gui_png, on_step=bar.update)
    dyn = dynamics_for(spec)
    static = dyn.static_torques(pose.servo, pose.support)
    root = "right" if pose.support == "right" else "left"
    lumped = forward(pose.book(spec), spec).com[:, 0]
    result = {**v.as_dict(), "pose": pose.name, "support": pose.support,
              "static_torque_nm": {n: float(x) for n, x in zip(spec.joint_names, static.torques)},
              "static_worst_joint": static.worst_joint, "static_worst_ratio": round(static.worst_ratio, 4),
              "com_full": [float(x) for x in dyn.com(pose.servo, root)], "com_full_model": COM_MODEL_FULL,
              "com_lumped": [float(x) for x in lumped]}
    if args.gui_png:
        result["png"] = args.gui_png
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
