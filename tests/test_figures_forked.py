"""Figures drawn in forked renderers are the figures drawn here."""

from __future__ import annotations

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
