"""``op2motion tune`` checks everything before it writes, and never converts a file that is not its own: a Ray address
that is closed or not Ray, an empty file, another program's SQLite or Optuna file, a FIFO or a device given as
``--study``, and a study made for another spec, task or parameter set are refused (exit 2, one line) with the
folder left exactly as it was (names, bytes, modification times). No trial runs here: every refusal comes first."""

from __future__ import annotations

import hashlib
import os
import socket
import sqlite3
import stat
import sys
import threading
from pathlib import Path

import pytest
from helpers import ROOT, run_cli

from op2motion.errors import InputError
from op2motion.gait import preset_path, read_preset
from op2motion.tune.space import Param, ParameterSpace
from op2motion.tune.spaces import walk_space
from op2motion.tune.study import MARK, check_study, open_study, rows, run_study
from op2motion.tune.trial import Task, identity
from op2motion.tune.walkers import PresetWalker

NAME = "tune-walk-forward"          # the study name `tune walk` uses by default
SEED = 0
TOY = ParameterSpace((Param("step_s", 0.2, 0.5, "s"), Param("step_length_m", 0.02, 0.08, "m")))


def snapshot(folder: Path) -> dict[str, tuple[int, int, str]]:
    """Every entry of ``folder``: (mode, modification time [ns], SHA-256 of a regular file's bytes)."""
    out = {}
    for entry in sorted(folder.iterdir()):
        info = entry.lstat()
        digest = hashlib.sha256(entry.read_bytes()).hexdigest() if stat.S_ISREG(info.st_mode) else ""
        out[entry.name] = (info.st_mode, info.st_mtime_ns, digest)
    return out


def shipped_task(preset: str = "forward", spec: str | None = None) -> Task:
    """The task `tune walk` makes (forward, from a shipped preset, on ``spec``)."""
    return Task(PresetWalker(read_preset(preset_path(preset))), "forward", spec)


def made_study(path: Path) -> None:
    """An op2motion study at ``path`` as `tune walk` would make it (the shipped spec, the forward preset)."""
    close(open_study(path, NAME, walk_space("forward"), SEED, identity(shipped_task())))


def close(study) -> None:
    """Close a study's connections now (the last one folds its log into the file), not when the tests end."""
    storage = study._storage                                    # Optuna keeps its RDB storage behind a cache
    getattr(storage, "_backend", storage).engine.dispose()


def refused(capsys, folder: Path, *argv: str) -> str:
    """Run ``tune walk --out FOLDER/fast.toml ARGV``; assert exit 2, one line, the folder untouched; the line."""
    before = snapshot(folder)
    code, out, err = run_cli(capsys, "tune", "walk", "--out", str(folder / "fast.toml"), *argv)
    assert (code, out, err.count("\n")) == (2, "", 1), err
    assert snapshot(folder) == before
    return err


@pytest.fixture
def closed_port():
    """A loopback port bound by nobody who listens: a connection is refused."""
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        yield holder.getsockname()[1]


@pytest.fixture
def web_port():
    """A loopback port that answers like a web server, not a Ray head."""
    server = socket.create_server(("127.0.0.1", 0))

    def answer() -> None:
        with server:
            conn, _ = server.accept()
            with conn:
                conn.recv(64)
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    yield server.getsockname()[1]
    thread.join(timeout=1.0)


@pytest.mark.parametrize("ray_installed", [True, False])
def test_a_closed_ray_address_is_refused_before_the_study_file_is_made(tmp_path, capsys, monkeypatch, closed_port,
                                                                      ray_installed):
    if not ray_installed:
        monkeypatch.setitem(sys.modules, "ray", None)        # `import ray` fails: the address is checked first
    err = refused(capsys, tmp_path, "--executor", "ray", "--address", f"127.0.0.1:{closed_port}")
    assert "--address: expected a running Ray cluster" in err
    assert list(tmp_path.iterdir()) == []


