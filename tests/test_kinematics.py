"""Both full-body models: known answers, the official ROBOTIS geometry, symmetry, link lengths, PB vs D-H."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from official_fk import official_points

from op2motion.book import STANDING_PHI_DEG, STANDING_TH_DEG
from op2motion.errors import InputError, ModelError
from op2motion.kinematics import POINT_NAMES, forward
from op2motion.robot.joints import BookAngles, book_to_servo, servo_to_book
from op2motion.robot.specfile import default_spec

EXACT_M = 1e-9          # D-H vs the official description: the same rigid geometry, rounding only
QUAT_SEED = 20261128    # the random rotations the quaternion is checked on
LENGTH_M = 1e-9         # link lengths preserved by the D-H chain
MODELS = ("dh", "pb")
SUPPORTS = ("left", "right")
# Projection vs D-H (README "Projection model accuracy"). Around standing the hands differ by the 16 mm elbow
# offset the projection model omits, plus the shoulder-roll point's 16 mm drop turning with shoulder pitch
# (16 mm x 2 sin 5° for ±10°) and the second-order projection error (~L (1 - cos 10°) over a 0.4 m chain, 6 mm).
PB_STANDING_ARM_M = 0.035       # elbows and hands
PB_STANDING_OTHER_M = 0.020     # legs, torso, head: second-order projection error only
PB_STANDING_COM_M = 0.008
# Over the book's whole PSO box (rolls to ±30°, pitches to ±90°) the projection's decoupling of roll and pitch
# errs by tens of mm: bounded by the median and 99th percentile of the CoM error on a fixed sample.
PB_BOX_COM_MEDIAN_M = 0.015
PB_BOX_COM_P99_M = 0.060


def _is_arm(name: str) -> bool:
    return name.endswith("hand") or name.endswith("_el")


def standing(support: str) -> BookAngles:
    return BookAngles.standing(support)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("support", SUPPORTS)
def test_standing_pose_stands_straight(spec, model, support):
    pts = forward(standing(support), spec, model)
    side = 1.0 if support == "left" else -1.0
    s, w = ("l", "r") if support == "left" else ("r", "l")
    assert pts.point(f"{support}_sole")[0] == pytest.approx([0, 0, 0], abs=EXACT_M)
    assert pts.point(f"{pts.swing}_sole")[0] == pytest.approx([0, -side * 0.074, 0], abs=EXACT_M)  # feet 74 mm apart
    for leg in (s, w):
        assert pts.point(f"{leg}_hip_pitch")[0][2] == pytest.approx(0.2195, abs=EXACT_M)   # sole to hip axis
        for joint in ("ank_roll", "knee", "hip_pitch", "hip_yaw"):
            assert pts.point(f"{leg}_{joint}")[0][0] == pytest.approx(0.0, abs=EXACT_M)    # legs vertical
    assert pts.point("neck")[0] == pytest.approx([0.005, -side * 0.037, 0.3417], abs=EXACT_M)
    assert pts.point("head_top")[0][2] == pytest.approx(0.3417 + 0.0505 + 0.069, abs=1e-6)
    assert pts.swing_foot_min_z[0] == pytest.approx(0.0, abs=EXACT_M)
    # Arms hang straight down beside the torso, 205 mm below the shoulder-pitch axis.
    for hand, y in (("left_hand", 0.082), ("right_hand", -0.082)):
        assert pts.point(hand)[0][1] == pytest.approx(-side * 0.037 + y, abs=EXACT_M)
        assert pts.point(hand)[0][2] == pytest.approx(0.3417 - 0.016 - 0.06 - 0.129, abs=EXACT_M)


MIRROR = {"left": "right", "right": "left", "l_": "r_", "r_": "l_"}


def _mirror_name(name: str) -> str:
    for a, b in (("left_", "right_"), ("right_", "left_"), ("l_", "r_"), ("r_", "l_")):
        if name.startswith(a):
            return b + name[len(a):]
    return name


@pytest.mark.parametrize("model", MODELS)
def test_left_and_right_support_standing_are_mirror_images(spec, model):
    left, right = forward(standing("left"), spec, model), forward(standing("right"), spec, model)
    for name in POINT_NAMES:
        x, y, z = left.point(_mirror_name(name))[0]
        assert right.point(name)[0] == pytest.approx([x, -y, z], abs=EXACT_M), name
    assert right.com[:, 0] == pytest.approx(left.com[:, 0] * [1, -1, 1], abs=EXACT_M)


def _check_official(spec, book: BookAngles) -> None:
    servo = book_to_servo(book, spec)
    pts = forward(book, spec, "dh")
    for i in range(book.n):
        ref = official_points(servo[i], spec, book.support)
        for name in POINT_NAMES:
            if name in ref:
                assert np.abs(pts.point(name)[i] - ref[name]).max() < EXACT_M, (name, i)


@pytest.mark.parametrize("support", SUPPORTS)
def test_dh_puts_joints_where_the_official_description_does(spec, rng, support):
    """Random poses over the book's PSO box (psi included) and a wider box, both supports."""
    _check_official(spec, BookAngles.random(150, rng, support, psi=True))
    wide = BookAngles.from_vector(rng.uniform(-math.pi, math.pi, (50, 20)), support)
    _check_official(spec, wide)


