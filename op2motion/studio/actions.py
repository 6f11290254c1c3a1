"""The pose studio's action-file panel: open a ROBOTIS action file, play a page and scrub its 8-ms goals, put the pose
on a page and save the file (atomically; nothing is written before). Files are opened and saved only inside the
studio's folder (:mod:`.folder`); a file is overwritten only when the studio opened or created it and the page
confirmed. A mixin of :class:`.server.Studio`."""

from __future__ import annotations

import math
from typing import Any, Callable

from op2motion.errors import InputError, Op2MotionError
from op2motion.studio.edits import Snapshot
from op2motion.studio.folder import Workspace
from op2motion.studio.session import PoseEdit, Readout

MAX_PAGE = 255


def _page_number(value: object) -> int:
    """A page number from the page: a whole number 1-255."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or value != int(value) or not 1 <= value <= MAX_PAGE:
        raise InputError(f"expected a whole number 1 to {MAX_PAGE}, got {value!r}", "page")
    return int(value)


def _seconds(value: object) -> float:
    """A step time from the page [s]: a finite number (the session checks its range)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"expected a number of seconds, got {value!r}", "step [s]")
    return float(value)


class ActionPanel:
    """The action-file controls (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    session: PoseEdit
    server: Any
    events: Any
    workspace: Workspace
    busy: dict[str, bool]
    _lock: Any
    _message: Any
    _quiet: bool
    _opened_path: str

    _show: Callable[[Readout], None]               # the page's own, from Studio
    _edit: Callable[..., None]
    _pen: Callable[[Any], str | None]
    _refused: Callable[..., None]
    _guard_input: Callable[[Any], Any]
    _settle_input: Callable[[Any, Any], None]

    def _build_action_gui(self) -> None:
        """Open an action file, play and scrub a page, put the pose on a page and save the file."""
        gui = self.server.gui
        with gui.add_folder("action file"):
            self._action_path = self._guard_input(gui.add_text(
                "file", self._opened_path, hint=f"a .bin file name inside {self.workspace.root}"))
            self._open_button = gui.add_button("open")
            self._open_button.on_click(lambda e: self._action_step("open", self._open, e))
            self._page = self._guard_input(gui.add_number("page", 1, min=1, max=MAX_PAGE, step=1))
            self._play_button = gui.add_button("play page")
            self._play_button.on_click(lambda e: self._action_step("play", self._play, e))
            self._time = gui.add_slider("time [s]", min=0.0, max=1.0, step=0.008, initial_value=0.0)
            self._time.on_update(lambda e: None if e.client_id is None else self._edit(
                "scrub", lambda: self.session.scrub(self._time.value), e))
            self._step_s = self._guard_input(gui.add_number("step [s]", 1.0, min=0.024, max=2.04, step=0.008))
            self._overwrite = self._guard_input(gui.add_checkbox("overwrite an occupied page", False))
            self._add_button = gui.add_button("put the pose on the page")
            self._add_button.on_click(lambda e: self._action_step("add", self._add, e))
            self._overwrite_file = self._guard_input(gui.add_checkbox("overwrite the file", False))
            gui.add_button("save action file").on_click(lambda e: self._action_step("save action", self._save_file, e))

    def _add(self) -> str:
        page = self.session.add_to_page(_page_number(self._page.value), _seconds(self._step_s.value),
                                        bool(self._overwrite.value))
        return f"the pose is page {page} (not saved yet: save the action file)"

    def _open(self) -> str:
        path = self.workspace.for_reading(self._action_path.value, ".bin", "action file")
        used = self.session.open_action(path)
        self.workspace.claim(path)
        return f"opened {self.workspace.relative(path)}: {used} pages in use"

    def _save_file(self) -> str:
        path = self.workspace.for_writing(self._action_path.value, ".bin", "action file",
                                          bool(self._overwrite_file.value))
        self.session.save_action(path)
        self.workspace.claim(path)
        self._settle_input(self._overwrite_file, False)
        return f"saved {self.workspace.relative(path)}"

    def _play(self) -> str:
        page = _page_number(self._page.value)
        length = self.session.play(page)
        self._quiet = True
        try:
            self._time.max = max(length, 0.008)
            self._time.value = 0.0
        finally:
            self._quiet = False
        self._show(self.session.scrub(0.0))
        return f"page {page}: {length:.2f} s of 8-ms goals; scrub with the time slider"

    def _action_step(self, kind: str, action: Callable[[], str], event: Any = None) -> None:
        """One action-file step; a refused one shows why and changes nothing."""
        with self._lock:
            why = self._pen(event)
            if why is None and self.busy["optimise"] and kind == "play":
                why = "the optimiser is working on this pose: wait until it ends"
            if why is not None:
                self._refused(kind, why, event)
                return
            before = Snapshot.of(self.session)
            try:
                text = action()
            except Exception as exc:  # noqa: BLE001 (bad input or a value no browser sends: nothing changes)
                before.restore(self.session)
                self._refused(kind, str(exc) if isinstance(exc, (Op2MotionError, OSError))
                              else f"not a value this control takes ({exc})", event)
                return
            self.events.append((kind, "applied"))
            self._message.content = text
