"""Regenerate the physics and torque figures of docs/model.md from the code: ``python tools/readme_figures.py``.

Prints Markdown: the static joint torques of the stock ROBOTIS poses (pinocchio), their verdicts in both engines at
0.5x, 1x and 2x the servo stiffness with the 2 N pushes, the full-inertia vs lumped CoM offsets, and the committed
book poses' margins. ``tests/test_readme.py`` checks that the torque and margin figures in docs/ match.
"""

from __future__ import annotations

from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STOCK = ("init", "walkready", "sit_down", "stand_up")
#: The static torque rows (docs/model.md): the stock poses on both feet as recorded, and on the left foot alone.
STATIC_TORQUE_CASES = (("init", "double"), ("walkready", "double"), ("sit_down", "double"), ("stand_up", "double"),
                       ("walkready", "left"), ("sit_down", "left"))
STIFFNESS = (0.5, 1.0, 2.0)
PUSH_N = 2.0


def _verdict(task: tuple[str, str, float, float]) -> tuple[tuple[str, str, float, float], dict]:
    from op2motion.formats.posefile import read_pose
    from op2motion.physics import Pushes, Schedule, Setup, check
    from op2motion.robot.specfile import default_spec

    name, engine, stiffness, push = task
    spec = default_spec()
    pose = read_pose(ROOT / "poses" / f"{name}.json", spec)
    report = check(Schedule.hold(pose.servo, pose.support, spec, 5.0), spec, (engine,),
                   Pushes(push) if push else None, setup=Setup(stiffness)).first
    v = report.run
    return task, {"stable": v.stable, "reasons": v.reasons, "margin_mm": v.support_margin_m * 1000,
                  "load_tilt": v.load_tilt_deg, "torque": v.max_torque_nm, "worst": v.worst_joint,
                  "pushes": {p.direction: p.stable for p in report.pushes}}


def main() -> int:
    from op2motion.formats.posefile import read_pose
    from op2motion.model.dynamics import dynamics_for
    from op2motion.robot.specfile import default_spec

    spec = default_spec()
    print("| pose | support | worst joint | static torque [N·m] | share of stall |\n|---|---|---|---|---|")
    for name, support in STATIC_TORQUE_CASES:
        report = dynamics_for(spec).static_torques(read_pose(ROOT / "poses" / f"{name}.json", spec).servo, support)
        print(f"| {name} | {support} | {report.worst_joint} | {abs(report.worst_torque_nm):.2f} | "
              f"{report.worst_ratio:.0%} |")
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
