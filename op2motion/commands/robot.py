"""CLI command ``op2motion robot``: the real OP2 on its bus (status, read, play, walk) and the emulated one
(emulate). Thin: each calls :mod:`op2motion.onrobot.tasks` or the emulator and prints."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
from typing import TYPE_CHECKING, Any, Callable, Iterator

from op2motion.commands.common import add_command, number, output_path, pose_name, say, ticker, walk_target, whole
from op2motion.commands.deliver import deliver
from op2motion.errors import InputError
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.bus.port import PortRequest
    from op2motion.onrobot.tasks import MotionResult, Options
    from op2motion.tasks.result import TaskResult

MAX_WAIT_S = 600.0
SHARED_PORT_HELP = ("open the port even though another process holds it open: the bridge that serves it (socat's "
                    "pty, which keeps the terminal side open itself; docs/robot.md). Without it such a port is "
                    "refused, naming the process")
ROBOT_BAR = "{desc}: {n:.2f} {unit} [{elapsed}]"     # the loop's time in 8 ms ticks: not a whole count


def register(sub: Any) -> None:
    """Add ``robot status|setup|read|play|walk|stand|getup|emulate``."""
    from op2motion.commands.common import Parser
    from op2motion.formats.actionlayout import NUM_PAGES

    top = sub.add_parser("robot", help="the real OP2 on its bus (status, read, play, walk, stand, getup) and an "
                                       "emulated one",
                         description="Drive the real OP2 from Python over its USB serial bus (Dynamixel Protocol "
                                     "1.0, the CM-730 at ID 200, 20 MX-28), safely; or run an emulated OP2 on a "
                                     "pseudo-terminal to develop without one.")
    inner = top.add_subparsers(dest="robot_command", metavar="ACTION", required=True, parser_class=Parser,
                               help="status, setup, read, play, walk, stand, getup or emulate")
    p = add_command(inner, "status", cmd_status, "the sub-controller, every servo and the IMU; exit 1 if a servo "
                                                 "is missing or reports an error, 2 if a device is of another model")
    _port(p)
    _setup_args(add_command(inner, "setup", cmd_setup, "set every servo's Return Delay Time (EEPROM) so the 8 ms "
                                                       "loop can read them all; written only where it differs"))
    _read_args(add_command(inner, "read", cmd_read, "the robot's present joint angles as a pose file (teach by hand "
                                                    "with --limp)"))
    p = add_command(inner, "play", cmd_play, "a pose, a motion file or an action page on the robot, from where it "
                                             "is")
    _port(p)
    p.add_argument("file", metavar="FILE", help="a pose file, a motion file, or an action file with --page")
    p.add_argument("--page", type=whole(1, NUM_PAGES - 1), help="with an action file: the page to play")
    p.add_argument("--force", action="store_true",
                   help="play it even if op2motion's checks (physics from the present pose) refuse it")
    p = add_command(inner, "walk", cmd_walk, "walk (WalkController with the robot's IMU and joints); ends standing")
    _port(p)
    p.add_argument("--preset", metavar="TOML", help="gait preset file or shipped name (default forward)")
    p.add_argument("--steps", type=whole(1, 200), help="number of steps (default: the preset's)")
    p.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "YAW"),
                   help="walk to this pose instead: x [m], y [m], heading [deg] from the start")
    p.add_argument("--commands", metavar="FILE",
                   help="steer the walk by a command timeline (CSV or JSON, as walk --commands); ends standing "
                        "after its stop")
    p.add_argument("--teleop", action="store_true",
                   help="steer the walk from the keyboard (w/s a/d q/e, space stands, z/c kick, x ends); standard "
                        "input must be the terminal")
    p.add_argument("--action", metavar="FILE", help="steered walks: an action file whose kick pages the kicks play")
    p.add_argument("--get-up", action="store_true",
                   help="steered walks: a fall lowers the torque, the robot gets up and walks on (otherwise a fall "
                        "stops the walk)")
    p.add_argument("--force", action="store_true", help="skip the physics check of the move to the first pose")
    p = add_command(inner, "getup", cmd_getup, "get up from lying (face down, face up or on a side); checked in "
                                               "physics from that side first")
    _port(p)
    p.add_argument("--action", metavar="FILE", help="an action file: its stock pages 10/11 get up when it has them")
    p.add_argument("--force", action="store_true", help="play it even if the physics check says it does not stand")
    p = add_command(inner, "stand", cmd_stand, "stand on both feet side by side in the walk-ready pose: a step "
                                               "closes feet that stand apart (a stopped walk), then a planned move; "
                                               "each checked in physics first")
    _port(p)
    p.add_argument("--force", action="store_true", help="play it even if the physics check says it fails")
    _emulate_args(add_command(inner, "emulate", cmd_emulate,
                              "an emulated OP2 on a pseudo-terminal (a link at --link), byte for byte, physics "
                              "behind it in real time"))


def _read_args(p: argparse.ArgumentParser) -> None:
    """``robot read``'s flags."""
    _port(p)
    p.add_argument("--out", type=output_path, required=True, metavar="POSE", help="pose file to write (atomically)")
    p.add_argument("--name", type=pose_name, help="pose name (default: the file's stem)")
    p.add_argument("--support", choices=("left", "right", "double"), default="double",
                   help="the support the pose stands on (default double)")
    p.add_argument("--limp", nargs="?", const="all", default=None, metavar="JOINTS",
                   help="switch the torque off in these joints first so you can move them by hand: limbs (all, head, "
                        "arms, left_arm, right_arm, legs, left_leg, right_leg) or joint names, comma-separated (bare "
                        "--limp: all); it asks first (--yes); the other joints hold; the angles are read when you "
                        "press Enter (or after --wait), then the torque holds them")
    p.add_argument("--wait", type=number(0.0, MAX_WAIT_S, "s"), default=None, metavar="S",
                   help="with --limp: read after S seconds instead of waiting for Enter")
    p.add_argument("--yes", action="store_true",
                   help="with --limp: do not ask (a standing robot whose legs go limp sags and falls: hold it)")
    p.add_argument("--force", action="store_true",
                   help="write the pose of a robot found fallen (tilted beyond 45°), marked fallen in the file "
                        "(otherwise refused, nothing written)")


