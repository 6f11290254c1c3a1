"""Regenerate the motion tables (docs/motions.md): stock action pages played from the init pose and the example motions,
each in PyBullet and MuJoCo with the calibrated servo model (1 kHz, goals every 8 ms, 1.5 s settle + 1.5 s hold).

Run from the repository root: ``python tools/motion_table.py``.
"""

from __future__ import annotations

from pathlib import Path

from op2motion.formats.action import ActionFile
from op2motion.formats.motionfile import read_motion
from op2motion.motion.pipeline import plan_motion, play_page
from op2motion.motion.trajectory import Trajectory
from op2motion.physics import ENGINES, check
from op2motion.robot.spec import Spec
from op2motion.robot.specfile import default_spec

ROOT = Path(__file__).resolve().parents[1]
PAGES = ((1, 1), (4, 1), (9, 1), (15, 1), (16, 1), (12, 9), (13, 9))   # (page, the page whose last step it starts from)


def row(label: str, trajectory: Trajectory, spec: Spec) -> str:
    cells = []
    for e in check(trajectory.schedule(spec), spec, ENGINES).engines.values():
        v = e.run
        assert v.motion is not None
        worst = v.motion.worst_torque
        verdict = "stands" if v.stable else ", ".join(v.reasons)
        cells.append(f"{verdict}; {max(v.motion.tracking_max_deg.values()):.1f}°; "
                     f"{worst.torque_nm:.2f}/{worst.available_nm:.2f} N·m {worst.joint}")
    return f"| {label} | {trajectory.duration_s:.2f} s | " + " | ".join(cells) + " |"


def main() -> None:
    spec = default_spec()
    action = ActionFile.read(ROOT / "tests" / "data" / "motion_4096.bin")
    print("| motion | length | PyBullet: verdict; max tracking error; worst torque / available | MuJoCo: same |")
    print("|---|---|---|---|")
    for page, origin in PAGES:
        played = play_page(action, page, spec, action.pose(origin, spec))
        print(row(f"stock page {page} ({played.page.name}) from {played.start.name}", played.trajectory, spec),
              flush=True)
    for path in sorted((ROOT / "poses" / "motions").glob("*.json")):
        if path.name.startswith(("getup_", "roll_")):      # they start lying: tools/getup_table.py
            continue
        print(row(f"`{path.name}`", plan_motion(read_motion(path, spec), spec), spec), flush=True)


if __name__ == "__main__":
    main()
