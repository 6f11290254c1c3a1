"""Two motions the straight joint interpolation cannot do: the right arm swung from in front of the hip to behind
the shoulder (the straight line passes the elbow through the hip, so the planner goes around it), and the right
hand 5 cm forward and back in a straight line from walk-ready with the whole body balanced. Both figures and the
line's motion file are written under out/.

    python examples/go_around_and_move_in_a_line.py
"""

from pathlib import Path

import numpy as np

import op2motion as op2
from op2motion.figures.paths import render_line, render_route
from op2motion.formats.motionfile import write_motion

ROOT = Path(__file__).resolve().parents[1]
out = Path("out")
out.mkdir(exist_ok=True)
spec = op2.load_spec()
init = op2.read_pose(ROOT / "poses" / "init.json", spec).servo
front, back = init.copy(), init.copy()
for joint, (a, b) in {"r_sho_pitch": (69.0, -178.0), "r_sho_roll": (-63.0, -51.0), "r_el": (-29.0, -24.0)}.items():
    front[spec.joint_names.index(joint)], back[spec.joint_names.index(joint)] = np.radians(a), np.radians(b)
poses = [op2.Waypoint("front", front, 0.0, 0.0, "double"), op2.Waypoint("back", back, 2.0, 0.0, "double")]
straight = op2.trajectory_through(poses, spec, planner="none")
planned = op2.trajectory_through(poses, spec, seed=0)
print("\n".join(planned.notes))
(out / "route.png").write_bytes(render_route(straight.goals, planned.goals, spec, "front -> back: around the hip"))

walkready = op2.read_pose(ROOT / "poses" / "walkready.json", spec)
line = op2.line_move(walkready, op2.LineRequest("right", 1.0, delta_m=(0.05, 0.0, 0.0), back=True), spec)
summary = line.as_dict(spec)
print(f"line: off the line <= {summary['line_deviation_max_m'] * 1000:.2f} mm, "
      f"CoM margin >= {summary['com_margin_min_m'] * 1000:.1f} mm")
report = op2.check(line.trajectory().schedule(spec), spec, engines=("pybullet", "mujoco"))
verdict = " | ".join(f"{e}: {r.run.reason}" for e, r in report.engines.items())
print(f"physics: {verdict}")
(out / "line.png").write_bytes(render_line(line, "right hand 5 cm forward and back from walk-ready", verdict))
write_motion(line.motion("line"), out / "line.json", spec)
print(f"wrote {out / 'route.png'}, {out / 'line.png'} and {out / 'line.json'}")
