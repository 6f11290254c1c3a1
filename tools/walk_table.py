"""Print the walking table (docs/walking.md) from ``op2motion walk --validate --engine both --json`` results.

Usage: for p in forward backward sideways turn_left turn_right; do
           op2motion walk --preset $p --validate --engine both [--push 2 --trials 10] --json > $p.json; done
       python tools/walk_table.py forward.json backward.json sideways.json turn_left.json turn_right.json
"""

from __future__ import annotations

import json
import sys


def _row(result: dict) -> str:
    cells = []
    for engine in ("pybullet", "mujoco"):
        s = result["physics"]["engines"][engine]
        verdict = "fell" if s["fell"] else "walked"
        if s["reasons"]:
            verdict += " (" + ", ".join(s["reasons"]) + ")"
        extra = ""
        if s.get("pushes"):
            extra += "; 2 N pushes: " + ", ".join(f"{p['from']} {'fell' if p['fell'] else 'ok'}" for p in s["pushes"])
        if "trials" in s:
            extra += f"; {s['trials']['walked']}/{s['trials']['runs']} perturbed starts walked"
        cells.append(f"{verdict}, {s['mean_speed_mps']:.3f} m/s, drift {s['lateral_drift_m'] * 1000:.0f} mm, "
                     f"heading {s['heading_error_deg']:+.1f}°, turn {s['turn_rate_deg_s']:+.1f}°/s, CoP inside "
                     f"{s['cop_inside_fraction']:.1%}, torque ≤ {s['worst_torque']['ratio']:.0%} (at the limit "
                     f"{s['worst_torque']['limited_share']:.0%}){extra}")
    return (f"| `{result['preset']}` | {result['steps']} | {result['planned_speed_mps']:.3f} m/s, ZMP margin "
            f"{result['zmp_margin_min_m'] * 1000:.1f} mm | " + " | ".join(cells) + " |")


def main(paths: list[str]) -> None:
    print("| preset | steps | plan | PyBullet (MX-28 P 32, 1 kHz) | MuJoCo (MX-28 P 32, 1 kHz) |")
    print("|---|---|---|---|---|")
    for path in paths:
        with open(path, encoding="utf-8") as handle:
            print(_row(json.load(handle)))


if __name__ == "__main__":
    main(sys.argv[1:])
