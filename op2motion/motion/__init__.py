"""Motions: action pages played as the robot plays them, pose-to-pose trajectories, and their checks; getting up
after a fall (:class:`GetUp`) and the fall supervisor (:class:`Supervisor`) that wraps any controller."""

from __future__ import annotations

from typing import Any

__all__ = ["GetUp", "Supervisor"]


def __getattr__(name: str) -> Any:
    """``GetUp`` and ``Supervisor`` imported on first use (no work at import time)."""
    if name == "GetUp":
        from op2motion.motion.getup import GetUp

        return GetUp
    if name == "Supervisor":
        from op2motion.motion.fall import Supervisor

        return Supervisor
    raise AttributeError(f"module 'op2motion.motion' has no attribute {name!r}")
