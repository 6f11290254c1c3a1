"""Measure the steered walk's envelope: the fastest forward, backward, sideways and turning commands that pass the
robustness family (every member, PyBullet and MuJoCo, 16 ms IMU latency), and the table for docs/steering.md.

Each run: the ``steer`` preset, standing 2 s, the command for :data:`COMMAND_S`, then stop; judged twice: by the
commanded walk's judge (:func:`op2motion.gait.robust.commanded_judge`: no fall, heading within 15° of the plan, the end
within 15 % of the way of the planned end), which sets the envelope, and by the straight walk's stricter judge
(:func:`op2motion.gait.robust.walk_judge`: drift at most 5 %, heading within 5°), whose failures the table lists; the
walk's envelope is opened wide for the measurement (:data:`WIDE`), so the commands are not clamped.

Run from the repository root: ``python tools/steer_envelope.py [direction ...]`` (default all; about an hour on 2
cores).
"""

from __future__ import annotations

import sys
import time

from op2motion.gait.commands import timeline_of
from op2motion.gait.envelope import Envelope
from op2motion.gait.presets import load_preset
from op2motion.gait.robust import commanded_judge, walk_judge
from op2motion.gait.steer import STEER_PRESET, SteerableWalk
from op2motion.physics import ENGINES, robust_check
from op2motion.robot.specfile import default_spec

COMMAND_S = 8.0
STAND_S = 2.0
WIDE = Envelope(forward_m_s=0.5, backward_m_s=0.4, sideways_m_s=0.2, turn_rad_s=1.5, combined=4.0)
#: The commands tried per direction, slowest first: (vx [m/s], vy [m/s], yaw rate [rad/s]).
SPEEDS = {"forward": [(0.2, 0.0, 0.0), (0.25, 0.0, 0.0)],
          "backward": [(-0.12, 0.0, 0.0), (-0.15, 0.0, 0.0)],
          "sideways": [(0.0, 0.05, 0.0), (0.0, 0.07, 0.0)],
          "turning": [(0.0, 0.0, 0.4), (0.0, 0.0, 0.5), (0.0, 0.0, 0.6), (0.0, 0.0, 0.8)],
          "forward and turning": [(0.1, 0.0, 0.3), (0.15, 0.0, 0.45)]}


def run(command: tuple[float, float, float]) -> tuple[int, int, int, list[str], float]:
    """One command across the family in both engines: passed (commanded judge), passed (straight judge), runs, the
    straight judge's failures, seconds."""
    spec = default_spec()
    params = load_preset(STEER_PRESET)
    timeline = timeline_of([(0.0, 0.0, 0.0, 0.0), (STAND_S, *command), (STAND_S + COMMAND_S, "stop")])
    base = SteerableWalk(params, spec, envelope=WIDE, commands=timeline)
    plan = base.plan

    def fresh() -> SteerableWalk:
        walk = SteerableWalk(params, spec, envelope=WIDE, commands=timeline)
        walk._plan = plan
        return walk

    start = time.time()
    report = robust_check(fresh, spec, ENGINES, walk_judge)
    failed = [f"{r.member.name} ({r.engine}): {r.problem}" for r in report.runs if not r.passed]
    commanded = sum(commanded_judge(r.report) is None for r in report.runs)
    return commanded, len(report.runs) - len(failed), len(report.runs), failed, time.time() - start


def main() -> None:
    directions = sys.argv[1:] or list(SPEEDS)
    print("| direction | command (vx m/s, vy m/s, yaw °/s) | runs passed (commanded judge) | (straight judge) | "
          "the straight judge's failures |")
    print("|---|---|---|---|---|")
    for direction in directions:
        for vx, vy, yaw in SPEEDS[direction]:
            commanded, passed, runs, failed, seconds = run((vx, vy, yaw))
            shown = f"({vx:g}, {vy:g}, {yaw * 57.29578:.0f})"
            print(f"| {direction} | {shown} | {commanded}/{runs} | {passed}/{runs} | {'; '.join(failed) or '–'} |",
                  flush=True)
            print(f"<!-- {seconds:.0f} s -->", file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
