"""Print the lean sweeps of ``tests/test_lean_sweeps.py`` as a table: ``python tools/lean_sweeps.py``.

For each sweep and engine: the last standing lean, the settled full-inertia CoM's margin there and the switch
margin (the margin halfway to the next step, where the verdict turns to "falls"), and the first falling lean's
reasons. The lean-sweep table of docs/model.md comes from here.
"""

from __future__ import annotations

from multiprocessing import Pool

from op2motion.physics.sweeps import sweep_verdict

STEP_DEG = 0.5
SECONDS = 3.0
SWEEPS = [("left", "pitch", 1), ("left", "pitch", -1), ("left", "roll", 1),
          ("double", "pitch", 1), ("double", "pitch", -1), ("double", "roll", 1)]
MAX_STEPS = 70


def sweep(task: tuple[str, str, int, str]) -> tuple[tuple, list]:
    support, kind, direction, engine = task
    out = []
    for k in range(MAX_STEPS):
        deg = direction * STEP_DEG * k
        verdict = sweep_verdict((support, kind, deg, engine, SECONDS))
        out.append((deg, verdict.stable, verdict.margin_m, verdict.reasons, verdict.foot_margin_m))
        if not verdict.stable:
            break
    return task, out


def main() -> int:
    tasks = [(s, k, d, e) for s, k, d in SWEEPS for e in ("pybullet", "mujoco")]
    with Pool(2) as pool:
        results = dict(pool.map(sweep, tasks))
    print("| support | lean | engine | last standing | settled CoM margin there | switch margin | "
          "loaded foot's own CoP margin there | first fall |")
    print("|---|---|---|---|---|---|---|---|")
    for task, rows in results.items():
        support, kind, direction, engine = task
        last, fall = rows[-2], rows[-1]
        step = rows[-3][2] - last[2]
        lean = f"{kind} {'forward' if kind == 'pitch' and direction > 0 else 'back' if kind == 'pitch' else 'outward'}"
        print(f"| {support} | {lean} | {engine} | {last[0]:+.1f}° | {last[2] * 1000:+.1f} mm | "
              f"{(last[2] - 0.5 * step) * 1000:+.1f} mm | {last[4] * 1000:+.1f} mm | "
              f"{fall[0]:+.1f}°: {', '.join(fall[3])} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
