"""The pose studio's page: viser serves a three.js view of the robot and the controls; :class:`Studio` wires them to
a :class:`~.session.PoseEdit`.

The robot is drawn from the generated URDF (its collision shapes: the bodies physics simulates), placed with its
stance sole on the floor at the origin; beside it the support polygon, both centres of mass with their ground
projections, and the readout (margins, swing-foot clearance, the closest links, red on a collision). Per joint a
slider over its mechanical range and jog buttons; a typed entry (joint, degrees) for exact values; the support
choice; "check in physics" runs the check on a worker thread (the page stays live) and draws the settled pose as a
grey ghost; "save pose" writes the pose file atomically. Every edit the page makes is recorded in
:attr:`Studio.events` (what the Python side saw), and refused edits show their message in the page.

Security (docs/studio.md): the page and its WebSocket only behind the per-run secret and from the studio's
own origin (:mod:`.guard`); files only inside one folder, overwriting only files the studio opened or created,
after confirmation (:mod:`.folder`); one editing tab, all-or-nothing edits, one check and one optimisation at a
time (:mod:`.edits`, :mod:`.long_work`).
"""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.model.urdf import build_urdf
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side
from op2motion.studio.actions import ActionPanel
from op2motion.studio.edits import Edits
from op2motion.studio.folder import Workspace
from op2motion.studio.guard import Gate, guarded_viser, new_secret
from op2motion.studio.long_work import LongWork
from op2motion.studio.robot_panel import RobotPanel
from op2motion.studio.root_pose import root_in_sole, wxyz
from op2motion.studio.session import PoseEdit, Readout

JOG_STEPS = ("-5°", "-1°", "+1°", "+5°")
PURPLE, GREEN = (0.55, 0.25, 0.75), (0.1, 0.6, 0.1)


