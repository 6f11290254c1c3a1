"""The studio's door, tried by hostile clients over real WebSockets on loopback (viser's own wire format, msgpack):
foreign origins, no secret, a rebound host name; the studio's own client saving and opening outside its folder,
over files it did not open, into folders it would create; numbers and strings no browser sends; a second tab;
clicks that would pile up work; the share tunnel. Nothing outside the folder may change, and the pose changes only
by accepted edits."""

from __future__ import annotations

import math
import os
import urllib.error
import urllib.request

import msgspec
import numpy as np
import pytest
from helpers import wait_for

from op2motion.formats.posefile import read_pose
from op2motion.studio.folder import Workspace
from op2motion.studio.session import PoseEdit

pytest.importorskip("viser")
ROOT = os.path.join(os.path.dirname(__file__), "..")
WALKREADY = os.path.join(ROOT, "poses", "walkready.json")
STOCK = os.path.join(ROOT, "tests", "data", "motion_4096.bin")


@pytest.fixture
def studio(spec, tmp_path):
    """A studio on 127.0.0.1 whose folder is tmp_path/work, opened on work/walkready.json; beside the folder a
    victim file that nothing may touch."""
    from op2motion.studio.server import Studio

    work = tmp_path / "work"
    work.mkdir()
    (work / "walkready.json").write_bytes(open(WALKREADY, "rb").read())
    (work / "other.json").write_text("not the studio's", encoding="utf-8")
    (tmp_path / "victim.json").write_text("precious", encoding="utf-8")
    (tmp_path / "victim.bin").write_bytes(b"x" * 651)
    os.symlink(tmp_path / "victim.json", work / "link.json")
    served = Studio(spec, PoseEdit(spec, read_pose(work / "walkready.json", spec)), workspace=Workspace(work),
                    pose_path=str(work / "walkready.json"))
    try:
        yield served
    finally:
        served.stop()


def _outside_untouched(tmp_path) -> None:
    assert (tmp_path / "victim.json").read_text(encoding="utf-8") == "precious"
    assert (tmp_path / "victim.bin").read_bytes() == b"x" * 651
    assert sorted(p.name for p in tmp_path.iterdir()) == ["victim.bin", "victim.json", "work"]


#: How long the client waits for the server's answer to its close frame [s] (viser drops the connection without
#: answering: the sync client's default 10 s was most of this module's time).
CLOSE_S = 0.2


class Client:
    """A viser client speaking the wire format by hand."""

    def __init__(self, studio, origin: str | None = "own", path: str | None = None):
        import viser
        from websockets.sync.client import connect

        base = f"ws://127.0.0.1:{studio.port}"
        own = f"http://127.0.0.1:{studio.port}"
        clients = len(studio.server.get_clients())
        self.ws = connect(base + (path if path is not None else f"/{studio.gate.secret}"),
                          origin=own if origin == "own" else origin, open_timeout=5, close_timeout=CLOSE_S,
                          subprotocols=[f"viser-v{viser.__version__}"])
        self.send({"type": "ViewerCameraMessage", "wxyz": (1.0, 0.0, 0.0, 0.0), "position": (0.5, 0.5, 0.5),
                   "fov": 1.0, "near": 0.01, "far": 100.0, "image_height": 800, "image_width": 900,
                   "look_at": (0.0, 0.0, 0.2), "up_direction": (0.0, 0.0, 1.0)})    # viser's "connected"
        wait_for(lambda: len(studio.server.get_clients()) > clients, "the client registered")

    def send(self, message: dict) -> None:
        self.ws.send(msgspec.msgpack.encode(message))

    def set(self, handle, value) -> None:
        self.send({"type": "GuiUpdateMessage", "uuid": handle._impl.uuid, "updates": {"value": value}})

    def click(self, handle) -> None:
        self.set(handle, True)

    def close(self) -> None:
        self.ws.close()


def _refusals(studio, kind: str) -> list[str]:
    return [v for k, v in studio.events if k == kind and v.startswith("refused")]


def _handshake(port: int, path: str, headers: list[tuple[str, str]]) -> str:
    """The status line a raw WebSocket opening handshake gets (headers exactly as given, duplicates included)."""
    import base64
    import socket

    lines = [f"GET {path} HTTP/1.1", "Upgrade: websocket", "Connection: Upgrade", "Sec-WebSocket-Version: 13",
             f"Sec-WebSocket-Key: {base64.b64encode(os.urandom(16)).decode()}",
             "Sec-WebSocket-Protocol: viser-v1.1.1", *(f"{k}: {v}" for k, v in headers)]
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        return s.recv(200).decode(errors="replace").splitlines()[0]


