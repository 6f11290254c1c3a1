"""The error contract, table-driven: every command refuses malformed or hostile input with exit 2, exactly one line
on stderr (no traceback), nothing on stdout, and no file created or changed anywhere it could write."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest
from helpers import ROOT, STOCK, pose_path, run_cli, without_progress

STAND = pose_path("standing")
WALKREADY = pose_path("walkready")
ANGLES_TH = ["90", "0", "0", "180", "0", "0", "180", "0", "180", "0", "0"]
ANGLES_PHI = ["0", "0", "180", "0", "180", "180"]
BOOK = ["--th", *ANGLES_TH, "--phi", *ANGLES_PHI]
SPEC_TEXT = (ROOT / "specs" / "op2.toml").read_text(encoding="utf-8")


def _fixtures(root: Path) -> dict[str, str]:
    """Malformed inputs written into ``root/in`` (before the snapshot), by name."""
    d = root / "in"
    d.mkdir()
    (d / "folder").mkdir()
    (d / "folder.png").mkdir()
    files = {
        "not_json": b'{"schema": "op2motion.pose/1", "servo_',
        "random": bytes(range(256)) * 8,
        "latin1": "caf\u00e9 = 1".encode("latin-1"),
        "truncated.bin": STOCK.read_bytes()[:-1],
        "neg_inertia.toml": SPEC_TEXT.replace("inertia = [1.98125e-03", "inertia = [-1.98125e-03").encode(),
        "ghost_link.toml": SPEC_TEXT.replace('parent = "l_knee_link"', 'parent = "l_calf_link"').encode(),
        "ghost_point.toml": SPEC_TEXT.replace('link = "head_tilt_link"', 'link = "hat_link"', 1).encode(),
        "empty.toml": b"",
    }
    doc = json.loads(Path(STAND).read_text(encoding="utf-8"))
    for name, change in (("escape_name.json", {"name": "../escape"}),
                         ("beyond_stop.json", {"servo_deg": {**doc["servo_deg"], "l_knee": -170.0}}),
                         ("nan_angle.json", {"servo_deg": {**doc["servo_deg"], "l_knee": "NaN"}}),
                         ("old_schema.json", {"schema": "op2motion.pose/0"}),
                         ("list.json", None)):
        files[name] = json.dumps([1, 2] if change is None else {**{k: v for k, v in doc.items() if k != "book_deg"},
                                                                **change}).encode()
    for name, data in files.items():
        (d / name).write_bytes(data)
    (d / "existing.json").write_bytes(Path(STAND).read_bytes())
    return {name: str(d / name) for name in [*files, "folder", "existing.json"]}


IN = "{in}"  # placeholder for the fixture folder in the table below
CASES = [
    # fk
    (["fk", "--gamma", "inf", *BOOK], "--gamma"),
    (["fk", "--gamma", "1e308", *BOOK], "--gamma"),
    (["fk", "--th", "1e308", *ANGLES_TH[1:], "--phi", *ANGLES_PHI], "--th"),
    (["fk", "--th", "nan", *ANGLES_TH[1:], "--phi", *ANGLES_PHI], "--th"),
    (["fk", "--th", "1", "2", "--phi", *ANGLES_PHI], "expected 11 angles"),
    (["fk", *BOOK, "--sp", "0", "0", "inf"], "--sp"),
    (["fk", *BOOK, "--br", "0"], "--br"),
    (["fk", *BOOK, "--br", "1.5"], "--br"),
    (["fk", "--pose", f"{IN}/folder"], "got a directory"),
    (["fk", "--pose", "/no/such/pose.json"], "no such pose file"),
    (["fk", "--pose", f"{IN}/not_json"], "not valid JSON"),
    (["fk", "--pose", f"{IN}/random"], "UTF-8"),
    (["fk", "--pose", f"{IN}/escape_name.json"], "pose name"),
    (["fk", "--pose", f"{IN}/beyond_stop.json"], "mechanical range"),
    (["fk", "--pose", f"{IN}/nan_angle.json"], "finite"),
    (["fk", "--pose", f"{IN}/old_schema.json"], "schema"),
    (["fk", "--pose", f"{IN}/list.json"], "JSON object"),
    (["fk", "--model", "xyz", *BOOK], "--model"),
    (["fk", "--support", "up", *BOOK], "--support"),
    (["--spec", f"{IN}/random", "fk", *BOOK], "UTF-8"),
    (["--spec", f"{IN}/latin1", "fk", *BOOK], "UTF-8"),
    (["--spec", f"{IN}/neg_inertia.toml", "fk", *BOOK], "positive definite"),
    (["--spec", f"{IN}/ghost_link.toml", "urdf"], "does not exist"),
    (["--spec", f"{IN}/ghost_point.toml", "fk", *BOOK], "does not exist"),
    (["--spec", f"{IN}/empty.toml", "fk", *BOOK], "schema"),
    (["--spec", f"{IN}/folder", "fk", *BOOK], "got a directory"),
    # convert
    (["convert", "--servo-deg", '{"l_knee": 0}'], "missing"),
    (["convert", "--servo-deg", "[1, 2]"], "expected an object"),
    (["convert", "--servo-deg", "/no/such.json"], "no such JSON file"),
    (["convert", "--servo-deg", f"{IN}/random"], "UTF-8"),
    (["convert", "--servo-deg", f"{IN}/beyond_stop.json", *BOOK], "not several"),
    # plot
    (["plot", "-o", f"{IN}/folder.png"], "directory"),
    (["plot", "-o", "w.jpg"], "ending in .png"),
    (["plot", "-o", ""], "empty"),
    (["plot", "-o", f"{IN}/existing.json/x.png"], "not a directory"),
    (["plot", "--target", "0", "0", "nan", "-o", "x.png"], "--target"),
    (["plot", "/no/such.json", "-o", "x.png"], "no such pose file"),
    # arm-ik
    (["arm-ik", "--hand", "left", "--delta", "nan", "0", "0", *BOOK], "--delta"),
    (["arm-ik", "--hand", "left", "--delta", "5", "0", "0", *BOOK], "--delta"),
    (["arm-ik", "--hand", "left", "--delta", "0.01", "0", "0", "--tol-mm", "0", *BOOK], "--tol-mm"),
    (["arm-ik", "--hand", "left", "--delta", "0.01", "0", "0", "--plot", f"{IN}/folder.png", *BOOK],
     "directory"),
    (["arm-ik", "--hand", "left", "--delta", "0.01", "0", "0"], "--th"),
    (["arm-ik", "--hand", "both", "--delta", "0.01", "0", "0", *BOOK], "--hand"),
    # optimize
    (["optimize", "--restarts", "-1"], "--restarts"),
    (["optimize", "--validate", "--seconds", "-1"], "--seconds"),
    (["optimize", "--name", "../escape"], "--name"),
    (["optimize", "--name", "sub/dir/x"], "--name"),
    (["optimize", "--name", ""], "--name"),
    (["optimize", "--name", ".hidden"], "--name"),
    (["optimize", "--particles", "1"], "--particles"),
    (["optimize", "--iters", "0"], "--iters"),
    (["optimize", "--seed", "-1"], "--seed"),
    (["optimize", "--target", "0.5", "nan", "0"], "--target"),
    (["optimize", "--target", "5", "0", "0"], "--target"),
    (["optimize", "--br", "0"], "--br"),
    (["optimize", "--out", f"{IN}/folder"], "directory"),
    (["optimize", "--plot", f"{IN}/folder.png"], "directory"),
    (["optimize", "--out", "x.png", "--plot", "x.png"], "another output"),
    # library build
    (["library", "build", "--x", "0.1", "0.2", "1000000000"], "--x"),
    (["library", "build", "--x", "0.1", "0.2", "2.5"], "--x"),
    (["library", "build", "--workers", "100000"], "--workers"),
    (["library", "build", "--workers", "-1"], "--workers"),
    (["library", "build", "--out", f"{IN}/existing.json"], "--out"),
    (["library", "build", "--br", "0.7", "0.7"], "same pose name"),
    (["library", "build", "--x", "0.1", "0.1005", "2"], "same pose name"),
    (["library", "build", "--x", "0", "1", "1000", "--y", "0", "1", "1000"], "at most 10000 targets"),
    (["library", "build", "--seconds", "0", "--validate"], "--seconds"),
    (["library", "build", "--robust"], "--validate"),
    (["library"], "SUBCOMMAND"),
    # export
    (["export", "--format", "action", "--time", "1e300", STAND, "-o", "x.bin"], "--time"),
    (["export", "--format", "action", "--time", "0", STAND, "-o", "x.bin"], "--time"),
    (["export", "--format", "action", "--time", "9", STAND, "-o", "x.bin"], "--time"),
    (["export", "--format", "action", "--page", "300", STAND, "-o", "x.bin"], "--page"),
    (["export", "--format", "webots", "-o", "x.motion"], "at least one pose"),
    (["export", "--format", "action", "--base", f"{IN}/random", STAND, "-o", "x.bin"], "action file"),
    (["export", "--format", "csv", STAND, "-o", f"{IN}/folder"], "directory"),
    (["export", "--format", "action", STAND, "-o", ""], "empty"),
    (["export", "--format", "csv", f"{IN}/escape_name.json", "-o", "x.csv"], "pose name"),
    # import-action
    (["import-action", f"{IN}/folder"], "got a directory"),
    (["import-action", str(STOCK), "--page", "0"], "--page"),
    (["import-action", str(STOCK), "--page", "7"], "no steps"),
    (["import-action", str(STOCK), "--page", "9", "--out", f"{IN}/folder"], "directory"),
    (["import-action", str(STOCK), "--page", "9", "--name", "../x", "--out", "y.json"], "--name"),
    (["import-action", f"{IN}/truncated.bin"], "truncated"),
    (["import-action", str(STOCK), "--out", "x.json"], "--page"),
    # validate
    (["validate", f"{IN}/folder"], "got a directory"),
    (["validate", WALKREADY, "--seconds", "inf"], "--seconds"),
    (["validate", WALKREADY, "--seconds", "1000"], "--seconds"),
    (["validate", WALKREADY, "--gui-png", f"{IN}/folder.png"], "directory"),
    (["validate", f"{IN}/beyond_stop.json"], "mechanical range"),
    # outputs the OS refuses (/proc takes no new files, even from root)
    (["plot", "-o", "/proc/op2motion/x.png"], "cannot write"),
    (["arm-ik", "--hand", "left", "--delta", "0", "0", "0.01", "--plot", "/proc/x.png", *BOOK], "cannot write"),
    (["optimize", "--iters", "100", "--out", "/proc/op2motion/x.json"], "cannot write"),
    (["export", "--format", "csv", STAND, "-o", "/proc/x.csv"], "cannot write"),
    (["import-action", str(STOCK), "--page", "9", "--out", "/proc/x.json"], "cannot write"),
    pytest.param(["validate", WALKREADY, "--seconds", "3", "--gui-png", "/proc/x.png"], "cannot write",
                 marks=pytest.mark.physics),                  # /proc passes the folder checks: it runs, then fails
    (["urdf", "-o", "/proc/op2.urdf"], "cannot write"),
    # urdf, bench, the parser itself
    (["urdf", "-o", f"{IN}/folder"], "directory"),
    (["urdf", "-o", ""], "empty"),
    (["bench", "--poses", "0"], "--poses"),
    (["bench", "--repeat", "0"], "--repeat"),
    (["frobnicate"], "invalid choice"),
    ([], "COMMAND"),
]


def _snapshot(*roots: Path) -> dict[str, str]:
    """Every file below the roots with a hash of its content (and every folder)."""
    out: dict[str, str] = {}
    for root in roots:
        for path in sorted(root.rglob("*")):
            out[str(path)] = "dir" if path.is_dir() else hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _argv(case) -> list[str]:
    return case.values[0] if hasattr(case, "values") else case[0]


def test_there_are_at_least_60_cases_covering_every_command():
    commands = {argv[0] if argv and argv[0] != "--spec" else (argv[2] if argv else "") for argv in map(_argv, CASES)}
    assert len(CASES) >= 60
    assert {"fk", "convert", "plot", "arm-ik", "optimize", "library", "export", "import-action", "validate", "urdf",
            "bench"} <= commands


@pytest.mark.parametrize("argv, needle", CASES,
                         ids=[" ".join(_argv(c))[:60] for c in CASES])
def test_bad_input_exit_2_one_line_nothing_written(capsys, tmp_path, monkeypatch, argv, needle):
    fixtures = _fixtures(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    before = _snapshot(tmp_path, ROOT / "poses")
    code, out, err = run_cli(capsys, *[a.replace(IN, str(Path(fixtures["folder"]).parent)) for a in argv])
    err = without_progress(err)          # a run that fails late (/proc) may have shown progress in the meantime
    assert code == 2, err
    assert out == "" and err.count("\n") == 1 and err.startswith("op2motion: error: "), err
    assert "Traceback" not in err and needle in err, err
    assert _snapshot(tmp_path, ROOT / "poses") == before
    assert not os.listdir(work)


def test_a_fixed_frame_with_a_zero_rotation_column_is_refused_even_under_python_O():
    """The check is an error, not an assert (asserts vanish under ``python -O``)."""
    import subprocess
    import sys

    code = ("from op2motion.kinematics.frames import Frame\nfrom op2motion.errors import InputError\n"
            "f = Frame.constant(((1, 0, 0), (0, 1, 0), (0, 0, 1)), (0, 0, 0), 2)\n"
            "try:\n    f.fixed(((0, 0, 0), (0, 1, 0), (0, 0, 1)))\nexcept InputError as e:\n    print(e.param)\n")
    out = subprocess.run([sys.executable, "-O", "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "rotation"
