"""Helpers shared by the tests: paths of the committed data and one way to run the CLI in-process."""

from __future__ import annotations

import ast
import re
import time
from pathlib import Path

import numpy as np

from op2motion.cli import main

ROOT = Path(__file__).resolve().parents[1]
POSES = ROOT / "poses"
DATA = Path(__file__).parent / "data"
STOCK = DATA / "motion_4096.bin"
SEED = 20261121


def compile_package(root: Path) -> None:
    """Write the bytecode of ``root``/op2motion (``__pycache__``, git-ignored) so that subprocesses import it without
    compiling it each time."""
    import compileall

    compileall.compile_dir(str(root / "op2motion"), quiet=2)
    share_numba_cache(root)


def share_numba_cache(root: Path) -> None:
    """Let a copy of the package at ``root`` reuse this tree's compiled kernels: numba keys its on-disk cache by the
    source file's timestamp and size, so copy the cache files and the sources' timestamps (when there are any)."""
    import os
    import shutil

    if root.resolve() == ROOT:
        return
    for cache in (ROOT / "op2motion").rglob("__pycache__/*.nb[ic]"):
        rel = cache.relative_to(ROOT)
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(cache, root / rel)
        source = rel.parent.parent / (cache.name.split(".")[0] + ".py")
        if (root / source).is_file():
            stat = (ROOT / source).stat()
            os.utime(root / source, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def source_tree(path: Path) -> ast.Module:
    """The parsed source of one file of the repository. Not kept: callers keep what they read from it (the package's
    220 syntax trees, held for the rest of a test process, made each of its full garbage collections 0.14 s
    slower; built while collecting, they cost every test process 1.4 s)."""
    return ast.parse(path.read_text(encoding="utf-8"))


def same_verdict(early, full) -> None:
    """Two reports of one physics run, ``early`` ended once its verdict was known and ``full`` played to its end:
    the same verdict, and every failure of the full run up to where the early one stopped, in the same order (the
    causes of a fall too: saturation, joint limits, collisions), at the same times."""
    import pytest

    from op2motion.physics.stopping import FULL

    assert full.ended == FULL and full.seconds == pytest.approx(full.planned_seconds)
    assert early.stable == full.stable, (early.reasons, full.reasons)
    until = [(f.reason, f.time_s) for f in full.failures if f.time_s <= early.seconds + 1e-9]
    assert [(f.reason, f.time_s) for f in early.failures] == until, (early.failures, full.failures)


def pose_path(name: str) -> str:
    """Path of a committed pose file."""
    return str(POSES / f"{name}.json")


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """Run ``op2motion ARGV`` in-process; returns (exit code, stdout, stderr)."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


PROGRESS_LINE = re.compile(r"^op2motion: [\w ]+: [\d.]+(/[\d.]+)? \S+ \(\d+ s\)(; .*)?$")


def without_progress(err: str) -> str:
    """stderr less the plain progress lines a long run prints in a log (``op2motion: PSO: 40/300 it (10 s)``)."""
    return "".join(line for line in err.splitlines(keepends=True) if not PROGRESS_LINE.match(line.rstrip("\n")))


def page_last_step_ticks(data: bytes, page: int) -> np.ndarray:
    """Goal ticks of joints 1..20 in the last used step of a page (layout: ROBOTIS framework Action.h)."""
    base = page * 512
    steps = data[base + 20]  # stepnum
    step = base + 64 + 64 * (steps - 1)
    words = np.frombuffer(data[step:step + 62], dtype="<u2")
    return words[1:21].astype(int)


def pybullet_pair_distances(client, robot, spec, servo_rows: np.ndarray, pairs, reach_m: float):
    """PyBullet's exact closest distances [m] between link pairs ``pairs`` (a list of (row, (link a, link b)))
    with the robot set to ``servo_rows`` (K, 20) [rad]; ``2 * reach_m`` where nothing is that close. A list of
    (row, link a, link b, distance)."""
    link_index = {client.getJointInfo(robot, j)[12].decode(): j for j in range(client.getNumJoints(robot))}
    link_index[client.getBodyInfo(robot)[0].decode()] = -1
    joint_index = {client.getJointInfo(robot, j)[1].decode(): j for j in range(client.getNumJoints(robot))}
    out, current = [], None
    for k, (a, b) in pairs:
        if k != current:
            for name, q in zip(spec.joint_names, servo_rows[k]):
                client.resetJointState(robot, joint_index[name], q)
            client.performCollisionDetection()
            current = k
        points = client.getClosestPoints(robot, robot, 2 * reach_m, link_index[a], link_index[b])
        out.append((k, a, b, min((c[8] for c in points), default=2 * reach_m)))
    return out


def wait_for(condition, what: str, timeout_s: float = 60.0, poll_s: float = 0.02) -> None:
    """Poll ``condition()`` until it is true; fail naming ``what`` after ``timeout_s`` [s]."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(poll_s)
    raise AssertionError(f"timed out waiting for {what}")
