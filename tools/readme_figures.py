"""Regenerate the README's physics and torque figures from the code: ``python tools/readme_figures.py``.

Prints Markdown: the static joint torques of the stock ROBOTIS poses (pinocchio), their verdicts in both engines at
0.5x, 1x and 2x the servo stiffness with the 2 N pushes, the full-inertia vs lumped CoM offsets, and the committed
book poses' margins. ``tests/test_readme.py`` checks that the torque and margin figures in the README match.
"""

from __future__ import annotations

import sys
from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STOCK = ("init", "walkready", "sit_down", "stand_up")
STIFFNESS = (0.5, 1.0, 2.0)
PUSH_N = 2.0


def _verdict(task: tuple[str, str, float, float]) -> tuple[tuple[str, str, float, float], dict]:
    from op2motion.formats.posefile import read_pose
    from op2motion.physics import validate
    from op2motion.robot.specfile import default_spec

    name, engine, stiffness, push = task
    spec = default_spec()
    pose = read_pose(ROOT / "poses" / f"{name}.json", spec)
    v = validate(pose.servo, pose.support, spec, 5.0, engine, push_n=push, stiffness=stiffness)
    return task, {"stable": v.stable, "reasons": v.reasons, "margin_mm": v.support_margin_m * 1000,
                  "load_tilt": v.load_tilt_deg, "torque": v.max_torque_nm, "worst": v.worst_joint,
                  "pushes": {p.direction: p.stable for p in v.pushes}}


def main() -> int:
    sys.path.insert(0, str(ROOT / "tests"))
    from helpers import static_torque_rows

    print("| pose | support | worst joint | static torque [N·m] | share of stall |\n|---|---|---|---|---|")
    for row in static_torque_rows():
        print(f"| {row[0]} | {row[1]} | {row[2]} | {row[3]:.2f} | {row[4]:.0%} |")
    tasks = [(n, e, s, PUSH_N if s == 1.0 else 0.0) for n in STOCK for e in ("pybullet", "mujoco") for s in STIFFNESS]
    with Pool(2) as pool:
        results = dict(pool.map(_verdict, tasks))
    print("\n| pose | engine | 0.5× stiffness | 1× (P = 32) | 2× | 2 N pushes survived (1×) |")
    print("|---|---|---|---|---|---|")
    for n in STOCK:
        for e in ("pybullet", "mujoco"):
            cells = []
            for s in STIFFNESS:
                r = results[(n, e, s, PUSH_N if s == 1.0 else 0.0)]
                verdict = "stands" if r["stable"] else "falls: " + ", ".join(r["reasons"])
                cells.append(f"{verdict} (margin {r['margin_mm']:.0f} mm, sag {r['load_tilt']:.1f}°)")
            pushes = results[(n, e, 1.0, PUSH_N)]["pushes"]
            print(f"| {n} | {e} | {' | '.join(cells)} | {sum(pushes.values())}/{len(pushes)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
