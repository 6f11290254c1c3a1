"""Check the shipped tuned walks in the foreign simulator (``tests/foreign_sim/harness.py``: MuJoCo, its own loop, servo
model, IMU and floor) on the independently built body (``tests/data/op2_official_mesh.toml``), planned on the shipped
spec: ``walking/fast.toml`` under ``WalkController`` and ``walking/stock_config.ini``
under op2motion's emulation of the stock Walking module, against the forward preset and the stock defaults; 20 steps
each on every body of the foreign body's robustness family (its torso's CoM and mass, the servos' stiffness, the
floor's friction), IMU readings 16 ms late. ``python tests/foreign_sim/tune_check.py fast`` checks one walk.

Run from the repository root: ``python tests/foreign_sim/tune_check.py`` (a few minutes on 2 cores); prints a
Markdown table.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

from foreign_sim.harness import ServoModel, simulate  # noqa: E402
from op2motion.gait.controller import WalkController  # noqa: E402
from op2motion.gait.stock_config import StockConfig, read_stock_config  # noqa: E402
from op2motion.gait.stock_controller import StockWalkController  # noqa: E402
from op2motion.model.urdf import build_urdf  # noqa: E402
from op2motion.robot.specfile import default_spec, load_spec  # noqa: E402

STEPS = 20


def walks() -> dict[str, object]:
    """The controllers' makers (planned on the shipped spec), by name."""
    spec = default_spec()
    stock_defaults = StockConfig(x_move_amplitude_mm=30.0)
    out = {"forward.toml": lambda: WalkController.from_preset("forward", steps=STEPS, spec=spec),
           "fast.toml": lambda: WalkController.from_preset("fast", steps=STEPS, spec=spec),
           "stock defaults (X 30 mm)": lambda: StockWalkController(stock_defaults, spec, STEPS)}
    tuned = read_stock_config(ROOT / "walking" / "stock_config.ini")
    out["stock_config.ini"] = lambda: StockWalkController(tuned, spec, STEPS)
    return out


def run(controller: object, member: object, official: object) -> dict:
    """One walk on one body of the foreign body's family in the foreign simulator, IMU 16 ms late."""
    return simulate(build_urdf(member.body(official)), controller, controller.plan.duration_s,  # type: ignore
                    friction=member.friction, latency_ticks=2,  # type: ignore[attr-defined]
                    servo=ServoModel(kp_nm_rad=member.stiffness * ServoModel().kp_nm_rad))  # type: ignore


def steady_speed(trace: list[tuple[float, ...]], clock: object) -> float:
    """The torso's forward speed [m/s] over the walk's steady window (the plan's clock, from the walk's start)."""
    times = np.array([row[0] for row in trace])
    x = np.array([row[4] for row in trace])
    t0 = clock.start_s + clock.steady_from_s  # type: ignore[attr-defined]
    t1 = clock.start_s + clock.steady_to_s  # type: ignore[attr-defined]
    return float((np.interp(t1, times, x) - np.interp(t0, times, x)) / max(t1 - t0, 1e-9))


def main() -> None:
    from op2motion.physics import family

    official = load_spec(ROOT / "tests" / "data" / "op2_official_mesh.toml")
    chosen = sys.argv[1:] or list(walks())
    print("| walk | body | fell | speed [m/s] | drift | heading [°] |")
    print("|---|---|---|---|---|---|")
    for name, make in walks().items():
        if not any(name.startswith(c) for c in chosen):
            continue
        for member in family(official):
            controller = make()
            result = run(controller, member, official)
            share = abs(result["lateral_m"]) / max(result["distance_m"], 1e-9)
            print(f"| {name} | {member.name} | {'yes' if result['fell'] else 'no'} | "
                  f"{steady_speed(result['trace'], controller.plan.walk):.3f} | {share:.1%} | "
                  f"{result['end_yaw_deg']:+.1f} |", flush=True)


if __name__ == "__main__":
    main()
