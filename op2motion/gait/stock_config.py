"""The stock ROBOTIS Walking module's settings: the ``[Walking Config]`` section of the framework's ``config.ini``.

:class:`StockConfig` holds every key that the framework's ``Walking::LoadINISettings`` reads (v1.6.0, ``Walking.cpp``),
in the file's own units (mm, deg, ms, ticks per gyro count), with the constructor's defaults
(``../shared/reference/op2_facts.md`` section 5). The commanded step (``X/Y/A_MOVE_AMPLITUDE``) is not part of the
file: the framework's demos set it at run time; op2motion records the forward amplitude a config was tuned for in an
``[op2motion]`` section (``x_move_amplitude_mm``), which the framework ignores.

:func:`read_stock_config` reads a ``config.ini`` (a missing key keeps its default, as the framework does; an unknown
key in the section, a value that is not a number or lies outside its range is bad input naming the file and key);
:func:`stock_config_text` writes one (every key Walking.cpp reads, then the ``[op2motion]`` section).
"""

from __future__ import annotations

import configparser
import math
from dataclasses import dataclass, fields
from pathlib import Path

from op2motion.errors import InputError
from op2motion.fileio import read_text

SECTION = "Walking Config"
OWN_SECTION = "op2motion"

#: ini key -> (attribute, lowest, highest, unit). The ranges are what a walk can use: wider than any published
#: config, narrower than what breaks the generator (a period under 200 ms, a double-support share of 1).
KEYS: dict[str, tuple[str, float, float, str]] = {
    "x_offset": ("x_offset_mm", -60.0, 60.0, "mm"),
    "y_offset": ("y_offset_mm", -30.0, 60.0, "mm"),
    "z_offset": ("z_offset_mm", 0.0, 80.0, "mm"),
    "roll_offset": ("roll_offset_deg", -20.0, 20.0, "deg"),
    "pitch_offset": ("pitch_offset_deg", -30.0, 30.0, "deg"),
    "yaw_offset": ("yaw_offset_deg", -30.0, 30.0, "deg"),
    "hip_pitch_offset": ("hip_pitch_offset_deg", -30.0, 45.0, "deg"),
    "period_time": ("period_time_ms", 200.0, 2000.0, "ms"),
    "dsp_ratio": ("dsp_ratio", 0.0, 0.8, "share"),
    "step_forward_back_ratio": ("step_fb_ratio", -1.0, 1.0, "share"),
    "foot_height": ("foot_height_mm", 0.0, 80.0, "mm"),
    "swing_right_left": ("swing_right_left_mm", 0.0, 60.0, "mm"),
    "swing_top_down": ("swing_top_down_mm", 0.0, 30.0, "mm"),
    "pelvis_offset": ("pelvis_offset_deg", -20.0, 20.0, "deg"),
    "arm_swing_gain": ("arm_swing_gain", 0.0, 5.0, "deg/mm"),
    "balance_knee_gain": ("balance_knee_gain", 0.0, 5.0, "ticks/count"),
    "balance_ankle_pitch_gain": ("balance_ankle_pitch_gain", 0.0, 5.0, "ticks/count"),
    "balance_hip_roll_gain": ("balance_hip_roll_gain", 0.0, 5.0, "ticks/count"),
    "balance_ankle_roll_gain": ("balance_ankle_roll_gain", 0.0, 5.0, "ticks/count"),
    "p_gain": ("p_gain", 1.0, 254.0, "MX-28 P"),
    "i_gain": ("i_gain", 0.0, 254.0, "MX-28 I"),
    "d_gain": ("d_gain", 0.0, 254.0, "MX-28 D"),
}
INTEGER_KEYS = ("p_gain", "i_gain", "d_gain")
OWN_KEYS: dict[str, tuple[str, float, float, str]] = {
    "x_move_amplitude_mm": ("x_move_amplitude_mm", -60.0, 60.0, "mm"),
}


