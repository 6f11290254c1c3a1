"""The one folder the studio reads and writes: paths typed in the page are names inside it, never anything else.

A path from the page is refused unless it is relative, made of plain names (no ``..``, no ``~``, no hidden or
empty parts, no control characters), ends in the suffix the action expects (``.json`` for poses, ``.bin`` for
action files), and resolves (symbolic links followed) to a file inside the folder whose own folder exists (the page
creates no folders). The message is the same whatever lies outside, so the page learns nothing about files outside
the folder. Writing over a file is allowed only for files this studio opened or created in this run
(:meth:`Workspace.claim`), and only when the page confirmed it; a file the studio did not open is never
overwritten.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from op2motion.errors import InputError

MAX_PATH_CHARS = 255
_PLAIN = re.compile(r"^[^\x00-\x1f\x7f/\\]+$")


class ConfirmOverwrite(InputError):
    """Saving would replace a file the studio opened or created: the page must confirm first."""


class Workspace:
    """The studio's folder (``root``) and the files it opened or created in this run."""

    def __init__(self, root: str | Path):
        folder = Path(root)
        if not folder.is_dir():
            raise InputError(f"expected an existing folder, got {str(root)!r}", "workdir")
        self.root = folder.resolve()
        self._ours: set[Path] = set()

    def _inside(self, text: object, suffix: str, what: str) -> Path:
        """The real path of page text ``text`` inside the folder, or :class:`InputError` (the same words for every
        path that is not a plain name inside it)."""
        refusal = InputError(f"expected a {what} name inside the studio's folder, such as mine{suffix} or "
                             f"poses/mine{suffix} (no '..', no absolute paths), got {str(text)[:80]!r}", what)
        if not isinstance(text, str) or not text.strip() or len(text) > MAX_PATH_CHARS or text != text.strip():
            raise refusal
        parts = text.split("/")
        if any(not _PLAIN.match(p) or p in (".", "..") or p.startswith((".", "~")) for p in parts):
            raise refusal
        if not parts[-1].lower().endswith(suffix) or len(parts[-1]) <= len(suffix):
            raise refusal
        path = Path(os.path.realpath(self.root.joinpath(*parts)))
        if not path.is_relative_to(self.root) or path == self.root:
            raise refusal
        return path

    def claim(self, path: str | Path) -> Path:
        """Record ``path`` as opened or created by the studio (it may be overwritten after confirmation)."""
        real = Path(os.path.realpath(path))
        self._ours.add(real)
        return real

    def relative(self, path: str | Path) -> str:
        """``path`` as the page shows it: relative to the folder, with ``/``."""
        return Path(os.path.realpath(path)).relative_to(self.root).as_posix()

    def for_reading(self, text: object, suffix: str, what: str) -> Path:
        """The file named ``text`` in the folder, which must exist as a regular file."""
        path = self._inside(text, suffix, what)
        if not path.is_file():
            raise InputError(f"no {what} {self.relative(path)} in the studio's folder", what)
        return path

    def for_writing(self, text: object, suffix: str, what: str, confirmed: bool) -> Path:
        """Where to write the file named ``text``: a new file in an existing folder inside, or a file this studio
        opened or created (:class:`ConfirmOverwrite` until ``confirmed``)."""
        path = self._inside(text, suffix, what)
        if not path.parent.is_dir():
            raise InputError(f"expected an existing folder inside the studio's folder, got {self.relative(path)}: "
                             f"the studio creates no folders", what)
        if path.exists() or path.is_symlink():
            if path not in self._ours or not path.is_file():
                raise InputError(f"{self.relative(path)} exists and the studio did not open or create it: choose "
                                 f"another name", what)
            if not confirmed:
                raise ConfirmOverwrite(f"{self.relative(path)} exists: tick 'overwrite' and save again to replace "
                                       f"it", what)
        return path