class Studio(Edits, LongWork, ActionPanel, RobotPanel):
    """A running studio page on ``host:port`` (port 0: a free one, read back in :attr:`port`); open :attr:`url`.

    Args:
        spec: The robot.
        session: The pose under edit.
        host: Address to listen on (127.0.0.1: this machine only).
        port: Port (0: a free one).
        action_path: An action file opened with the studio (inside ``workspace``), or "".
        workspace: The folder the page may read and write (default: the current folder).
        pose_path: The pose file the session came from (inside ``workspace``), the save box's default.
        follower: A robot following the pose (:class:`op2motion.onrobot.follow.Follower`, started), or None.
    """

    def __init__(self, spec: Spec, session: PoseEdit, host: str = "127.0.0.1", port: int = 0, action_path: str = "",
                 workspace: Workspace | None = None, pose_path: str = "", follower: Any = None):
        import yourdfpy
        from viser.extras import ViserUrdf

        self.spec, self.session, self.follower = spec, session, follower
        self.workspace = workspace if workspace is not None else Workspace(".")
        self._opened_path = self.workspace.relative(self.workspace.claim(action_path)) if action_path else ""
        self._pose_path = self.workspace.relative(self.workspace.claim(pose_path)) if pose_path else ""
        self._quiet = False
        self.gate = Gate(host, new_secret())                  # a fresh secret for every run
        with contextlib.redirect_stdout(io.StringIO()):        # viser's banner: the CLI prints its own line
            self.server = guarded_viser(host, port, self.gate)
        self.port = int(self.server.get_port())
        shown = host if ":" not in host else f"[{host}]"
        self.url = f"http://{'127.0.0.1' if host in ('0.0.0.0', '::') else shown}:{self.port}/{self.gate.secret}/"
        self._init_edits()
        self.server.scene.configure_environment_map(hdri=None)
        with tempfile.TemporaryDirectory(prefix="op2motion-studio-") as tmp:
            path = Path(tmp) / "op2.urdf"
            path.write_text(build_urdf(spec), encoding="utf-8")
            urdf = yourdfpy.URDF.load(str(path), build_collision_scene_graph=True, load_collision_meshes=True)
        self._robot = ViserUrdf(self.server, urdf, root_node_name="/robot", load_meshes=False,
                                load_collision_meshes=True, collision_mesh_color_override=(0.75, 0.75, 0.8))
        self._ghost: Any = None
        self._urdf = urdf
        self._order = list(self._robot.get_actuated_joint_names())
        self.server.scene.add_grid("/floor", width=0.6, height=0.6, cell_size=0.05)
        self._targets: dict[str, Any] = {}
        self._dragging = False
        self._build_gui()
        self._build_targets(session.readout())
        self.server.initial_camera.position = (0.55, 0.45, 0.35)
        self.server.initial_camera.look_at = (0.0, 0.0, 0.18)
        self._show(session.readout())

    # -- the page ------------------------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        self._readout = gui.add_markdown("")
        self._message = gui.add_markdown("")
        self._support = gui.add_dropdown("support", ("left", "right", "double"),
                                         initial_value=self.session.support.value)
        self._support.on_update(lambda e: None if e.client_id is None else self._edit(
            "support", lambda: self.session.set_support(self._support.value), e))
        self._pen_button = gui.add_button("edit in this tab")
        self._pen_button.on_click(self._take_pen)
        self._check_button = gui.add_button("check in physics")
        self._check_button.on_click(self._start_check)
        self._verdict = gui.add_markdown("physics: not checked")
        self._target_goal: dict[str, tuple[float, float, float]] = {}
        with gui.add_folder("optimise"):
            self._hand = self._guard_input(gui.add_dropdown("hand", ("left", "right")))
            self._optimise_button = gui.add_button("optimise to the hand target")
            self._optimise_button.on_click(self._start_optimise)
            self._pins = self._guard_input(gui.add_text("pinned joints", "",
                                                        hint="comma-separated joint names kept as they are"))
            gui.add_button("balance (keep the hand and the pins)").on_click(self._start_balance)
            self._progress = gui.add_progress_bar(0.0, visible=False)
        with gui.add_folder("type a value"):
            self._joint = self._guard_input(gui.add_dropdown("joint", tuple(self.spec.joint_names)))
            self._value = self._guard_input(gui.add_text("degrees", ""))
            gui.add_button("set").on_click(lambda e: self._edit(
                "set", lambda: self.session.set_joint(self._joint.value, self._value.value), e))
        with gui.add_folder("save"):
            self._path = self._guard_input(gui.add_text(
                "pose file", self._pose_path or f"{self.session.name}.json",
                hint=f"a .json file name inside {self.workspace.root}"))
            self._overwrite_pose = self._guard_input(gui.add_checkbox("overwrite", False))
            self._save_button = gui.add_button("save pose")
            self._save_button.on_click(self._save)
        self._build_action_gui()
        self._build_robot_gui()
        with gui.add_folder("joint table", expand_by_default=False):
            self._table = gui.add_markdown("")
        self._sliders: dict[str, Any] = {}
        with gui.add_folder("joints"):
            for joint, state in zip(self.spec.joints, self.session.readout().joints):
                lo, hi = state.mechanical
                slider = gui.add_slider(joint.name, min=lo, max=hi, step=0.5, initial_value=state.degrees)
                slider.on_update(self._slider_handler(joint.name, slider))
                jog = gui.add_button_group(f"{joint.name} jog", JOG_STEPS)
                jog.on_click(self._jog_handler(joint.name))
                self._sliders[joint.name] = slider

    def _build_targets(self, readout: Readout) -> None:
        """A draggable target at each hand: dragging moves that arm by the arm IK."""
        for hand in ("left", "right"):
            control = self.server.scene.add_transform_controls(f"/target/{hand}", scale=0.06, disable_rotations=True,
                                                               position=readout.hands[f"{hand}_hand"])
            control.on_update(self._target_handler(hand, control))
            self._targets[hand] = control

    def _target_handler(self, hand: Side, control: Any) -> Any:
        def dragged(event: Any) -> None:
            self._dragging = True
            try:
                self._edit("target", lambda: self._reach(hand, tuple(control.position)), event)
            finally:
                self._dragging = False
        return dragged

    def _reach(self, hand: Side, target: tuple[float, float, float]) -> Readout:
        readout, left = self.session.reach(hand, target)
        self._target_goal[hand] = target
        self._verdict.content = (f"{hand} hand {left * 1000:.1f} mm from its target"
                                 + ("" if left < 0.002 else " (out of the arm's reach: optimise to get there)"))
        return readout

    def _slider_handler(self, name: str, slider: Any) -> Any:
        def moved(event: Any) -> None:
            if event.client_id is not None:       # from a tab (not the page following the pose)
                self._edit("slider", lambda: self.session.set_joint(name, slider.value), event)
        return moved

    def _jog_handler(self, name: str) -> Any:
        def jogged(event: Any) -> None:
            self._edit("jog", lambda: self.session.jog(name, _jog_degrees(event.target.value)), event)
        return jogged

    def _show(self, readout: Readout) -> None:
        """Draw the pose and its readout."""
        s = self.session
        rot, origin = root_in_sole(self.spec, s.servo, s.support.stance)
        self.server.scene.add_frame("/robot", wxyz=wxyz(rot), position=tuple(origin), show_axes=False)
        by_name = dict(zip(self.spec.joint_names, s.servo))
        self._robot.update_cfg(np.array([by_name[n] for n in self._order]))
        ring = np.array([(x, y, 0.001) for x, y in readout.polygon])
        if len(ring):
            self.server.scene.add_line_segments("/support", np.stack([ring, np.roll(ring, -1, axis=0)], axis=1),
                                                colors=PURPLE, thickness=3.0)
        for hand, control in self._targets.items():
            if not self._dragging:                  # the targets follow the hands unless one is being dragged
                control.position = readout.hands[f"{hand}_hand"]
        for name, com, rgb in (("full", readout.com_full, PURPLE), ("lumped", readout.com_lumped, GREEN)):
            self.server.scene.add_icosphere(f"/com/{name}", radius=0.008, color=rgb, position=com)
            self.server.scene.add_icosphere(f"/com/{name}_ground", radius=0.004, color=rgb,
                                            position=(com[0], com[1], 0.0))
        self._quiet = True                    # the sliders follow the pose (events from Python edit nothing)
        try:
            if self._support.value != s.support.value:
                self._support.value = s.support.value
            for state in readout.joints:
                if not abs(self._sliders[state.name].value - state.degrees) <= 1e-6:     # NaN too
                    self._sliders[state.name].value = state.degrees
        finally:
            self._quiet = False
        marks = [f"{j.name} {j.degrees:+.1f}° ({j.ticks}){' outside cable-safe' if j.outside_cable_safe else ''}"
                 for j in readout.joints if j.outside_cable_safe]
        self._follow()
        self._table.content = "| joint | deg | ticks | cable-safe |\n|---|---|---|---|\n" + "\n".join(
            f"| {j.name} | {j.degrees:+.1f} | {j.ticks} | {j.cable_safe[0]:.0f}..{j.cable_safe[1]:.0f}"
            f"{' **outside**' if j.outside_cable_safe else ''} |" for j in readout.joints)
        tint = "red" if readout.colliding else "green"
        self._readout.content = ("\n\n".join(readout.lines()) + f"\n\n<span style='color:{tint}'>"
                                 f"{'self-collision' if readout.colliding else 'no self-collision'}</span>"
                                 + ("\n\n" + "\n\n".join(marks) if marks else ""))

    def _save(self, event: Any = None) -> None:
        """Write the pose inside the studio's folder (see :mod:`.folder`)."""
        from op2motion.robot.pose import check_pose_name

        with self._lock:
            why = self._pen(event)
            if why is not None:
                self._refused("save", why, event)
                return
            try:
                path = self.workspace.for_writing(self._path.value, ".json", "pose file",
                                                  bool(self._overwrite_pose.value))
                with contextlib.suppress(Op2MotionError):       # the pose takes the file's name when it can
                    self.session.name = check_pose_name(path.stem)
                self.session.save(path)
            except (Op2MotionError, OSError) as exc:
                self._refused("save", str(exc), event)
                return
            self.workspace.claim(path)
            self._settle_input(self._overwrite_pose, False)
            shown = self.workspace.relative(path)
            self._message.content = f"saved {shown}"
            self.events.append(("save", shown))

    def stop(self) -> None:
        """End the server."""
        self.server.stop()


def _jog_degrees(label: object) -> float:
    """A jog button's label ("-5°" ... "+5°") as degrees; anything else is refused."""
    if label not in JOG_STEPS:
        raise ValueError(f"expected one of {', '.join(JOG_STEPS)}, got {label!r}")
    return float(str(label).rstrip("°"))
