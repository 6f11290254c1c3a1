"""A failed or interrupted command writes nothing and leaves nothing running: SIGTERM ends every command as Ctrl-C
does (one line, exit 130, temp files gone), for the process pool and for Ray; a build with Ray started here leaves
no Ray process after ``kill -9``; a name that would make an unreadable file is refused before writing."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time

import pytest
from helpers import pose_path, run_cli, wait_for

STAND, INIT = pose_path("standing"), pose_path("init")
END_S = 10.0                  # a terminated command ends within this [s]
GRID = ["--hands", "left", "--supports", "left", "--x", "0.06", "0.14", "20", "--y", "-0.05", "0.05", "10", "--z",
        "0.07", "0.11", "3"]  # 600 targets: half a minute of work on an idle machine (about 17 poses a second)
UNDER_WAY = 5                 # poses written: the build is under way when terminated
WALK_UNDER_WAY_S = 3.0        # a validated walk is in physics this long after its start [s]


def _start(cwd, *argv, env=None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "op2motion", *argv], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def _terminated(proc: subprocess.Popen, after_s: float, sig: int = signal.SIGTERM) -> tuple[int, str, float]:
    time.sleep(after_s)
    assert proc.poll() is None, proc.stderr.read()
    proc.send_signal(sig)
    t0 = time.monotonic()
    code = proc.wait(timeout=60)
    return code, proc.stderr.read(), time.monotonic() - t0


def _last_line(err: str) -> str:
    assert "Traceback" not in err and "SIGTERM" not in err, err
    return err.strip().splitlines()[-1]


@pytest.mark.physics
def test_sigterm_to_a_validated_walk_writes_nothing(tmp_path):
    proc = _start(tmp_path, "walk", "--steps", "60", "--validate", "--engine", "both", "--plot", "w.png", "--out",
                  "w.csv")                                # planned in about a second, then 15 s or more of physics
    code, err, took = _terminated(proc, WALK_UNDER_WAY_S)
    assert code == 130 and took < END_S and _last_line(err).startswith("op2motion: interrupted"), err
    assert list(tmp_path.iterdir()) == []                 # no outputs, no temp files


@pytest.mark.slow
def test_sigterm_to_a_process_pool_build_leaves_a_complete_index(tmp_path):
    proc = _start(tmp_path, "library", "build", *GRID, "--out", "lib", "--workers", "2")
    lib = tmp_path / "lib"
    wait_for(lambda: lib.is_dir() and len(list(lib.glob("reach-*.json"))) >= UNDER_WAY or proc.poll() is not None,
             "the build's first poses")
    code, err, took = _terminated(proc, 0.0)
    assert code == 130 and took < END_S and "resume" in _last_line(err)
    assert (tmp_path / "lib" / "index.json").exists()
    assert not [p for p in (tmp_path / "lib").iterdir() if p.name.endswith(".tmp")]


#: Run before the command in a test's process: the first worker process started sends this process a SIGTERM right
#: after it is spawned, before it has been handed its start-up message (the moment a real SIGTERM once landed in).
SIGTERM_AS_A_WORKER_STARTS = """
import os, signal, multiprocessing.util as util
_spawn = util.spawnv_passfds
def _spawn_then_sigterm(path, args, passfds):
    pid = _spawn(path, args, passfds)
    if any(b"spawn_main" in os.fsencode(arg) for arg in args):      # a worker, not the resource tracker
        util.spawnv_passfds = _spawn
        os.kill(os.getpid(), signal.SIGTERM)
    return pid
util.spawnv_passfds = _spawn_then_sigterm
"""


def test_a_sigterm_while_the_build_starts_its_workers_is_an_interrupt_without_a_traceback(tmp_path):
    """A SIGTERM while the pool spawned its workers left one reading half its start-up message: it printed
    ``EOFError: Ran out of input`` with a traceback after the build's last line."""
    script = SIGTERM_AS_A_WORKER_STARTS + (
        "import sys\nfrom op2motion.cli import entry\n"
        f"sys.argv = ['op2motion', 'library', 'build', {', '.join(repr(a) for a in GRID)}, '--out', 'lib', "
        "'--workers', '2']\nentry()\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 130 and "resume" in _last_line(done.stderr), done.stderr
    assert "Traceback" not in done.stderr and "EOFError" not in done.stderr, done.stderr
    assert (tmp_path / "lib" / "index.json").exists()


def test_a_sigterm_while_a_study_starts_a_worker_is_an_interrupt_and_its_workers_use_one_thread():
    """The tuning pool spawns its workers as trials are submitted: a SIGTERM then is held until the worker has
    started (then raised as an interrupt, no traceback), and a worker started then runs one maths thread."""
    script = SIGTERM_AS_A_WORKER_STARTS + """
import signal, sys
from op2motion.tune.executor import ProcessTrials
def _terminated(signum, frame):
    raise KeyboardInterrupt
signal.signal(signal.SIGTERM, _terminated)
trials = ProcessTrials(2)
try:
    trials.submit(0, os.getenv, "NUMBA_NUM_THREADS")
    print("not interrupted")
except KeyboardInterrupt:
    print("interrupted")
trials.submit(1, os.getenv, "NUMBA_NUM_THREADS")
found = []
while trials.running:
    found += trials.finished()
print(sorted(found))
trials.close()
"""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert done.stdout.splitlines()[0] == "interrupted"
    assert done.stdout.splitlines()[-1] in ("[(0, '1'), (1, '1')]", "[(1, '1')]"), done.stdout


def _ray_processes(mark: str) -> list[int]:
    """Processes whose environment carries the build's Ray mark (op2motion.library.reaper)."""
    found = []
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            try:
                with open(f"/proc/{pid}/environ", "rb") as f:
                    if mark.encode() in f.read().split(b"\0"):
                        found.append(int(pid))
            except OSError:
                pass
    return found


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "kill -9"])
def test_a_ray_build_ends_cleanly_and_leaves_no_ray_process(tmp_path, sig):
    pytest.importorskip("ray")
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    proc = _start(tmp_path, "library", "build", *GRID, "--out", "lib", "--executor", "ray", "--workers", "2", env=env)
    mark = f"OP2MOTION_RAY_OWNER={proc.pid}"
    deadline = time.monotonic() + 60
    while not [p for p in _ray_processes(mark) if p != proc.pid] and time.monotonic() < deadline:
        time.sleep(0.5)
    assert [p for p in _ray_processes(mark) if p != proc.pid], "Ray started"
    code, err, _ = _terminated(proc, 3.0, sig)
    if sig == signal.SIGTERM:
        assert code == 130 and "resume" in _last_line(err), err
    deadline = time.monotonic() + 15
    while _ray_processes(mark) and time.monotonic() < deadline:
        time.sleep(0.5)
    assert _ray_processes(mark) == []


