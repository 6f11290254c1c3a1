"""library build on a Ray cluster: a local Ray head on this machine (started with Ray's own CLI), a small grid
built through it, compared with the process pool; resumable with the same index."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

import pytest

#: Skipped where Ray (the optional extra) is not installed; looked up, not imported: every test process collects this
#: module, and importing Ray costs each 0.4 s.
pytestmark = [pytest.mark.slow, pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="ray not installed")]
GRID = ["--hands", "left", "--supports", "left", "--x", "0.08", "0.12", "2", "--y", "0.03", "0.03", "1",
        "--z", "0.07", "0.07", "1", "--iters", "60"]
SAME_DEG = 1e-9


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def ray_head():
    """A Ray head on this machine (token authentication off: a test cluster on loopback; a short temp folder:
    Ray's sockets must fit in 107 bytes)."""
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")
    env = {**os.environ, "RAY_AUTH_MODE": "disabled", "RAY_USAGE_STATS_ENABLED": "0", HEAD_MARK: temp}
    port = _free_port()
    cli = [sys.executable, "-c", "from ray.scripts.scripts import main; main()"]
    started = subprocess.run([*cli, "start", "--head", f"--port={port}", "--num-cpus=2", "--include-dashboard=false",
                              "--disable-usage-stats", f"--temp-dir={temp}"], env=env, capture_output=True,
                             text=True, timeout=120)
    assert started.returncode == 0, started.stderr
    try:
        yield f"127.0.0.1:{port}", env
    finally:
        _stop_cluster(temp)
        shutil.rmtree(temp, ignore_errors=True)


#: Set in the environment of the test head's ``ray start``, which every process of that head inherits.
HEAD_MARK = "OP2MOTION_TEST_RAY_HEAD"


def _head_processes(temp: str) -> list[int]:
    """This head's processes: those naming its temp folder on their command line or carrying its mark in their
    environment, and everything below them (a Ray agent renames itself, ``ray::DashboardAgent``, which hides both:
    they outlived the clean-up)."""
    mark = f"{HEAD_MARK}={temp}".encode()
    parents, mine = {}, set()
    for pid in os.listdir("/proc"):
        if pid.isdigit() and int(pid) != os.getpid():
            try:
                with open(f"/proc/{pid}/stat", "rb") as f:
                    parents[int(pid)] = int(f.read().rsplit(b")", 1)[1].split()[1])
                with open(f"/proc/{pid}/cmdline", "rb") as f:
                    named = temp.encode() in f.read()
                with open(f"/proc/{pid}/environ", "rb") as f:
                    marked = mark in f.read().split(b"\0")
            except (OSError, IndexError, ValueError):
                continue
            if named or marked:
                mine.add(int(pid))
    grown = True
    while grown:
        below = {pid for pid, parent in parents.items() if parent in mine} - mine
        mine |= below
        grown = bool(below)
    return sorted(mine)


def _stop_cluster(temp: str) -> None:
    """End this head's processes only: ``ray stop`` would end every Ray on the machine, a library build's or tuning
    study's in another test among them."""
    for _ in range(3):
        mine = _head_processes(temp)
        if not mine:
            return
        for pid in mine:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        time.sleep(0.5)


def _build(cwd, env, out, *extra):
    done = subprocess.run([sys.executable, "-m", "op2motion", "library", "build", *GRID, "--out", out, "--json",
                           *extra], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _poses(folder):
    rows = {r["name"]: r for r in json.loads((folder / "index.json").read_text())}
    servo = {name: json.loads((folder / r["file"]).read_text())["servo_deg"] for name, r in rows.items() if r["file"]}
    return {name: (r["reached"], r["attempts"]) for name, r in rows.items()}, servo


def test_a_grid_built_on_a_ray_cluster_equals_the_process_pool(tmp_path, ray_head):
    """The grid built on the cluster is the process pool's, pose for pose, and resumes with the same index; then the
    fixture's clean-up ends every process of its head, the renamed Ray agents too (they once outlived it, found only
    by the test they were started in). One head for both: each start costs seconds of CPU."""
    address, env = ray_head
    on_ray = _build(tmp_path, env, "ray_lib", "--executor", "ray", "--address", address)
    pooled = _build(tmp_path, env, "pool_lib", "--workers", "2")
    assert on_ray["targets"] == pooled["targets"] == 2 and on_ray["solved"] == pooled["solved"] > 0
    rows_ray, servo_ray = _poses(tmp_path / "ray_lib")
    rows_pool, servo_pool = _poses(tmp_path / "pool_lib")
    assert rows_ray == rows_pool and servo_ray.keys() == servo_pool.keys()
    for name in servo_ray:                       # {joint: degrees}
        assert servo_ray[name] == pytest.approx(servo_pool[name], abs=SAME_DEG)
    again = _build(tmp_path, env, "ray_lib", "--executor", "ray", "--address", address)   # resumable: all done
    assert again["skipped"] == 2 and again["solved"] == on_ray["solved"]
    _head_ends_whole(env[HEAD_MARK])


def _head_ends_whole(temp: str) -> None:
    """Stop the head started with temp folder ``temp`` as the fixture does; nothing of it may be left running."""
    started = _head_processes(temp)
    assert any(_name(pid).startswith("ray::") for pid in started), [_name(pid) for pid in started]
    _stop_cluster(temp)
    test = os.environ["PYTEST_CURRENT_TEST"].split(" ")[0].encode()
    left = []
    for pid in os.listdir("/proc"):
        if pid.isdigit() and _alive(int(pid)) and _name(int(pid)).startswith("ray::"):
            try:
                with open(f"/proc/{pid}/environ", "rb") as f:
                    if test in f.read():
                        left.append(_name(int(pid)))
            except OSError:
                pass
    assert [pid for pid in started if _alive(pid)] == [] and left == []


def _name(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().split(b"\0")[0].decode(errors="replace")
    except OSError:
        return ""


def _alive(pid: int) -> bool:
    """Running (a zombie waiting for its new parent to reap it has ended)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return False


def test_ray_asked_of_a_cluster_that_is_not_there(tmp_path):
    done = subprocess.run([sys.executable, "-m", "op2motion", "library", "build", *GRID, "--out", "lib",
                           "--executor", "ray", "--address", f"127.0.0.1:{_free_port()}"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "RAY_AUTH_MODE": "disabled", "RAY_USAGE_STATS_ENABLED": "0"})
    assert done.returncode == 2 and "--address" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "lib" / "reach-ll-80-30-70-br70.json").exists()


def test_address_without_ray_is_refused(tmp_path):
    done = subprocess.run([sys.executable, "-m", "op2motion", "library", "build", *GRID, "--address", "auto"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "--executor ray" in done.stderr
