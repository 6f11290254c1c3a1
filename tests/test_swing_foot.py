"""The walk controller's opt-in swing shaping (:mod:`op2motion.gait.swing_foot`: the swing sole kept level in the
world, its toe raised): fast checks, no physics (the walks on the foreign simulator's family: docs/tuning.md)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from op2motion.errors import InputError
from op2motion.gait import load_preset
from op2motion.gait.controller import WalkController
from op2motion.gait.params import GaitParams
from op2motion.gait.swing_foot import toe_raised
from op2motion.kinematics.leg_ik import leg_fk, rot_x, rot_y, rot_z
from op2motion.robot.specfile import default_spec

SHORT_STEPS = 4
BACK_M = 0.05                 # a sole's heel edge behind its centre [m] (made up)
TOE_DEG = 10.0
ERROR_RAD = (0.06, 0.04)      # a torso pitched 3.4° forward of its plan and rolled 2.3° (pitch, roll)
POSITION_TOL_M = 1e-6         # the IK's closed form puts the sole there to rounding
ANGLE_TOL_RAD = 1e-6
TILT_SEEN_M = 1e-3            # without levelling the same error moves the swing sole by more than this


@pytest.fixture(scope="module")
def spec():
    return default_spec()


@pytest.fixture(scope="module")
def gait(spec):
    return WalkController.from_preset("forward", steps=SHORT_STEPS, spec=spec).gait


def _with(gait, **keys):
    return replace(gait, params=replace(gait.params, **keys))


def _mid_swing(ctl):
    """A gait row half way through the first single support, and the side swinging there."""
    rows = ctl.rows
    k = next(k for k in range(rows.end) if rows.obj("contact", k) != "double" and rows.value("swing_phase", k) >= 0.5)
    return k, "left" if rows.obj("contact", k) == "right" else "right"


def _sole_in_world(ctl, k, side, change, error):
    """Where the ``side`` sole is (position [m], rotation) with the goals of row ``k`` plus ``change`` on a torso
    whose pose is the plan's turned by ``error`` (pitch, roll) [rad] about the row's support point."""
    rows, leg = ctl.rows, ctl.legs[side]
    pivot, pos, rot = rows.get("support_point", k), rows.get("torso_pos", k), rows.get("torso_rot", k)
    tilt = rot_y(error[0]) @ rot_x(error[1])
    body_pos, body_rot = pivot + tilt @ (pos - pivot), tilt @ rot
    joints = (rows.get("joints", k) + change)[list(leg.index)]
    p, r = (a[0] for a in leg_fk(leg, joints))
    return body_pos + body_rot @ p, body_rot @ r


def test_a_raised_toe_keeps_the_heel_and_is_flat_at_lift_off_and_landing():
    sole, rot = np.array([0.1, 0.05, 0.02]), rot_z(0.3)
    heel = sole + rot @ np.array([-BACK_M, 0.0, 0.0])
    for phase in (0.0, 1.0):
        same = toe_raised(sole, rot, phase, math.radians(TOE_DEG), BACK_M)
        assert np.allclose(same[0], sole) and np.allclose(same[1], rot)
    pos, turned = (np.asarray(v) for v in toe_raised(sole, rot, 0.5, math.radians(TOE_DEG), BACK_M))  # tuples
    assert np.allclose(pos + turned @ np.array([-BACK_M, 0.0, 0.0]), heel)         # the heel edge stays put
    toe_up = math.asin(turned[2, 0])                                               # the sole's x axis rises
    assert toe_up == pytest.approx(math.radians(TOE_DEG))
    assert math.atan2(turned[1, 0], turned[0, 0]) == pytest.approx(0.3)           # its heading unchanged


def test_a_levelled_swing_sole_stays_where_the_plan_puts_it_in_the_world(spec, gait):
    """swing_level and swing_level_roll 1: with the torso pitched and rolled off its plan the swing leg is solved
    for the torso as it is, so its sole lands on the planned place, level; without them (the shipped presets) it
    follows the torso; the standing leg is the same either way."""
    plain = WalkController(gait, spec)
    level = WalkController(_with(gait, swing_level=1.0, swing_level_roll=1.0), spec)
    k, swing = _mid_swing(level)
    stance = "left" if swing == "right" else "right"
    changes = {}
    for name, ctl in (("plain", plain), ("level", level)):
        ctl.start({n: 0.0 for n in spec.joint_names})
        ctl.state.error = np.array(ERROR_RAD)
        changes[name] = ctl._leg_change(k, 0.0, 0.0)
    planned = level.rows.feet(swing, k)
    pos, rot = _sole_in_world(level, k, swing, changes["level"], ERROR_RAD)
    assert np.allclose(pos, planned[:3], atol=POSITION_TOL_M)
    assert np.allclose(rot, rot_z(planned[3]), atol=ANGLE_TOL_RAD)
    pos_plain, _ = _sole_in_world(plain, k, swing, changes["plain"], ERROR_RAD)
    assert np.linalg.norm(pos_plain - planned[:3]) > TILT_SEEN_M
    index = list(level.legs[stance].index)
    assert np.allclose(changes["level"][index], changes["plain"][index])


def test_the_shipped_presets_shape_nothing_but_the_fast_walk(spec):
    """The new keys default to off; every shipped walking preset leaves them so but ``fast``, tuned with them."""
    fast = load_preset("fast")
    assert fast.swing_level > 0.0 and fast.swing_toe_deg > 0.0
    for name in ("forward", "backward", "sideways", "turn_left", "turn_right", "steer"):
        p = load_preset(name)
        assert (p.swing_level, p.swing_level_roll, p.swing_toe_deg) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("key, value", [("swing_level", 1.5), ("swing_level_roll", -0.1), ("swing_toe_deg", 20.0)])
def test_out_of_range_swing_keys_are_refused_by_name(key, value):
    with pytest.raises(InputError) as e:
        GaitParams(**{key: value})
    assert e.value.param == key


def test_tune_walk_searches_the_swing_keys_only_when_asked_for():
    from op2motion.tune.spaces import walk_space

    space = walk_space("forward")
    assert not {"swing_level", "swing_level_roll", "swing_toe_deg"} & set(space.names)
    added = space.narrowed([["swing_level", "0.5", "1"]])
    assert added.names[-1] == "swing_level" and (added.params[-1].low, added.params[-1].high) == (0.5, 1.0)
    with pytest.raises(InputError, match="within"):
        space.narrowed([["swing_toe_deg", "0", "30"]])
