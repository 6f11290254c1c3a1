"""The error contract for walk, motion, export and file reads: hostile input is exit 2 with one line naming
the flag or file, nothing written and no input changed; a check that ran and failed is exit 1 with nothing
written. Inputs must be regular files (a device such as /dev/zero is refused before reading) and reads are
capped (op2motion.fileio.MAX_INPUT_BYTES)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest
from helpers import ROOT, STOCK, pose_path, run_cli, without_progress

from op2motion.formats import actionlayout as layout

STAND = pose_path("standing")
INIT = pose_path("init")
IN = "{in}"
PAGE = 4                                    # the stock file's "hi"


def _page_with(field: int | None, value: int, goals: int | None = None) -> bytes:
    """The stock file with page 4's header byte ``field`` set to ``value`` (or every goal word set to
    ``goals``), its checksum fixed: bytes a real Action Editor file could hold."""
    data = bytearray(STOCK.read_bytes())
    off = PAGE * layout.PAGE_SIZE
    page = bytearray(data[off:off + layout.PAGE_SIZE])
    if field is not None:
        page[field] = value
    if goals is not None:
        for s in range(layout.MAX_STEPS):
            base = layout.step_offset(s)
            for slot in range(1, 21):
                page[base + 2 * slot:base + 2 * slot + 2] = goals.to_bytes(2, "little")
    data[off:off + layout.PAGE_SIZE] = layout.with_checksum(page)
    return bytes(data)


def _fixtures(root: Path) -> None:
    d = root / "in"
    d.mkdir()
    stand = json.loads(Path(STAND).read_text(encoding="utf-8"))
    text = Path(STAND).read_text(encoding="utf-8")
    files = {
        "steps200.bin": _page_with(layout.OFF_STEPNUM, 200),
        "selfchain.bin": _page_with(layout.OFF_NEXT, PAGE),
        "tick4095.bin": _page_with(None, 0, goals=4095),
        "dup_key.json": text.replace('"name": "standing",', '"name": "standing",\n  "name": "other",').encode(),
        "unknown_field.json": json.dumps({**stand, "colour": "red"}).encode(),
        "unreachable.toml": b'name = "unreachable"\nsteps = 4\nstep_length_m = 0.12\nstep_s = 0.5\n'
                            b'hip_lower_m = 0.0\nstep_height_m = 0.05\n',
        "stance.json": text.encode(),
        "pgain1.toml": b'name = "pgain1"\nsteps = 4\np_gain = 1\n',
        "leaning.json": json.dumps({**{k: v for k, v in stand.items() if k != "book_deg"}, "servo_deg": {
            **stand["servo_deg"], "l_ank_pitch": stand["servo_deg"]["l_ank_pitch"] - 35.0,
            "r_ank_pitch": stand["servo_deg"]["r_ank_pitch"] + 35.0}}).encode(),
        "inline.json": json.dumps({"schema": "op2motion.motion/1", "name": "inline", "steps": [
            {"servo_deg": stand["servo_deg"]}, {"servo_deg": stand["servo_deg"], "duration_s": 1.0}]}).encode(),
    }
    for name, data in files.items():
        (d / name).write_bytes(data)


CASES = [
    # walk: targets, flags that do nothing or contradict, presets that plan into the impossible
    (["walk", "--target", "0", "0", "1e300"], "--target"),
    (["walk", "--target", "0", "0", "100000"], "--target"),
    (["walk", "--target", "0.2", "0.2", "720"], "--target"),
    (["walk", "--target", "5", "0", "0"], "--target"),
    (["walk", "--target", "0.1", "0", "0", "--steps", "4"], "--steps"),
    (["walk", "--seed", "3"], "--seed"),
    (["walk", "--perturb-deg", "1"], "--perturb-deg"),
    (["walk", "--push", "2"], "--validate"),
    (["walk", "--preset", ""], "--preset"),
    (["walk", "--plot", "w.jpg"], ".png"),
    (["walk", "--out", "w.csv", "w.csv"], "another output"),
    (["walk", "--out", "w.csv", "w.txt"], "--out"),
    (["walk", "--preset", f"{IN}/unreachable.toml"], "--preset"),
    (["walk", "--preset", f"{IN}/pgain1.toml", "--out", "w.motion"], "--preset"),
    (["walk", "--preset", f"{IN}/pgain1.toml", "--retime", "--out", "w.motion"], "mechanical range"),
    (["motion", "play", str(STOCK), "--page", "9", "--push", "10"], "--validate"),
    (["motion", "plan", INIT, STAND, "--durations", "1", "--engine", "mujoco"], "--validate"),
    (["motion", "plan", INIT, STAND, "--durations", "1", "--planner", "none", "--seed", "3"], "--seed"),
    (["optimize", "--seconds", "3"], "--validate"),
    (["library", "build", "--robust", "--out", "lib"], "--validate"),
    # devices: not regular files, refused before reading
    (["motion", "play", "/dev/zero", "--page", "4"], "character device"),
    (["validate", "/dev/zero"], "character device"),
    (["--spec", "/dev/zero", "urdf", "-o", "op2.urdf"], "character device"),
    (["export", "--format", "action", STAND, "--base", "/dev/zero", "-o", "x.bin"], "character device"),
    (["import-action", "/dev/zero", "--page", "4", "--out", "z.json"], "character device"),
    (["walk", "--preset", "/dev/zero"], "--preset"),
    # action pages the framework cannot play
    (["motion", "play", f"{IN}/steps200.bin", "--page", "4"], "at most 7"),
    (["import-action", f"{IN}/steps200.bin", "--page", "4", "--out", "z.json"], "at most 7"),
    (["motion", "play", f"{IN}/selfchain.bin", "--page", "4"], "never ends"),
    # outputs over inputs or over each other
    (["export", "--format", "action", f"{IN}/stance.json", "-o", f"{IN}/stance.json"], "input file"),
    (["motion", "export", f"{IN}/inline.json", "--format", "action", "-o", f"{IN}/inline.json"], "input file"),
    (["motion", "plan", INIT, STAND, "--durations", "1", "--out", "o.json", "--csv", "o.json"], "another output"),
    (["motion", "plan", INIT, STAND, "--durations", "1", "--plot", "m.jpg"], ".png"),
    # pose files: every key once, no unknown fields
    (["fk", "--pose", f"{IN}/dup_key.json"], "twice"),
    (["fk", "--pose", f"{IN}/unknown_field.json"], "unknown field"),
]

FAILED_CHECKS = [
    pytest.param(["motion", "play", f"{IN}/tick4095.bin", "--page", "4", "--plot", "p.png", "--csv", "p.csv"],
                 "mechanical range", id="page of goals beyond the joints' range"),
    # (in MuJoCo: what is tested is the failed check's exit and that nothing is written, not the engine; the same
    # runs took PyBullet twice the time)
    pytest.param(["motion", "play", str(STOCK), "--page", "9", "--validate", "--engine", "mujoco", "--push", "100",
                  "--plot", "p.png"], "pushed", marks=pytest.mark.physics, id="page pushed over"),
    pytest.param(["walk", "--steps", "4", "--validate", "--engine", "mujoco", "--push", "100", "--plot", "w.png",
                  "--out", "w.csv"], "pushed", marks=pytest.mark.physics, id="a walk pushed over"),
    pytest.param(["validate", f"{IN}/leaning.json", "--seconds", "3", "--gui-png", "g.png"], "does not stand",
                 marks=pytest.mark.physics, id="a falling pose's snapshot"),
]


def _snapshot(*roots: Path) -> dict[str, str]:
    return {str(p): "dir" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
            for root in roots for p in sorted(root.rglob("*"))}


def _run(capsys, tmp_path, monkeypatch, argv):
    _fixtures(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    before = _snapshot(tmp_path, ROOT / "poses")
    code, out, err = run_cli(capsys, *[a.replace(IN, str(tmp_path / "in")) for a in argv])
    err = without_progress(err)
    assert _snapshot(tmp_path, ROOT / "poses") == before and not os.listdir(work)   # nothing written or changed
    assert err.count("\n") == 1 and err.startswith("op2motion: error: ") and "Traceback" not in err, err
    assert err.count("op2motion") == 1, err                                           # the program named once
    return code, out, err


@pytest.mark.parametrize("argv, needle", CASES, ids=[" ".join(c[0])[:60] for c in CASES])
def test_bad_input_is_exit_2_naming_the_flag_or_file(capsys, tmp_path, monkeypatch, argv, needle):
    code, out, err = _run(capsys, tmp_path, monkeypatch, argv)
    assert code == 2 and out == "" and needle in err, err


@pytest.mark.parametrize("argv, needle", FAILED_CHECKS)
def test_a_failed_check_is_exit_1_with_nothing_written(capsys, tmp_path, monkeypatch, argv, needle):
    code, _, err = _run(capsys, tmp_path, monkeypatch, argv)
    assert code == 1 and needle in err, err


def test_a_saved_motion_planned_into_another_folder_keeps_its_poses(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "elsewhere" / "deeper" / "o.json"
    code, _, err = run_cli(capsys, "motion", "plan", str(ROOT / "poses" / "motions" / "stand_sit_stand.json"),
                           "--out", out)
    assert code == 0, err
    code, _, err = run_cli(capsys, "motion", "plan", out)              # its pose references resolve from there
    assert code == 0, err


def test_a_page_repeated_255_times_is_named_once_with_its_count():
    from op2motion.tasks.motion import _chain

    assert _chain([4] * 255) == "4 x255" and _chain([4, 4, 5, 9, 9]) == "4 x2 -> 5 -> 9 x2"
