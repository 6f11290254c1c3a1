"""Property tests: random mutations of the spec and random pose documents reach the loaders; only op2motion's own
errors may come out, and whatever loads is usable by the models."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from helpers import ROOT, pose_path
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from op2motion.errors import Op2MotionError, PoseFileError
from op2motion.formats.posefile import parse_pose
from op2motion.kinematics import forward
from op2motion.model.urdf import build_urdf
from op2motion.robot.joints import BookAngles
from op2motion.robot.specfile import default_spec, parse_spec

SPEC_TEXT = (ROOT / "specs" / "op2.toml").read_text(encoding="utf-8")
SPEC_LINES = SPEC_TEXT.splitlines()
VALUE_LINES = [i for i, line in enumerate(SPEC_LINES) if re.match(r"^[\w.]+ = ", line)]
HOSTILE = ["-1", "0", "nan", "inf", "-inf", "1e308", "-1e308", '"text"', "[]", "[1, 2]", "[nan, 0, 0]", "true",
           "{}", '"../x"', "1e-300", "[-1.0, -1.0, -1.0, 0.0, 0.0, 0.0]", "[1.0, 1.0, 5.0, 0.0, 0.0, 0.0]"]
EXAMPLES = 120


def _mutated(edits: list[tuple[int, str]]) -> str:
    lines = list(SPEC_LINES)
    for which, value in edits:
        i = VALUE_LINES[which % len(VALUE_LINES)]
        key = lines[i].split(" = ", 1)[0]
        lines[i] = f"{key} = {value}"
    return "\n".join(lines)


def _use(spec) -> None:
    """What loads must be usable: forward kinematics and the URDF."""
    points = forward(BookAngles.standing("left"), spec)
    assert np.all(np.isfinite(points.data))
    build_urdf(spec)


@pytest.mark.slow
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, 10_000), st.sampled_from(HOSTILE)), min_size=1, max_size=4))
def test_spec_value_mutations_give_only_spec_errors(edits):
    try:
        spec = parse_spec(_mutated(edits), "mutated.toml")
    except Op2MotionError:
        return
    _use(spec)


@pytest.mark.slow
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, len(SPEC_TEXT) - 1), st.characters()), min_size=1, max_size=6))
def test_spec_character_mutations_give_only_spec_errors(edits):
    text = list(SPEC_TEXT)
    for offset, char in edits:
        text[offset] = char
    try:
        spec = parse_spec("".join(text), "mutated.toml")
    except Op2MotionError:
        return
    _use(spec)


JSON = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=8),
                    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
                    max_leaves=20)
GOOD = json.loads(open(pose_path("walkready"), encoding="utf-8").read())
FIELDS = ["schema", "name", "support", "servo_deg", "book_deg", "metrics", "provenance"]


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(JSON)
def test_random_documents_are_pose_file_errors(doc):
    try:
        parse_pose(doc, default_spec(), "random.json")
    except PoseFileError:
        pass


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(FIELDS), JSON, st.sampled_from(sorted(GOOD["servo_deg"])),
       st.one_of(st.floats(allow_nan=True, allow_infinity=True), JSON))
def test_mutated_pose_files_load_or_are_pose_file_errors(field, value, joint, angle):
    for doc in ({**GOOD, field: value}, {**GOOD, "servo_deg": {**GOOD["servo_deg"], joint: angle}}):
        try:
            pose = parse_pose(doc, default_spec(), "mutated.json")
        except PoseFileError:
            continue
        assert pose.servo.shape == (20,) and np.all(np.isfinite(pose.servo))
        assert all(math.isfinite(v) for v in pose.servo)
