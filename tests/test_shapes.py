"""Self-clearance on the D-H chain (op2motion.kinematics.shapes) against PyBullet's exact distances, and the link
attachments it stands on against the official joint table."""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest
from helpers import POSES, pybullet_pair_distances

from op2motion.formats.posefile import read_pose
from op2motion.kinematics.dh_chain import matrix_frames
from op2motion.kinematics.links import attachments
from op2motion.kinematics.shapes import clearances, shape_set
from op2motion.kinematics.tree import link_frames
from op2motion.posture.cost import SELF_CLEARANCE_M
from op2motion.robot.joints import BookAngles, book_to_servo, servo_to_book

POSES_CHECKED = 150
NEAR_M = 0.025               # pairs compared where our clearance is below this
# ours against PyBullet's exact distances: segment-against-box sampling and PyBullet's box distances (1.3 mm
# seen), plus the cylinders' rims and caps (ShapeSet.approximation_m)
SAMPLING_M = 0.0015
DEEP_M = -0.003              # deeper overlaps are depths of an edge, not PyBullet's penetration: compared by sign
FRAME_TOL_M = 1e-9


@pytest.mark.parametrize("support", ["left", "right"])
def test_clearance_agrees_with_pybullets_closest_points(spec, pybullet_robot, support):
    client, robot = pybullet_robot
    angles = BookAngles.random(POSES_CHECKED, np.random.default_rng(7), support)
    servo = book_to_servo(angles, spec)
    shapes = shape_set(spec, support)
    ours = clearances(matrix_frames(angles.vector(), spec, support), shapes)
    names, (over, under) = shapes.pair_names(), shapes.approximation_m()
    near = [(k, p) for k in range(POSES_CHECKED) for p in range(len(names)) if ours[p, k] <= NEAR_M]
    exact = pybullet_pair_distances(client, robot, spec, servo, [(k, names[p]) for k, p in near], NEAR_M)
    compared = overlapping = 0
    for (k, p), (_, a, b, d) in zip(near, exact):
        if d > DEEP_M:
            assert -SAMPLING_M - under[p] <= ours[p, k] - d <= SAMPLING_M + over[p], (k, a, b, ours[p, k], d)
            compared += 1
        else:
            assert ours[p, k] < 0.0, (k, a, b, ours[p, k], d)
            overlapping += 1
    assert compared > 200 and overlapping > 5      # the random poses exercise both sides of contact


def test_pairs_are_the_ones_physics_checks(spec):
    """Shapes on the same link or on a parent and its child never collide in the engines (URDF parent exclusion);
    every other pair is checked."""
    names = {tuple(sorted(p)) for p in shape_set(spec, "left").pair_names()}
    assert ("l_hip_pitch_link", "l_knee_link") not in names                 # thigh and shank: parent and child
    assert ("l_el_link", "l_sho_roll_link") not in names                    # forearm and upper arm
    for pair in [("body_link", "l_sho_roll_link"), ("body_link", "l_hip_pitch_link"), ("l_el_link", "l_hip_pitch_link"),
                 ("l_hip_pitch_link", "r_hip_pitch_link"), ("l_ank_roll_link", "l_knee_link")]:
        assert tuple(sorted(pair)) in names
    links = {c.link for c in spec.collisions}
    assert len(names) == len({tuple(sorted(p)) for p in names})
    assert all(a in links and b in links for a, b in names)


def test_the_standing_pose_is_symmetric_and_clear(spec):
    """Physical facts: standing, each left-side pair is exactly as clear as its mirror on the right, and nothing
    touches."""
    shapes = shape_set(spec, "left")
    clear = clearances(matrix_frames(BookAngles.standing("left").vector(), spec, "left"), shapes)[:, 0]
    by_pair = {tuple(p): c for p, c in zip(shapes.pair_names(), clear)}
    mirror = lambda link: {"l_": "r_", "r_": "l_"}.get(link[:2], link[:2]) + link[2:]  # noqa: E731
    for (a, b), c in by_pair.items():
        other = by_pair.get((mirror(a), mirror(b)), by_pair.get((mirror(b), mirror(a))))
        assert other == pytest.approx(c, abs=1e-9), (a, b)
    assert clear.min() > SELF_CLEARANCE_M


def test_committed_poses_keep_their_links_apart(spec):
    for path in sorted(glob.glob(os.path.join(POSES, "*.json"))):
        pose = read_pose(path, spec)
        support = "left" if pose.support == "double" else pose.support
        angles = servo_to_book(pose.servo[None], support, spec)
        clear = clearances(matrix_frames(angles.vector(), spec, support), shape_set(spec, support))
        assert clear.min() > 0.0, path


@pytest.mark.parametrize("support", ["left", "right"])
def test_links_ride_on_the_chain_as_in_the_joint_table(spec, support):
    """Every link frame placed by its attachment equals the official joint table's, seen from the support sole."""
    angles = BookAngles.random(4, np.random.default_rng(3), support)
    frames = matrix_frames(angles.vector(), spec, support)
    servo = book_to_servo(angles, spec)
    drop = np.array([0.0, 0.0, -spec.foot.sole_below_ankle])
    for k in range(4):
        tree = link_frames(spec, servo[k])
        r_foot, p_foot = tree[spec.joint(f"{support[0]}_ank_roll").child]
        for link, at in attachments(spec, support).items():
            placed = frames[at.slot, k] @ at.local
            r, p = tree[link]
            assert np.allclose(placed[:3, :3], r_foot.T @ r, atol=FRAME_TOL_M)
            assert np.allclose(placed[:3, 3], r_foot.T @ (p - p_foot - r_foot @ drop), atol=FRAME_TOL_M)