def _setup_args(p: argparse.ArgumentParser) -> None:
    _port(p)
    p.add_argument("--return-delay", type=whole(0, 254), required=True, metavar="N",
                   help="the value to set (2 µs units; 0: answer at once, as the OP2 ships)")
    p.add_argument("--yes", action="store_true", help="do not ask: write it (the EEPROM keeps it over power cycles)")


def _port(p: argparse.ArgumentParser) -> None:
    p.add_argument("--port", required=True, metavar="PORT",
                   help="the robot's serial port, e.g. /dev/ttyUSB0; or lockstep[:key=value,...]: an emulated OP2 in "
                        "this process, in lockstep with the wire model (docs/robot.md)")
    p.add_argument("--shared-port", action="store_true", help=SHARED_PORT_HELP)


def port_of(path: str, shared: bool) -> str | PortRequest:
    """The robot's port as the tasks take it: its path, or with ``shared`` (``--shared-port``) a request to open it
    although another process holds it."""
    from op2motion.bus.port import PortRequest

    return PortRequest(path, shared=True) if shared else path


def _robot(args: argparse.Namespace) -> str | PortRequest:
    """The ``robot`` command's port (``--port``, ``--shared-port``)."""
    return port_of(args.port, args.shared_port)


def _emulate_args(p: argparse.ArgumentParser) -> None:
    from op2motion.bus.emulator.body import STARTS
    from op2motion.bus.emulator.faults import BOARDS
    from op2motion.bus.emulator.timing import DEFAULT_LATENCY_TIMER_MS, KERNEL_LATENCY_TIMER_MS
    from op2motion.physics import ENGINES

    p.add_argument("--link", required=True, metavar="PATH", help="where to put the link to the emulated port")
    p.add_argument("--engine", choices=ENGINES, default="mujoco", help="physics engine (default mujoco: faster)")
    p.add_argument("--start", choices=STARTS, default="standing", help="how the robot starts (default standing)")
    p.add_argument("--missing", type=whole(1, 20), nargs="+", default=[], metavar="ID",
                   help="servos not on the bus")
    p.add_argument("--unplug", nargs="+", default=[], metavar="ID@S",
                   help="a servo that goes silent S seconds into the motion (from the first SYNC_WRITE)")
    p.add_argument("--overheat", nargs="+", default=[], metavar="ID@S[:C]",
                   help="a servo at C °C (default 85) from S seconds into the motion")
    p.add_argument("--lose", type=number(0.0, 0.5), default=0.0, metavar="SHARE",
                   help="share of replies lost (e.g. 0.02)")
    p.add_argument("--corrupt", type=number(0.0, 0.5), default=0.0, metavar="SHARE",
                   help="share of replies with one byte changed")
    p.add_argument("--supply", type=number(0.0, 25.5, "V"), default=None, metavar="V",
                   help="supply voltage (default the spec's, 12 V)")
    p.add_argument("--push", nargs="+", default=[], metavar="N@S",
                   help="push the robot forward with N newtons for 0.1 s, S seconds into the motion (e.g. 30@4)")
    p.add_argument("--seed", type=whole(0, 2 ** 31 - 1), default=0, help="seed of the lost and corrupted replies")
    p.add_argument("--board", choices=tuple(BOARDS), default=None,
                   help="the sub-controller it plays: cm730 (DARwIn-OP's, the default) or cm740 (the OP2's): the "
                        "model number it reports")
    p.add_argument("--model", nargs="+", default=[], metavar="ID:NUMBER",
                   help="a device that reports another model number (e.g. 14:12, an AX-12 as r_knee; 200:... the "
                        "board)")
    p.add_argument("--errors", nargs="+", default=[], metavar="ID:BITS",
                   help="a device whose every reply carries these status error bits (e.g. 14:all, 14:0x24)")
    p.add_argument("--wire", choices=("real", "instant"), default="real",
                   help="real (default): the bus's time as a real CM-730 behind its FTDI adapter keeps it (1 Mbps "
                        "bytes, each servo's return delay, 62-byte USB packets, the latency timer); instant: as fast "
                        "as a pseudo-terminal answers")
    p.add_argument("--latency-timer-ms", type=whole(1, 255), default=DEFAULT_LATENCY_TIMER_MS, metavar="MS",
                   help=f"with --wire real: the FTDI adapter's latency timer (default {DEFAULT_LATENCY_TIMER_MS}: what "
                        f"op2motion sets at open; {KERNEL_LATENCY_TIMER_MS}: a current kernel's default, for a "
                        f"program that does not)")
    p.add_argument("--return-delay", type=whole(0, 254), default=None, metavar="N",
                   help="every servo's Return Delay Time register (2 µs units; default 0 as the OP2 ships, 250 as "
                        "an MX-28 from the factory)")
    p.add_argument("--cold", action="store_true",
                   help="the robot just switched on: the servos unpowered (silent, limp) until a program sets the "
                        "board's power register (default: powered and holding the start pose)")
    p.add_argument("--seconds", type=number(0.0, 86400.0, "s"), default=None, metavar="S",
                   help="stop after S seconds (default: run until Ctrl-C)")
    p.add_argument("--truth", type=output_path, metavar="JSON",
                   help="keep this file up to date (every 0.1 s) with what the emulated robot does: the torso's "
                        "position, heading and tilt, each servo's goal, torque and torque limit")


