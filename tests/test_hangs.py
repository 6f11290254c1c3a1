"""Nothing hangs: a named pipe, a socket or a device given as an input file is refused before anything is read (a
FIFO without a writer would block the command forever); a TCP port that is not Ray is refused within 15 s, with
nothing written; a studio host that does not resolve, is not this machine's, or is empty is refused at once and told
from a port in use. The cases run the real CLI in a subprocess with a hard timeout (those of one kind one after another
in one process: a command that blocked would stop the process, and the timeout names the case it was on)."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time

import pytest
from helpers import pose_path

STAND = pose_path("standing")
FIFO_BOUND_S = 20.0           # a command given a FIFO ends within this (it used to block forever) [s]
RAY_BOUND_S = 15.0            # a port that is not Ray: refused within this [s] (the bound)
HOST_BOUND_S = 12.0           # a studio host that does not resolve: refused within this [s] (5 s lookup cap)


def _op2motion(cwd, *argv, timeout=60.0, env=None):
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "op2motion", *map(str, argv)], cwd=cwd, capture_output=True,
                          text=True, timeout=timeout, env=env)
    return done, time.monotonic() - t0


#: A Python process running ``op2motion.cli.main`` on each argv of a JSON list, one after another, printing one JSON
#: line per case (exit code, stderr, seconds) as it ends it, so that a case that blocks is the one after the last line.
_BATCH = """
import contextlib, io, json, sys, time
from op2motion.cli import main
for argv in json.loads(sys.argv[1]):
    err, t0 = io.StringIO(), time.monotonic()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    print(json.dumps([code, err.getvalue(), time.monotonic() - t0]), flush=True)
"""


def _op2motion_each(cwd, argvs: list[list[str]], timeout: float) -> list[tuple[int, str, float]]:
    """Exit code, stderr and seconds of ``op2motion ARGV`` for each of ``argvs``, run in one subprocess that must end
    within ``timeout`` [s] (if not: the case it was on is named)."""
    argvs = [[str(a) for a in argv] for argv in argvs]
    try:
        done = subprocess.run([sys.executable, "-c", _BATCH, json.dumps(argvs)], cwd=cwd, capture_output=True,
                              text=True, timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        ended = len((exc.stdout or b"").splitlines())
        raise AssertionError(f"op2motion {' '.join(argvs[ended])} did not end within {timeout} s") from None
    assert done.returncode == 0, done.stderr
    return [tuple(json.loads(line)) for line in done.stdout.splitlines()]


def _one_line(err: str) -> str:
    lines = [line for line in err.strip().splitlines() if line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture
def specials(tmp_path):
    """A FIFO (nobody writes to it), a bound Unix socket and a device, each named like an input file."""
    fifo = tmp_path / "pose.json"
    os.mkfifo(fifo)
    sock_path = tmp_path / "sock.json"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(sock_path))
    try:
        yield {"named pipe": fifo, "socket": sock_path, "character device": "/dev/null"}
    finally:
        sock.close()


#: Commands given a special file where they read one (``{f}``).
READERS = [
    ["fk", "--pose", "{f}"], ["validate", "{f}"], ["plot", "{f}", "-o", "p.png"],
    ["export", "--format", "webots", "{f}", "-o", "x.motion"], ["motion", "plan", STAND, "{f}", "--durations", "1"],
    ["motion", "play", "{f}", "--page", "4"], ["walk", "--preset", "{f}"], ["--spec", "{f}", "urdf"],
    ["convert", "--servo-deg", "{f}", "--support", "left"], ["studio", "{f}", "--port", "0"],
    ["import-action", "{f}"], ["motion", "line", "{f}", "--hand", "left", "--by", "0.01", "0", "0", "--duration", "1"],
]


def test_special_files_are_refused_before_reading(tmp_path, specials):
    cases = [(argv, kind, [a.replace("{f}", str(path)) for a in argv]) for argv in READERS
             for kind, path in specials.items()]
    results = _op2motion_each(tmp_path, [run for _, _, run in cases], timeout=FIFO_BOUND_S * len(cases))
    for (argv, kind, run), (code, err, took) in zip(cases, results, strict=True):
        line = _one_line(err)
        assert code == 2 and took < FIFO_BOUND_S, (run, kind, line)
        if kind != "character device" or "preset" not in argv:      # a preset's name is its flag's business
            assert kind in line or "--preset" in line, (run, kind, line)
        assert not (tmp_path / "p.png").exists() and not (tmp_path / "x.motion").exists(), run


def _silent_server() -> tuple[socket.socket, int]:
    """A TCP server on loopback that accepts and never says anything (not Ray)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    keep: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                keep.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    return server, server.getsockname()[1]


