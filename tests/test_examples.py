"""Every script in examples/ runs as written (from an empty folder, writing under out/) and prints what it promises."""

from __future__ import annotations

import subprocess
import sys

import pytest
from helpers import ROOT

EXAMPLES = ROOT / "examples"
#: script -> (what it prints, the files it writes under out/, whether it runs a physics engine)
PROMISES = {
    "optimise_a_pose.py": ("physics: stands", ["reach.json", "reach.png"], True),
    "play_a_page_in_physics.py": ("the engines agree", [], True),
    "plan_and_check_a_walk.py": ("PyBullet: walked", ["walk.csv"], True),
    "build_a_small_library.py": ("3 targets: 3 reached", ["library/index.json", "library/index.csv"], False),
    "closed_loop_controller.py": ("closed loop on the accelerometer", [], True),
    "go_around_and_move_in_a_line.py": ("physics: pybullet: stands | mujoco: stands",
                                        ["route.png", "line.png", "line.json"], True),
}


def test_every_example_is_tested():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(PROMISES)


@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.physics) if physics else
                                    pytest.param(s, marks=pytest.mark.slow) if "library" in s else s
                                    for s, (_, _, physics) in PROMISES.items()])   # a library build: worker processes
def test_the_example_runs(tmp_path, script):
    printed, files, _ = PROMISES[script]
    done = subprocess.run([sys.executable, str(EXAMPLES / script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert printed in done.stdout
    for name in files:
        assert (tmp_path / "out" / name).is_file(), name
    assert {p.name for p in tmp_path.iterdir()} <= {"out"}            # nothing written outside out/