@dataclass(frozen=True)
class StockConfig:
    """Every ``[Walking Config]`` key (defaults: the v1.6.0 ``Walking`` constructor) and the forward step a config
    was tuned for (``x_move_amplitude_mm``: the ``[op2motion]`` section; 0 when not given)."""

    x_offset_mm: float = -10.0
    y_offset_mm: float = 5.0
    z_offset_mm: float = 20.0
    roll_offset_deg: float = 0.0
    pitch_offset_deg: float = 0.0
    yaw_offset_deg: float = 0.0
    hip_pitch_offset_deg: float = 13.0
    period_time_ms: float = 600.0
    dsp_ratio: float = 0.1
    step_fb_ratio: float = 0.28
    foot_height_mm: float = 40.0
    swing_right_left_mm: float = 20.0
    swing_top_down_mm: float = 5.0
    pelvis_offset_deg: float = 3.0
    arm_swing_gain: float = 1.5
    balance_knee_gain: float = 0.3
    balance_ankle_pitch_gain: float = 0.9
    balance_hip_roll_gain: float = 0.5
    balance_ankle_roll_gain: float = 1.0
    p_gain: int = 32
    i_gain: int = 0
    d_gain: int = 0
    x_move_amplitude_mm: float = 0.0

    def __post_init__(self) -> None:
        for key, (name, low, high, unit) in {**KEYS, **OWN_KEYS}.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not low <= value <= high:
                raise InputError(f"expected {low:g} to {high:g} {unit}, got {value!r}", key)
            if key in INTEGER_KEYS and value != int(value):
                raise InputError(f"expected a whole number, got {value!r}", key)

    def with_values(self, **values: float) -> "StockConfig":
        """This config with some attributes changed (checked as any config)."""
        current = {f.name: getattr(self, f.name) for f in fields(self)}
        unknown = set(values) - set(current)
        if unknown:
            raise InputError(f"expected stock walking settings, got {', '.join(sorted(unknown))}", "config")
        return StockConfig(**{**current, **values})


def _number(text: str, key: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{key}: expected a number, got {text!r}", where) from None
    return value


def parse_stock_config(text: str, where: str = "<config.ini>") -> StockConfig:
    """A config from the text of a ``config.ini`` (see the module docstring); errors name ``where`` and the key."""
    parser = configparser.ConfigParser(interpolation=None, strict=True)
    parser.optionxform = str                           # type: ignore[assignment, method-assign]  # keys as written
    try:
        parser.read_string(text, source=where)
    except configparser.Error as exc:
        raise InputError(f"expected an ini file: {str(exc).splitlines()[0]}", where) from None
    if not parser.has_section(SECTION):
        raise InputError(f"expected a [{SECTION}] section", where)
    values: dict[str, float] = {}
    for section, keys in ((SECTION, KEYS), (OWN_SECTION, OWN_KEYS)):
        if not parser.has_section(section):
            continue
        for key, text_value in parser.items(section):
            if key not in keys:
                raise InputError(f"[{section}] {key}: unknown key (expected one of {', '.join(keys)})", where)
            number = _number(text_value, key, f"{where}: [{section}]")
            values[keys[key][0]] = int(number) if key in INTEGER_KEYS and number == int(number) else number
    try:
        return StockConfig(**values)   # type: ignore[arg-type]
    except InputError as exc:
        raise InputError(f"{exc.param}: {exc.message}", f"{where}: [{SECTION}]") from None


def read_stock_config(path: str | Path) -> StockConfig:
    """Read a ``config.ini`` (see :func:`parse_stock_config`)."""
    return parse_stock_config(read_text(path, "config file"), str(path))


def stock_config_text(config: StockConfig, note: str = "") -> str:
    """The ``config.ini`` text of ``config``: the ``[Walking Config]`` section with every key the framework reads, in
    its order, then the ``[op2motion]`` section; ``note`` lines go first as comments."""
    lines = [f"; {line}" for line in note.splitlines()] + [f"[{SECTION}]"]
    for key, (name, *_rest) in KEYS.items():
        value = getattr(config, name)
        lines.append(f"{key} = {int(value) if key in INTEGER_KEYS else _short(value)}")
    lines += ["", f"[{OWN_SECTION}]"]
    lines += [f"{key} = {_short(getattr(config, name))}" for key, (name, *_rest) in OWN_KEYS.items()]
    return "\n".join(lines) + "\n"


def _short(value: float) -> str:
    """A number as the framework's minIni writes and reads it, without trailing noise (6 significant digits)."""
    return f"{value:.6g}"
