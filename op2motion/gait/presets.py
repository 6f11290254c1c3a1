"""Where gait presets live: ``walking/NAME.toml`` in the source tree, shipped as package data ``op2motion.walking``.

A preset argument is a path to a TOML file; a bare name (``forward``) or a path under ``walking/`` that does not
exist where the command runs (an installed op2motion used from another folder) falls back to the shipped preset
of that name.
"""

from __future__ import annotations

from pathlib import Path

from op2motion.errors import InputError
from op2motion.gait.params import GaitParams, read_preset

PRESETS = ("forward", "backward", "sideways", "turn_left", "turn_right", "steer")
DEFAULT_PRESET = "forward"


def _shipped(name: str) -> Path | None:
    source_tree = Path(__file__).resolve().parents[2] / "walking" / f"{name}.toml"
    if source_tree.is_file():
        return source_tree
    try:
        from importlib import resources

        found = resources.files("op2motion.walking").joinpath(f"{name}.toml")
        return Path(str(found)) if found.is_file() else None
    except (ModuleNotFoundError, FileNotFoundError):
        return None


def preset_path(preset: str | None) -> Path:
    """The preset file for a path or a shipped preset's name (default: :data:`DEFAULT_PRESET`)."""
    text = preset or DEFAULT_PRESET
    path = Path(text)
    if path.is_file():
        return path
    name = path.stem if path.suffix == ".toml" else text
    shipped = _shipped(name) if path.parent in (Path("."), Path("walking")) else None
    if shipped is None:
        raise InputError(f"expected a gait preset file or one of {', '.join(PRESETS)}, got {text!r}", "preset")
    return shipped


def load_preset(preset: str | None = None) -> GaitParams:
    """The gait parameters of a preset file or a shipped preset's name (default: :data:`DEFAULT_PRESET`)."""
    return read_preset(preset_path(preset))