def test_book_arbitrary_pose_code_2_6(spec):
    """Book code 2.6 (D-H, with psi) and code 2.13 (projection, psi = 0)."""
    th, phi = [80, 10, 0, 210, -10, -5, 170, 10, 200, 20, 0], [-10, 5, 170, 10, 200, 170]
    with_psi = BookAngles.from_deg(th, phi, [10, -5, 0], "left")
    _check_official(spec, with_psi)
    flat = BookAngles.from_deg(th, phi, [0, 0, 0], "left")
    dh, pb = forward(flat, spec, "dh"), forward(flat, spec, "pb")
    # The book: the two models give "almost the same" figure (figs. 2.32/2.53).
    for name in POINT_NAMES:
        limit = PB_STANDING_ARM_M if _is_arm(name) else PB_STANDING_OTHER_M
        assert np.linalg.norm(dh.point(name)[0] - pb.point(name)[0]) < limit, name
    # Right leg raised forward, right arm raised forward, swing foot clear of the floor.
    pts = forward(with_psi, spec, "dh")
    assert pts.swing_foot_min_z[0] > 0.005
    assert pts.point("right_hand")[0][0] > pts.point("left_hand")[0][0] + 0.05
    assert pts.point("r_knee")[0][0] > 0.03


def test_conventions_shoulder_pitch_and_knee(spec):
    base = book_to_servo(standing("left"), spec)[0]
    names = spec.joint_names
    arm = base.copy()
    arm[names.index("l_sho_pitch")] = math.radians(-90)  # official sign: negative swings the left arm forward
    pts = forward(servo_to_book(arm, "left", spec), spec, "dh")
    hand, shoulder = pts.point("left_hand")[0], pts.point("l_sho_pitch")[0]
    assert hand[0] - shoulder[0] == pytest.approx(0.016 + 0.06 + 0.129, abs=EXACT_M)  # straight out in front
    assert hand[2] - shoulder[2] == pytest.approx(0.016, abs=EXACT_M)  # shoulder height; the elbow offset now points up
    knee = base.copy()
    knee[names.index("r_knee")] = math.radians(60)       # right knee flexion (positive on the right)
    pts = forward(servo_to_book(knee, "left", spec), spec, "dh")
    # The ankle rises by calf (1 - cos 60°) and the foot tips toe-down by 60°: the front corner is lowest.
    c, s = math.cos(math.radians(60)), math.sin(math.radians(60))
    ankle_z = 0.0335 + 0.093 * (1 - c)
    assert pts.point("r_ank_roll")[0][2] == pytest.approx(ankle_z, abs=EXACT_M)
    assert pts.swing_foot_min_z[0] == pytest.approx(ankle_z - 0.0335 * c - 0.052 * s, abs=EXACT_M)
    assert pts.point("right_sole")[0][0] < -0.07           # the shin swings back


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-math.pi, math.pi, allow_nan=False), min_size=20, max_size=20),
       st.sampled_from(SUPPORTS))