@pytest.mark.parametrize("path, headers", [
    ("/{secret}", [("Host", "127.0.0.1:{port}"), ("Origin", "http://evil.example")]),   # any page the user visits
    ("/{secret}", [("Host", "127.0.0.1:{port}")]),                                       # no Origin
    ("/", [("Host", "127.0.0.1:{port}"), ("Origin", "http://127.0.0.1:{port}")]),         # no secret
    ("/wrong", [("Host", "127.0.0.1:{port}"), ("Origin", "http://127.0.0.1:{port}")]),
    ("/{secret}", [("Host", "127.0.0.1:{port}"), ("Origin", "http://127.0.0.1:1")]),      # another port's page
    ("/{secret}", [("Host", "evil.example:{port}"), ("Origin", "http://evil.example:{port}")]),   # DNS rebinding
    ("/{secret}", [("Host", "127.0.0.1:{port}"), ("Host", "evil.example"), ("Origin", "http://127.0.0.1:{port}")]),
    ("/{secret}", [("Host", "127.0.0.1:{port}"), ("Origin", "http://127.0.0.1:{port}"), ("Origin", "null")]),
])
def test_websockets_not_from_the_studios_page_are_refused(studio, path, headers):
    fill = {"port": studio.port, "secret": studio.gate.secret}
    status = _handshake(studio.port, path.format(**fill), [(k, v.format(**fill)) for k, v in headers])
    assert " 403 " in status, status
    own = [("Host", f"127.0.0.1:{studio.port}"), ("Origin", f"http://127.0.0.1:{studio.port}")]
    assert " 101 " in _handshake(studio.port, f"/{studio.gate.secret}", own)       # the page's own: switched


def test_the_page_needs_the_secret_and_this_machines_name(studio):
    own = f"http://127.0.0.1:{studio.port}"
    with urllib.request.urlopen(studio.url, timeout=5) as page:
        assert page.status == 200 and b"<html" in page.read(200).lower()
    for url, headers in ((own + "/", {}), (own + "/wrong/", {}), (studio.url, {"Host": f"evil.example:{studio.port}"})):
        with pytest.raises(urllib.error.HTTPError, match="403"):
            urllib.request.urlopen(urllib.request.Request(url, headers=headers), timeout=5)


def test_saving_outside_the_folder_or_over_files_it_did_not_open_is_refused(studio, tmp_path):
    client = Client(studio)
    try:
        hostile = ["../victim.json", str(tmp_path / "victim.json"), "link.json", "new/dir/x.json", "other.json",
                   "..\\victim.json", "~/x.json", ".hidden.json", "x.txt", "a" * 300 + ".json", "sub/../../victim.json"]
        for i, path in enumerate(hostile):
            client.set(studio._path, path)
            wait_for(lambda: studio._path.value == path, "the save box")
            client.click(studio._save_button)
            wait_for(lambda: len(_refusals(studio, "save")) == i + 1, f"the refusal of {path}")
        _outside_untouched(tmp_path)
        assert (tmp_path / "work" / "other.json").read_text(encoding="utf-8") == "not the studio's"
        assert not (tmp_path / "work" / "new").exists()
        outside = [r.split(", got")[0] for r in _refusals(studio, "save")[:3]]
        assert len(set(outside)) == 1                                # one message for every path outside
        before = (tmp_path / "work" / "walkready.json").read_bytes()
        client.set(studio._path, "walkready.json")                  # the file it opened: only when confirmed
        client.click(studio._save_button)
        wait_for(lambda: any("tick 'overwrite'" in r for r in _refusals(studio, "save")), "the confirmation")
        assert (tmp_path / "work" / "walkready.json").read_bytes() == before
        client.set(studio._overwrite_pose, True)
        wait_for(lambda: studio._overwrite_pose.value is True, "the checkbox")
        client.click(studio._save_button)
        wait_for(lambda: ("save", "walkready.json") in studio.events, "the save")
        client.set(studio._path, "mine.json")                       # a new file: written, then its own
        client.click(studio._save_button)
        wait_for(lambda: ("save", "mine.json") in studio.events, "the new file")
        assert read_pose(tmp_path / "work" / "mine.json", studio.spec).name == "mine"
        assert not [p for p in (tmp_path / "work").iterdir() if p.name.endswith(".tmp")]
        _outside_untouched(tmp_path)
    finally:
        client.close()


def test_opening_outside_the_folder_tells_nothing_about_it(studio, tmp_path):
    client = Client(studio)
    try:
        for i, path in enumerate(("../victim.bin", "../nothing-here.bin", str(tmp_path / "victim.bin"))):
            client.set(studio._action_path, path)
            wait_for(lambda: studio._action_path.value == path, "the file box")
            client.click(studio._open_button)
            wait_for(lambda: len(_refusals(studio, "open")) == i + 1, f"the refusal of {path}")
        said = [r.split(", got")[0] for r in _refusals(studio, "open")]
        assert len(set(said)) == 1 and "651" not in " ".join(_refusals(studio, "open"))
        (tmp_path / "work" / "stock.bin").write_bytes(open(STOCK, "rb").read())
        client.set(studio._action_path, "stock.bin")
        client.click(studio._open_button)
        wait_for(lambda: ("open", "applied") in studio.events, "opening a file inside")
        _outside_untouched(tmp_path)
    finally:
        client.close()


