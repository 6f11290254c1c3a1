"""Optimise a pose: the left hand to (0.10, 0.05, 0.07) m standing on the left foot, checked in physics, written
to out/reach.json with its figure.

    python examples/optimise_a_pose.py
"""

from pathlib import Path

import op2motion as op2
from op2motion.figures.pose import Drawing, pose_figure

spec = op2.load_spec()
problem = op2.PostureProblem(support="left", hand="left", target=(0.10, 0.05, 0.07), br=0.7)
outcome = op2.solve(problem, spec, op2.PSOSettings(seed=0), validate=op2.Validate(seconds=3.0))
result = outcome.result
print(f"{outcome.message}; full-inertia margin {result.margin_full_m * 1000:.1f} mm, "
      f"physics: {outcome.validation.reason if outcome.validation else 'not checked'}")
if outcome.ok:
    out = Path("out")
    pose = outcome.pose("reach", spec, {"command": "examples/optimise_a_pose.py"})
    op2.write_pose(pose, out / "reach.json", spec)
    png = pose_figure("reach", result.angles, spec, Drawing(br=problem.br, target=problem.target),
                      outcome.validation).png
    (out / "reach.png").write_bytes(png)
    print(f"wrote {out / 'reach.json'} and {out / 'reach.png'}")
