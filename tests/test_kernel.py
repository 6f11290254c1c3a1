"""The compiled swarm cost (op2motion.posture.kernel) against the NumPy cost model it stands in for."""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from op2motion.posture.cost import CLEARANCE_EXACT_M, SELF_CLEARANCE_M, CostModel, CostTerms, PostureProblem
from op2motion.posture.kernel import TERMS, swarm_terms
from op2motion.posture.pso import variable_bounds
from op2motion.robot.balance import COM_MODEL_FULL, COM_MODEL_LUMPED
from op2motion.robot.joints import BookAngles

SWARM = 64
SAME_M = 1e-12          # terms in metres or radians agree to this
SAME_COST = 1e-10       # cost units (100 per penalty, metres of reach)


@pytest.mark.parametrize("support", ["left", "right"])
@pytest.mark.parametrize("hand", ["left", "right"])
@pytest.mark.parametrize("com_model", [COM_MODEL_FULL, COM_MODEL_LUMPED])
def test_every_term_matches_the_numpy_cost_model(spec, support, hand, com_model):
    problem = PostureProblem(support, hand, (0.1, 0.05 if hand == "left" else -0.05, 0.07), 0.7, "dh", com_model)
    model = CostModel(problem, spec)
    plan = model.kernel_plan()
    lo, hi = variable_bounds(problem, spec)
    rng = np.random.default_rng(7)
    q = lo + (hi - lo) * rng.random((SWARM, lo.size))
    q[0] = np.clip(BookAngles.standing(support).vector()[0], lo, hi)          # a pose that stands
    got = swarm_terms(plan, q)
    ref = model.reference(BookAngles.from_vector(q, support))
    near = ref.clearance < SELF_CLEARANCE_M
    assert near.any() and (~near).any(), "the sample must hold colliding and clear poses"
    for j, name in enumerate(TERMS):
        want, have = getattr(ref, name), got[:, j]
        if name == "clearance":   # exact where it matters (below the threshold), a lower bound above it
            assert np.allclose(have[near], want[near], rtol=0, atol=SAME_M)
            assert np.all(have[~near] >= SELF_CLEARANCE_M) and np.all(have[~near] <= want[~near] + SAME_M)
            continue
        assert np.array_equal(np.isfinite(have), np.isfinite(want)), name
        finite = np.isfinite(want)
        tol = SAME_COST if name in ("total", "book", "collision") else SAME_M
        assert np.allclose(have[finite], want[finite], rtol=0, atol=tol), name
        assert np.array_equal(have[~finite], want[~finite]), name


def test_the_cost_model_runs_on_the_kernel_with_the_references_clearances(spec):
    """CostModel itself evaluates the D-H model with the kernel, clearances exact where the reference is (below
    CLEARANCE_EXACT_M), so the refinement's clearance constraint sees the same values."""
    assert TERMS == tuple(f.name for f in fields(CostTerms))
    problem = PostureProblem("left", "left", (0.1, 0.05, 0.07))
    model = CostModel(problem, spec)
    lo, hi = variable_bounds(problem, spec)
    q = lo + (hi - lo) * np.random.default_rng(3).random((SWARM, lo.size))
    got, want = model(BookAngles.from_vector(q, "left")), model.reference(BookAngles.from_vector(q, "left"))
    exact = want.clearance < CLEARANCE_EXACT_M
    assert exact.any() and np.allclose(got.clearance[exact], want.clearance[exact], rtol=0, atol=SAME_M)
    assert np.all(got.clearance[~exact] >= CLEARANCE_EXACT_M - SAME_M)
    assert np.allclose(got.total, want.total, rtol=0, atol=SAME_COST)


def test_skipped_clearance_is_reported_as_such(spec):
    problem = PostureProblem("left", "left", (0.1, 0.05, 0.07))
    plan = CostModel(problem, spec).kernel_plan()
    q = np.tile(BookAngles.standing("left").vector(), (3, 1))
    terms = swarm_terms(plan, q, np.array([np.inf, -np.inf, 0.0]))
    clearance, collision = terms[:, TERMS.index("clearance")], terms[:, TERMS.index("collision")]
    assert np.isfinite(clearance[0]) and np.isnan(clearance[1:]).all() and (collision[1:] == 0).all()


def test_the_projection_model_has_no_kernel(spec):
    assert CostModel(PostureProblem("left", "left", (0.1, 0.05, 0.07), model="pb", com_model=COM_MODEL_LUMPED),
                     spec).kernel_plan() is None
