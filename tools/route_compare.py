"""Compare the route planners (docs/motions.md, "Route planners: RRT-Connect (ours) against OMPL"): our RRT-Connect
(``planner="rrt"``) and OMPL's (``"ompl"``) on the colliding pose pairs of tests/test_route.py (its data file,
tests/data/route_pairs.json) and the segments of the example motions whose straight line collides, each planned by
:func:`op2motion.motion.route.route_segment` (the same narrow-then-wide search, checks, caps and shortcuts for
both) over several seeds.

Per planner and case: how many seeds found a path, the median wall time of ``route_segment`` [s] (the straight
line's check included, the first call's compilation excluded by a warm-up), the least clearance between links along
the path (checked every 0.005 rad of the fastest joint by :class:`~op2motion.motion.body_checks.BodyChecks`) [mm],
worst and median over the seeds, and the median path length in joint space (the 20 servo angles, Euclidean) [rad],
after the shortcuts. Prints a Markdown table. ``--samples`` lowers the sample cap (default: the planner's 4,000) to
see which search needs fewer.

Run from the repository root: ``python tools/route_compare.py [--seeds N] [--samples N]`` (needs the ompl extra).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from op2motion.errors import CheckFailed
from op2motion.formats.motionfile import read_motion
from op2motion.formats.posefile import read_pose
from op2motion.motion.body_checks import BodyChecks
from op2motion.motion.pipeline import waypoints_of
from op2motion.motion.route import SEARCH_NAMES, route_segment
from op2motion.motion.rrt import RrtSettings
from op2motion.motion.shift import segment_side, with_weight_shifts
from op2motion.motion.waypoint import Waypoint
from op2motion.robot.spec import Spec
from op2motion.robot.specfile import default_spec

ROOT = Path(__file__).resolve().parents[1]
PAIRS = ROOT / "tests" / "data" / "route_pairs.json"
DENSE_RAD = 0.005            # each edge is measured this finely [rad of the fastest joint]
MOTIONS = ("stand_book_2_44", "stand_book_2_45", "stand_book_2_46", "stand_book_2_47")


def pair(entry: dict, spec: Spec) -> tuple[Waypoint, Waypoint]:
    """Two waypoints (2 s apart) of a ``tests/data/route_pairs.json`` entry: its base pose, each named joint at its
    first and second angle [deg]."""
    a = read_pose(ROOT / "poses" / f"{entry['base']}.json", spec).servo.copy()
    b = a.copy()
    for joint, (x, y) in entry["joints_deg"].items():
        a[spec.joint_names.index(joint)], b[spec.joint_names.index(joint)] = np.radians(x), np.radians(y)
    support = entry["support"]
    return Waypoint("a", a, 0.0, 0.0, support), Waypoint("b", b, 2.0, 0.0, support)


def cases(spec: Spec) -> dict[str, tuple[Waypoint, Waypoint]]:
    """The test pairs (tests/data/route_pairs.json, as tests/test_route.py uses them) and every colliding segment
    of the example motions."""
    pairs = json.loads(PAIRS.read_text(encoding="utf-8"))["pairs"]
    out = {name: pair(entry, spec) for name, entry in sorted(pairs.items())}
    for motion in MOTIONS:
        path = ROOT / "poses" / "motions" / f"{motion}.json"
        if not path.is_file():
            continue
        waypoints, _ = with_weight_shifts(waypoints_of(read_motion(path, spec)), spec)
        for a, b in zip(waypoints, waypoints[1:]):
            if route_segment(a, b, spec, 0, RrtSettings(), "rrt")[1] is not None:
                out[f"{motion}: {a.name} -> {b.name}"] = (a, b)
    return out


def measure(a: Waypoint, b: Waypoint, spec: Spec, planner: str, seed: int, settings: RrtSettings = RrtSettings()
            ) -> tuple[float, float, float] | None:
    """(seconds, least clearance [m], joint-space length [rad]) of one routed segment, None if none was found."""
    started = time.perf_counter()
    try:
        pieces, _ = route_segment(a, b, spec, seed, settings, planner)
    except CheckFailed:
        return None
    seconds = time.perf_counter() - started
    poses = [a.servo] + [p.servo for p in pieces]
    checks = BodyChecks(spec, segment_side(a, b))
    least, length = np.inf, 0.0
    for x, y in zip(poses, poses[1:]):
        n = int(np.ceil(np.abs(y - x).max() / DENSE_RAD)) + 1
        least = min(least, float(checks.measure(x + np.linspace(0.0, 1.0, n)[:, None] * (y - x)).clearance.min()))
        length += float(np.linalg.norm(y - x))
    return seconds, least, length


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 per planner and case (default 10)")
    parser.add_argument("--samples", type=int, default=RrtSettings().max_samples,
                        help=f"the sample cap per segment (default {RrtSettings().max_samples}, as motion plan)")
    args = parser.parse_args()
    settings = RrtSettings(max_samples=args.samples)
    spec = default_spec()
    found = cases(spec)
    planners = tuple(SEARCH_NAMES)
    first = next(iter(found.values()))
    for planner in planners:                       # warm-up: compile the kernels, import OMPL
        measure(*first, spec, planner, 0)
    rows, totals = [], {p: list[tuple[float, float, float]]() for p in planners}
    tries = 0
    with tqdm(total=len(found) * len(planners) * args.seeds, desc="routes", file=sys.stderr) as bar:
        for name, (a, b) in found.items():
            straight = float(np.linalg.norm(b.servo - a.servo))
            tries += args.seeds
            for planner in planners:
                runs = []
                for seed in range(args.seeds):
                    runs.append(measure(a, b, spec, planner, seed, settings))
                    bar.update()
                ok = [r for r in runs if r is not None]
                totals[planner] += [(r[0], r[1], r[2] / straight) for r in ok]
                if not ok:
                    rows.append(f"| {name} | {SEARCH_NAMES[planner]} | 0/{args.seeds} | – | – | – |")
                    continue
                clear = [r[1] * 1000 for r in ok]
                rows.append(f"| {name} | {SEARCH_NAMES[planner]} | {len(ok)}/{args.seeds} | "
                            f"{statistics.median(r[0] for r in ok):.2f} | {min(clear):.1f} / "
                            f"{statistics.median(clear):.1f} | {statistics.median(r[2] for r in ok):.2f} "
                            f"(straight {straight:.2f}) |")
    print("| case | planner | found | median time [s] | least clearance [mm]: worst / median | "
          "median length [rad] |")
    print("|---|---|---|---|---|---|")
    print("\n".join(rows))
    for planner, ok in totals.items():
        if ok:
            print(f"| all {len(found)} cases | {SEARCH_NAMES[planner]} | {len(ok)}/{tries} | "
                  f"{statistics.median(r[0] for r in ok):.2f} | {min(r[1] for r in ok) * 1000:.1f} / "
                  f"{statistics.median(r[1] for r in ok) * 1000:.1f} | "
                  f"{statistics.median(r[2] for r in ok):.3f} × straight |")


if __name__ == "__main__":
    main()
