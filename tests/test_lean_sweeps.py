"""Lean sweeps: a pose leaned in 0.5° steps at the support ankle(s) until it falls, in both engines.

The verdict must be monotonic (once a pose falls, every further lean falls too), the two engines must agree on every
pose whose margin is beyond ±5 mm, and the verdict must switch where the pose runs out of support: where the settled
full-inertia CoM reaches the edge of the support polygon, within 5 mm. The switch is measured as the margin halfway
between the last standing pose and the next step (the last standing margin less half the margin lost per step).

One sweep runs out of support before its CoM reaches that edge, for a reason the engines agree on and the README
explains: on two legs leaning sideways as a parallelogram, the compliant legs (P = 32) shear, the unloaded foot
rolls onto its inner edge from about 10° of lean (the statically sagged solution with both soles flat would need
its centre of pressure beyond that edge) and the loaded foot tips over its outer edge while the other still carries
12 % of the weight, so the CoM is 10 mm inside the hull of both soles: there the switch is measured on the loaded
foot's own centre of pressure, which reaches its edge within 5 mm.
"""

from __future__ import annotations

import multiprocessing

import pytest

from op2motion.physics.sweeps import sweep_verdict

STEP_DEG = 0.5
SECONDS = 3.0
FALLS_PAST_SWITCH = 3          # steps leaned on after the first fall, to see that nothing stands again
MAX_STEPS = 70
AGREE_BEYOND_M = 0.005         # the engines agree wherever the margin is beyond this
SWITCH_TOL_M = 0.005           # the switch lies this close to the edge
pytestmark = pytest.mark.physics

SWEEPS = [  # support, kind, direction, what runs out (the CoM's polygon or a loaded foot's own sole)
    ("left", "pitch", 1, "com"), ("left", "pitch", -1, "com"), ("left", "roll", 1, "com"),
    ("double", "pitch", 1, "com"), ("double", "pitch", -1, "com"), ("double", "roll", 1, "foot"),
]


@pytest.fixture(scope="module")
def sweeps():
    """Every sweep run in MuJoCo step by step, then every pose of it in PyBullet (two processes)."""
    results = {}
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(2) as pool:
        for support, kind, direction, _ in SWEEPS:
            angles, mujoco, falls = [], [], 0
            while falls < 1 + FALLS_PAST_SWITCH and len(angles) < MAX_STEPS:
                deg = direction * STEP_DEG * len(angles)
                verdict = sweep_verdict((support, kind, deg, "mujoco", SECONDS))
                angles.append(deg)
                mujoco.append(verdict)
                falls += (not verdict[0]) or falls > 0
            pybullet = pool.map(sweep_verdict, [(support, kind, a, "pybullet", SECONDS) for a in angles])
            results[(support, kind, direction)] = (angles, {"mujoco": mujoco, "pybullet": pybullet})
    return results


def _switch_margin(verdicts: list, index: int = 1) -> float:
    stable = [v[0] for v in verdicts]
    last = stable.index(False) - 1
    assert last >= 1, "the sweep must start standing"
    step = verdicts[last - 1][index] - verdicts[last][index]
    return verdicts[last][index] - 0.5 * step


@pytest.mark.parametrize("support, kind, direction, criterion", SWEEPS,
                         ids=[f"{s}-{k}-{d:+d}" for s, k, d, _ in SWEEPS])
def test_lean_sweep(sweeps, support, kind, direction, criterion):
    angles, by_engine = sweeps[(support, kind, direction)]
    assert any(not v[0] for v in by_engine["mujoco"]), "the sweep never fell"
    for engine, verdicts in by_engine.items():
        stable = [v[0] for v in verdicts]
        first_fall = stable.index(False)
        assert not any(stable[first_fall:]), f"{engine}: stands again after falling at {angles[first_fall]}°"
        switch = _switch_margin(verdicts, 1 if criterion == "com" else 3)
        assert abs(switch) <= SWITCH_TOL_M, (engine, criterion, switch)
    for deg, mj, pb in zip(angles, by_engine["mujoco"], by_engine["pybullet"]):
        if min(abs(mj[1]), abs(pb[1])) > AGREE_BEYOND_M:
            assert mj[0] == pb[0], f"{deg}°: MuJoCo {mj}, PyBullet {pb}"
