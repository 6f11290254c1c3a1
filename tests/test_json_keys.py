"""The ``--json`` keys of the commands are today's: every key path (nested keys, list items as ``[]``) of a set of
fixed invocations is compared with ``tests/data/json_keys.json``, so that reshaping how results are built (typed
results, one encoder) cannot drop, rename or add a key unnoticed. A change that means to change the keys regenerates
the file (``OP2MOTION_UPDATE_JSON_KEYS=1 python -m pytest tests/test_json_keys.py``) and says so in docs/cli.md.

Only key paths are compared, not values; keys that are data (a joint's name, a file's role) are key paths too, so a
joint renamed shows here as well."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest
from helpers import POSES, ROOT, run_cli

KEYS_FILE = ROOT / "tests" / "data" / "json_keys.json"
DATA = ROOT / "tests" / "data"
THETA = ["80", "10", "0", "210", "-10", "-5", "170", "10", "200", "20", "0"]
PHI = ["-10", "5", "170", "10", "200", "170"]

#: name -> the command line after ``op2motion`` (``OUT`` is replaced by a file in the test's folder); each a yes.
INVOCATIONS: dict[str, list[str]] = {
    "fk dh": ["fk", "--model", "dh", "--support", "left", "--th", *THETA, "--phi", *PHI, "--psi", "10", "-5", "0"],
    "fk pose": ["fk", "--pose", str(POSES / "walkready.json")],
    "convert": ["convert", "--servo-deg", str(POSES / "init.json"), "--support", "left"],
    "arm-ik": ["arm-ik", "--hand", "left", "--delta", "0.02", "0", "0", "--th", "90", "0", "0", "180", "0", "0",
               "200", "100", "180", "0", "0", "--phi", "0", "0", "180", "0", "200", "180", "--single-step"],
    "import-action": ["import-action", str(DATA / "motion_4096.bin"), "--page", "15", "--out", "OUT.json"],
    "export webots": ["export", "--format", "webots", str(POSES / "init.json"), str(POSES / "walkready.json"),
                      "--time", "0.5", "-o", "OUT.motion"],
    "urdf": ["urdf", "-o", "OUT.urdf"],
    "motion play": ["motion", "play", str(DATA / "motion_4096.bin"), "--page", "9"],
    "walk": ["walk", "--steps", "4", "--plot", "OUT.png", "--out", "OUT.csv"],
    "walk commands": ["walk", "--commands", str(ROOT / "examples" / "steer_commands.csv")],
    "optimize": ["optimize", "--out", "OUT.json", "--plot", "OUT.png", "--iters", "20", "--particles", "20"],
    "list pages": ["import-action", str(DATA / "motion_4096.bin")],
    "urdf shown": ["urdf"],
}


def key_paths(value: Any, prefix: str = "") -> set[str]:
    """Every key path of a JSON value: ``a``, ``a.b``, list items as ``a[]`` (the union over the items)."""
    paths: set[str] = set()
    if isinstance(value, dict):
        for key, item in value.items():
            path = f"{prefix}.{key}" if prefix else str(key)
            paths |= {path} | key_paths(item, path)
    elif isinstance(value, list):
        for item in value:
            paths |= key_paths(item, f"{prefix}[]")
    return paths


def _run(capsys: Any, tmp_path: Path, argv: list[str]) -> dict[str, Any]:
    argv = [str(tmp_path / a.replace("OUT", "out")) if a.startswith("OUT") else a for a in argv]
    code, out, err = run_cli(capsys, *argv, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert isinstance(data, dict), out[:200]
    return data


@pytest.mark.parametrize("name", list(INVOCATIONS))
def test_the_json_keys_are_todays(capsys, tmp_path, name):
    paths = sorted(p.replace(str(tmp_path), "TMP") for p in key_paths(_run(capsys, tmp_path, INVOCATIONS[name])))
    if os.environ.get("OP2MOTION_UPDATE_JSON_KEYS"):
        known = json.loads(KEYS_FILE.read_text(encoding="utf-8")) if KEYS_FILE.exists() else {}
        known[name] = paths
        KEYS_FILE.write_text(json.dumps(dict(sorted(known.items())), indent=1) + "\n", encoding="utf-8")
    known = json.loads(KEYS_FILE.read_text(encoding="utf-8"))
    assert name in known, f"no keys recorded for {name!r}: regenerate {KEYS_FILE.name} (see the module docstring)"
    missing, added = sorted(set(known[name]) - set(paths)), sorted(set(paths) - set(known[name]))
    assert not missing and not added, f"{name}: keys gone {missing}, keys new {added}"


def test_key_paths_reach_into_lists_and_dicts():
    assert key_paths({"a": 1, "b": {"c": [{"d": 1}, {"e": [1]}]}}) == {"a", "b", "b.c", "b.c[].d", "b.c[].e"}
