"""Every script in examples/ runs as written (from an empty folder, writing under out/) and prints what it promises."""

from __future__ import annotations

import runpy
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


#: Scripts whose worker processes import them: run as programs.
OWN_PROCESS = ("build_a_small_library.py",)


def test_every_example_is_tested():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(PROMISES)


@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.physics) if physics else
                                    pytest.param(s, marks=pytest.mark.slow) if "library" in s else s
                                    for s, (_, _, physics) in PROMISES.items()])   # a library build: worker processes
def test_the_example_runs(tmp_path, script, monkeypatch, capsys):
    """From an empty folder. A script that starts worker processes (which import it) runs as a program of its own;
    the others as ``__main__`` in this process (a program each cost the suite a second or two of imports)."""
    printed, files, _ = PROMISES[script]
    if script in OWN_PROCESS:
        done = subprocess.run([sys.executable, str(EXAMPLES / script)], cwd=tmp_path, capture_output=True,
                              text=True, timeout=600)
        code, out, err = done.returncode, done.stdout, done.stderr
    else:
        monkeypatch.chdir(tmp_path)
        monkeypatch.setattr(sys, "argv", [str(EXAMPLES / script)])
        try:
            runpy.run_path(str(EXAMPLES / script), run_name="__main__")
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        out, err = capsys.readouterr()
    assert code == 0, err
    assert printed in out
    for name in files:
        assert (tmp_path / "out" / name).is_file(), name
    assert {p.name for p in tmp_path.iterdir()} <= {"out"}            # nothing written outside out/
