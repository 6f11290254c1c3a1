"""PyBullet validation: real poses stand, falling poses fall, clashes are reported, the known traps are handled."""

from __future__ import annotations

import math
import os
import tempfile

import numpy as np
import pytest

from op2motion.errors import InputError
from op2motion.export.posefile import read_pose
from op2motion.joints import BookAngles, book_to_servo
from op2motion.model.urdf import FRAME_LINK_MASS_KG, link_inertial
from op2motion.physics import PLACEMENT_CLEARANCE_M, Sim, load_robot, quiet_c_output, validate_servo

POSES = os.path.join(os.path.dirname(__file__), "..", "poses")
PYBULLET_POSE_M = 1e-6   # PyBullet hands poses through single-precision transforms


@pytest.mark.parametrize("name", ["init", "walkready", "sit_down", "stand_up", "standing"])
def test_stock_standing_pages_stand(spec, name):
    pose = read_pose(os.path.join(POSES, f"{name}.json"), spec)
    v = validate_servo(pose.servo, pose.support, spec, seconds=2.0)
    assert v.stable, v.reason
    assert v.max_tilt_deg < 5 and v.feet_slip_m < 0.005 and v.self_collisions == [] and v.torque_ok


def _stand(spec) -> np.ndarray:
    return book_to_servo(BookAngles.standing("left"), spec)[0]


def test_leaning_back_at_the_ankles_falls(spec):
    servo = _stand(spec)
    names = spec.joint_names
    servo[names.index("l_ank_pitch")] = math.radians(35)    # both shins tilt 35° backwards
    servo[names.index("r_ank_pitch")] = math.radians(-35)
    v = validate_servo(servo, "double", spec, seconds=2.0)
    assert not v.stable and v.max_tilt_deg > 20


def test_legs_tilted_sideways_fall(spec):
    """A parallelogram: both legs lean 30° to the right, torso upright: the CoM leaves both feet."""
    lean = 30
    book = BookAngles.from_deg([90, 0, 0, 180, 0, 0, 180, 0, 180, 0, 0], [lean, -lean, 180 + lean, -lean, 180, 180],
                               [0, 0, 0], "left")
    v = validate_servo(book_to_servo(book, spec)[0], "double", spec, seconds=2.0)
    assert not v.stable


def test_arm_through_the_torso_is_reported(spec):
    servo = _stand(spec)
    names = spec.joint_names
    servo[names.index("l_sho_roll")] = math.radians(75)     # upper arm swung 30° inwards, through the chest
    v = validate_servo(servo, "double", spec, seconds=0.5)
    assert ["body_link", "l_sho_roll_link"] in v.self_collisions


def test_same_input_same_verdict(spec):
    servo = _stand(spec)
    assert validate_servo(servo, "double", spec, 1.0) == validate_servo(servo, "double", spec, 1.0)


def test_bad_input(spec):
    with pytest.raises(InputError, match="support"):
        validate_servo(_stand(spec), "both", spec)
    with pytest.raises(InputError, match="seconds"):
        validate_servo(_stand(spec), "left", spec, seconds=float("nan"))


# --- PyBullet traps -------------------------------------------------------------------------------------------

def test_trap_inertia_is_taken_from_the_file_only_when_told(spec):
    expected = np.linalg.eigvalsh(link_inertial(next(i for i in spec.inertials if i.link == "l_knee_link")).tensor)
    for from_file in (True, False):
        with Sim(spec, use_inertia_from_file=from_file) as sim:
            diag = np.sort(sim.client.getDynamicsInfo(sim.robot, sim.link_index["l_knee_link"])[2])
        if from_file:
            assert diag == pytest.approx(expected, rel=1e-6)
        else:  # recomputed from the collision box: a different tensor
            assert not np.allclose(diag, expected, rtol=0.05)


def test_trap_a_link_without_inertial_weighs_one_kilogram(spec):
    bare = ('<robot name="t"><link name="a"><inertial><mass value="0.5"/><inertia ixx="1e-3" iyy="1e-3" '
            'izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"/>'
            '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint></robot>')
    with Sim(spec) as sim:
        other = load_robot(sim.client, bare, sim.pb.URDF_USE_INERTIA_FROM_FILE)
        assert sim.client.getDynamicsInfo(other, 0)[0] == pytest.approx(1.0)   # PyBullet's default
        masses = sim.masses()                                                  # ours: every link as specified
    webots = {i.link: i.mass for i in spec.inertials}
    for link, mass in masses.items():
        assert mass == pytest.approx(webots.get(link, FRAME_LINK_MASS_KG))
    assert sum(masses.values()) == pytest.approx(2.925, abs=0.001)


def test_trap_loadurdf_needs_a_file_and_the_temp_file_is_removed(spec):
    before = set(os.listdir(tempfile.gettempdir()))
    with Sim(spec) as sim:
        assert sim.client.getNumJoints(sim.robot) == 20 + 6   # 20 servos + named frames
    leftovers = {f for f in set(os.listdir(tempfile.gettempdir())) - before if f.endswith(".urdf")}
    assert leftovers == set()


def test_trap_base_position_is_the_centre_of_mass(spec):
    with Sim(spec) as sim:
        sim.set_joints(_stand(spec))
        sim.place("left")
        com_pos = np.array(sim.client.getBasePositionAndOrientation(sim.robot)[0])
        link_pos = np.array(sim.base_link_frame()[0])
        inertial = next(i for i in spec.inertials if i.link == "body_link")
        assert com_pos - link_pos == pytest.approx(inertial.com, abs=PYBULLET_POSE_M)  # upright: offset = its CoM
        sole = np.array(sim.link_frame("left_sole_link")[0])
        assert sole == pytest.approx([0.0, 0.0, PLACEMENT_CLEARANCE_M], abs=PYBULLET_POSE_M)
        assert sim.link_frame("right_sole_link")[0][2] == pytest.approx(PLACEMENT_CLEARANCE_M, abs=PYBULLET_POSE_M)


def test_pybullet_banner_is_silenced(capfd):
    with quiet_c_output():
        os.write(1, b"noise")
        os.write(2, b"noise")
    out, err = capfd.readouterr()
    assert "noise" not in out and "noise" not in err