def _http_server() -> tuple[socket.socket, int]:
    """A TCP server on loopback that answers everything with an HTTP/1.1 error, as a web server would."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()

    def serve() -> None:
        while True:
            try:
                conn = server.accept()[0]
            except OSError:
                return
            with conn:
                conn.recv(1024)
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")

    threading.Thread(target=serve, daemon=True).start()
    return server, server.getsockname()[1]


@pytest.mark.slow
@pytest.mark.parametrize("make", [_silent_server, _http_server], ids=["silent port", "web server"])
def test_a_port_that_is_not_ray_is_refused_in_time_and_nothing_is_written(tmp_path, make):
    pytest.importorskip("ray")
    server, port = make()
    try:
        done, took = _op2motion(tmp_path, "library", "build", "--hands", "left", "--supports", "left", "--x", "0.08",
                                "0.12", "2", "--y", "0.03", "0.03", "1", "--z", "0.07", "0.07", "1", "--out", "lib",
                                "--executor", "ray", "--address", f"127.0.0.1:{port}", timeout=60)
    finally:
        server.close()
    line = _one_line(done.stderr)
    assert done.returncode == 2 and took < RAY_BOUND_S and "--address" in line and "Ray" in line, (took, line)
    assert list(tmp_path.iterdir()) == []                               # no folder, no index


#: Studio hosts refused before anything listens, each with the flag it is told against.
HOSTS = [
    ("no-such-host.invalid", "--host"),     # does not resolve (RFC 6761: never does)
    ("192.0.2.1", "--host"),                # resolves, but no interface of this machine has it (TEST-NET-1)
    ("", "--host"),                         # empty: would listen everywhere
    (" 127.0.0.1", "--host"),
]


def test_studio_hosts_are_refused_at_once_and_told_from_ports(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        cases = [(["studio", STAND, "--host", host, "--port", "0"], flag) for host, flag in HOSTS]
        cases.append((["studio", STAND, "--port", str(busy.getsockname()[1])], "--port"))   # a port in use: the port
        results = _op2motion_each(tmp_path, [argv for argv, _ in cases], timeout=HOST_BOUND_S * len(cases))
    for (argv, flag), (code, err, took) in zip(cases, results, strict=True):
        line = _one_line(err)
        assert code == 2 and took < HOST_BOUND_S and line.startswith(f"op2motion: error: {flag}:"), (argv, line)
        assert flag == "--port" or "in use" not in line, (argv, line)


#: Commands given a special file where they write one (``{f}``), and the suffix the output must have.
WRITERS = [(["urdf", "-o", "{f}"], ".urdf"), (["plot", STAND, "-o", "{f}"], ".png"),
           (["export", "--format", "webots", STAND, "-o", "{f}"], ".motion")]


def test_special_files_are_refused_as_outputs(tmp_path):
    """Outputs are written by renaming a temp file over them: a device (/dev/null), a FIFO or a socket would be
    replaced, so each is refused."""
    cases, socks = [], []
    for argv, suffix in WRITERS:
        fifo, sock_path = tmp_path / f"fifo{suffix}", tmp_path / f"sock{suffix}"
        os.mkfifo(fifo)
        socks.append(socket.socket(socket.AF_UNIX))
        socks[-1].bind(str(sock_path))
        for kind, path in (("named pipe", fifo), ("socket", sock_path), ("character device", "/dev/null")):
            if kind != "character device" or suffix != ".png":      # (a PNG output must end in .png)
                cases.append((kind, [a.replace("{f}", str(path)) for a in argv]))
    try:
        results = _op2motion_each(tmp_path, [argv for _, argv in cases], timeout=FIFO_BOUND_S * len(cases))
    finally:
        for sock in socks:
            sock.close()
    for (kind, argv), (code, err, _) in zip(cases, results, strict=True):
        line = _one_line(err)
        assert code == 2 and kind in line, (argv, kind, line)
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")
    assert all((tmp_path / f"fifo{suffix}").is_fifo() for _, suffix in WRITERS)