def test_a_server_that_is_not_ray_is_refused_before_the_study_file_is_made(tmp_path, capsys, web_port):
    err = refused(capsys, tmp_path, "--executor", "ray", "--address", f"127.0.0.1:{web_port}")
    assert "does not answer as Ray does" in err
    assert list(tmp_path.iterdir()) == []


def test_ray_missing_is_refused_before_anything_is_written(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    assert "expected Ray for --executor ray" in refused(capsys, tmp_path, "--executor", "ray")
    assert list(tmp_path.iterdir()) == []


def _foreign_sqlite(path: Path, wal: bool) -> None:
    connection = sqlite3.connect(path)
    if wal:
        connection.execute("PRAGMA journal_mode=WAL")
    connection.execute("CREATE TABLE notes (text TEXT)")
    connection.execute("INSERT INTO notes VALUES ('mine')")
    connection.commit()
    connection.close()


def _plain_optuna(path: Path) -> None:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    optuna.create_study(storage=f"sqlite:///{path}", study_name=NAME).set_user_attr("owner", "someone else")


FOREIGN = {
    "empty": (lambda p: p.write_bytes(b""), "an empty file"),
    "text": (lambda p: p.write_text("name = 'not a database'\n", encoding="utf-8"), "not SQLite"),
    "sqlite": (lambda p: _foreign_sqlite(p, wal=False), "without Optuna's tables"),
    "sqlite-wal": (lambda p: _foreign_sqlite(p, wal=True), "without Optuna's tables"),
    "optuna": (_plain_optuna, "op2motion did not make"),
}


@pytest.mark.parametrize("kind", FOREIGN)
def test_a_file_that_is_not_an_op2motion_study_is_refused_byte_for_byte_untouched(tmp_path, capsys, kind):
    make, words = FOREIGN[kind]
    make(tmp_path / "theirs.db")
    os.utime(tmp_path / "theirs.db", ns=(1_000_000_000, 1_000_000_000))   # an mtime a write would change
    err = refused(capsys, tmp_path, "--study", str(tmp_path / "theirs.db"))
    assert "--study: expected an op2motion study file" in err and words in err


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_fifo_or_a_device_as_the_study_is_named_for_what_it_is(tmp_path, capsys, kind):
    path = tmp_path / "pipe" if kind == "fifo" else Path(os.devnull)
    if kind == "fifo":
        os.mkfifo(path)
    err = refused(capsys, tmp_path, "--study", str(path))
    what = "named pipe (FIFO)" if kind == "fifo" else "character device"
    assert f"expected a regular file to write, got a {what}" in err and "folder" not in err
    assert stat.S_ISFIFO(path.stat().st_mode) if kind == "fifo" else stat.S_ISCHR(path.stat().st_mode)


def test_a_study_file_that_is_also_an_output_is_refused(tmp_path, capsys):
    err = refused(capsys, tmp_path, "--study", str(tmp_path / "fast.json"))
    assert "--study: expected a study file other than an output (the JSON beside --out)" in err
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def other_spec(tmp_path):
    """The shipped spec with one mass changed: another body."""
    text = (ROOT / "specs" / "op2.toml").read_text(encoding="utf-8")
    first = text.index("mass_kg = ")
    end = text.index("\n", first)
    path = tmp_path / "my_op2.toml"
    path.write_text(text[:first] + "mass_kg = 1.5" + text[end:], encoding="utf-8")
    return path


def test_a_study_is_not_resumed_for_another_spec_naming_both(tmp_path, capsys, other_spec):
    study = tmp_path / "runs" / "s.db"
    made_study(study)
    err = refused(capsys, study.parent, "--spec", str(other_spec), "--study", str(study))
    shipped = identity(shipped_task())["spec"]["sha256"]
    mine = identity(shipped_task(spec=str(other_spec)))["spec"]["sha256"]
    assert "was made for spec the shipped specs/op2.toml" in err and shipped[:12] in err
    assert f"this run's spec is {other_spec}" in err and mine[:12] in err and shipped != mine


@pytest.mark.parametrize("argv, words", [
    (("--preset", "walking/fast.toml"), ("base preset forward", "base is preset fast")),
    (("--only", "step_s", "step_length_m"), ("searched double_support_ratio", "this run searches step_s")),
])
def test_a_study_is_not_resumed_for_another_base_or_parameter_set(tmp_path, capsys, argv, words):
    study = tmp_path / "runs" / "s.db"
    made_study(study)
    err = refused(capsys, study.parent, *argv, "--study", str(study))
    assert all(w in err for w in words), err


def test_a_study_is_not_resumed_by_another_task(tmp_path, capsys):
    study = tmp_path / "runs" / "s.db"
    made_study(study)
    before = snapshot(study.parent)
    code, _, err = run_cli(capsys, "tune", "stock", "--out", str(tmp_path / "config.ini"), "--study", str(study),
                           "--study-name", NAME)
    assert code == 2 and "was made for task walk forward; this run's task is stock forward" in err
    assert snapshot(study.parent) == before and not (tmp_path / "config.ini").exists()


def test_a_new_study_file_is_made_whole_with_its_mark_and_resumed_only_for_the_same(tmp_path):
    path = tmp_path / "new" / "s.db"
    about = identity(shipped_task())
    study = open_study(path, NAME, TOY, SEED, about)
    assert study.user_attrs[MARK]["spec"] == about["spec"] and study.user_attrs[MARK]["params"] == list(TOY.names)
    assert {p.name for p in path.parent.iterdir()} <= {"s.db", "s.db-wal", "s.db-shm"}   # no temp file left
    # the mark is in the file itself, read without its log: the read-only check sees it
    fast = identity(shipped_task("fast"))
    with pytest.raises(InputError, match="was made for base"):
        check_study(path, NAME, TOY, fast)
    assert check_study(path, NAME, TOY.narrowed([["step_s", "0.25", "0.4"]]), about)   # narrowed ranges resume
    run_study(study, TOY, lambda point: _outcome(), (), 2, _Here())
    again = open_study(path, NAME, TOY, SEED, about)
    assert len(rows(again)) == 2
    close(study)
    close(again)


def test_an_unmarked_study_with_trials_in_an_op2motion_file_is_refused(tmp_path):
    import optuna

    path = tmp_path / "s.db"
    close(open_study(path, "ours", TOY, SEED))
    theirs = optuna.create_study(storage=f"sqlite:///{path}", study_name="theirs")
    theirs.tell(theirs.ask(), 1.0)
    close(theirs)
    with pytest.raises(InputError, match="carries no op2motion mark"):
        check_study(path, "theirs", TOY)
    assert check_study(path, "another", TOY)                 # a new study in op2motion's file may be made


def test_the_tuning_page_s_spec_example_runs(tmp_path, capsys, monkeypatch, other_spec):
    """docs/tuning.md's `op2motion --spec my_op2.toml fk ...` example, run as written from the repository."""
    import re
    import shlex

    text = (ROOT / "docs" / "tuning.md").read_text(encoding="utf-8")
    line = re.search(r"`op2motion (--spec my_op2\.toml fk[^`]*)`", text)
    assert line is not None
    monkeypatch.chdir(ROOT)
    argv = [str(other_spec) if a == "my_op2.toml" else a for a in shlex.split(line.group(1))]
    code, out, err = run_cli(capsys, *argv)
    assert code == 0 and "centre of mass" in out, err


def _outcome():
    from op2motion.tune.study import TrialOutcome

    return TrialOutcome(0.2, 0.5, True, 1, 1, None, 0.0)


class _Here:
    """Trials run at once, here."""

    workers = 1

    def __init__(self):
        self._done = []

    def submit(self, number, fn, *args):
        self._done.append((number, fn(*args)))

    def finished(self):
        out, self._done = self._done, []
        return out

    @property
    def running(self):
        return len(self._done)
