"""The pose studio: its model (edits, refusals, readout), and the page in a real headless Chromium (Debian's, driven by
Playwright with the system browser; nothing downloaded): the robot drawn, a joint slider moved, "check in physics"
clicked, both seen by the Python side, the verdict on the page, the view changed where the robot is."""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import wait_for

from op2motion.errors import InputError
from op2motion.formats.posefile import read_pose
from op2motion.studio.folder import Workspace
from op2motion.studio.session import CLEARANCE_WARN_M, PoseEdit

ROOT = os.path.join(os.path.dirname(__file__), "..")
WALKREADY = os.path.join(ROOT, "poses", "walkready.json")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
BROWSER_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
                "--disable-quic"]
VIEW = (0, 0, 900, 800)            # the 3D view (x0, y0, x1, y1) [px]: left of the control panel
CHANGED_PIXELS = 2000              # a joint moved 40° changes at least this many pixels of the view
WAIT_S = 60.0


def test_edits_are_checked_and_the_readout_follows(spec, tmp_path):
    session = PoseEdit(spec, read_pose(WALKREADY, spec))
    before = session.servo.copy()
    for bad in (500, "abc", float("nan")):
        with pytest.raises(InputError, match="l_sho_pitch"):
            session.set_joint("l_sho_pitch", bad)
    with pytest.raises(InputError, match="joint"):
        session.set_joint("no_such_joint", 0)
    assert np.array_equal(session.servo, before)
    assert not (tmp_path / "x.json").exists()
    readout = session.readout()
    assert readout.support == "double" and readout.margin_full_m > 0.02 and not readout.colliding
    clash = session.set_joint("l_sho_roll", 75)                      # the upper arm swung into the torso
    assert clash.colliding and clash.self_clearance_m < CLEARANCE_WARN_M and "body_link" in clash.closest_links
    one_leg = PoseEdit(spec, read_pose(os.path.join(ROOT, "poses", "book_2_44.json"), spec)).readout()
    assert one_leg.support == "left" and one_leg.swing_clearance_m > 0.01 and one_leg.margin_settled_m > 0.0
    hand = np.array(session.readout().hands["right_hand"])
    moved, left = session.reach("right", hand + (0.02, 0.0, 0.02))   # the arm IK: 2 cm forward and up
    assert left < 0.002 and np.linalg.norm(np.array(moved.hands["right_hand"]) - hand - (0.02, 0.0, 0.02)) < 0.002
    with pytest.raises(InputError, match="target"):
        session.reach("right", ("a", 0, 0))
    saved = session.save(tmp_path / "x.json")
    assert read_pose(saved, spec).servo[spec.joint_names.index("l_sho_roll")] == pytest.approx(np.radians(75))


def test_balance_keeps_the_hand_and_the_pins_and_restores_the_margin(spec):
    session = PoseEdit(spec, read_pose(os.path.join(ROOT, "poses", "book_2_44.json"), spec))
    for joint, degrees in (("r_hip_pitch", -50), ("r_knee", 0), ("l_sho_pitch", -60)):   # a leg out, an arm up
        edited = session.set_joint(joint, degrees)
    hip = session.servo[spec.joint_names.index("r_hip_pitch")]
    balanced, message = session.balance("left", ["r_hip_pitch", "r_knee"])
    assert message.startswith("reached") and balanced.margin_settled_m > edited.margin_settled_m + 0.005
    assert session.servo[spec.joint_names.index("r_hip_pitch")] == pytest.approx(hip, abs=1e-6)
    assert np.linalg.norm(np.subtract(balanced.hands["left_hand"], edited.hands["left_hand"])) < 0.001
    with pytest.raises(InputError, match="joint"):
        session.balance("left", ["no_such_joint"])
    with pytest.raises(InputError, match="one foot"):
        PoseEdit(spec, read_pose(WALKREADY, spec)).balance("left", [])


def test_an_action_file_is_played_scrubbed_and_written_only_when_saved(spec, tmp_path):
    stock = os.path.join(ROOT, "tests", "data", "motion_4096.bin")
    session = PoseEdit(spec, read_pose(WALKREADY, spec))
    with pytest.raises(InputError, match="action file"):
        session.play(15)
    assert session.open_action(stock) > 0
    length = session.play(15)                                       # sit down
    assert length > 1.0
    start, end = session.scrub(0.0), session.scrub(length)
    assert start.com_full[2] > end.com_full[2] + 0.03                # it sat down: the CoM came down
    free = session.action.first_empty_run(1)
    assert session.add_to_page(free, 0.5) == free
    with pytest.raises(InputError, match="force|overwrite|hold actions"):
        session.add_to_page(15, 0.5)                                # an occupied page, not confirmed
    with pytest.raises(InputError, match="24 ms"):
        session.add_to_page(free + 1, 0.01)                         # shorter than the robot moves
    assert not list(tmp_path.iterdir())                             # nothing written yet
    saved = session.save_action(tmp_path / "mine.bin")
    from op2motion.formats.action import ActionFile

    again = ActionFile.read(saved)
    assert not again.is_empty(free) and again.data[:free * 512] == ActionFile.read(stock).data[:free * 512]


