"""Centre of mass, support rectangle, the book's penalties and the signed stability margin."""

from __future__ import annotations

import numpy as np
import pytest

from op2motion.errors import InputError
from op2motion.kinematics import forward
from op2motion.kinematics.com import mass_weights
from op2motion.robot.balance import (
    PENALTY,
    penalty_stability,
    penalty_swing_foot_height,
    stability_margin,
    support_polygon,
)
from op2motion.robot.joints import BookAngles

EXACT_M = 1e-12


def test_com_weights_total_the_lumped_masses(spec):
    assert mass_weights(spec).sum() == pytest.approx(spec.lumped_total_mass, abs=1e-12)


def test_standing_com_is_between_the_feet_at_mid_height(spec):
    pts = forward(BookAngles.standing("left"), spec, "dh")
    com = pts.com.T[0]
    assert com[1] == pytest.approx(-0.037, abs=EXACT_M)      # mid-plane of the feet
    assert 0.20 < com[2] < 0.25                               # about at the hips, as on the real robot
    assert 0.0 < com[0] < 0.01                                # the torso sits 5 mm ahead of the hips


@pytest.mark.parametrize("support, left, right", [("left", 0.043, 0.023), ("right", 0.023, 0.043)])
def test_margin_known_answers(spec, support, left, right):
    pts = np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.03], [-0.06, -0.05], [0.05, 0.0]])
    m = stability_margin(pts, spec, support, br=1.0)
    assert m[0] == pytest.approx(min(0.052, left, right), abs=EXACT_M)            # the nearer side edge
    assert m[1] == pytest.approx(-(0.1 - 0.052), abs=EXACT_M)                     # beyond the toe
    assert m[2] == pytest.approx(left - 0.03 if left > 0.03 else -(0.03 - left), abs=EXACT_M)
    assert m[3] == pytest.approx(-np.hypot(0.06 - 0.052, 0.05 - right), abs=EXACT_M)  # off a corner
    assert m[4] == pytest.approx(0.002, abs=EXACT_M)
    half = stability_margin(pts[:1], spec, support, br=0.5)
    assert half[0] == pytest.approx(0.5 * min(0.052, left, right), abs=EXACT_M)


def test_penalties_follow_the_book(spec):
    pts = np.array([[0.9 * 0.052, 0.0], [0.0, -0.9 * 0.023], [0.0, 0.9 * 0.043], [-0.06, 0.0]])
    assert list(penalty_stability(pts, spec, "left", 1.0)) == [0, 0, 0, PENALTY]
    assert list(penalty_stability(pts, spec, "left", 0.7)) == [PENALTY, PENALTY, PENALTY, PENALTY]
    # On the right foot the inner edge is on the left: 0.9 * 0.043 to the left is now outside.
    assert list(penalty_stability(pts, spec, "right", 1.0)) == [0, 0, PENALTY, PENALTY]
    # Margin and penalty agree on inside/outside.
    for br in (1.0, 0.7, 0.4):
        inside = stability_margin(pts, spec, "left", br) >= 0
        assert np.array_equal(inside, penalty_stability(pts, spec, "left", br) == 0)
    assert list(penalty_swing_foot_height(np.array([0.01, 0.0, -1e-12, -0.001]))) == [0, 0, 0, PENALTY]


def test_support_polygon_and_bad_br(spec):
    poly = support_polygon(spec, "left", 1.0, (0.1, 0.2))
    assert np.allclose(poly, [[0.152, 0.243], [0.152, 0.177], [0.048, 0.177], [0.048, 0.243]], atol=EXACT_M)
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(InputError, match="br"):
            stability_margin(np.zeros((1, 2)), spec, "left", bad)
