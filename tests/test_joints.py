"""Book variables <-> servo angles <-> ticks, checked against the stock ROBOTIS action file."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import page_last_step_ticks
from hypothesis import given, settings
from hypothesis import strategies as st

from op2motion.errors import InputError
from op2motion.kinematics import forward
from op2motion.robot.balance import stability_margin
from op2motion.robot.joints import (
    BookAngles,
    book_to_servo,
    servo_dict,
    servo_from_mapping,
    servo_to_book,
    servo_to_ticks,
    ticks_to_servo,
)
from op2motion.robot.specfile import default_spec

EXACT_RAD = 1e-12            # book -> servo -> book is a linear map and its inverse
HALF_TICK_RAD = math.pi / 4096
# op2_facts.md §4 decodes with the framework's rounded 0.088°/tick and prints one decimal.
DECODE_TOL_DEG = 0.05 + 180 * (0.088 - 360 / 4096) / 0.088 + 1e-9

angles20 = st.lists(st.floats(-math.pi, math.pi, allow_nan=False), min_size=20, max_size=20)


@settings(max_examples=200, deadline=None)
@given(angles20, st.sampled_from(["left", "right"]))
def test_book_servo_book_is_exact(values, support):
    spec = default_spec()
    book = BookAngles.from_vector(np.array(values), support)
    back = servo_to_book(book_to_servo(book, spec), support, spec)
    assert np.max(np.abs(back.vector() - book.vector())) < EXACT_RAD


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-math.pi + 0.01, math.pi - 0.01, allow_nan=False), min_size=20, max_size=20))
def test_servo_ticks_servo_within_half_a_tick(values):
    spec = default_spec()
    servo = np.array(values)
    ticks = servo_to_ticks(servo, spec)
    assert np.all((0 <= ticks) & (ticks <= 4095))
    assert np.max(np.abs(ticks_to_servo(ticks, spec) - servo)) <= HALF_TICK_RAD + 1e-15
    assert np.array_equal(servo_to_ticks(ticks_to_servo(ticks, spec), spec), ticks)


def test_standing_maps_to_servo_zero_with_the_arm_offsets(spec):
    servo = dict(zip(spec.joint_names, np.degrees(book_to_servo(BookAngles.standing("left"), spec)[0])))
    arms = {"l_sho_roll": 45.0, "r_sho_roll": -45.0, "l_el": 90.0, "r_el": -90.0}
    for name, deg in servo.items():
        assert deg == pytest.approx(arms.get(name, 0.0), abs=1e-9), name
    right = dict(zip(spec.joint_names, np.degrees(book_to_servo(BookAngles.standing("right"), spec)[0])))
    assert right == pytest.approx(servo, abs=1e-9)


# op2_facts.md §4: decoded degrees of the stock pages, (right, left) per joint pair, then head pan/tilt.
STOCK = {
    1: {"sho_pitch": (-50.0, 49.5), "sho_roll": (-26.5, 26.0), "el": (8.7, -9.2), "hip_yaw": (0, 0),
        "hip_roll": (0, 0), "hip_pitch": (-3.1, 2.8), "knee": (0, 0), "ank_pitch": (1.3, -1.6), "ank_roll": (0, 0),
        "head": (0.0, 10.7)},
    9: {"sho_pitch": (-48.4, 41.4), "sho_roll": (-17.9, 17.6), "el": (29.3, -29.6), "hip_yaw": (0, 0),
        "hip_roll": (0.4, -0.4), "hip_pitch": (-36.2, 36.2), "knee": (53.2, -53.2), "ank_pitch": (30.0, -30.0),
        "ank_roll": (0.8, -0.8), "head": (0.0, 9.9)},
    15: {"sho_pitch": (-48.2, 41.3), "sho_roll": (-18.8, 20.7), "el": (29.2, -29.7), "hip_yaw": (-0.4, -1.3),
         "hip_roll": (0.8, -0.4), "hip_pitch": (-67.8, 65.9), "knee": (128.9, -130.0), "ank_pitch": (70.0, -71.1),
         "ank_roll": (2.6, -1.0), "head": (0.2, 11.0)},
}


def _stock_servo_deg(page: int) -> dict[str, float]:
    out = {}
    for joint, (r, left) in STOCK[page].items():
        if joint == "head":
            out["head_pan"], out["head_tilt"] = r, left
        else:
            out[f"r_{joint}"], out[f"l_{joint}"] = r, left
    return out


@pytest.mark.parametrize("page", sorted(STOCK))
def test_stock_pages_decode_to_the_published_degrees(spec, stock_action_bytes, page):
    ticks = page_last_step_ticks(stock_action_bytes, page)
    decoded = dict(zip(spec.joint_names, np.degrees(ticks_to_servo(ticks, spec))))
    for name, deg in _stock_servo_deg(page).items():
        assert decoded[name] == pytest.approx(deg, abs=DECODE_TOL_DEG), name
    # ... and our encoder gives back the file's ticks.
    assert np.array_equal(servo_to_ticks(ticks_to_servo(ticks, spec), spec), ticks)


def test_walkready_reads_as_the_walking_stance(spec, stock_action_bytes):
    """Page 9 in book variables: bent knees, 13° forward torso lean, both feet flat on the floor side by side."""
    servo = ticks_to_servo(page_last_step_ticks(stock_action_bytes, 9), spec)
    for support in ("left", "right"):
        book = servo_to_book(servo, support, spec)
        th = np.degrees(book.th[0])
        assert th[1] == pytest.approx(53.2, abs=0.1)                       # support knee flexion
        assert th[0] + th[1] + th[2] == pytest.approx(90 - 13, abs=0.2)    # HIP_PITCH_OFFSET 13° lean
        pts = forward(book, spec, "dh")
        swing = pts.swing_foot_corners[0]
        assert np.all(np.abs(swing[:, 2]) < 0.002)                         # flat on the floor (±0.8° rolls)
        other = pts.point(f"{pts.swing}_sole")[0]
        assert abs(abs(other[1]) - 0.074 - 0.005) < 0.004 and abs(other[0]) < 0.002  # y_offset 5 mm wider


def test_init_page_is_a_balanced_double_support_stance(spec, stock_action_bytes):
    servo = ticks_to_servo(page_last_step_ticks(stock_action_bytes, 1), spec)
    book = servo_to_book(servo, "left", spec)
    pts = forward(book, spec, "dh")
    com = pts.com.T[0]
    # The CoM lies between the feet (double support): on neither foot alone, but inside both feet's hull.
    assert stability_margin(com[None, :2], spec, "left")[0] < 0
    assert -0.074 < com[1] < 0.0 and -0.052 < com[0] < 0.052


def test_servo_mapping_rejects_bad_input(spec):
    good = servo_dict(book_to_servo(BookAngles.standing(), spec)[0], spec)
    with pytest.raises(InputError, match="unknown joint 'l_wrist'"):
        servo_from_mapping({**good, "l_wrist": 0.0}, spec)
    missing = dict(good)
    del missing["head_pan"]
    with pytest.raises(InputError, match="missing head_pan"):
        servo_from_mapping(missing, spec)
    with pytest.raises(InputError, match="finite"):
        servo_from_mapping({**good, "l_knee": float("nan")}, spec)
    with pytest.raises(InputError, match="ticks 0 to 4095"):
        servo_to_ticks(np.full(20, math.radians(181.0)), spec)
    with pytest.raises(InputError, match="expected 11 angles, got 10"):
        BookAngles.from_deg([0] * 10, [0] * 6)
    with pytest.raises(InputError, match="support"):
        BookAngles.standing("both")
