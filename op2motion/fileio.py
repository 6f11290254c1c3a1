"""Reading input files with clear errors, and atomic file writing.

Reading: a missing file, a directory, an unreadable file or text that is not UTF-8 is bad input, reported in one
line naming the file. Writing: a temp file in the target directory, flushed and synced, then renamed over the
target, so that a failed or killed run leaves either the old file or the new one, never a half-written file.
The temp file is created with mode 0666 and the process umask applied by the kernel (an existing target keeps its
own mode); the umask itself is never changed.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
import threading
from pathlib import Path
from typing import Iterator, Mapping, Type

from op2motion.errors import InputError, Op2MotionError, OutputError
from op2motion.processes.interrupts import signals_held

MAX_INPUT_BYTES = 16 * 2 ** 20    # every file op2motion reads is far smaller (an action file: 128 KiB)


def file_kind(mode: int) -> str:
    """What a file of ``mode`` (``os.stat``'s ``st_mode``) is, in words (for messages)."""
    for test, kind in ((stat.S_ISREG, "regular file"), (stat.S_ISDIR, "directory"),
                       (stat.S_ISFIFO, "named pipe (FIFO)"), (stat.S_ISSOCK, "socket"),
                       (stat.S_ISCHR, "character device"), (stat.S_ISBLK, "block device")):
        if test(mode):
            return kind
    return "special file"


def read_bytes(path: str | Path, what: str, error: Type[Op2MotionError] = InputError) -> bytes:
    """The bytes of ``path``; errors (``error`` class) say what file was expected and why it cannot be read.

    The file is opened without blocking and must be a regular file: a named pipe, a device (``/dev/zero``,
    ``/dev/ttyUSB0``), a socket or a directory is refused before anything is read, so no input can make a command
    wait for a writer that never comes. At most :data:`MAX_INPUT_BYTES` are read: a larger file is refused."""
    p = Path(path)
    try:
        mode = os.stat(p).st_mode                  # a socket cannot even be opened: tell what it is first
        if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
            raise error(f"expected a {what} (a regular file), got a {file_kind(mode)}", str(p))
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise error(f"no such {what}", str(p)) from None
    except IsADirectoryError:
        raise error(f"expected a {what}, got a directory", str(p)) from None
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror or exc}", str(p)) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = file_kind(info.st_mode)
            raise error(f"expected a {what} (a regular file), got a {kind}", str(p))
        if info.st_size > MAX_INPUT_BYTES:
            raise error(f"expected at most {MAX_INPUT_BYTES // 2 ** 20} MiB ({what}), got {info.st_size} bytes",
                        str(p))
        chunks, size = [], 0
        while size <= MAX_INPUT_BYTES:       # a file may grow while it is read (or claim size 0, as /proc files do)
            chunk = os.read(fd, min(2 ** 20, MAX_INPUT_BYTES + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror or exc}", str(p)) from None
    finally:
        os.close(fd)
    if size > MAX_INPUT_BYTES:
        raise error(f"expected at most {MAX_INPUT_BYTES // 2 ** 20} MiB ({what}), got more", str(p))
    return b"".join(chunks)


def read_text(path: str | Path, what: str, error: Type[Op2MotionError] = InputError) -> str:
    """The UTF-8 text of ``path`` (see :func:`read_bytes`); bytes that are not UTF-8 are bad input."""
    data = read_bytes(path, what, error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"expected a UTF-8 text {what}, got undecodable bytes at offset {exc.start}", str(path)) from None


def check_output_path(path: str | Path, param: str = "output") -> Path:
    """Check that ``path`` can be written as a file (before any work is done): not empty, not a directory, its
    folder (created if missing) writable. Raises :class:`OutputError`; creates nothing but missing folders."""
    text = str(path)
    if not text.strip():
        raise OutputError("expected a file path, got an empty string", param)
    target = Path(text)
    if target.is_dir() or text.endswith(os.sep):
        raise OutputError(f"expected a file path, got a directory: {text}", param)
    folder = target.parent
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise OutputError(f"cannot write {text}: {existing} is not a directory", param)
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {text}: {existing} is not writable", param)
    if target.exists():
        mode = target.stat().st_mode
        if not stat.S_ISREG(mode):          # written by rename: a device such as /dev/null would be replaced
            raise OutputError(f"expected a regular file to write, got a {file_kind(mode)}: {text}", param)
        if not os.access(target, os.W_OK):
            raise OutputError(f"cannot write {text}: the file is read-only", param)
    return target


_temps: set[Path] = set()          # temp files being written now (removed by remove_temps on an interrupt)
_temps_lock = threading.Lock()
_closing = False


def _temp_beside(target: Path) -> tuple[int, Path]:
    """Create a new temp file beside ``target`` (mode 0666 less the umask) and return (fd, path); it is recorded
    until :func:`_done_with` so that :func:`remove_temps` can clean up after an interrupt. It is recorded before it
    is created: an interrupt raised the moment the file exists (a signal's handler runs as soon as ``os.open``
    returns) must not leave it unrecorded."""
    for _ in range(100):
        tmp = target.with_name(f".{target.name}.{secrets.token_hex(6)}.tmp")
        with _temps_lock:
            if _closing:
                raise OutputError("not written: the program is ending", str(target))
            _temps.add(tmp)
            try:
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
            except FileExistsError:     # another's temp file (48 random bits alike): not ours to remove
                _temps.discard(tmp)
                continue
            except OSError:
                _temps.discard(tmp)
                raise
            return fd, tmp
    raise OutputError("cannot create a temporary file", str(target))  # pragma: no cover


def _done_with(tmp: Path) -> None:
    with _temps_lock:
        _temps.discard(tmp)


def remove_temps(final: bool = False) -> int:
    """Remove every temp file still being written (a run interrupted by Ctrl-C or SIGTERM, or a thread cut short
    as the program ends); with ``final`` (the program ends now) also refuse new ones. Returns how many were
    removed. The targets keep their old content."""
    global _closing
    removed = 0
    with _temps_lock:
        _closing = _closing or final
        for tmp in list(_temps):
            with contextlib.suppress(OSError):
                os.unlink(tmp)
                removed += 1
        _temps.clear()
    return removed


def write_atomic(path: str | Path, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` atomically; parent directories are created. Returns the path."""
    target = Path(path)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = _temp_beside(target)
    except OSError as exc:
        raise OutputError(f"cannot write: {exc.strerror or exc}", str(target)) from None
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(payload)
            handle.flush()
            os.fsync(handle.fileno())
        with contextlib.suppress(FileNotFoundError):
            os.chmod(tmp, target.stat().st_mode & 0o7777)  # an existing file keeps its mode
        os.replace(tmp, target)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise OutputError(f"cannot write: {exc.strerror or exc}", str(target)) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    finally:
        _done_with(tmp)
    return target


@contextlib.contextmanager
def new_file_beside(target: str | Path, param: str = "output") -> Iterator[Path]:
    """A new file built in place by another library (a database), moved into place whole: yields a new, empty temp
    file beside ``target`` (its folder made if missing); when the block ends without an error the temp file becomes
    ``target``, which must still not exist (a file another run made meanwhile is never replaced:
    :class:`OutputError`); otherwise it is removed. Recorded like :func:`write_atomic`'s (removed on an interrupt).
    """
    target = Path(target)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = _temp_beside(target)
        os.close(fd)
    except OSError as exc:
        raise OutputError(f"cannot write {target}: {exc.strerror or exc}", param) from None
    try:
        yield tmp
        _link_new(tmp, target, param)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(tmp)               # moved: only the temp name goes; the target keeps the file
        _done_with(tmp)


def _link_new(tmp: Path, target: Path, param: str) -> None:
    """``tmp`` also named ``target``, which must not exist: a hard link (atomic and never replacing), or a rename
    where the file system has no hard links."""
    try:
        os.link(tmp, target)
    except FileExistsError:
        raise OutputError(f"expected no file there yet, but another run made it meanwhile: {target}", param) from None
    except OSError as exc:
        if target.exists() or exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK):
            raise OutputError(f"cannot write {target}: {exc.strerror or exc}", param) from None
        try:
            os.rename(tmp, target)
        except OSError as again:
            raise OutputError(f"cannot write {target}: {again.strerror or again}", param) from None


class OutputSet:
    """The output files of one command, checked before any work and written together at the end.

    Each path is checked when the set is made (:func:`check_output_path`); :meth:`put` stages a file's content in
    memory; :meth:`commit` writes every staged file to a temp file beside its target, then renames them all into
    place while holding an exclusive lock on each target folder, so two runs writing the same outputs never mix
    their files: one run's set replaces the other's whole. A command that fails before :meth:`commit` writes
    nothing.
    """

    def __init__(self, paths: Mapping[str, str | Path]):
        self.paths = {key: check_output_path(path, key) for key, path in paths.items()}
        seen: dict[Path, str] = {}
        for key, path in self.paths.items():
            resolved = path.resolve()
            if resolved in seen:
                raise OutputError(f"the same file as {seen[resolved]}: {path}", key)
            seen[resolved] = key
        self.staged: dict[str, bytes] = {}

    def put(self, key: str, data: bytes | str) -> None:
        """Stage the content of output ``key``."""
        self.staged[key] = data.encode("utf-8") if isinstance(data, str) else data

    def commit(self) -> dict[str, Path]:
        """Write every staged output (see the class docstring); returns ``{key: path}`` of the written files."""
        import fcntl

        targets = {key: self.paths[key] for key in self.staged}
        folders = sorted({p.parent.resolve() for p in targets.values()}, key=str)
        temps: list[tuple[Path, Path]] = []
        made: list[Path] = []
        locks: list[int] = []
        try:
            for folder in folders:
                folder.mkdir(parents=True, exist_ok=True)
                fd = os.open(folder, os.O_RDONLY)
                locks.append(fd)
                fcntl.flock(fd, fcntl.LOCK_EX)
            for key, target in targets.items():
                fd, tmp = _temp_beside(target)
                made.append(tmp)
                temps.append((tmp, target))
                with os.fdopen(fd, "wb") as handle:
                    handle.write(self.staged[key])
                    handle.flush()
                    os.fsync(handle.fileno())
                with contextlib.suppress(FileNotFoundError):
                    os.chmod(tmp, target.stat().st_mode & 0o7777)
            with signals_held():        # renamed all or none: an interrupt here waits for the last rename
                for tmp, target in temps:
                    os.replace(tmp, target)
                temps.clear()
        except OSError as exc:
            raise OutputError(f"cannot write: {exc.strerror or exc}", getattr(exc, "filename", None)) from None
        finally:
            for tmp, _ in temps:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            for tmp in made:
                _done_with(tmp)
            for fd in locks:
                os.close(fd)  # closing releases the lock
        return targets
