"""Build a small pose library: the left hand to three targets in front of the left foot, solved in worker processes,
written with its index to out/library (run it again: the targets already done are skipped).

    python examples/build_a_small_library.py
"""

import op2motion as op2
from op2motion.library.build import BuildSettings
from op2motion.library.grid import axis, grid_jobs

if __name__ == "__main__":                 # worker processes import this file: build only in the parent
    spec = op2.load_spec()
    jobs = grid_jobs(["left"], ["left"], [0.7], axis(0.08, 0.12, 3, "x"), axis(0.04, 0.04, 1, "y"),
                     axis(0.07, 0.07, 1, "z"))
    settings = BuildSettings(op2.PSOSettings(iterations=120), restarts=1)
    summary = op2.build_library(jobs, spec, "out/library", settings, workers=2,
                                on_done=lambda row: print(f"  {row.name}: {row.message}"))
    print(f"{summary.targets} targets: {summary.solved} reached, {summary.failed} not, {summary.skipped} done before; "
          f"index {summary.index}")
