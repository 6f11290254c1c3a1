"""Regenerate the README's motion tables: stock action pages played from the init pose and the example motions,
each in PyBullet and MuJoCo with the calibrated servo model (1 kHz, goals every 8 ms, 1.5 s settle + 1.5 s hold).

Run from the repository root: ``python tools/motion_table.py``.
"""

from __future__ import annotations

from pathlib import Path

from op2motion.formats.action import page_to_pose, requested_page
from op2motion.formats.motionfile import read_motion
from op2motion.motion.planner import plan
from op2motion.motion.player import IDS, play
from op2motion.motion.trajectory import from_playback
from op2motion.motion.waypoint import Waypoint
from op2motion.physics import validate_motion
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.specfile import default_spec

ROOT = Path(__file__).resolve().parents[1]
PAGES = ((1, 1), (4, 1), (9, 1), (15, 1), (16, 1), (12, 9), (13, 9))   # (page, the page whose last step it starts from)


def row(label: str, trajectory, spec) -> str:  # type: ignore[no-untyped-def]
    cells = []
    for engine in ("pybullet", "mujoco"):
        v = validate_motion(trajectory.goals, trajectory.p_gains, trajectory.supports, spec, engine=engine)
        worst = v.motion_worst_torque
        cells.append(f"{'stands' if v.stable else ', '.join(v.reasons)}; {max(v.tracking_max_deg.values()):.1f}°; "
                     f"{worst['torque_nm']:.2f}/{worst['available_nm']:.2f} N·m {worst['joint']}")
    return f"| {label} | {trajectory.duration_s:.2f} s | " + " | ".join(cells) + " |"


def main() -> None:
    spec = default_spec()
    data = (ROOT / "tests" / "data" / "motion_4096.bin").read_bytes()
    print("| motion | length | PyBullet: verdict; max tracking error; worst torque / available | MuJoCo: same |")
    print("|---|---|---|---|")
    for page, origin in PAGES:
        start = page_to_pose(requested_page(data, origin, spec, "stock"), spec)
        by_id = {j.id: int(t) for j, t in zip(spec.joints, servo_to_ticks(start.servo, spec))}
        name = requested_page(data, page, spec, "stock").name
        played = from_playback(play(data, page, [by_id[i] for i in IDS]), spec)
        print(row(f"stock page {page} ({name}) from {start.name}", played, spec), flush=True)
    for path in sorted((ROOT / "poses" / "motions").glob("*.json")):
        motion = read_motion(path, spec)
        waypoints = [Waypoint(s.pose.name, s.pose.servo, s.duration_s, s.pause_s, s.pose.support)
                     for s in motion.steps]
        print(row(f"`{path.name}`", plan(waypoints, spec, motion.profile, motion.p_gain), spec), flush=True)


if __name__ == "__main__":
    main()
