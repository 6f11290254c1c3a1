"""How the studio takes an edit from the page: one editing tab at a time, nothing changed by a refused edit, no
edit while the optimiser works on the pose. A mixin of :class:`.server.Studio`.

* **One editor.** Every tab sees the same page (viser shares its widgets), so only one tab edits: the first that
  acts holds the pen until it closes or another tab presses "edit in this tab". A change made in another tab is
  undone on the page and that tab is told why.
* **All or nothing.** An edit runs on the session with a snapshot taken first; if it fails for any reason (bad
  input, or a value no browser would send: NaN, a string where a number goes) the snapshot is put back, so the
  pose, the support, the open action file and the played page are exactly as before, and the page says why.
* **The optimiser's pose is never mixed with edits.** While "optimise" or "balance" runs, edits are refused; its
  result is adopted as a whole when it ends.
"""

from __future__ import annotations

import collections
import threading
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.studio.session import PoseEdit, Readout

MAX_EVENTS = 1000                 # the last events kept for tests and the log
NOTIFY_S = 6.0                    # a refusal shown to one tab closes after this long [s]


@dataclass
class Snapshot:
    servo: np.ndarray
    support: Any
    name: str
    action: Any
    played: Any

    @classmethod
    def of(cls, s: PoseEdit) -> "Snapshot":
        return cls(s.servo.copy(), s.support, s.name, s.action, s.played)

    def restore(self, s: PoseEdit) -> None:
        s.servo, s.support, s.name, s.action, s.played = self.servo, self.support, self.name, self.action, self.played


class Edits:
    """The editing rules of the module docstring; the page's parts come from :class:`.server.Studio`."""

    session: PoseEdit
    server: Any
    _message: Any
    _show: Callable[[Readout], None]

    def _init_edits(self) -> None:
        self.events: collections.deque[tuple[str, str]] = collections.deque(maxlen=MAX_EVENTS)
        self._lock = threading.RLock()
        self._editor: int | None = None
        self._clients: set[int] = set()
        self.busy = {"check": False, "optimise": False}
        self._inputs: dict[int, tuple[Any, Any]] = {}       # id(handle): (handle, the value last accepted)
        self.server.on_client_connect(lambda client: self._clients.add(client.client_id))
        self.server.on_client_disconnect(self._gone)

    def _gone(self, client: Any) -> None:
        self._clients.discard(client.client_id)
        if self._editor == client.client_id:
            self._editor = None

    def _pen(self, event: Any) -> str | None:
        """Why the tab of ``event`` may not edit now (None: it may; events from Python always may)."""
        client = getattr(event, "client_id", None)
        if client is None:
            return None
        if self._editor is None or self._editor not in self._clients:
            self._editor = client
        if client != self._editor:
            return "another tab is editing this pose: close it, or press 'edit in this tab' here"
        return None

    def _take_pen(self, event: Any) -> None:
        client = getattr(event, "client_id", None)
        if client is not None:
            self._editor = client
            self._tell(event, "editing", "this tab edits the pose now")
            self.events.append(("pen", f"tab {client}"))

    def _tell(self, event: Any, title: str, text: str) -> None:
        """Show ``text`` to the tab of ``event`` only (to every tab when it came from Python)."""
        client = getattr(event, "client", None)
        if client is not None:
            try:
                client.add_notification(title, text, auto_close_seconds=NOTIFY_S)
                return
            except Exception:  # noqa: BLE001 (the tab went away)
                return
        self._message.content = f"**{title}**: {text}"

    def _refused(self, kind: str, why: str, event: Any = None) -> None:
        self.events.append((kind, f"refused: {why}"))
        self._tell(event, "refused", why)
        if getattr(event, "client", None) is not None and self._editor == getattr(event, "client_id", None):
            self._message.content = f"**refused**: {why}"

    def _edit(self, kind: str, action: Callable[[], Readout], event: Any = None) -> None:
        """Apply one edit all or nothing (see the module docstring) and show the pose."""
        with self._lock:
            why = self._pen(event)
            if why is None and self.busy["optimise"]:
                why = "the optimiser is working on this pose: edits wait until it ends"
            if why is not None:
                self._show(self.session.readout())          # undo what the page moved, then say why
                self._refused(kind, why, event)
                return
            before = Snapshot.of(self.session)
            try:
                readout = action()
            except Exception as exc:  # noqa: BLE001 (bad input, or a value no browser sends: nothing changes)
                before.restore(self.session)
                why = str(exc) if isinstance(exc, Op2MotionError) else f"not a value this control takes ({exc})"
                self._show(self.session.readout())
                self._refused(kind, why, event)
                return
            self._message.content = ""
            self._show(readout)
            self.events.append((kind, "applied"))          # after the page shows it

    def _guard_input(self, handle: Any) -> Any:
        """Keep changes of a free-form input (text, number, checkbox, dropdown) from tabs that do not edit: they are
        put back to the value last accepted."""
        self._inputs[id(handle)] = (handle, handle.value)

        def changed(event: Any) -> None:
            with self._lock:
                accepted = self._inputs[id(handle)][1]
                if self._pen(event) is None:
                    self._inputs[id(handle)] = (handle, handle.value)
                elif handle.value != accepted:
                    handle.value = accepted
                    self._refused("input", "another tab is editing this pose", event)
        handle.on_update(changed)
        return handle

    def _settle_input(self, handle: Any, value: Any) -> None:
        """Set a guarded input from Python (accepted as it is)."""
        handle.value = value
        self._inputs[id(handle)] = (handle, value)
