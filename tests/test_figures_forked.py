"""Figures drawn in forked renderers are the figures drawn here."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from op2motion.figures.background import Renderers
from op2motion.figures.draw import render_cost_curve


def _curve(scale: float) -> bytes:
    history = np.geomspace(1.0, 1e-3, 30) * scale
    return render_cost_curve([history], [history / 10], 1e-3, f"test {scale}", 0)


def _fails() -> bytes:
    raise ValueError("drawn here, it fails here")


@pytest.mark.slow
def test_renderers_draw_the_same_bytes_and_fall_back_here():
    with Renderers(2) as renderers:
        jobs = [renderers.submit(_curve, 1.0), renderers.submit(_curve, 2.0), renderers.submit(_curve, 3.0)]
        drawn = [renderers.result(j) for j in jobs]          # the third has no renderer left: drawn here
    assert drawn == [_curve(1.0), _curve(2.0), _curve(3.0)] and drawn[0] != drawn[1]


def test_a_failing_figure_fails_where_the_caller_sees_it():
    with Renderers(1) as renderers:
        job = renderers.submit(_fails)
        with pytest.raises(ValueError, match="fails here"):      # the error reaches the caller
            renderers.result(job)


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


@pytest.mark.slow
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


class _Sum:
    """A staged job: begun with ``a``, finished with ``b``."""

    def __init__(self, a: int):
        if a < 0:
            raise ValueError("begun here, it fails here")
        self.a = a

    def finish(self, b: int) -> int:
        return self.a + b


def test_a_staged_job_is_begun_at_once_and_finished_with_what_comes_later():
    with Renderers(1) as renderers:
        forked, here = renderers.begin(_Sum, 1), renderers.begin(_Sum, 10)     # the second: no renderer left
        renderers.finish(here, 20)
        renderers.finish(forked, 2)
        assert renderers.result(forked) == 3 and renderers.result(here) == 30
    with Renderers(1) as renderers:
        failing = renderers.begin(_Sum, -1)
        renderers.finish(failing, 2)
        with pytest.raises(ValueError, match="fails here"):
            renderers.result(failing)


@pytest.fixture(scope="module")
def outcomes(spec):
    """Two outcomes of a small search (seeds 0 and 1), as the first physics check sees the first (its candidate)
    and as it ends (stands; falls)."""
    from dataclasses import replace
    from types import SimpleNamespace

    from op2motion.book import DEFAULT_PROBLEM
    from op2motion.posture.cost import PostureProblem
    from op2motion.posture.pso import PSOSettings
    from op2motion.workflow import Outcome, solve

    problem = PostureProblem.from_scenario(DEFAULT_PROBLEM)
    first, second = (solve(problem, spec, PSOSettings(particles=8, iterations=5, seed=seed), restarts=0,
                           refine=False).result for seed in (0, 1))
    candidate = Outcome(replace(first, attempts=1, attempt_pso=(first.pso,)), None)
    stands = Outcome(replace(candidate.result, seconds=1.0), SimpleNamespace(stable=True, seconds=1.0, reason=""))
    falls = Outcome(second, SimpleNamespace(stable=False, seconds=0.4, reason="fell"))
    return candidate, stands, falls


@pytest.mark.slow
def test_a_pose_figure_drawn_before_its_verdict_is_the_figure_drawn_in_one_go(spec, outcomes):
    """optimize --validate draws the pose while its physics check runs and the verdict after: the PNG is the one
    matplotlib writes for the finished figure; a final outcome that shows another pose is drawn again."""
    import io

    from op2motion.figures.draw import DPI, _pyplot
    from op2motion.figures.pose import StagedPoseFigure, verdict_of

    candidate, stands, falls = outcomes
    early = StagedPoseFigure(candidate, "staged", spec)
    png, drawn = early.finish(stands)
    whole = StagedPoseFigure(stands, "staged", spec).canvas         # the same figure, written by savefig
    verdict, ok = verdict_of(stands.validation)
    whole.fig.text(0.99, 1 - 0.2 / whole.height, verdict, fontsize=13, weight="bold", color="#1b7a1b", va="top",
                   ha="right")
    buf = io.BytesIO()
    whole.fig.savefig(buf, format="png", dpi=DPI)
    _pyplot().close(whole.fig)
    assert ok and drawn["verdict"] == verdict and png == buf.getvalue()
    other, redrawn = StagedPoseFigure(candidate, "staged", spec).finish(falls)
    assert other != png and redrawn["verdict"] == "FALLS in physics: fell" and "PSO seed 1" in redrawn["lines"][1]


@pytest.mark.slow
def test_the_cost_curves_drawn_for_the_candidate_are_kept_only_if_the_outcome_has_them(outcomes):
    from op2motion.figures.pose import StagedCostCurve, outcome_cost_curve

    candidate, stands, falls = outcomes
    assert StagedCostCurve(candidate, "staged").finish(stands) == outcome_cost_curve(stands, "staged")
    assert StagedCostCurve(candidate, "staged").finish(falls) == outcome_cost_curve(falls, "staged")
