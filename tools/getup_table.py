"""Regenerate the getting-up tables (docs/motions.md) and figure: ``GetUp()`` from lying face down, face up and on
either side, on every member of the robustness family in PyBullet and MuJoCo (MX-28 model, 1 kHz, 16 ms IMU latency,
20 s each), with op2motion's own motions, and on the nominal body with the stock pages 10/11
(``tests/data/motion_4096.bin``); op2motion's rolls alone from each side on the family; the supervisor catching a 30
N push mid-walk from each direction; and ``docs/getup.png`` (the torso's height and tilt while getting up, nominal
body, both engines).

Run from the repository root: ``python tools/getup_table.py [own|stock|rolls|falls|figure ...]`` (default all; about an
hour on 2 cores).
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from op2motion.gait import SteerableWalk, timeline_of
from op2motion.motion import GetUp, Supervisor
from op2motion.physics import ENGINES, Pushes, Setup, check, family
from op2motion.robot.specfile import default_spec

ROOT = Path(__file__).resolve().parents[1]
STOCK = ROOT / "tests" / "data" / "motion_4096.bin"
SIDES = ("front", "back", "left", "right")
UPRIGHT_TILT_DEG, UPRIGHT_HEIGHT_M = 25.0, 0.25
PUSH_N, PUSH_AT_S = 30.0, 3.5
WALK = [(0.0, 0.0, 0.0, 0.0), (1.0, 0.15, 0.0, 0.0), (30.0, "stop")]


def up_at(track) -> float | None:
    """The first time [s] the torso is within 25° of vertical and its origin above 0.25 m."""
    for t, rot, pos in zip(track.times, track.rot, track.base_pos):
        if math.degrees(math.acos(np.clip(rot[2, 2], -1.0, 1.0))) < UPRIGHT_TILT_DEG and pos[2] > UPRIGHT_HEIGHT_M:
            return float(t)
    return None


def family_table(action: Path | None, whole: bool = True) -> None:
    """Per start and engine: stood in how many members (``whole``: the family, else the nominal body), and the time
    to upright (median, slowest)."""
    spec = default_spec()
    members = family(spec) if whole else family(spec)[:1]
    print("| start | engine | stood up | upright after [s] (median, slowest) | ways played |")
    print("|---|---|---|---|---|")
    for side in SIDES:
        for engine in ENGINES:
            times, ways = [], set()
            for m in members:
                getup = GetUp(m.body(spec), action)
                setup = replace(m.setup(), keep_track=True, full_length=True, lying=side)
                track = check(getup, m.body(spec), (engine,), setup=setup).run.track
                t = up_at(track)
                if getup.stood and t is not None:
                    times.append(t)
                ways |= {what.split("plays ")[1] for _, what in getup.events if what.startswith("plays ")}
            shown = f"{np.median(times):.1f}, {max(times):.1f}" if times else "–"
            print(f"| {side} | {engine} | {len(times)}/{len(members)} | {shown} | {', '.join(sorted(ways))} |",
                  flush=True)


def rolls_table() -> None:
    """op2motion's rolls alone (planned, played open loop) from lying on their side: where each member ends."""
    from op2motion.formats.motionfile import read_motion
    from op2motion.motion.getup_ways import motion_path
    from op2motion.motion.lying import lying_side
    from op2motion.motion.pipeline import plan_motion

    spec = default_spec()
    print("| roll | engine | ends on its back | ends otherwise |")
    print("|---|---|---|---|")
    for side in ("left", "right"):
        trajectory = plan_motion(read_motion(motion_path(f"roll_{side}"), spec), spec, planner="none")
        for engine in ENGINES:
            ends = []
            for m in family(spec):
                setup = replace(m.setup(), keep_track=True, full_length=True, lying=side)
                track = check(trajectory.schedule(m.body(spec)), m.body(spec), (engine,), setup=setup).run.track
                ends.append(lying_side(track.rot[-1].T @ np.array([0.0, 0.0, 1.0])))
            others = [f"{e}" for e in ends if e != "back"]
            print(f"| `roll_{side}` from the {side} side | {engine} | {ends.count('back')}/{len(ends)} | "
                  f"{', '.join(others) or '–'} |", flush=True)


def falls_table() -> None:
    """A steered walk at 0.15 m/s pushed with 30 N for 0.1 s from each side, nominal body, both engines."""
    spec = default_spec()
    print("| push | engine | detected after [s] | standing again after [s] | walked on [m] |")
    print("|---|---|---|---|---|")
    for direction in ("forward", "backward", "left", "right"):
        for engine in ENGINES:
            walk = SteerableWalk.make(spec, commands=timeline_of(WALK))
            supervisor = Supervisor(walk, spec=spec, extra_s=0.0)
            report = check(supervisor, spec, (engine,), Pushes(PUSH_N, (direction,), at_s=PUSH_AT_S),
                           setup=Setup(keep_track=True, full_length=True)).engines[engine]
            events = dict((what.split(" (")[0], t) for t, what in supervisor.events)
            track = report.pushes[0].run.track
            walked = "–"
            if "resumed" in events:
                at = int(np.searchsorted(track.times, events["resumed"]))
                walked = f"{np.hypot(*(track.base_pos[-1][:2] - track.base_pos[at][:2])):.2f}"
            detected = events.get("fall detected")
            stood = events.get("standing again")
            print(f"| {direction} | {engine} | {'–' if detected is None else f'{detected - PUSH_AT_S:.2f}'} | "
                  f"{'–' if stood is None else f'{stood - PUSH_AT_S:.1f}'} | {walked} |", flush=True)


def figure() -> None:
    """docs/getup.png: the torso's height and tilt while getting up from each start, nominal body, both engines."""
    from op2motion.figures.draw import _png, _pyplot

    spec = default_spec()
    plt = _pyplot()
    fig, (top, low) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    colours = dict(zip(SIDES, ("tab:blue", "tab:red", "tab:green", "tab:purple")))
    for side in SIDES:
        for engine, style in zip(ENGINES, ("-", "--")):
            getup = GetUp(spec)
            track = check(getup, spec, (engine,), setup=Setup(keep_track=True, full_length=True, lying=side)).run.track
            tilt = np.degrees(np.arccos(np.clip(track.rot[:, 2, 2], -1.0, 1.0)))
            label = f"{side}, {engine}"
            top.plot(track.times, track.base_pos[:, 2], style, color=colours[side], lw=1.0, label=label)
            low.plot(track.times, tilt, style, color=colours[side], lw=1.0)
    top.axhline(UPRIGHT_HEIGHT_M, color="k", lw=0.6, ls=":")
    low.axhline(UPRIGHT_TILT_DEG, color="k", lw=0.6, ls=":")
    top.set_ylabel("torso height [m]")
    low.set_ylabel("torso tilt [deg]")
    low.set_xlabel("time [s] (the robot starts lying)")
    top.legend(fontsize=7, ncol=4, loc="lower right")
    top.set_title("GetUp() from lying face down, face up and on each side (nominal body, MX-28 P 32, 1 kHz)",
                  fontsize=10)
    fig.tight_layout()
    (ROOT / "docs" / "getup.png").write_bytes(_png(fig))
    print("wrote docs/getup.png")


def main() -> None:
    asked = sys.argv[1:] or ["own", "stock", "rolls", "falls", "figure"]
    if "own" in asked:
        family_table(None)
    if "stock" in asked:
        family_table(STOCK, whole=False)
    if "rolls" in asked:
        rolls_table()
    if "falls" in asked:
        falls_table()
    if "figure" in asked:
        figure()


if __name__ == "__main__":
    main()
