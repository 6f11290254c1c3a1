"""The spec loads, holds the real OP2, and a malformed spec is a clear error naming file and key."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from op2motion.errors import SpecError
from op2motion.spec import load_spec, parse_spec

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
    # Book table 2.8: head, neck, torso once; shoulder, upper/lower arm, gripper, pelvis, femur, tibia, heel, foot twice.
    expected = 0.15804 + 0.02436 + 0.9756 + 2 * (0.02591 + 0.16838 + 0.05929 + 0.010 + 0.16711 + 0.11904 + 0.07031
                                                 + 0.16711 + 0.07945)
    assert spec.lumped_total_mass == pytest.approx(expected, abs=1e-9)
    assert 2.8 <= spec.lumped_total_mass <= 3.0
    assert sum(i.mass for i in spec.inertials) == pytest.approx(2.925, abs=0.002)  # Webots per-link set


def _mutate(pattern: str, repl: str, count: int = 1) -> str:
    text, n = re.subn(pattern, repl, SPEC_TEXT, count=count, flags=re.M)
    assert n == count, pattern
    return text


@pytest.mark.parametrize("text, key", [
    (_mutate(r"^ticks_per_rev = 4096.*$", ""), "servo.ticks_per_rev"),
    (_mutate(r"^front_m = 0.052", "front_m = 0.052\nheel_m = 0.01"), "foot.heel_m"),
    (_mutate(r"^front_m = 0.052", 'front_m = "long"'), "foot.front_m"),
    (_mutate(r"^back_m = 0.052", "back_m = -0.052"), "foot.back_m"),
    (_mutate(r"^limit_deg = \[-75.0, 135.0\]", "limit_deg = [135.0, -75.0]"), "limit_deg"),
    (_mutate(r'book.left = \{ var = "th9"', 'book.left = { var = "th7"'), "book.left"),
    (_mutate(r'^schema = "op2motion.spec/1"', 'schema = "op2motion.spec/9"'), "schema"),
    (_mutate(r"^origin_xyz_m = \[0.0, 0.0, -0.093\]    # THIGH", "origin_xyz_m = [0.0, 0.0, 0.093]    # THIGH"),
     "r_knee origin must mirror l_knee"),
])
def test_malformed_spec_names_file_and_key(text, key):
    with pytest.raises(SpecError) as err:
        parse_spec(text, "bad/op2.toml")
    message = str(err.value)
    assert message.startswith("bad/op2.toml: ") and key in message and "\n" not in message


def test_missing_and_garbled_files_are_spec_errors(tmp_path):
    with pytest.raises(SpecError, match="cannot read spec"):
        load_spec(tmp_path / "none.toml")
    bad = tmp_path / "garbled.toml"
    bad.write_text("schema = [", encoding="utf-8")
    with pytest.raises(SpecError, match="not valid TOML"):
        load_spec(bad)
