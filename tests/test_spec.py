"""The spec loads, holds the real OP2, and a malformed spec is a clear error naming file and key."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from op2motion.errors import SpecError
from op2motion.robot.specfile import load_spec, parse_spec

SPEC_TEXT = (Path(__file__).parents[1] / "specs" / "op2.toml").read_text(encoding="utf-8")
LENGTH_TOL_M = 1e-12


def test_shipped_spec_holds_the_real_op2(spec):
    assert len(spec.joints) == 20
    assert [j.id for j in spec.joints] == list(range(1, 21))
    assert spec.joint("l_knee").id == 14 and spec.joint("l_knee").webots == "LegLowerL"
    g = spec.geometry
    assert abs(g.ankle_to_sole + g.calf + g.thigh - 0.2195) < LENGTH_TOL_M       # LEG_LENGTH
    assert abs(2 * g.hip_half_width - 0.074) < LENGTH_TOL_M
    assert abs(g.hip_yaw_to_roll - 0.0315) < LENGTH_TOL_M                       # real robot, book 0.03
    assert abs(g.hip_yaw_to_roll + g.torso - 0.1222) < LENGTH_TOL_M             # hip axis below the torso origin
    assert abs(g.elbow_forward - 0.016) < LENGTH_TOL_M                          # the offset the book omits
    assert abs(g.lower_arm - 0.129) < LENGTH_TOL_M
    assert abs(g.head_length - 0.069) < 1e-6
    assert spec.servo.stall_torque_nm == 2.5 and spec.servo.ticks_per_rev == 4096


def test_lumped_masses_total_the_book_table(spec):
    # Book table 2.8: head, neck, torso once; shoulder, upper/lower arm, gripper, pelvis, femur, tibia, heel, foot
    # twice.
    expected = 0.15804 + 0.02436 + 0.9756 + 2 * (0.02591 + 0.16838 + 0.05929 + 0.010 + 0.16711 + 0.11904 + 0.07031
                                                 + 0.16711 + 0.07945)
    assert spec.lumped_total_mass == pytest.approx(expected, abs=1e-9)
    assert 2.8 <= spec.lumped_total_mass <= 3.0
    assert sum(i.mass for i in spec.inertials) == pytest.approx(2.925, abs=0.002)  # the ROBOTIS CAD parts


def test_every_mass_figure_names_a_source_and_an_uncertainty(spec):
    """Each link's mass, CoM and tensor cite an entry of [sources]; each states how far it may be off, and the
    torso's (the figure that matters most) covers what the robustness checks vary: ±20 mm fore-aft, ±10 mm sideways,
    ±15 % mass."""
    assert len(spec.inertials) == 21
    for item in spec.inertials:
        assert set(item.sources) == {"mass", "com", "inertia"}, item.link
        assert all(key in spec.sources and spec.sources[key] for key in item.sources.values()), item.link
        u = item.uncertainty
        assert u is not None and 0.0 < u.mass_fraction < 0.5, item.link
        assert all(lo < 0.0 < hi for lo, hi in u.com_m), item.link
    torso = spec.inertial(spec.root_link).uncertainty
    assert torso.mass_fraction >= 0.15 and torso.com_m[0] == (-0.020, 0.020) and torso.com_m[1] == (-0.010, 0.010)


def test_the_body_is_mirror_symmetric(spec):
    """Every left link's mass, CoM and tensor mirror its right twin's (y -> -y)."""
    flip = [1.0, -1.0, 1.0]
    for left in (i for i in spec.inertials if i.link.startswith("l_")):
        right = spec.inertial("r_" + left.link[2:])
        assert right.mass == left.mass
        assert right.link_com == pytest.approx(left.link_com * flip, abs=1e-9)
        assert right.link_tensor == pytest.approx(left.link_tensor * np.outer(flip, flip), abs=1e-12)
    assert spec.inertial(spec.root_link).com[1] == 0.0


def test_an_inertial_in_a_turned_frame_is_read_into_the_link_frame(spec):
    """Older files give an inertial in its source's frame, placed in the link frame by webots_frame_xyz_m and
    webots_frame_rpy_deg: the loader turns the CoM and the tensor into the link frame."""
    head = spec.inertial("head_tilt_link")
    pitch = math.radians(12.0)
    rot = np.array([[math.cos(pitch), 0.0, math.sin(pitch)], [0.0, 1.0, 0.0], [-math.sin(pitch), 0.0, math.cos(pitch)]])
    offset = np.array([0.001, 0.0, -0.002])
    com = (rot.T @ (head.link_com - offset)).tolist()
    t = (rot.T @ head.link_tensor @ rot).tolist()
    block = re.search(r'\[\[inertial\]\]\nlink = "head_tilt_link"\n(?:.*\n)*?com_uncertainty_m = .*\n', SPEC_TEXT)
    turned = (f'[[inertial]]\nlink = "head_tilt_link"\nwebots = "Head"\nmass_kg = {head.mass!r}\n'
              f"com_m = [{com[0]!r}, {com[1]!r}, {com[2]!r}]\n"
              f"inertia = [{t[0][0]!r}, {t[1][1]!r}, {t[2][2]!r}, {t[0][1]!r}, {t[0][2]!r}, {t[1][2]!r}]\n"
              "webots_frame_xyz_m = [0.001, 0.0, -0.002]\n"
              "webots_frame_rpy_deg = [0.0, 12.0, 0.0]\n")
    read = parse_spec(SPEC_TEXT.replace(block.group(0), turned)).inertial("head_tilt_link")
    assert read.link_com == pytest.approx(head.link_com, abs=1e-12)
    assert read.link_tensor == pytest.approx(head.link_tensor, abs=1e-15)
    assert read.uncertainty is None and not read.sources


def _mutate(pattern: str, repl: str, count: int = 1) -> str:
    text, n = re.subn(pattern, repl, SPEC_TEXT, count=count, flags=re.M)
    assert n == count, pattern
    return text


@pytest.mark.parametrize("text, key", [
    (_mutate(r"^ticks_per_rev = 4096.*$", ""), "servo.ticks_per_rev"),
    (_mutate(r"^front_m = 0.052", "front_m = 0.052\nheel_m = 0.01"), "foot.heel_m"),
    (_mutate(r"^front_m = 0.052", 'front_m = "long"'), "foot.front_m"),
    (_mutate(r"^back_m = 0.052", "back_m = -0.052"), "foot.back_m"),
    (_mutate(r"^back_m = 0.052", "back_m = nan"), "foot.back_m"),
    (_mutate(r"^front_m = 0.052", "front_m = inf"), "foot.front_m"),
    (_mutate(r"^cable_safe_deg = \[-75.0, 135.0\]", "cable_safe_deg = [135.0, -75.0]"), "cable_safe_deg"),
    (_mutate(r"^cable_safe_deg = \[-75.0, 135.0\]", "cable_safe_deg = [-75.0, 160.0]"), "inside the mechanical"),
    (_mutate(r"^mechanical_deg = \[-91.0, 150.0\]", "mechanical_deg = [-91.0, 200.0]"), "servo's ±180°"),
    (_mutate(r'book.left = \{ var = "th9"', 'book.left = { var = "th7"'), "book.left"),
    (_mutate(r'^schema = "op2motion.spec/2"', 'schema = "op2motion.spec/9"'), "schema"),
    (_mutate(r"^origin_xyz_m = \[0.0, 0.0, -0.093\]    # THIGH", "origin_xyz_m = [0.0, 0.0, 0.093]    # THIGH"),
     "r_knee origin must mirror l_knee"),
    (_mutate(r"^supply_voltage_v = 12.0", "supply_voltage_v = 13.0"), "servo.supply_voltage_v"),
    # Physical sense: inertia tensors, masses, references that exist.
    (_mutate(r"^inertia = \[1.98125e-03", "inertia = [-1.98125e-03"), "positive definite"),
    (_mutate(r"^inertia = \[1.13515e-04, 9.33696e-05, 4.62955e-05, 2.39921e-07",
             "inertia = [1.13515e-04, 9.33696e-05, 4.62955e-04, 2.39921e-07"), "triangle inequality"),
    (_mutate(r'^sources = \{ mass = "robotis_cad", com = "robotis_cad", inertia = "mesh_official" \}',
             'sources = { mass = "robotis_cad", com = "a_guess", inertia = "mesh_official" }'), "sources.com"),
    (_mutate(r"^mass_uncertainty = 0.15\ncom_uncertainty_m = \[\[-0.020, 0.020\]",
             "mass_uncertainty = 0.15\ncom_uncertainty_m = [[0.020, 0.020]"), "com_uncertainty_m"),
    (_mutate(r"^mass_uncertainty = 0.15\n", ""), "mass_uncertainty and com_uncertainty_m together"),
    (_mutate(r"^mass_kg = 0.975599", "mass_kg = -0.975599"), "mass_kg"),
    (_mutate(r'^link = "l_knee_link"', 'link = "l_shin_link"'), "'l_shin_link' does not exist"),
    (_mutate(r'^link = "head_tilt_link"', 'link = "hat_link"'), "points.head_top"),
    (_mutate(r'^parent = "l_knee_link"', 'parent = "l_calf_link"'), "parent link 'l_calf_link' does not exist"),
    (_mutate(r'^from = "head_tilt"', 'from = "eyebrow"'), "body point 'eyebrow' does not exist"),
    (_mutate(r'^id = 20', 'id = 21'), "joint.id"),
])
def test_malformed_spec_names_file_and_key(text, key):
    with pytest.raises(SpecError) as err:
        parse_spec(text, "bad/op2.toml")
    message = str(err.value)
    assert message.startswith("bad/op2.toml: ") and key in message and "\n" not in message


def test_missing_garbled_and_binary_files_are_spec_errors(tmp_path):
    with pytest.raises(SpecError, match="no such spec file"):
        load_spec(tmp_path / "none.toml")
    with pytest.raises(SpecError, match="got a directory"):
        load_spec(tmp_path)
    bad = tmp_path / "garbled.toml"
    bad.write_text("schema = [", encoding="utf-8")
    with pytest.raises(SpecError, match="not valid TOML"):
        load_spec(bad)
    binary = tmp_path / "random.toml"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(SpecError, match="UTF-8"):
        load_spec(binary)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(SPEC_TEXT.replace("ROBOTIS OP2", "ROBOTIS OP2 \u00e9").encode("latin-1"))
    with pytest.raises(SpecError, match="UTF-8"):
        load_spec(latin)


def test_mechanical_ranges_hold_every_goal_of_the_stock_file(spec, stock_action_bytes):
    """The stock pages ran on real robots: every goal lies inside the mechanical range (hard), while 7 joints go
    beyond the cable-safe range (advice), so the cable-safe range must never be used as a hard limit."""
    import numpy as np

    from op2motion.formats.action import ActionFile
    from op2motion.robot.joints import limit_violations, ticks_to_servo

    beyond_safe = set()
    for page in ActionFile(stock_action_bytes).pages(spec):
        for step in page.steps:
            servo = np.zeros(20)
            given = np.array([step.ticks[j.id] is not None for j in spec.joints])
            servo[given] = ticks_to_servo(np.array([step.ticks[j.id] for j in spec.joints if step.ticks[j.id]
                                                    is not None]), spec)
            assert limit_violations(servo, spec, "mechanical") == [], (page.index, page.name)
            beyond_safe |= {v.joint for v in limit_violations(servo, spec, "cable-safe")}
    assert len(beyond_safe) == 7 and {"l_knee", "r_knee", "l_el"} <= beyond_safe
