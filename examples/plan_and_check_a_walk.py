"""Plan a walk with the shipped forward preset (6 steps), play it in PyBullet on the MX-28 servo model, and write
the goals every 8 ms as CSV to out/walk.csv.

    python examples/plan_and_check_a_walk.py
"""

from pathlib import Path

import op2motion as op2
from op2motion.gait import gait_csv, walk_summary

spec = op2.load_spec()
params = op2.load_preset("forward").with_steps(6)
gait = op2.generate_gait(params, spec)
print(f"planned {len(gait.footsteps.steps)} steps in {gait.walking_s:.2f} s, ZMP margin >= "
      f"{gait.zmp_margin.min() * 1000:.1f} mm")
schedule = op2.gait_schedule(gait, spec)
report = op2.check(schedule, spec)
walk = report.run.walk
print(f"PyBullet: {'fell' if report.fell else 'walked'} {walk.distance_m:.3f} m at {walk.mean_speed_mps:.3f} m/s "
      f"steady, CoP inside the soles {walk.cop_inside_fraction:.0%} of the time")
summary = walk_summary(report, schedule.plan.walk.start_s)          # the JSON `op2motion walk --validate` prints
assert summary["fell"] == report.fell
out = Path("out")
out.mkdir(exist_ok=True)
(out / "walk.csv").write_text(gait_csv(gait, spec), encoding="utf-8")
print(f"wrote {out / 'walk.csv'}")
