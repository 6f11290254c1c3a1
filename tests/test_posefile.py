"""Pose files: round trip, validation, atomic writes that never corrupt an existing file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from op2motion.errors import LimitError, PoseFileError
from op2motion.formats.posefile import read_pose, write_pose
from op2motion.robot.joints import BookAngles
from op2motion.robot.pose import Pose


def _pose(spec, name="test") -> Pose:
    book = BookAngles.from_deg([80, 10, 0, 210, -10, -5, 170, 10, 200, 20, 0], [-10, 5, 170, 10, 200, 170],
                               [10, -5, 0], "left")
    return Pose.from_book(name, book, spec, metrics={"cost": 0.1})


def test_round_trip(spec, tmp_path):
    path = write_pose(_pose(spec), tmp_path / "poses" / "test.json", spec)
    back = read_pose(path, spec)
    assert back.name == "test" and back.support == "left" and back.metrics["cost"] == 0.1
    assert np.allclose(back.servo, _pose(spec).servo, atol=np.radians(1e-6))
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["schema"] == "op2motion.pose/1" and doc["provenance"]["spec_sha256"] == spec.sha256
    assert doc["book_deg"]["th"][0] == pytest.approx(80.0)


def _write(tmp_path, doc) -> str:
    p = tmp_path / "p.json"
    p.write_text(json.dumps(doc) if not isinstance(doc, str) else doc, encoding="utf-8")
    return str(p)


def test_minimal_file_with_servo_only_is_valid(spec, tmp_path):
    doc = json.loads(write_pose(_pose(spec), tmp_path / "a.json", spec).read_text(encoding="utf-8"))
    minimal = {k: doc[k] for k in ("schema", "name", "support", "servo_deg")}
    minimal["support"] = "double"
    pose = read_pose(_write(tmp_path, minimal), spec)
    assert pose.support == "double" and pose.book(spec).support == "left"


@pytest.mark.parametrize("mutate, needle", [
    (lambda d: d.update(schema="op2motion.pose/2"), "schema"),
    (lambda d: d["servo_deg"].pop("l_knee"), "missing l_knee"),
    (lambda d: d["servo_deg"].update(l_wrist=0), "unknown joint"),
    (lambda d: d["servo_deg"].update(l_knee=-170.0), "l_knee = -170.0° is outside its"),
    (lambda d: d["servo_deg"].update(l_knee="bent"), "finite number"),
    (lambda d: d.update(support="both"), "support"),
    (lambda d: d["book_deg"]["th"].__setitem__(0, 70.0), "disagrees"),
    (lambda d: d.update(name=""), "name"),
])
def test_bad_files_are_clear_errors(spec, tmp_path, mutate, needle):
    doc = json.loads(write_pose(_pose(spec), tmp_path / "a.json", spec).read_text(encoding="utf-8"))
    mutate(doc)
    with pytest.raises(PoseFileError, match=needle):
        read_pose(_write(tmp_path, doc), spec)


def test_corrupted_json_is_a_clear_error(spec, tmp_path):
    with pytest.raises(PoseFileError, match="not valid JSON"):
        read_pose(_write(tmp_path, '{"schema": "op2motion.pose/1", "servo_'), spec)


def test_failed_write_keeps_the_existing_file(spec, tmp_path):
    path = write_pose(_pose(spec), tmp_path / "keep.json", spec)
    before = path.read_bytes()
    bad = Pose("bad", "left", np.full(20, 3.0))  # far outside the limits
    with pytest.raises(LimitError, match="outside its"):
        write_pose(bad, path, spec)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["keep.json"]  # no temp file left behind


def test_written_files_get_normal_permissions(spec, tmp_path):
    import os
    import stat

    umask = os.umask(0o022)
    try:
        path = write_pose(_pose(spec), tmp_path / "perm.json", spec)
        assert stat.S_IMODE(path.stat().st_mode) == 0o644        # not mkstemp's 0600
        os.chmod(path, 0o640)
        write_pose(_pose(spec), path, spec)
        assert stat.S_IMODE(path.stat().st_mode) == 0o640        # an existing file keeps its mode
    finally:
        os.umask(umask)