def test_dh_preserves_link_lengths(values, support):
    spec = default_spec()
    g = spec.geometry
    pts = forward(BookAngles.from_vector(np.array(values), support), spec, "dh")
    p = lambda n: pts.point(n)[0]  # noqa: E731
    pairs = {("l_ank_roll", "l_knee"): g.calf, ("r_knee", "r_hip_pitch"): g.thigh,
             ("l_hip_pitch", "l_hip_yaw"): g.hip_yaw_to_roll, ("l_hip_yaw", "r_hip_yaw"): 2 * g.hip_half_width,
             ("right_sole", "r_ank_roll"): g.ankle_to_sole, ("l_ank_roll", "left_sole"): g.ankle_to_sole,
             ("l_sho_pitch", "r_sho_pitch"): 2 * g.shoulder_half_width,
             ("l_sho_pitch", "l_sho_roll"): math.hypot(g.shoulder_roll_lateral, g.shoulder_roll_drop),
             ("r_sho_roll", "r_el"): math.hypot(g.upper_arm, g.elbow_forward), ("l_el", "left_hand"): g.lower_arm,
             ("neck", "head_tilt"): g.head_tilt_height, ("head_tilt", "head_top"): g.head_length}
    for (a, b), length in pairs.items():
        assert abs(np.linalg.norm(p(a) - p(b)) - length) < LENGTH_M, (a, b)
    for side in SUPPORTS:
        c = pts.foot_corners(side)[0]
        assert abs(np.linalg.norm(c[0] - c[3]) - (spec.foot.front + spec.foot.back)) < LENGTH_M
        assert abs(np.linalg.norm(c[0] - c[1]) - (spec.foot.inner + spec.foot.outer)) < LENGTH_M


def _mirrored(values: list[float], joints: tuple[str, ...], tilt: float) -> np.ndarray:
    """Servo vector with each left joint's angle mirrored onto the right (right = -left), head pan 0."""
    names = default_spec().joint_names
    servo = np.zeros(20)
    for value, joint in zip(values, joints):
        servo[names.index(f"l_{joint}")] = value
        servo[names.index(f"r_{joint}")] = -value
    servo[names.index("head_tilt")] = tilt
    return servo


SAGITTAL = ("sho_pitch", "sho_roll", "el", "hip_pitch", "knee", "ank_pitch")
ALL_PAIRS = SAGITTAL + ("hip_yaw", "hip_roll", "ank_roll")


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-0.6, 0.6, allow_nan=False), min_size=6, max_size=6), st.floats(-0.4, 0.9),
       st.sampled_from(MODELS))
def test_symmetric_pose_has_its_com_on_the_mid_plane(values, tilt, model):
    """Mirrored pitch joints and shoulder rolls keep the body upright: the CoM is midway between the feet."""
    spec = default_spec()
    for support in SUPPORTS:
        pts = forward(servo_to_book(_mirrored(values, SAGITTAL, tilt), support, spec), spec, model)
        mid = 0.5 * (pts.point("left_sole")[0] + pts.point("right_sole")[0])
        assert abs(pts.com.T[0][1] - mid[1]) < 1e-9
        assert abs(pts.point("neck")[0][1] - mid[1]) < 1e-9


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-0.6, 0.6, allow_nan=False), min_size=9, max_size=9), st.floats(-0.4, 0.9))
def test_any_mirrored_pose_has_its_com_on_the_body_mirror_plane(values, tilt):
    """With rolls and yaws the body tilts, but the CoM stays on the plane that bisects shoulders and hips."""
    spec = default_spec()
    for support in SUPPORTS:
        pts = forward(servo_to_book(_mirrored(values, ALL_PAIRS, tilt), support, spec), spec, "dh")
        a, b = pts.point("l_sho_pitch")[0], pts.point("r_sho_pitch")[0]
        normal = (a - b) / np.linalg.norm(a - b)
        mid = 0.5 * (a + b)
        assert abs(np.dot(pts.com.T[0] - mid, normal)) < 1e-9
        hips = 0.5 * (pts.point("l_hip_yaw")[0] + pts.point("r_hip_yaw")[0])
        assert abs(np.dot(hips - mid, normal)) < 1e-9


