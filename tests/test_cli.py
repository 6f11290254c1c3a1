"""The command line: the documented JSON keys, exit codes 0/2, one-line errors, nothing written on bad input."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from helpers import pose_path, run_cli

from op2motion import book

STANDING_POSE = pose_path("standing")
STAND_TH = [f"{v:g}" for v in book.STANDING_TH_DEG]
STAND_PHI = [f"{v:g}" for v in book.STANDING_PHI_DEG]
CODE_2_6 = ["--th", *map(str, book.CODE_2_6_TH_DEG), "--phi", *map(str, book.CODE_2_6_PHI_DEG)]


def test_fk_json_has_the_contract_keys(capsys):
    code, out, err = run_cli(capsys, "fk", "--model", "dh", "--support", "left", *CODE_2_6, "--psi", "10", "-5", "0",
                         "--json")
    assert code == 0 and err == ""
    doc = json.loads(out)
    for key in ("points", "com", "left_hand", "right_hand", "swing_foot_corners", "swing_foot_min_z", "servo_deg"):
        assert key in doc
    assert len(doc["points"]) >= 27 and "l_el" in doc["points"] and "right_sole" in doc["points"]
    assert len(doc["swing_foot_corners"]) == 4 and len(doc["servo_deg"]) == 20
    assert doc["left_hand"] == doc["points"]["left_hand"]


def test_fk_human_output_and_pb_model(capsys):
    code, out, _ = run_cli(capsys, "fk", "--model", "pb", *CODE_2_6)
    assert code == 0 and "centre of mass" in out and "stability margin" in out


def test_convert_round_trip(capsys):
    code, out, _ = run_cli(capsys, "convert", "--th", *STAND_TH, "--phi", *STAND_PHI, "--support", "right", "--json")
    doc = json.loads(out)
    assert code == 0 and doc["ticks"]["4"] == 2560 and doc["servo_deg"]["l_el"] == pytest.approx(90.0)
    code, out, _ = run_cli(capsys, "convert", "--servo-deg", json.dumps(doc["servo_deg"]), "--support", "right",
                           "--json")
    back = json.loads(out)
    assert code == 0 and back["th"] == pytest.approx([float(v) for v in STAND_TH], abs=1e-9)
    assert back["phi"] == pytest.approx([float(v) for v in STAND_PHI], abs=1e-9)


def test_plot_writes_a_png(capsys, tmp_path):
    png = tmp_path / "standing.png"
    code, out, _ = run_cli(capsys, "plot", "--model", "both", "-o", str(png), "--target", "0.1", "0.05", "0.07")
    assert code == 0 and "wrote" in out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


@pytest.mark.parametrize("argv, needle", [
    (["fk", "--th", "1", "2", "--phi", *STAND_PHI], "expected 11 angles, got 2"),
    (["fk", "--th", "nan", *STAND_TH[1:], "--phi", *STAND_PHI], "finite"),
    (["fk", "--support", "up"], "invalid choice"),
    (["fk", "--pose", "/no/such/pose.json"], "no such pose file"),
    (["fk", "--model", "pb", *CODE_2_6, "--psi", "5", "0", "0"], "--model: the projection model assumes psi = 0"),
    (["fk", "--br", "0", "--th", *STAND_TH, "--phi", *STAND_PHI], "br"),
    (["convert", "--servo-deg", '{"l_knee": 0}'], "missing"),
    (["plot", "/no/such/pose.json", "-o", "OUT.png"], "no such pose file"),
    (["--spec", "/no/spec.toml", "fk"], "no such spec file"),
    (["frobnicate"], "invalid choice"),
    (["validate", STANDING_POSE, "--seconds", "nan"], "--seconds"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(capsys, tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and needle in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_malformed_spec_file_is_exit_2(capsys, tmp_path):
    bad = tmp_path / "op2.toml"
    bad.write_text('schema = "op2motion.spec/2"\nname = 3\n', encoding="utf-8")
    code, _, err = run_cli(capsys, "--spec", str(bad), "fk")
    assert code == 2 and str(bad) in err and "name" in err


def test_module_entry_point_exit_codes():
    ok = subprocess.run([sys.executable, "-m", "op2motion", "fk", "--th", *STAND_TH, "--phi", *STAND_PHI, "--json"],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and json.loads(ok.stdout)["support"] == "left"
    bad = subprocess.run([sys.executable, "-m", "op2motion", "fk", "--th", "1"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stdout == "" and len(bad.stderr.strip().splitlines()) == 1


def test_urdf_command(capsys, tmp_path):
    import xml.etree.ElementTree as ET

    out_file = tmp_path / "op2.urdf"
    code, out, _ = run_cli(capsys, "urdf", "-o", str(out_file))
    assert code == 0 and "20 joints" in out
    assert ET.parse(out_file).getroot().get("name") == "robotis_op2"
    code, out, _ = run_cli(capsys, "urdf")
    assert code == 0 and out.startswith("<?xml")


@pytest.mark.physics
def test_validate_command(capsys, tmp_path):
    import os

    poses = os.path.join(os.path.dirname(__file__), "..", "poses")
    png = tmp_path / "snap.png"
    code, out, err = run_cli(capsys, "validate", os.path.join(poses, "walkready.json"), "--seconds", "3",
                             "--gui-png", str(png), "--json")
    doc = json.loads(out)
    assert code == 0 and err == ""
    for key in ("stable", "reasons", "engine", "support_margin_m", "cop_xy", "max_tilt_deg", "settled_tilt_deg",
                "com_drift_m", "feet_slip_m", "self_collisions", "max_torque_nm", "torque_ok", "torque_ratio",
                "sag_deg", "servo", "time_step_s", "seconds", "pushes"):
        assert key in doc
    assert doc["stable"] is True and doc["reasons"] == [] and png.read_bytes()[:4] == b"\x89PNG"
    assert doc["time_step_s"] == 0.001 and "P 32" in doc["servo"]
    code, out, _ = run_cli(capsys, "validate", os.path.join(poses, "walkready.json"), "--seconds", "3",
                           "--engine", "both", "--json")
    both = json.loads(out)
    assert code == 0 and both["agree"] is True and set(both["engines"]) == {"pybullet", "mujoco"}
    # A pose that falls: exit 1, one line on stderr, the measurements still on stdout.
    stand = json.load(open(os.path.join(poses, "standing.json"), encoding="utf-8"))
    stand["servo_deg"]["l_ank_pitch"], stand["servo_deg"]["r_ank_pitch"] = 35.0, -35.0
    stand["name"] = "lean_back"
    del stand["book_deg"]
    falling = tmp_path / "lean_back.json"
    falling.write_text(json.dumps(stand), encoding="utf-8")
    code, out, err = run_cli(capsys, "validate", str(falling), "--seconds", "3")
    assert code == 1 and "does not stand: tilt" in err and err.count("\n") == 1 and "NOT STABLE (tilt" in out
    code, out, err = run_cli(capsys, "validate", str(tmp_path / "none.json"))
    assert code == 2 and out == "" and err.count("\n") == 1