def test_values_no_browser_sends_change_nothing(studio):
    client = Client(studio)
    before = studio.session.servo.copy()
    try:
        hostile = [(studio._sliders["l_knee"], value, None, "slider") for value in (math.nan, math.inf, -1e308)]
        hostile += [(studio._support, "diagonal", None, "support"), (studio._hand, "middle", studio._optimise_button,
                                                                      "optimise"),
                    (studio._page, 1e9, studio._play_button, "play"),       # (NaN there: viser itself refuses it)
                    (studio._step_s, math.nan, studio._add_button, "add")]
        for handle, value, button, kind in hostile:          # one at a time: a handler reads the control's value
            refused = len(_refusals(studio, kind))
            client.set(handle, value)
            if button is not None:
                client.click(button)
            wait_for(lambda: len(_refusals(studio, kind)) > refused, f"{kind} refused for {value!r}")
            assert np.array_equal(studio.session.servo, before) and studio.session.support.value == "double"
        assert studio._support.value == "double" and studio._sliders["l_knee"].value == pytest.approx(
            np.degrees(before[studio.spec.joint_names.index("l_knee")]), abs=1e-3)    # the page is put back too
    finally:
        client.close()


def test_a_second_tab_cannot_edit_while_the_first_does(studio):
    first, second = Client(studio), Client(studio)
    try:
        knee = studio.spec.joint_names.index("l_knee")
        client_value = float(np.degrees(studio.session.servo[knee])) + 5.0
        first.set(studio._sliders["l_knee"], client_value)
        wait_for(lambda: ("slider", "applied") in studio.events, "the first tab's edit")
        held = studio.session.servo.copy()
        second.set(studio._sliders["l_knee"], client_value + 10.0)
        second.set(studio._path, "../victim.json")
        wait_for(lambda: len(_refusals(studio, "slider")) == 1 and _refusals(studio, "input"), "the second tab refused")
        assert np.array_equal(studio.session.servo, held) and studio._path.value == "walkready.json"
        second.click(studio._pen_button)                             # take over, then it may edit
        wait_for(lambda: any(k == "pen" for k, _ in studio.events), "the pen")
        second.set(studio._sliders["l_knee"], client_value + 10.0)
        wait_for(lambda: studio.events.count(("slider", "applied")) == 2, "the second tab's edit")
    finally:
        first.close()
        second.close()


@pytest.mark.physics
def test_clicks_do_not_pile_up_work_and_the_share_tunnel_is_off(studio):
    client = Client(studio)
    try:
        for _ in range(20):
            client.click(studio._check_button)
        client.send({"type": "ShareUrlRequest"})
        wait_for(lambda: any(k == "check" and v in ("STANDS", "FALLS", "FAILS") for k, v in studio.events), "the check")
        assert studio.events.count(("check", "started")) == 1
        assert len(_refusals(studio, "check")) >= 1 and studio.server._share_tunnel is None
    finally:
        client.close()


def test_edits_while_the_optimiser_works_are_refused_and_its_pose_adopted_whole(spec, tmp_path):
    from op2motion.studio.server import Studio

    one_foot = tmp_path / "book_2_44.json"
    one_foot.write_bytes(open(os.path.join(ROOT, "poses", "book_2_44.json"), "rb").read())
    served = Studio(spec, PoseEdit(spec, read_pose(one_foot, spec)), workspace=Workspace(tmp_path),
                    pose_path=str(one_foot))
    client = Client(served)
    try:
        client.click(served._optimise_button)
        wait_for(lambda: served.busy["optimise"], "the optimiser started")
        knee = served.spec.joint_names.index("r_knee")
        client.set(served._sliders["r_knee"], float(np.degrees(served.session.servo[knee])) + 10.0)
        client.click(served._optimise_button)                       # a second optimisation: refused too
        wait_for(lambda: _refusals(served, "slider") and _refusals(served, "optimise"), "the refusals")
        assert "optimiser" in _refusals(served, "slider")[0]
        wait_for(lambda: not served.busy["optimise"], "the optimiser's end")
        outcome = [v for k, v in served.events if k == "optimise" and not v.startswith("refused")]
        assert outcome[-1] in ("reached", "not reached")
        assert served.events.count(("slider", "applied")) == 0
    finally:
        client.close()
        served.stop()
