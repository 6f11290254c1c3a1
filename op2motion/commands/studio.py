"""CLI command studio: the pose studio in the browser."""

from __future__ import annotations

import argparse
import socket
import time
from typing import Any

from op2motion.commands.common import add_command, whole
from op2motion.errors import InputError
from op2motion.robot.spec import Spec


def register(sub: Any) -> None:
    """Add studio."""
    p = add_command(sub, "studio", cmd_studio, "edit a pose in the browser: joints, balance, physics check, save",
                    "Serve the pose studio on a local web page (viser; install with pip install '.[studio]'): "
                    "the robot from the generated URDF, a slider and jog buttons per joint, the support, both "
                    "centres of mass and their margins, the closest links, check in physics, save. Ctrl-C ends it.")
    p.add_argument("pose", nargs="?", metavar="POSE|ACTION_FILE",
                   help="pose file to start from, or a ROBOTIS action file (.bin) to play and edit pages of (starting "
                        "from its page 1's last step); default: the standing pose")
    p.add_argument("--port", type=whole(0, 65535), default=8080, help="port (0: a free one, printed; default 8080)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1, this machine only)")


def _port_free(host: str, port: int) -> None:
    """viser quietly takes the next port when one is in use: refuse instead, naming the port."""
    if port == 0:
        return
    with socket.socket() as s:
        try:
            s.bind((host, port))
        except OSError as exc:
            raise InputError(f"expected a free port, but {host}:{port} is in use ({exc.strerror})", "port") from None


def cmd_studio(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion studio``."""
    from op2motion.formats.posefile import read_pose
    from op2motion.robot.joints import BookAngles, book_to_servo
    from op2motion.robot.pose import Pose
    from op2motion.robot.support import Support
    from op2motion.studio.session import Session

    action = args.pose is not None and args.pose.lower().endswith(".bin")
    if action:
        from op2motion.formats.action import ActionFile

        pose = ActionFile.read(args.pose).pose(1, spec)
    else:
        pose = (read_pose(args.pose, spec) if args.pose else
                Pose("standing", Support.DOUBLE, book_to_servo(BookAngles.standing("left"), spec)[0]))
    _port_free(args.host, args.port)
    try:
        from op2motion.studio.server import Studio
    except ImportError as exc:
        raise InputError(f"expected the studio extra (pip install '.[studio]'): {exc}", "studio") from None
    session = Session(spec, pose)
    if action:
        session.open_action(args.pose)
    studio = Studio(spec, session, args.host, args.port, action_path=args.pose if action else "")
    try:                                  # Ctrl-C from the moment the address is printed ends it cleanly
        print(f"op2motion studio: http://{args.host}:{studio.port} (Ctrl-C ends it)", flush=True)
        while True:
            time.sleep(0.2)
    except KeyboardInterrupt:
        print("op2motion studio: stopped", flush=True)
    finally:
        studio.stop()
    return 0
