"""The generated URDF and pinocchio: official joints, inertials, mass, D-H agreement, static torques."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import page_last_step_ticks

from op2motion.kinematics import POINT_NAMES, forward
from op2motion.model.dynamics import dynamics_for
from op2motion.model.urdf import build_urdf, link_inertial
from op2motion.robot.joints import BookAngles, book_to_servo, ticks_to_servo

DH_VS_PINOCCHIO_M = 0.5e-3   # the acceptance bound; measured 4e-10 m
GRAVITY = 9.81


def test_urdf_has_the_official_joints_and_an_inertial_everywhere(spec):
    root = ET.fromstring(build_urdf(spec))
    joints = {j.get("name"): j for j in root.iter("joint") if j.get("type") == "revolute"}
    assert list(joints) == list(spec.joint_names)
    for joint in spec.joints:
        el = joints[joint.name]
        assert el.find("parent").get("link") == joint.parent and el.find("child").get("link") == joint.child
        assert [float(v) for v in el.find("origin").get("xyz").split()] == pytest.approx(joint.origin_xyz)
        assert [float(v) for v in el.find("axis").get("xyz").split()] == pytest.approx(joint.axis)
        lim = el.find("limit")
        assert float(lim.get("effort")) == 2.5 and float(lim.get("velocity")) == 5.76
        assert float(lim.get("lower")) == pytest.approx(joint.mechanical[0])
        assert float(lim.get("upper")) == pytest.approx(joint.mechanical[1])
    # ROS tools find what they expect: base_link as the root, the torso on a fixed joint, the camera as head_cam
    assert root.find("link").get("name") == "base_link"
    base = next(j for j in root.iter("joint") if j.find("child").get("link") == "body_link")
    assert base.get("type") == "fixed" and base.find("parent").get("link") == "base_link"
    assert all(link.find("inertial") is not None for link in root.iter("link"))
    frames = {link.get("name") for link in root.iter("link")}
    assert {"left_hand_link", "right_hand_link", "left_sole_link", "right_sole_link", "head_cam"} <= frames
    cam = next(j for j in root.iter("joint") if j.find("child").get("link") == "head_cam")
    assert cam.find("parent").get("link") == "head_tilt_link"
    assert [float(v) for v in cam.find("origin").get("xyz").split()] == pytest.approx([0.0332, 0.0, 0.0344])
    assert build_urdf(spec) == build_urdf(spec)  # deterministic


def test_inertials_are_physical(spec):
    for item in spec.inertials:
        li = link_inertial(item)
        w = np.linalg.eigvalsh(li.tensor)
        assert w.min() > 0 and w[2] <= w[0] + w[1] + 1e-12, item.link           # triangle inequality
        assert np.trace(li.tensor) == pytest.approx(sum(item.inertia[:3]), rel=1e-12)  # rotation keeps the trace


def test_pinocchio_mass_and_joint_centres_match_dh(spec, rng):
    dyn = dynamics_for(spec)
    assert 2.8 <= dyn.total_mass <= 3.0
    for support in ("left", "right"):
        book = BookAngles.random(60, rng, support, psi=True)
        servo, pts = book_to_servo(book, spec), forward(book, spec, "dh")
        for i in range(book.n):
            ref = dyn.joint_centres(servo[i], support)
            for name in POINT_NAMES:
                if name in ref:
                    assert np.linalg.norm(pts.point(name)[i] - ref[name]) < DH_VS_PINOCCHIO_M, name


def test_full_and_lumped_com_are_close(spec):
    """The two CoM models differ mostly fore-aft: the Webots torso CoM sits 5 cm behind the torso origin."""
    dyn = dynamics_for(spec)
    book = BookAngles.standing("left")
    full = dyn.com(book_to_servo(book, spec)[0], "left")
    lumped = forward(book, spec).com[:, 0]
    assert abs(full[1] - lumped[1]) < 1e-3                   # both on the mid-plane
    assert abs(full[2] - lumped[2]) < 0.02
    assert -0.03 < full[0] - lumped[0] < 0.0


@pytest.mark.parametrize("lean_deg", [-6.0, 12.0])
def test_static_torques_balance_the_weight(spec, lean_deg):
    """On one foot the support ankle-pitch servo carries the gravity moment, about its axis, of everything on the
    knee side of it; gravity acts along the support sole's -Z even when the body leans on the ankle."""
    dyn, pin = dynamics_for(spec), dynamics_for(spec).pin
    names = spec.joint_names
    servo = book_to_servo(BookAngles.standing("left"), spec)[0]
    servo[names.index("l_sho_pitch")] = math.radians(-90)   # left arm straight out in front
    servo[names.index("l_ank_pitch")] = math.radians(-lean_deg)  # the whole body leans forward on the ankle
    report = dyn.static_torques(servo, "left")
    q = dyn.level_configuration(servo, "left")
    pin.forwardKinematics(dyn.model, dyn.data, q)
    ankle = dyn.model.getJointId("l_ank_pitch")
    foot_side = [ankle, dyn.model.getJointId("l_ank_roll")]
    m_total = dyn.total_mass
    com = pin.centerOfMass(dyn.model, dyn.data, q)
    m_foot = sum(dyn.model.inertias[j].mass for j in foot_side)
    c_foot = sum(dyn.model.inertias[j].mass * dyn.data.oMi[j].act(dyn.model.inertias[j].lever) for j in foot_side)
    c_above = (m_total * com - c_foot) / (m_total - m_foot)
    axis = dyn.data.oMi[ankle].rotation @ np.array(spec.joint("l_ank_pitch").axis)
    lever = c_above - dyn.data.oMi[ankle].translation
    moment = float(axis @ np.cross(lever, (m_total - m_foot) * np.array([0.0, 0.0, -GRAVITY])))
    assert abs(report.torques[names.index("l_ank_pitch")]) == pytest.approx(abs(moment), rel=1e-6)
    assert abs(moment) > 0.05


def test_stock_standing_pages_are_within_the_servo_torque(spec, stock_action_bytes):
    dyn = dynamics_for(spec)
    for page in (1, 9, 16):
        servo = ticks_to_servo(page_last_step_ticks(stock_action_bytes, page), spec)
        assert dyn.static_torques(servo, "double").worst_ratio < 0.6


@pytest.mark.parametrize("support", ["left", "right"])
def test_frame_jacobian_matches_finite_differences_of_dh(spec, rng, support):
    from op2motion.robot.joints import servo_to_book

    dyn = dynamics_for(spec)
    servo = book_to_servo(BookAngles.random(1, rng, support, psi=True), spec)[0]
    jac = dyn.frame_jacobian(servo, "right_hand", support)
    step = 1e-6
    for k in range(20):
        plus, minus = servo.copy(), servo.copy()
        plus[k] += step
        minus[k] -= step
        hand = lambda s: forward(servo_to_book(s, support, spec), spec).point("right_hand")[0]  # noqa: E731
        assert jac[:3, k] == pytest.approx((hand(plus) - hand(minus)) / (2 * step), abs=1e-8)
