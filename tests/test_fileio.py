"""Output files: checked before work, written together, never mixed between two runs, never half-written."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from op2motion.errors import OutputError
from op2motion.fileio import OutputSet, check_output_path, new_file_beside, remove_temps, write_atomic

ROUNDS = 30
SLOW_RENAME_S = 0.002


def test_two_writers_of_the_same_outputs_never_mix_their_files(tmp_path, monkeypatch):
    paths = {"pose": tmp_path / "p.json", "figure": tmp_path / "p.png", "curve": tmp_path / "p_cost.png"}
    mixed = []
    replace = os.replace

    def slow_replace(a, b):     # a slow file system: renames take time, so interleaved renames would show
        replace(a, b)
        time.sleep(SLOW_RENAME_S)

    monkeypatch.setattr("op2motion.fileio.os.replace", slow_replace)

    def writer(tag: bytes) -> None:
        for _ in range(ROUNDS):
            outputs = OutputSet(paths)
            for key in paths:
                outputs.put(key, tag * 200_000)
            outputs.commit()

    done = threading.Event()

    def reader() -> None:
        import fcntl

        while not done.is_set():
            fd = os.open(tmp_path, os.O_RDONLY)
            fcntl.flock(fd, fcntl.LOCK_SH)          # a reader that respects the lock sees whole sets only
            try:
                tags = {p.read_bytes()[:1] for p in paths.values() if p.exists()}
            finally:
                os.close(fd)
            if len(tags) > 1:
                mixed.append(tags)

    writers = [threading.Thread(target=writer, args=(t,)) for t in (b"a", b"b")]
    watcher = threading.Thread(target=reader)
    for t in [*writers, watcher]:
        t.start()
    for t in writers:
        t.join()
    done.set()
    watcher.join()
    assert mixed == []
    assert len({p.read_bytes()[:1] for p in paths.values()}) == 1
    assert sorted(os.listdir(tmp_path)) == ["p.json", "p.png", "p_cost.png"]   # no temp file left


def test_outputs_are_checked_before_any_work(tmp_path):
    (tmp_path / "folder").mkdir()
    (tmp_path / "file").write_text("x", encoding="utf-8")
    for bad, needle in ((tmp_path / "folder", "directory"), ("", "empty"), (tmp_path / "file" / "x.png", "not a dir")):
        with pytest.raises(OutputError, match=needle):
            check_output_path(bad, "output")
    with pytest.raises(OutputError, match="the same file"):
        OutputSet({"a": tmp_path / "x.json", "b": tmp_path / "." / "x.json"})


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_folder_is_refused_before_work(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="not writable"):
            check_output_path(folder / "x.png", "output")
    finally:
        folder.chmod(0o700)


def test_a_failed_commit_leaves_nothing(tmp_path):
    outputs = OutputSet({"ok": tmp_path / "a.json", "bad": "/proc/op2motion-test/b.json"})
    outputs.put("ok", "{}")
    outputs.put("bad", "{}")
    with pytest.raises(OutputError, match="cannot write"):
        outputs.commit()
    assert os.listdir(tmp_path) == []


def test_an_interrupt_the_moment_a_temp_file_exists_leaves_no_temp_file(tmp_path, monkeypatch):
    """SIGTERM's handler runs as soon as ``os.open`` returns: a build terminated then left ``.index.csv.*.tmp``
    behind (4 runs in 25 on a loaded machine), because the temp file was recorded only after it was created."""
    real_open = os.open

    def open_then_interrupted(path, flags, mode=0o777):
        real_open(path, flags, mode)        # the file exists; the interrupt lands before the caller sees its fd
        raise KeyboardInterrupt

    (tmp_path / "index.csv").write_text("old\n")
    monkeypatch.setattr("op2motion.fileio.os.open", open_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(tmp_path / "index.csv", "new\n")
    monkeypatch.undo()
    assert remove_temps() == 1          # what the CLI does on every interrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["index.csv"]
    assert (tmp_path / "index.csv").read_text() == "old\n"


def test_ctrl_c_between_a_sets_renames_waits_for_the_last_one(tmp_path, monkeypatch):
    """A pose, its figure and its cost curve are renamed into place one after the other: Ctrl-C between two renames
    left a new pose beside the old figures. It now waits for the last rename (and interrupts just after)."""
    paths = {name: tmp_path / name for name in ("p.json", "p.png", "p_cost.png")}
    for path in paths.values():
        path.write_text("old")
    replace = os.replace

    def replace_then_ctrl_c(a, b):
        replace(a, b)
        os.kill(os.getpid(), signal.SIGINT)       # as a Ctrl-C lands, after the first rename

    monkeypatch.setattr("op2motion.fileio.os.replace", replace_then_ctrl_c)
    outputs = OutputSet(paths)
    for key in paths:
        outputs.put(key, "new")
    with pytest.raises(KeyboardInterrupt):
        outputs.commit()
    assert {path.read_text() for path in paths.values()} == {"new"}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(paths)


def test_a_held_signal_reaches_the_handler_there_before_once_the_moment_ends():
    from op2motion.processes.interrupts import signals_held

    came: list[int] = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: came.append(signum))
    try:
        with signals_held():
            os.kill(os.getpid(), signal.SIGTERM)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.01)
            assert came == []                       # held
        assert came == [signal.SIGTERM]             # delivered once, to the handler there before
        with signals_held(ignore_ctrl_c=True):
            assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_a_file_built_beside_its_place_arrives_whole_or_not_at_all(tmp_path, monkeypatch):
    import errno

    target = tmp_path / "new" / "s.db"
    with new_file_beside(target) as tmp:
        assert tmp.parent == target.parent and tmp.exists() and not target.exists()
        tmp.write_bytes(b"built")
    assert target.read_bytes() == b"built" and [p.name for p in target.parent.iterdir()] == ["s.db"]
    with pytest.raises(OutputError, match="another run made it meanwhile"):      # never replaced
        with new_file_beside(target) as tmp:
            tmp.write_bytes(b"second")
    assert target.read_bytes() == b"built" and [p.name for p in target.parent.iterdir()] == ["s.db"]
    with pytest.raises(RuntimeError):                                           # a failed build leaves nothing
        with new_file_beside(tmp_path / "other.db") as tmp:
            raise RuntimeError("build failed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new"]

    def no_links(src, dst):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "link", no_links)                                   # a file system without hard links
    with new_file_beside(tmp_path / "renamed.db") as tmp:
        tmp.write_bytes(b"moved")
    assert (tmp_path / "renamed.db").read_bytes() == b"moved"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new", "renamed.db"]