def test_a_motion_name_that_would_not_read_back_is_refused_before_writing(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("two\nlines", "tab\there", "x" * 101, ""):
        code, _, err = run_cli(capsys, "motion", "plan", INIT, STAND, "--durations", "1", "--name", name, "--out",
                               "m.json")
        assert code == 2 and "--name" in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_inside_a_compiled_modules_import_is_an_interrupt(monkeypatch, capsys):
    """A SIGTERM landing while a compiled module initialises surfaces as ``ImportError: initialization failed`` with
    the interrupt as its context: the command still ends as interrupted (130), not as an internal error."""
    from op2motion import cli
    from op2motion.commands import physics

    def failing_import(args, spec):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise ImportError("initialization failed")

    monkeypatch.setattr(physics, "cmd_urdf", failing_import)
    assert cli.main(["urdf"]) == 130
    assert capsys.readouterr().err.strip() == "op2motion: interrupted"
    assert not cli._interrupted_within(ImportError("no module named x"))


@pytest.mark.slow
def test_the_ray_watchdog_ends_its_drivers_session_and_nothing_else():
    """The watchdog a Ray build starts (op2motion.library.reaper), told its driver ended: it kills what it saw below
    the driver, the processes marked with the driver, those naming the driver's Ray session folder, and everything
    below them, and leaves another driver's session and other Ray-looking processes of the same process group alone
    (a ``kill -9`` of one of two builds started from one shell killed the other's GCS server, whose build then hung
    60 s)."""
    from op2motion.library.reaper import _WATCHDOG, MARK

    sleeper = "import subprocess, sys, time; subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)']);" \
              " time.sleep(60)"

    def start(*argv, env=None):
        return subprocess.Popen([sys.executable, "-c", sleeper, *argv], env=env)

    driver = start()
    ours = f"/tmp/ray/session_2026-11-27_00-04-40_496552_{driver.pid}/logs"
    theirs = f"/tmp/ray/session_2026-11-27_00-04-40_496552_{driver.pid}7/logs"
    doomed = {"session": start(f"--log_dir={ours}"), "marked": start(env={**os.environ, MARK: str(driver.pid)})}
    spared = {"other session": start(f"--log_dir={theirs}"), "ray-named": start("ray::DashboardAgent")}
    everyone = (driver, *doomed.values(), *spared.values())
    try:
        wait_for(lambda: all(len(_children(p.pid)) == 1 for p in everyone), "the children")
        below = {name: _children(p.pid)[0] for name, p in {"driver": driver, **doomed, **spared}.items()}
        watchdog = subprocess.Popen([sys.executable, "-c", _WATCHDOG, f"{MARK}={driver.pid}", str(driver.pid)],
                                    stdin=subprocess.PIPE)
        time.sleep(WATCHDOG_LOOK_S)                 # it has noted the driver's child
        driver.kill()
        driver.wait()
        watchdog.stdin.close()                      # the driver's end
        assert watchdog.wait(timeout=30) == 0
        for name, proc in doomed.items():
            assert proc.wait(timeout=10) == -signal.SIGKILL, name
        for name in ("driver", *doomed):
            wait_for(lambda: not _alive(below[name]), f"the child of the {name} process")
        for name, proc in spared.items():
            assert proc.poll() is None and _alive(below[name]), name
    finally:
        for proc in everyone:
            for pid in [proc.pid, *_children(proc.pid)]:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)
            proc.wait()


WATCHDOG_LOOK_S = 1.5         # the watchdog notes the driver's descendants twice a second: this is three looks [s]


def _children(pid: int) -> list[int]:
    """Live children of ``pid`` (Linux /proc)."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                fields = open(f"/proc/{entry}/stat", encoding="utf-8").read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                found.append(int(entry))
    return found


def _alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat", encoding="utf-8").read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
