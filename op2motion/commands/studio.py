"""CLI command studio: the pose studio in the browser."""

from __future__ import annotations

import argparse
import contextlib
import errno
import socket
import sys
import threading
import time
from pathlib import Path
from typing import Any

from op2motion.commands.common import add_command, whole
from op2motion.commands.robot import SHARED_PORT_HELP
from op2motion.errors import InputError, Interrupted, Op2MotionError
from op2motion.robot.spec import Spec

RESOLVE_TIMEOUT_S = 5.0      # a host name that does not resolve in this long is refused [s]
STOP_WAIT_S = 1.5            # the server gets this long to close its connections on Ctrl-C [s]


def register(sub: Any) -> None:
    """Add studio."""
    p = add_command(sub, "studio", cmd_studio, "edit a pose in the browser: joints, balance, physics check, save",
                    "Serve the pose studio on a local web page (viser; install with pip install '.[studio]'): "
                    "the robot from the generated URDF, a slider and jog buttons per joint, the support, both "
                    "centres of mass and their margins, the closest links, check in physics, save. The printed "
                    "address carries a secret; the page saves and opens files only inside one folder. Ctrl-C ends it.")
    p.add_argument("pose", nargs="?", metavar="POSE|ACTION_FILE",
                   help="pose file to start from, or a ROBOTIS action file (.bin) to play and edit pages of (starting "
                        "from its page 1's last step); default: the standing pose")
    p.add_argument("--port", type=whole(0, 65535), default=8080, help="port (0: a free one, printed; default 8080)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1, this machine only; another address lets other "
                        "machines that have the printed address edit and save files in the folder)")
    p.add_argument("--robot", metavar="PORT",
                   help="an OP2 on this serial port (or an emulated one, op2motion robot emulate) follows the pose at "
                        "a capped speed; the page can read the pose from it (docs/robot.md)")
    p.add_argument("--shared-port", action="store_true", help=f"with --robot: {SHARED_PORT_HELP}")
    p.add_argument("--workdir", metavar="DIR",
                   help="the one folder the page may open and save files in (default: the folder of POSE, or the "
                        "current folder)")


def _resolve(host: str, port: int) -> tuple[int, Any]:
    """The address family and socket address ``host`` resolves to, within :data:`RESOLVE_TIMEOUT_S`."""
    if not host.strip() or host != host.strip():
        raise InputError(f"expected an address to listen on (127.0.0.1, or 0.0.0.0 for every interface), got "
                         f"{host!r}", "host")
    found: list[Any] = []

    def lookup() -> None:
        try:
            found.append(socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)[0])
        except (OSError, UnicodeError) as exc:
            found.append(exc)

    worker = threading.Thread(target=lookup, daemon=True)
    worker.start()
    worker.join(RESOLVE_TIMEOUT_S)
    if not found:
        raise InputError(f"expected a host name that resolves, got {host!r} (no answer in {RESOLVE_TIMEOUT_S:g} s)",
                         "host")
    if isinstance(found[0], BaseException):
        raise InputError(f"expected an address of this machine or a name that resolves, got {host!r}", "host")
    family, _, _, _, address = found[0]
    return family, address


def check_listen(host: str, port: int) -> None:
    """Refuse, naming the right flag, a host that does not resolve or is not this machine's, and a port in use or
    not allowed (viser would quietly take the next port, or wait forever on an address it cannot bind)."""
    family, address = _resolve(host, port)
    with socket.socket(family, socket.SOCK_STREAM) as s:
        try:
            s.bind(address)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                raise InputError(f"expected a free port, but {host}:{port} is in use", "port") from None
            if exc.errno == errno.EACCES:
                raise InputError(f"expected a port this user may open (1024 and up), got {port}", "port") from None
            raise InputError(f"expected an address of this machine, got {host!r} ({exc.strerror})", "host") from None


def _folder(args: argparse.Namespace) -> Path:
    """The studio's folder: ``--workdir``, else the folder of the file given, else the current folder; a file given
    must lie inside it."""
    from op2motion.studio.folder import Workspace

    given = Path(args.pose).resolve() if args.pose else None
    root = Path(args.workdir) if args.workdir else (given.parent if given is not None else Path("."))
    workspace = Workspace(root)
    if given is not None and not given.is_relative_to(workspace.root):
        raise InputError(f"expected {args.pose} inside the studio's folder {workspace.root}", "workdir")
    return workspace.root


def cmd_studio(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion studio``."""
    from op2motion.formats.posefile import read_pose
    from op2motion.robot.joints import BookAngles, book_to_servo
    from op2motion.robot.pose import Pose
    from op2motion.robot.support import Support
    from op2motion.studio.folder import Workspace
    from op2motion.studio.guard import is_loopback
    from op2motion.studio.session import PoseEdit

    if args.shared_port and args.robot is None:
        raise InputError("expected --robot with --shared-port (it opens the robot's port)", "shared_port")
    action = args.pose is not None and args.pose.lower().endswith(".bin")
    if action:
        from op2motion.formats.action import ActionFile

        pose = ActionFile.read(args.pose).pose(1, spec)
    else:
        pose = (read_pose(args.pose, spec) if args.pose else
                Pose("standing", Support.DOUBLE, book_to_servo(BookAngles.standing("left"), spec)[0]))
    workspace = Workspace(_folder(args))
    check_listen(args.host, args.port)
    try:
        from op2motion.studio.server import Studio
    except ImportError as exc:
        raise InputError(f"expected the studio extra (pip install '.[studio]'): {exc}", "studio") from None
    session = PoseEdit(spec, pose)
    if action:
        session.open_action(args.pose)
    follower = _follower(args.robot, args.shared_port, spec)
    try:
        studio = Studio(spec, session, args.host, args.port, action_path=args.pose if action else "",
                        workspace=workspace, pose_path="" if action or not args.pose else args.pose,
                        follower=follower)
    except BaseException:
        if follower is not None:
            follower.close()
        raise
    try:                                  # Ctrl-C from the moment the address is printed ends it cleanly
        if not is_loopback(args.host):
            print(f"op2motion studio: warning: listening on {args.host}, not only this machine: whoever has the "
                  f"address below can edit poses and save files in {workspace.root}", file=sys.stderr, flush=True)
        print(f"op2motion studio: {studio.url} (files in {workspace.root}; Ctrl-C ends it)", flush=True)
        while True:
            time.sleep(0.2)
    except KeyboardInterrupt:
        raise Interrupted("studio stopped") from None
    finally:
        _stop(studio)


def _follower(port: str | None, shared: bool, spec: Spec) -> Any:
    """The robot on ``port`` (``shared``: although another process holds it) following the pose (started: torque on
    where its joints are), or None. An error about the robot's port names ``--robot`` (``--port`` is the page's)."""
    if port is None:
        return None
    from op2motion.commands.robot import port_of
    from op2motion.onrobot.follow import Follower

    follower = Follower(port_of(port, shared), spec)
    try:
        follower.start()
    except Op2MotionError as exc:
        if exc.param == "port":
            exc.param = "robot"
        raise
    return follower


def _stop(studio: Any) -> None:
    """End the server, waiting at most :data:`STOP_WAIT_S` (a client that stopped reading cannot hold the exit);
    a robot following the pose stops where it is (the servos hold)."""
    from op2motion.fileio import remove_temps

    closer = threading.Thread(target=studio.stop, daemon=True)
    closer.start()
    if studio.follower is not None:
        with contextlib.suppress(Exception):
            studio.follower.close()
    closer.join(STOP_WAIT_S)
    remove_temps()