def test_a_pose_file_that_does_not_load_is_one_line(tmp_path):
    (tmp_path / "bad.json").write_text("{not json", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "op2motion", "studio", "bad.json", "--port", "0"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "bad.json" in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_a_port_in_use_is_one_line(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        done = subprocess.run([sys.executable, "-m", "op2motion", "studio", "--port", str(port)], cwd=tmp_path,
                              capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "--port" in done.stderr and "in use" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def _stable_view(page) -> bytes:
    """A screenshot of the 3D view once two in a row are equal (software WebGL fades colours in)."""
    previous, deadline = b"", time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        shot = page.screenshot(clip={"x": VIEW[0], "y": VIEW[1], "width": VIEW[2] - VIEW[0],
                                     "height": VIEW[3] - VIEW[1]})
        if shot == previous:
            return shot
        previous = shot
        time.sleep(0.5)
    return previous


def _pixels(png: bytes) -> np.ndarray:
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)


@pytest.mark.physics
def test_the_page_moves_a_joint_and_checks_in_physics(spec, tmp_path):
    playwright = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (the CI script installs it)")
    from op2motion.studio.server import Studio

    studio = Studio(spec, PoseEdit(spec, read_pose(WALKREADY, spec)), workspace=Workspace(tmp_path))
    try:
        with playwright.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=BROWSER_ARGS, headless=True)
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(studio.url)
            page.wait_for_selector("canvas", timeout=WAIT_S * 1000)
            before = _stable_view(page)
            label = page.locator("label").filter(has_text=re.compile(r"^l_sho_pitch$")).first   # the slider's
            box = label.locator("xpath=ancestor::div[.//input][1]").locator("input[type=text]").last
            box.fill("-20")                                           # the left arm from 41° to -20°
            box.press("Enter")
            joint = spec.joint_names.index("l_sho_pitch")
            wait_for(lambda: abs(studio.session.servo[joint] - np.radians(-20)) < 1e-9 and "| l_sho_pitch | -20.0 |"
                  in studio._table.content, "the slider edit on the Python side and in the joint table")
            assert ("slider", "applied") in studio.events
            page.get_by_text("optimise to the hand target", exact=True).click()    # on two feet: refused
            wait_for(lambda: ("optimise", "refused: double support") in studio.events, "the optimiser's refusal")
            page.get_by_text("choose left or right support").first.wait_for(timeout=WAIT_S * 1000)
            page.get_by_text("check in physics", exact=True).click()
            wait_for(lambda: any(k == "check" and v in ("STANDS", "FALLS", "FAILS") for k, v in studio.events),
                  "the physics check")
            page.get_by_text("STANDS").first.wait_for(timeout=WAIT_S * 1000)
            after = _stable_view(page)
            if os.environ.get("OP2MOTION_STUDIO_SHOT"):                  # the README's picture
                page.screenshot(path=os.environ["OP2MOTION_STUDIO_SHOT"])
            browser.close()
        changed = np.any(np.abs(_pixels(after) - _pixels(before)) > 30, axis=2)
        assert changed.sum() > CHANGED_PIXELS, changed.sum()
        assert _pixels(after).std() > 10                                # not blank
        assert ("check", "started") in studio.events
    finally:
        studio.stop()


def _stuck_client(url: str) -> socket.socket:
    """A client that opens the page's WebSocket and then stops reading (a tiny receive buffer, never read)."""
    import base64
    from urllib.parse import urlsplit

    parts = urlsplit(url)
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1024)
    s.connect((parts.hostname, parts.port))
    s.sendall((f"GET {parts.path.rstrip('/')} HTTP/1.1\r\nHost: {parts.netloc}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: "
               f"{base64.b64encode(os.urandom(16)).decode()}\r\nSec-WebSocket-Protocol: viser-v1.1.1\r\n"
               f"Origin: http://{parts.netloc}\r\n\r\n").encode())
    return s


@pytest.mark.slow
def test_ctrl_c_ends_the_server_within_3_s_even_with_a_stuck_client(tmp_path):
    import signal

    proc = subprocess.Popen([sys.executable, "-m", "op2motion", "studio", WALKREADY, "--port", "0"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stuck = None
    try:
        line = proc.stdout.readline()
        assert "http://127.0.0.1:" in line and ":0/" not in line, line
        stuck = _stuck_client(line.split()[2])
        time.sleep(1.0)                                  # the server fills what the client will never read
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
        assert proc.wait(timeout=10) == 130 and time.monotonic() - t0 < 3.0
        err = proc.stderr.read()
        assert "Traceback" not in err and err.strip().splitlines()[-1].startswith("op2motion: interrupted"), err
    finally:
        proc.kill()
        if stuck is not None:
            stuck.close()