@contextlib.contextmanager
def stop_on_signals() -> Iterator[threading.Event]:
    """An event set by the first Ctrl-C (or SIGTERM): the motion stops safely; a second one raises at once."""
    stop = threading.Event()
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum: int, frame: Any) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    for s in previous:
        signal.signal(s, handler)
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def cmd_status(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot status``."""
    from op2motion.tasks.robot import robot_status

    return deliver(args, robot_status(_robot(args), spec))


def confirmer(args: argparse.Namespace) -> Callable[[str], bool]:
    """How a command confirms what it is about to do (``--yes``; else a question on the terminal, answered y or n;
    with no terminal to ask on, bad input naming ``--yes``)."""
    def confirm(question: str) -> bool:
        if args.yes:
            print(f"op2motion: {question} yes (--yes)", file=sys.stderr, flush=True)
            return True
        if not stdin_is_terminal():
            raise InputError(f"expected --yes to {question.rstrip('?')} (no terminal to ask on)", "yes")
        print(f"op2motion: {question} [y/N] ", end="", file=sys.stderr, flush=True)
        return sys.stdin.readline().strip().lower() in ("y", "yes")

    return confirm


def stdin_is_terminal() -> bool:
    """Whether standard input is a terminal (closed or missing: no)."""
    try:
        return sys.stdin is not None and sys.stdin.isatty()
    except (ValueError, OSError):
        return False


def cmd_setup(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot setup``."""
    from op2motion.tasks.robot import robot_setup

    return deliver(args, robot_setup(_robot(args), spec, args.return_delay, confirmer(args)))


def cmd_read(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot read``: the flags checked before the port is opened (a limp without a way to confirm it or
    to wait for the user: exit 2, nothing done)."""
    from pathlib import Path

    from op2motion.fileio import OutputSet
    from op2motion.onrobot.tasks import Limp
    from op2motion.robot.limbs import describe_joints, select_joints
    from op2motion.tasks.robot import robot_read

    if args.limp is None and args.wait is not None:
        raise InputError("expected --limp with --wait (it is the time to move the limp joints)", "wait")
    if args.limp is None and args.yes:
        raise InputError("expected --limp with --yes (it confirms the limp)", "yes")
    limp = None
    if args.limp is not None:
        joints = select_joints(args.limp, spec.joint_names)
        if not args.yes and not stdin_is_terminal():
            raise InputError(f"expected --yes to switch the torque off in {describe_joints(joints, spec.joint_names)}"
                             f" (no terminal to ask on; nothing done)", "yes")
        if args.wait is None and not stdin_is_terminal():
            raise InputError("expected --wait S with --limp (no terminal: no Enter to wait for)", "wait")
        limp = Limp(joints, confirmer(args), _wait_for_enter if args.wait is None else _announce(args.wait), args.wait)
    outputs = OutputSet({"out": args.out})
    name = args.name or pose_name_of(Path(args.out).stem)
    result = robot_read(_robot(args), spec, name, outputs.paths["out"], args.support, limp, args.force)
    return deliver(args, result, outputs, "none")


def _announce(wait_s: float) -> Callable[[], None]:
    """``robot read --limp --wait S``: a line once the joints are limp (the wait itself is the robot's clock's)."""
    return lambda: print(f"op2motion: the chosen joints are limp: move them; reading in {wait_s:g} s", file=sys.stderr,
                         flush=True)


def _wait_for_enter() -> None:
    """``robot read --limp`` on a terminal: until the user presses Enter."""
    print("op2motion: the chosen joints are limp: move them, then press Enter", file=sys.stderr, flush=True)
    sys.stdin.readline()


def pose_name_of(stem: str) -> str:
    """A pose name from a file stem."""
    from op2motion.robot.pose import safe_pose_name

    return safe_pose_name(stem, "robot")


def _motion(args: argparse.Namespace, task: Callable[[Options], TaskResult[MotionResult]]) -> int:
    """Run a robot motion ``task`` with Ctrl-C handling and progress (its :class:`Options`); deliver its result;
    the exit code."""
    from op2motion.onrobot.tasks import Options

    with stop_on_signals() as stop, ticker(args, "robot", "s", bar_format=ROBOT_BAR) as bar, \
            ticker(args, "check", "s") as check:
        def on_progress(done: float, total: float) -> None:
            check.total = total
            check.update(done - check.n)

        def on_tick(tick: Any) -> None:
            check.close()              # the physics check is over once the loop runs: its bar goes (not left stale)
            bar.update(0.008)

        result = task(Options(args.force, stop, on_tick, on_progress, lambda text: say(args, text)))
    return deliver(args, result)


def cmd_play(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot play``."""
    from op2motion.tasks.robot import robot_play

    return _motion(args, lambda options: robot_play(_robot(args), spec, args.file, args.page, options))


def cmd_walk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot walk``."""
    from op2motion.tasks.robot import RobotWalk, robot_walk

    if args.commands is not None or args.teleop:
        return _steered(args, spec)
    for flag in ("action", "get_up"):
        if getattr(args, flag):
            raise InputError(f"expected --{flag.replace('_', '-')} only with --commands or --teleop (a steered walk)",
                             flag)
    request = RobotWalk(args.preset, args.steps, walk_target(args))
    return _motion(args, lambda options: robot_walk(_robot(args), spec, request, options))


def _steered(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot walk --commands FILE | --teleop``."""
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import read_commands
    from op2motion.gait.envelope import STEER_ENVELOPE
    from op2motion.onrobot.teleop import HELP, Teleop, read_keys
    from op2motion.tasks.robot import SteeredRobotWalk, robot_steered_walk

    for flag in ("steps", "target"):
        if getattr(args, flag) is not None:
            raise InputError(f"expected --{flag} only with a planned walk, not with --commands or --teleop", flag)
    if args.teleop and not stdin_is_terminal():
        # keys from a file or a pipe could neither steer nor end the walk once they ran out (it would walk on for
        # up to an hour): refused before anything moves; a file of commands is what --commands takes
        raise InputError(f"expected a terminal on standard input to steer by keys, got {_stdin_kind()} (the walk "
                         f"could not be steered or ended); --commands FILE steers from a file", "teleop")
    commands = read_commands(args.commands) if args.commands is not None else None
    action = ActionFile.read(args.action) if args.action is not None else None
    if not args.teleop:
        request = SteeredRobotWalk(args.preset, commands, None, action, args.get_up)
        return _motion(args, lambda options: robot_steered_walk(_robot(args), spec, request, options))
    teleop = Teleop(STEER_ENVELOPE, lambda line: say(args, line))
    with read_keys(sys.stdin.fileno(), teleop):
        say(args, HELP)
        request = SteeredRobotWalk(args.preset, commands, teleop, action, args.get_up)
        return _motion(args, lambda options: robot_steered_walk(_robot(args), spec, request, options))


def _stdin_kind() -> str:
    """What standard input is, in words (``a regular file``, ``a named pipe``, ``a character device``, ...)."""
    import os

    from op2motion.fileio import file_kind

    try:
        return f"a {file_kind(os.fstat(sys.stdin.fileno()).st_mode)}"
    except (AttributeError, ValueError, OSError):
        return "none (closed)"


def cmd_stand(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot stand``."""
    from op2motion.tasks.robot import robot_stand

    return _motion(args, lambda options: robot_stand(_robot(args), spec, options))


def cmd_getup(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot getup``."""
    from op2motion.formats.action import ActionFile
    from op2motion.tasks.robot import robot_getup

    action = ActionFile.read(args.action) if args.action is not None else None
    return _motion(args, lambda options: robot_getup(_robot(args), spec, action, options))


def cmd_emulate(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion robot emulate``."""
    from op2motion.bus.emulator.faults import ALL_ERRORS, Faults, parse_pair, parse_timed, with_board
    from op2motion.bus.emulator.server import Emulator
    from op2motion.bus.emulator.timing import INSTANT, WireTiming
    from op2motion.tasks.robot import emulated

    faults = Faults(set(args.missing), [parse_timed(u, "unplug")[:2] for u in args.unplug], args.lose, args.corrupt,
                    [parse_timed(o, "overheat", 85.0) for o in args.overheat], args.supply, args.seed,
                    [(float(n), t) for n, t, _ in (parse_timed(p, "push", first="N") for p in args.push)],
                    with_board(dict(parse_pair(m, "model") for m in args.model), args.board, "board"),
                    dict(parse_pair(e, "errors", ALL_ERRORS) for e in args.errors))
    timing = INSTANT if args.wire == "instant" else WireTiming(latency_timer_s=args.latency_timer_ms / 1000.0)
    emulator = Emulator(spec, args.engine, args.start, faults, args.truth, timing, args.return_delay, args.cold)
    interrupted = False
    try:
        with stop_on_signals() as stop:
            pty = emulator.open(args.link)
            print(f"op2motion: emulated OP2 on {args.link} -> {pty} ({args.engine}, {args.start}, {timing.describe()}"
                  f"{', ' + ', '.join(faults.describe()) if faults.describe() else ''}); Ctrl-C stops it",
                  file=sys.stderr, flush=True)
            if args.seconds is not None:
                timer = threading.Timer(args.seconds, stop.set)
                timer.daemon = True
                timer.start()
            emulator.serve(stop)
            interrupted = args.seconds is None
    finally:
        emulator.close()
    return deliver(args, emulated(emulator, args.link, args.engine, args.start, faults, interrupted))
