"""Figures drawn in forked renderers are the figures drawn here."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from op2motion.figures.background import Renderers
from op2motion.figures.draw import render_cost_curve


def _curve(scale: float) -> bytes:
    history = np.geomspace(1.0, 1e-3, 30) * scale
    return render_cost_curve([history], [history / 10], 1e-3, f"test {scale}", 0)


def _fails() -> bytes:
    raise ValueError("drawn here, it fails here")


def test_renderers_draw_the_same_bytes_and_fall_back_here():
    with Renderers(2) as renderers:
        jobs = [renderers.submit(_curve, 1.0), renderers.submit(_curve, 2.0), renderers.submit(_curve, 3.0)]
        drawn = [renderers.result(j) for j in jobs]          # the third has no renderer left: drawn here
    assert drawn == [_curve(1.0), _curve(2.0), _curve(3.0)] and drawn[0] != drawn[1]


def test_a_failing_figure_fails_where_the_caller_sees_it():
    with Renderers(1) as renderers:
        job = renderers.submit(_fails)
        try:
            renderers.result(job)
        except ValueError as exc:
            assert "fails here" in str(exc)
        else:
            raise AssertionError("the error must reach the caller")


#: Each renderer forked sends itself Ctrl-C's signal the moment it exists (as a Ctrl-C at a command's start would
#: reach it, before it could say it ignores Ctrl-C); it then draws its figure as asked.
CTRL_C_AS_A_RENDERER_FORKS = """
import os, signal
_fork = os.fork
def _fork_then_ctrl_c():
    pid = _fork()
    if pid == 0:
        os.kill(os.getpid(), signal.SIGINT)
    return pid
os.fork = _fork_then_ctrl_c
import sys
sys.path.insert(0, "tests")
from test_figures_forked import _curve
from op2motion.figures.background import Renderers
with Renderers(2) as renderers:
    jobs = [renderers.submit(_curve, 1.0), renderers.submit(_curve, 2.0)]
    drawn = [renderers.result(j) for j in jobs]
print(drawn == [_curve(1.0), _curve(2.0)])
"""


def test_a_ctrl_c_as_the_renderers_fork_is_ignored_by_them():
    """The renderers start with Ctrl-C ignored (the command decides what it ends): one forked before it set that
    itself printed a KeyboardInterrupt traceback when a Ctrl-C reached it at that moment."""
    done = subprocess.run([sys.executable, "-c", CTRL_C_AS_A_RENDERER_FORKS], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "True", done.stdout + done.stderr
    assert "Traceback" not in done.stderr and "KeyboardInterrupt" not in done.stderr, done.stderr


def _loaded_here(module: str) -> bool:
    import sys

    return module in sys.modules


def test_the_renderers_load_the_figures_modules_before_the_data_arrives():
    """``preload``: the figure modules are loaded with matplotlib while the caller computes, not when the job
    (and its arguments) arrive."""
    import sys

    assert "xml.dom.minidom" not in sys.modules          # a module nothing here loads
    with Renderers(2, ("xml.dom.minidom",)) as renderers:
        jobs = [renderers.submit(_loaded_here, "xml.dom.minidom"), renderers.submit(_loaded_here, "matplotlib")]
        assert [renderers.result(j) for j in jobs] == [True, True]
    assert "xml.dom.minidom" not in sys.modules
