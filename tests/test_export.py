"""ROBOTIS action files, Webots motions, CSV, and the library build."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import DATA, page_last_step_ticks, run_cli, without_progress
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from op2motion.errors import InputError, PoseFileError
from op2motion.formats.action import ActionFile
from op2motion.formats.actionlayout import FILE_SIZE, PAGE_SIZE, checksum_ok, reset_file, reset_page
from op2motion.formats.posefile import read_pose
from op2motion.formats.tables import csv_table, webots_motion
from op2motion.library.build import BuildSettings, build_library
from op2motion.library.grid import axis, grid_jobs
from op2motion.posture.pso import PSOSettings
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.specfile import default_spec

POSES = os.path.join(os.path.dirname(__file__), "..", "poses")
STOCK = str(DATA / "motion_4096.bin")
STOCK_NAMES = {1: "init", 2: "ok", 3: "no", 4: "hi", 9: "walkready", 10: "f up", 11: "b up", 12: "rk", 13: "lk",
               15: "sit down", 16: "stand up", 90: "lie down", 91: "lie up"}


def test_stock_file_imports_with_all_its_pages(spec, stock_action_bytes):
    pages = ActionFile(stock_action_bytes).pages(spec)
    assert len(pages) == 45
    names = {p.index: p.name for p in pages}
    for index, name in STOCK_NAMES.items():
        assert names[index] == name
    assert len(next(p for p in pages if p.index == 6).steps) == 7          # talk1
    assert next(p for p in pages if p.index == 17).next == 18              # mul1 -> mul2


def test_reset_pages_match_the_action_editor(stock_action_bytes):
    empty = [i for i in range(1, 256) if stock_action_bytes[i * PAGE_SIZE + 20] == 0
             and checksum_ok(stock_action_bytes[i * PAGE_SIZE:(i + 1) * PAGE_SIZE])]
    assert len(empty) == 210
    assert all(stock_action_bytes[i * PAGE_SIZE:(i + 1) * PAGE_SIZE] == reset_page() for i in empty)
    assert len(reset_file()) == FILE_SIZE and reset_file()[:PAGE_SIZE] == stock_action_bytes[:PAGE_SIZE]



def test_reexport_is_byte_identical_and_pages_round_trip(capsys, spec, stock_action_bytes, tmp_path):
    same = tmp_path / "same.bin"
    assert run_cli(capsys, "export", "--format", "action", "--base", STOCK, "-o", str(same))[0] == 0
    assert same.read_bytes() == stock_action_bytes
    # Turn page 9 into a pose, write it and two library poses from page 200 on: read back the same ticks.
    pose_file = tmp_path / "walkready.json"
    assert run_cli(capsys, "import-action", STOCK, "--page", "9", "--out", str(pose_file))[0] == 0
    files = [str(pose_file), os.path.join(POSES, "book_2_44.json"), os.path.join(POSES, "standing.json")]
    out = tmp_path / "out.bin"
    code, _, _ = run_cli(capsys, "export", "--format", "action", *files, "--base", STOCK, "--page", "200",
                      "--time", "1.5", "-o", str(out))
    data = out.read_bytes()
    assert code == 0 and len(data) == FILE_SIZE
    for k, path in enumerate(files):
        page = ActionFile(data, "out").page(200 + k, spec)
        pose = read_pose(path, spec)
        assert page.name == pose.name[:13] and page.steps[0].time == round(1.5 / 0.008)
        ticks = np.array([page.steps[0].ticks[j.id] for j in spec.joints])
        assert np.all(np.abs(ticks - servo_to_ticks(pose.servo, spec)) <= 1)
    for i in set(range(256)) - {200, 201, 202}:  # every other page kept byte for byte, page 0 (invalid) included
        assert data[i * PAGE_SIZE:(i + 1) * PAGE_SIZE] == stock_action_bytes[i * PAGE_SIZE:(i + 1) * PAGE_SIZE]
    assert np.array_equal(page_last_step_ticks(data, 200), page_last_step_ticks(stock_action_bytes, 9))


def test_invalid_pages_of_the_base_are_kept(spec, stock_action_bytes, tmp_path):
    base = bytearray(stock_action_bytes)
    base[30 * PAGE_SIZE + 5] ^= 0xFF                      # break page 30's checksum
    written = ActionFile(bytes(base)).with_poses([read_pose(os.path.join(POSES, "standing.json"), spec)], spec,
                                                 100).action
    out = written.data
    assert out[30 * PAGE_SIZE:31 * PAGE_SIZE] == bytes(base[30 * PAGE_SIZE:31 * PAGE_SIZE])
    with pytest.raises(InputError, match="checksum"):
        ActionFile(bytes(base), "base").page(30, spec)


@pytest.mark.parametrize("argv, needle", [
    (["import-action", "/no/such.bin"], "no such action file"),
    (["import-action", STOCK, "--page", "300"], "--page"),
    (["import-action", STOCK, "--page", "0"], "--page"),
    (["import-action", STOCK, "--page", "7"], "no steps"),
    (["import-action", STOCK, "--out", "x.json"], "--page"),
    (["export", "--format", "webots", "-o", "x.motion"], "at least one pose"),
    (["export", "--format", "action", "--time", "9", os.path.join(POSES, "standing.json"), "-o", "x.bin"], "--time"),
    (["export", "--format", "action", "--time", "0.016", os.path.join(POSES, "standing.json"), "-o", "x.bin"],
     "24 ms"),
    (["export", "--format", "action", "--base", STOCK, "--page", "9", os.path.join(POSES, "standing.json"), "-o",
      "x.bin"], "--force"),
])
def test_bad_action_input(capsys, tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and needle in err and out == "" and os.listdir(tmp_path) == []


def test_truncated_file_is_a_clear_error(capsys, tmp_path, stock_action_bytes):
    short = tmp_path / "short.bin"
    short.write_bytes(stock_action_bytes[:-1])
    code, _, err = run_cli(capsys, "import-action", str(short))
    assert code == 2 and "truncated" in err


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.binary(max_size=2048),
                 st.lists(st.tuples(st.integers(0, FILE_SIZE - 1), st.integers(0, 255)), max_size=40)),
       st.integers(1, 255))
def test_reader_fuzz_only_clear_errors(blob, page):
    """Random bytes, or the stock file with random bytes changed: the reader succeeds or raises InputError."""
    spec = default_spec()
    if isinstance(blob, bytes):
        data = blob
    else:
        buf = bytearray((DATA / "motion_4096.bin").read_bytes())
        for offset, value in blob:
            buf[offset] = value
        data = bytes(buf)
    for call in (lambda: ActionFile(data).pages(spec), lambda: ActionFile(data, "f").pose(page, spec)):
        try:
            call()
        except InputError:
            pass


def test_webots_and_csv(spec):
    poses = [read_pose(os.path.join(POSES, n), spec) for n in ("walkready.json", "standing.json")]
    motion = webots_motion(poses, spec, 0.5).splitlines()
    assert motion[0].split(",")[:4] == ["#WEBOTS_MOTION", "V1.0", "ShoulderR", "ShoulderL"]
    assert motion[0].split(",")[-1] == "Head" and len(motion[0].split(",")) == 22
    assert motion[2].startswith("00:00:500,standing,0.000000,0.000000,-0.785398,0.785398")
    table = csv_table(poses, spec).splitlines()
    assert table[0].startswith("name,time_s,support,r_sho_pitch_deg") and table[2].startswith("standing,1.000,double")


@pytest.mark.slow
def test_library_build_and_resume(spec, tmp_path):
    jobs = grid_jobs(["left"], ["left", "right"], [0.7], axis(0.09, 0.11, 2, "x"), [0.03], [0.07])
    settings = BuildSettings(PSOSettings(iterations=120), restarts=0)
    first = build_library(jobs, spec, tmp_path, settings, workers=1)     # (two workers: the interrupted builds)
    assert first.targets == 4 and first.solved + first.failed == 4 and first.skipped == 0
    rows = json.loads((tmp_path / "index.json").read_text(encoding="utf-8"))
    assert len(rows) == 4 and (tmp_path / "index.csv").read_text(encoding="utf-8").startswith("name,hand,support")
    for row in rows:
        if row["reached"]:
            assert read_pose(tmp_path / row["file"], spec).name == row["name"]
    again = build_library(jobs, spec, tmp_path, settings, workers=1)
    assert again.skipped == 4 and again.seconds < 1.0


@pytest.mark.physics
def test_a_robust_library_build_holds_each_pose_on_the_family_and_counts(spec, tmp_path):
    """``--robust``: a pose that stands is held on every member of the robustness family; its index row says how
    many runs passed and the worst, the summary how many poses did not stand in every run."""
    from op2motion.physics import family
    from op2motion.physics.plan import MIN_SECONDS
    from op2motion.workflow import Validate

    jobs = grid_jobs(["left"], ["left"], [0.7], [0.10], [0.05], [0.07])
    # (held in MuJoCo: what is tested is the robust runs' count and how the index and the summary report them, in
    # the check's engine, whichever it is; PyBullet took four times as long)
    settings = BuildSettings(PSOSettings(iterations=120), restarts=0, validate=Validate(MIN_SECONDS, "mujoco"),
                             robust=True)
    summary = build_library(jobs, spec, tmp_path, settings, workers=1)
    row = json.loads((tmp_path / "index.json").read_text(encoding="utf-8"))[0]
    assert row["reached"] and row["stable"]
    assert row["robust_runs"] == len(family(spec)) and 0 <= row["robust_passed"] <= row["robust_runs"]
    assert (row["robust_worst"] == "") == (row["robust_passed"] == row["robust_runs"])
    assert summary.robust_checked == 1 and summary.robust_failed == int(row["robust_passed"] < row["robust_runs"])
    assert "robust_passed" in (tmp_path / "index.csv").read_text(encoding="utf-8").splitlines()[0]


@pytest.mark.slow
def test_killed_library_build_leaves_no_half_written_file(tmp_path):
    cmd = [sys.executable, "-m", "op2motion", "library", "build", "--x", "0.06", "0.14", "5", "--y", "0", "0.04",
           "2", "--z", "0.07", "0.07", "1", "--hands", "left", "--supports", "left", "--workers", "2",
           "--iters", "80", "--particles", "20", "--restarts", "0", "--out", str(tmp_path / "lib")]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 60
    while time.time() < deadline and not list((tmp_path / "lib").glob("reach-*.json")):
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    spec = default_spec()
    for path in (tmp_path / "lib").glob("*.json"):
        if path.name == "index.json":
            json.loads(path.read_text(encoding="utf-8"))
        else:
            read_pose(path, spec)                     # every pose file that exists is whole and valid
    resumed = subprocess.run(cmd + ["--json"], capture_output=True, text=True, timeout=300)
    summary = json.loads(resumed.stdout)
    assert resumed.returncode == 0 and summary["targets"] == 10 and summary["skipped"] >= 1
    assert not list((tmp_path / "lib").glob(".*.tmp"))
    with pytest.raises(PoseFileError):
        read_pose(tmp_path / "lib" / "missing.json", spec)


def _descendants(pid: int) -> set[int]:
    """Every live descendant of ``pid`` (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = open(f"/proc/{entry}/stat", encoding="utf-8").read()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(entry))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time a process has used [s] (0 if it is gone)."""
    try:
        fields = open(f"/proc/{pid}/stat", encoding="utf-8").read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _alive(pid: int) -> bool:
    try:
        state = open(f"/proc/{pid}/stat", encoding="utf-8").read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


ORPHAN_GRACE_S = 10.0
WORKER_BUSY_S = 1.5     # CPU time after which a worker is surely solving, not starting up (imports: < 1 s)


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc"), reason="needs Linux /proc to list processes")
def test_sigkill_of_the_parent_leaves_no_worker_and_the_rerun_completes(tmp_path):
    cmd = [sys.executable, "-m", "op2motion", "library", "build", "--x", "0.06", "0.14", "4", "--y", "0", "0.04",
           "2", "--z", "0.07", "0.07", "1", "--hands", "left", "--supports", "left", "--workers", "2",
           "--restarts", "0", "--out", str(tmp_path / "lib")]
    # Solves long enough (about a minute each) that a worker outlives the grace period unless it dies with its parent.
    proc = subprocess.Popen(cmd + ["--iters", "100000"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.time() + 60
    busy: list[int] = []
    while time.time() < deadline and len(busy) < 2:         # both workers deep in a solve
        busy = [p for p in _descendants(proc.pid) if _cpu_seconds(p) > WORKER_BUSY_S]
        time.sleep(0.1)
    assert len(busy) == 2
    workers = _descendants(proc.pid)                         # the workers and multiprocessing's resource tracker
    os.kill(proc.pid, signal.SIGKILL)                        # the parent only, as `kill -9 PID` does
    proc.wait()
    deadline = time.time() + ORPHAN_GRACE_S
    while time.time() < deadline and any(_alive(p) for p in workers):
        time.sleep(0.1)
    survivors = [p for p in workers if _alive(p)]
    for p in survivors:                                      # do not leave them behind if the test fails
        os.kill(p, signal.SIGKILL)
    assert survivors == []
    resumed = subprocess.run(cmd + ["--iters", "60", "--particles", "20", "--json"], capture_output=True, text=True,
                             timeout=300)
    summary = json.loads(resumed.stdout)
    assert resumed.returncode == 0 and summary["targets"] == 8 and summary["solved"] + summary["failed"] == 8
    rows = json.loads((tmp_path / "lib" / "index.json").read_text(encoding="utf-8"))
    assert len(rows) == 8 and all(r["hand"] == "left" and r["support"] == "left" for r in rows)


INTERRUPT_EXIT_S = 3.0


@pytest.mark.slow
def test_ctrl_c_stops_a_build_fast_with_a_complete_index_and_it_resumes(tmp_path, spec):
    cmd = [sys.executable, "-m", "op2motion", "library", "build", "--x", "0.06", "0.14", "5", "--y", "0", "0.04",
           "2", "--z", "0.07", "0.07", "1", "--hands", "left", "--supports", "left", "--workers", "2",
           "--iters", "150", "--restarts", "0", "--out", str(tmp_path / "lib")]
    # Ctrl-C as a terminal delivers it: a test run started in the background of a script has SIGINT ignored, and
    # its children would inherit that
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 90
    while time.time() < deadline and len(list((tmp_path / "lib").glob("reach-*.json"))) < 2:
        time.sleep(0.02)
    workers = _descendants(proc.pid)
    proc.send_signal(signal.SIGINT)
    t0 = time.time()
    _, err = proc.communicate(timeout=30)
    assert time.time() - t0 < INTERRUPT_EXIT_S and proc.returncode == 130
    err = without_progress(err)                     # (a slow machine may have printed a progress line first)
    assert err.count("\n") == 1 and "to resume" in err and "Traceback" not in err
    deadline = time.time() + INTERRUPT_EXIT_S       # the workers (and multiprocessing's tracker) are gone too
    while time.time() < deadline and any(_alive(p) for p in workers):
        time.sleep(0.05)
    assert not [p for p in workers if _alive(p)]
    files = sorted(p.name for p in (tmp_path / "lib").glob("reach-*.json"))
    rows = json.loads((tmp_path / "lib" / "index.json").read_text(encoding="utf-8"))
    assert sorted(r["file"] for r in rows if r["file"]) == files and len(files) < 10
    resumed = subprocess.run(cmd + ["--json"], capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0 and json.loads(resumed.stdout)["targets"] == 10
    rows = json.loads((tmp_path / "lib" / "index.json").read_text(encoding="utf-8"))
    assert len(rows) == 10
    for row in rows:
        assert row["hand"] == "left" and row["support"] == "left" and row["br"] == 0.7
        assert row["x"] is not None and row["y"] is not None and row["z"] == 0.07


def test_action_export_finds_an_empty_page_and_never_overwrites_unasked(capsys, spec, stock_action_bytes, tmp_path):
    """Without --page the poses go to the first run of empty pages (the stock file's first empty page is 5), the
    result names the pages; an occupied page is written only with --force."""
    stand = os.path.join(POSES, "standing.json")
    out = tmp_path / "out.bin"
    code, text, _ = run_cli(capsys, "export", "--format", "action", stand, stand, "--base", STOCK, "-o", str(out),
                            "--json")
    first = next(i for i in range(1, 255) if requested_page_or_none(stock_action_bytes, i, spec) is None
                 and requested_page_or_none(stock_action_bytes, i + 1, spec) is None)
    assert code == 0 and json.loads(text)["pages"] == [first, first + 1]
    assert ActionFile(out.read_bytes(), "out").page(first, spec).name == "standing"
    forced = tmp_path / "forced.bin"
    assert run_cli(capsys, "export", "--format", "action", stand, "--base", STOCK, "--page", "9", "--force", "-o",
                   str(forced))[0] == 0
    assert ActionFile(forced.read_bytes(), "out").page(9, spec).name == "standing"


def requested_page_or_none(data, index, spec):
    try:
        return ActionFile(data, "data").page(index, spec)
    except InputError:
        return None


def test_webots_export_sanitises_names_and_warns_outside_the_webots_ranges(capsys, spec, tmp_path):
    """A pose name with a comma and a line break cannot break the motion file; a knee beyond the Webots model's
    stop (LegLowerR 128.9°) is written (Webots clamps it) with a warning naming the motor."""
    from op2motion.robot.pose import Pose

    servo = read_pose(os.path.join(POSES, "standing.json"), spec).servo.copy()
    servo[spec.joint_names.index("r_knee")] = np.radians(130.0)
    odd = Pose("deep,knee", "double", servo, {}, {})
    text = webots_motion([odd, odd], spec, times=[0.0, 0.5])
    lines = text.splitlines()
    assert len(lines) == 3 and lines[1].split(",")[1] == "deep_knee" and lines[2].startswith("00:00:500,")
    with pytest.raises(InputError, match="strictly increasing"):
        webots_motion([odd, odd], spec, times=[0.0, 0.0])
    from op2motion.formats.tables import webots_warnings

    warnings = webots_warnings([odd], spec)
    assert len(warnings) == 1 and "LegLowerR (r_knee) 130.0°" in warnings[0] and "128.9" in warnings[0]
