"""Regenerate the kick table (docs/motions.md): the stock kick pages (12 right, 13 left, ``tests/data/motion_4096.bin``,
played from walk-ready as the robot's framework plays them) and op2motion's own kicks (``poses/motions/kick_*.json``,
planned), each from standing and as an event inside a commanded walk (walk, stop, kick, walk on), in PyBullet and
MuJoCo (MX-28 model, 1 kHz). Ball-less: the kicking sole's peak speed (the recorded track, every 10 ms).

Run from the repository root: ``python tools/kick_table.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from op2motion.formats.action import ActionFile
from op2motion.formats.motionfile import read_motion
from op2motion.gait import SteerableWalk, timeline_of
from op2motion.motion.getup_ways import motion_path
from op2motion.motion.pipeline import plan_motion, play_page
from op2motion.physics import ENGINES, Setup, check
from op2motion.robot.specfile import default_spec

ROOT = Path(__file__).resolve().parents[1]
STOCK = ActionFile.read(ROOT / "tests" / "data" / "motion_4096.bin")
WALK_READY = 9


def peak_speed(track, side: str, window: tuple[float, float] = (0.0, np.inf)) -> float:
    """The kicking sole's peak speed [m/s] within ``window`` [s]."""
    sole = track.soles[side]
    speed = np.linalg.norm(np.diff(sole, axis=0), axis=1) / np.diff(track.times)
    inside = (track.times[1:] >= window[0]) & (track.times[1:] <= window[1])
    return float(speed[inside].max())


def kick_window(walk) -> tuple[float, float]:
    """When the kick phase of a commanded walk plays [s] (its dry run)."""
    from op2motion.gait.steer import LEAD_S

    first, phase = next((f, p) for f, p in walk.dry.planner.phases if p.kind == "kick")
    return LEAD_S + first * 0.008, LEAD_S + (first + phase.rows) * 0.008


def cell(report, side: str, window: tuple[float, float] = (0.0, np.inf)) -> str:
    run = report.run
    speed = peak_speed(run.track, side, window)
    verdict = "stands" if not run.fell else "FELL (" + ", ".join(run.reasons) + ")"
    return f"{verdict}; foot {speed:.2f} m/s"


def main() -> None:
    spec = default_spec()
    print("| kick | from standing: PyBullet | MuJoCo | inside a walk: PyBullet | MuJoCo |")
    print("|---|---|---|---|---|")
    for side, page in (("right", 12), ("left", 13)):
        for label, action in ((f"stock page {page}", STOCK), (f"own `kick_{side}`", None)):
            if action is not None:
                trajectory = play_page(action, page, spec, action.pose(WALK_READY, spec)).trajectory
            else:
                trajectory = plan_motion(read_motion(motion_path(f"kick_{side}"), spec), spec)
            standing = check(trajectory.schedule(spec), spec, ENGINES, setup=Setup(keep_track=True))
            timeline = timeline_of([(0.0, 0.0, 0.0, 0.0), (1.5, 0.12, 0.0, 0.0), (3.0, f"kick_{side}"),
                                    (22.0, "stop")])
            walk = SteerableWalk.make(spec, commands=timeline, action=action)
            window = kick_window(walk) if walk.plan is not None else (0.0, np.inf)
            walking = check(walk, spec, ENGINES, setup=Setup(keep_track=True))
            cells = [cell(standing.engines[e], side) for e in ENGINES] + [cell(walking.engines[e], side, window)
                                                                          for e in ENGINES]
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