@pytest.mark.parametrize("support", SUPPORTS)
def test_projection_agrees_with_dh_around_standing(spec, rng, support):
    base = np.radians(np.r_[STANDING_TH_DEG, STANDING_PHI_DEG, 0, 0, 0])
    x = base + np.radians(rng.uniform(-10, 10, (4000, 20)))
    x[:, 17:] = 0.0
    book = BookAngles.from_vector(x, support)
    dh, pb = forward(book, spec, "dh"), forward(book, spec, "pb")
    for name in POINT_NAMES:
        err = np.linalg.norm(dh.point(name) - pb.point(name), axis=1).max()
        assert err < (PB_STANDING_ARM_M if _is_arm(name) else PB_STANDING_OTHER_M), name
    assert np.linalg.norm(dh.com - pb.com, axis=0).max() < PB_STANDING_COM_M


@pytest.mark.parametrize("support", SUPPORTS)
def test_projection_error_over_the_pso_box_is_bounded(spec, rng, support):
    book = BookAngles.random(20000, rng, support, psi=False)
    err = np.linalg.norm(forward(book, spec, "dh").com - forward(book, spec, "pb").com, axis=0)
    assert np.median(err) < PB_BOX_COM_MEDIAN_M
    assert np.percentile(err, 99) < PB_BOX_COM_P99_M


def test_batched_equals_one_by_one(spec, rng):
    """Large batches run in chunks on threads (column evaluator), single poses as 4x4 matrices: the same answer."""
    book = BookAngles.random(20001, rng, "right", psi=False)
    for model in MODELS:
        batch = forward(book, spec, model)
        for i in (0, 9999, 10000, 20000):
            one = forward(book.row(i), spec, model)
            assert np.abs(one.data[:, :, 0] - batch.data[:, :, i]).max() < 1e-15
            assert np.abs(one.com[:, 0] - batch.com[:, i]).max() < 1e-15


def test_sp_and_gamma_place_the_body_in_the_world(spec):
    book = standing("left")
    pts = forward(book, spec, "dh", sp=(0.1, 0.2, 0.0), gamma=math.pi / 2)
    assert pts.point("left_sole")[0] == pytest.approx([0.1, 0.2, 0.0], abs=EXACT_M)
    assert pts.point("right_sole")[0] == pytest.approx([0.1 + 0.074, 0.2, 0.0], abs=EXACT_M)  # turned 90° left
    assert pts.com[:, 0] == pytest.approx([0.1 + 0.037, 0.2 + forward(book, spec).com[0, 0], pts.com[2, 0]],
                                          abs=EXACT_M)


def test_projection_refuses_psi_and_unknown_models(spec):
    with pytest.raises(ModelError, match="psi = 0.*choose dh"):
        forward(BookAngles.from_deg(STANDING_TH_DEG, STANDING_PHI_DEG, [5, 0, 0]), spec, "pb")
    with pytest.raises(InputError, match="model"):
        forward(standing("left"), spec, "urdf")


def test_the_quaternion_of_a_rotation_is_scipys_bit_for_bit():
    """kinematics.frames.quat_xyzw (PyBullet's start orientation, the studio's frames) gives SciPy's
    ``Rotation.from_matrix(...).as_quat()`` exactly: random rotations, half turns, ties between the diagonal
    terms, the identity; a matrix off orthonormal and a reflection go to SciPy (orthonormalised, refused)."""
    from scipy.spatial.transform import Rotation

    from op2motion.kinematics.frames import quat_xyzw

    mats = list(Rotation.random(2000, random_state=QUAT_SEED).as_matrix())
    for axis in ([1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, -1, 0], [1, 1, 1]):
        for angle in (0.0, np.pi, np.pi / 2, 1e-9, np.pi - 1e-9):
            mats.append(Rotation.from_rotvec(np.array(axis) / np.linalg.norm(axis) * angle).as_matrix())
    mats.append(mats[0] * (1 + 1e-6))                                           # not a rotation: SciPy's answer
    for m in mats:
        assert np.array_equal(np.array(quat_xyzw(m)), Rotation.from_matrix(m).as_quat())
    with pytest.raises(ValueError):
        quat_xyzw(np.diag([1.0, 1.0, -1.0]))
