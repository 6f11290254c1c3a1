"""The pose studio's action-file panel: open a ROBOTIS action file, play a page and scrub its 8-ms goals, put the pose
on a page and save the file (atomically; nothing is written before). A mixin of :class:`.server.Studio`."""

from __future__ import annotations

from typing import Any, Callable

from op2motion.errors import Op2MotionError
from op2motion.studio.session import Readout, Session


class ActionPanel:
    """The action-file controls (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    session: Session
    server: Any
    events: list[tuple[str, str]]
    _lock: Any
    _message: Any
    _quiet: bool
    _opened_path: str

    _show: Callable[[Readout], None]               # the page's own, from Studio
    _edit: Callable[[str, Any], None]

    def _build_action_gui(self) -> None:
        """Open an action file, play and scrub a page, put the pose on a page and save the file."""
        gui = self.server.gui
        with gui.add_folder("action file"):
            self._action_path = gui.add_text("file", self._opened_path)
            gui.add_button("open").on_click(lambda _: self._action_step("open", lambda: self._open()))
            self._page = gui.add_number("page", 1, min=1, max=255, step=1)
            gui.add_button("play page").on_click(lambda _: self._action_step("play", lambda: self._play()))
            self._time = gui.add_slider("time [s]", min=0.0, max=1.0, step=0.008, initial_value=0.0)
            self._time.on_update(lambda _: None if self._quiet else self._edit(
                "scrub", lambda: self.session.scrub(self._time.value)))
            self._step_s = gui.add_number("step [s]", 1.0, min=0.024, max=2.04, step=0.008)
            self._overwrite = gui.add_checkbox("overwrite an occupied page", False)
            gui.add_button("put the pose on the page").on_click(lambda _: self._action_step("add", self._add))
            gui.add_button("save action file").on_click(lambda _: self._action_step("save action", lambda: (
                f"saved {self.session.save_action(self._action_path.value)}")))

    def _add(self) -> str:
        page = self.session.add_to_page(int(self._page.value), float(self._step_s.value), bool(self._overwrite.value))
        return f"the pose is page {page} (not saved yet: save the action file)"

    def _open(self) -> str:
        used = self.session.open_action(self._action_path.value)
        return f"opened {self._action_path.value}: {used} pages in use"

    def _play(self) -> str:
        length = self.session.play(int(self._page.value))
        self._quiet = True
        try:
            self._time.max = max(length, 0.008)
            self._time.value = 0.0
        finally:
            self._quiet = False
        self._show(self.session.scrub(0.0))
        return f"page {int(self._page.value)}: {length:.2f} s of 8-ms goals; scrub with the time slider"

    def _action_step(self, kind: str, action: Any) -> None:
        """One action-file step; a refused one shows why and changes nothing."""
        with self._lock:
            try:
                text = action()
            except (Op2MotionError, OSError) as exc:
                self.events.append((kind, f"refused: {exc}"))
                self._message.content = f"**refused**: {exc}"
                return
            self.events.append((kind, "applied"))
            self._message.content = text
