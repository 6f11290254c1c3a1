"""Ctrl-C and SIGTERM held for a moment that must not be cut in two.

Python runs a signal's handler between two bytecodes, wherever the main thread is: a Ctrl-C or SIGTERM (which the
CLI turns into :class:`KeyboardInterrupt`) can land between a worker's spawn and its start-up message, or between
the renames of a set of output files. :func:`signals_held` makes such a moment whole: a signal that arrives inside
it is noted, and delivered again, to whatever handler was there before, as the block ends.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Any, Iterator

HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def signals_held(ignore_ctrl_c: bool = False) -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) and SIGTERM in this block; deliver them as it ends (however it ends), to the handlers
    there before. With ``ignore_ctrl_c`` a Ctrl-C in the block is ignored instead: processes started in it inherit
    "ignored" (a held signal's handler is Python's and does not survive ``exec``). Only the main thread receives
    signals: elsewhere the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        arrived.append(signum)

    previous = {sig: signal.getsignal(sig) for sig in HELD_SIGNALS}
    signal.signal(signal.SIGINT, signal.SIG_IGN if ignore_ctrl_c else hold)
    signal.signal(signal.SIGTERM, hold)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        for signum in dict.fromkeys(arrived):           # each once, in the order they came
            signal.raise_signal(signum)
