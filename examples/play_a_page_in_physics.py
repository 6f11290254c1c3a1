"""Play a ROBOTIS action page as the robot's framework does (every 8 ms, from the init pose) and check it in
PyBullet and MuJoCo with the MX-28 servo model.

    python examples/play_a_page_in_physics.py [ACTION_FILE] [PAGE]
"""

import sys
from pathlib import Path

import op2motion as op2

ROOT = Path(__file__).resolve().parents[1]
path = sys.argv[1] if len(sys.argv) > 1 else ROOT / "tests" / "data" / "motion_4096.bin"
page = int(sys.argv[2]) if len(sys.argv) > 2 else 9          # the stock file's "walk ready"

spec = op2.load_spec()
played = op2.play_page(op2.ActionFile.read(path), page, spec)   # starts from page 1's last step (init)
print(f"page {page} ({played.page.name}) from {played.start.name}: {played.playback.calls} ticks, "
      f"{played.trajectory.duration_s:.2f} s")
report = op2.check(played.trajectory.schedule(spec), spec, engines=("pybullet", "mujoco"))
for name, engine in report.engines.items():
    run = engine.run
    worst = run.motion.worst_torque
    print(f"  {name}: {run.reason}; tracking error <= {max(run.motion.tracking_max_deg.values()):.1f}°, "
          f"worst torque {worst.torque_nm:.2f} of {worst.available_nm:.2f} N·m ({worst.joint})")
print("the engines agree" if report.agree else f"the engines disagree: {report.outcomes()}")
sys.exit(0 if report.stable else 1)
