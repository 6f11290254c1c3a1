"""Kernels compiled by one process at a time (op2motion.processes.compiled): processes that start together on a
fresh install compile a kernel once between them; the others load what the first cached."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest
from helpers import ROOT

from op2motion.processes.compiled import lock_path

PROCESSES = 2
WAIT_HERE_S = 0.3          # the wait for a held lock, shortened for the test [s]

KERNEL = textwrap.dedent('''
    import json, sys, time
    import numpy as np
    from numba import njit
    from op2motion.processes.compiled import CompileOnce

    @njit(cache=True)
    def _twice(x):                          # a sort: compiles for about a second, time enough to overlap
        return 2.0 * np.sort(x).sum()

    twice = CompileOnce(_twice)
    sys.stdin.read()                        # all started: go together
    value = twice(np.arange(4.0))
    print(json.dumps({"value": value, "hits": sum(_twice.stats.cache_hits.values()),
                      "misses": sum(_twice.stats.cache_misses.values())}))
''')


@pytest.mark.slow
def test_processes_started_together_compile_a_kernel_once(tmp_path):
    (tmp_path / "tiny_kernel.py").write_text(KERNEL, encoding="utf-8")
    procs = [subprocess.Popen([sys.executable, "-c", "import tiny_kernel"], cwd=tmp_path, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env={"PYTHONPATH": f"{tmp_path}:{ROOT}", "PATH": "/usr/bin:/bin",
                                   "NUMBA_CACHE_DIR": str(tmp_path / "cache")})
             for _ in range(PROCESSES)]
    for p in procs:                             # all imported numba and wait at stdin: let them go at once
        p.stdin.close()
    outs = [(p.stdout.read(), p.stderr.read(), p.wait(timeout=120))[:2] for p in procs]
    assert [p.returncode for p in procs] == [0] * PROCESSES, [err for _, err in outs]
    found = [json.loads(out) for out, _ in outs]
    assert all(f["value"] == 12.0 for f in found)
    assert sorted(f["misses"] for f in found) == [0] * (PROCESSES - 1) + [1]     # one compiled ...
    assert sum(f["hits"] for f in found) == PROCESSES - 1                        # ... the others loaded its cache


def test_the_lock_names_the_kernel_and_its_copy():
    from numba import njit

    def a(x):
        return x

    def b(x):
        return x

    assert lock_path(njit(a)) != lock_path(njit(b))
    assert lock_path(njit(a)) == lock_path(a) and lock_path(a).name.startswith("op2motion-compile-")


def test_a_lock_held_elsewhere_delays_the_first_call_at_most_the_wait(tmp_path, monkeypatch):
    """A process stopped mid-compile (Ctrl-Z) keeps its lock: the next process waits :data:`WAIT_S`, then compiles
    by itself; a symbolic link planted as the lock file is not followed."""
    import fcntl
    import os
    import time

    import numpy as np
    from numba import njit

    import op2motion.processes.compiled as compiled

    def _sum(x):
        return x.sum()

    kernel = njit(_sum)
    path = lock_path(kernel)
    held = os.open(path, os.O_RDWR | os.O_CREAT)
    fcntl.flock(held, fcntl.LOCK_EX)                      # as another process mid-compile would
    monkeypatch.setattr(compiled, "WAIT_S", WAIT_HERE_S)
    try:
        t0 = time.monotonic()
        assert compiled.CompileOnce(kernel)(np.arange(3.0)) == 3.0
        assert WAIT_HERE_S <= time.monotonic() - t0
    finally:
        os.close(held)
        path.unlink(missing_ok=True)
    target = tmp_path / "not_ours"
    target.write_text("kept", encoding="utf-8")
    path.symlink_to(target)
    try:
        assert compiled.CompileOnce(kernel)(np.arange(4.0)) == 6.0
        assert target.read_text(encoding="utf-8") == "kept" and path.is_symlink()
    finally:
        path.unlink()
