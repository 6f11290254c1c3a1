"""The pose studio's page: viser serves a three.js view of the robot and the controls; :class:`Studio` wires them to
a :class:`~.session.Session`.

The robot is drawn from the generated URDF (its collision shapes: the bodies physics simulates), placed with its
stance sole on the floor at the origin; beside it the support polygon, both centres of mass with their ground
projections, and the readout (margins, swing-foot clearance, the closest links, red on a collision). Per joint a
slider over its mechanical range and jog buttons; a typed entry (joint, degrees) for exact values; the support
choice; "check in physics" runs the check on a worker thread (the page stays live) and draws the settled pose as a
grey ghost; "save pose" writes the pose file atomically. Every edit the page makes is recorded in
:attr:`Studio.events` (what the Python side saw), and refused edits show their message in the page.
"""

from __future__ import annotations

import contextlib
import io
import tempfile
import threading
from pathlib import Path
from typing import Any

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.kinematics.tree import link_frames
from op2motion.model.urdf import build_urdf
from op2motion.robot.spec import Spec
from op2motion.studio.session import Readout, Session

JOG_STEPS = ("-5°", "-1°", "+1°", "+5°")
CHECK_SECONDS = 3.0
PURPLE, GREEN, RED, GREY = (0.55, 0.25, 0.75), (0.1, 0.6, 0.1), (0.8, 0.1, 0.1), (0.6, 0.6, 0.6)


def _wxyz(rot: np.ndarray) -> tuple[float, float, float, float]:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(rot).as_quat()
    return float(w), float(x), float(y), float(z)


def root_in_sole(spec: Spec, servo: np.ndarray, stance: str) -> tuple[np.ndarray, np.ndarray]:
    """The torso (URDF root) frame in the stance sole frame: rotation (3, 3) and origin (3,) [m]."""
    rot, origin = link_frames(spec, servo)[spec.joint(f"{stance[0]}_ank_roll").child]
    sole = origin + rot @ np.array([0.0, 0.0, -spec.foot.sole_below_ankle])
    return rot.T, -rot.T @ sole


class Studio:
    """A running studio page on ``host:port`` (port 0: a free one, read back in :attr:`port`)."""

    def __init__(self, spec: Spec, session: Session, host: str = "127.0.0.1", port: int = 0, action_path: str = ""):
        import viser
        import yourdfpy
        from viser.extras import ViserUrdf

        self.spec, self.session, self._opened_path = spec, session, action_path
        self.events: list[tuple[str, str]] = []
        self._lock, self._quiet = threading.Lock(), False
        with contextlib.redirect_stdout(io.StringIO()):        # viser's banner: the CLI prints its own line
            self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.port = int(self.server.get_port())
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
        self._support.on_update(lambda _: self._edit("support", lambda: self.session.set_support(self._support.value)))
        check = gui.add_button("check in physics")
        check.on_click(lambda _: self._start_check())
        self._verdict = gui.add_markdown("physics: not checked")
        self._target_goal: dict[str, tuple[float, float, float]] = {}
        with gui.add_folder("optimise"):
            self._hand = gui.add_dropdown("hand", ("left", "right"))
            gui.add_button("optimise to the hand target").on_click(lambda _: self._start_optimise())
            self._progress = gui.add_progress_bar(0.0, visible=False)
        with gui.add_folder("type a value"):
            self._joint = gui.add_dropdown("joint", tuple(self.spec.joint_names))
            self._value = gui.add_text("degrees", "")
            gui.add_button("set").on_click(lambda _: self._edit(
                "set", lambda: self.session.set_joint(self._joint.value, self._value.value)))
        with gui.add_folder("save"):
            self._path = gui.add_text("pose file", f"poses/{self.session.name}.json")
            gui.add_button("save pose").on_click(lambda _: self._save())
        self._build_action_gui()
        self._sliders: dict[str, Any] = {}
        with gui.add_folder("joints"):
            for joint, state in zip(self.spec.joints, self.session.readout().joints):
                lo, hi = state.mechanical
                slider = gui.add_slider(joint.name, min=lo, max=hi, step=0.5, initial_value=state.degrees)
                slider.on_update(self._slider_handler(joint.name, slider))
                jog = gui.add_button_group(f"{joint.name} jog", JOG_STEPS)
                jog.on_click(self._jog_handler(joint.name))
                self._sliders[joint.name] = slider

    def _build_action_gui(self) -> None:
        """Open an action file, play and scrub a page, put the pose on a page and save the file."""
        gui = self.server.gui
        with gui.add_folder("action file"):
            self._action_path = gui.add_text("file", self._opened_path)
            gui.add_button("open").on_click(lambda _: self._action_step("open", lambda: self._open()))
            self._page = gui.add_number("page", 1, min=1, max=255, step=1)
            gui.add_button("play page").on_click(lambda _: self._action_step("play", lambda: self._play()))
            self._time = gui.add_slider("time [s]", min=0.0, max=1.0, step=0.008, initial_value=0.0)
            self._time.on_update(lambda _: None if self._quiet else self._edit(
                "scrub", lambda: self.session.scrub(self._time.value)))
            self._step_s = gui.add_number("step [s]", 1.0, min=0.024, max=2.04, step=0.008)
            self._overwrite = gui.add_checkbox("overwrite an occupied page", False)
            gui.add_button("put the pose on the page").on_click(lambda _: self._action_step("add", self._add))
            gui.add_button("save action file").on_click(lambda _: self._action_step("save action", lambda: (
                f"saved {self.session.save_action(self._action_path.value)}")))

    def _add(self) -> str:
        page = self.session.add_to_page(int(self._page.value), float(self._step_s.value), bool(self._overwrite.value))
        return f"the pose is page {page} (not saved yet: save the action file)"

    def _open(self) -> str:
        used = self.session.open_action(self._action_path.value)
        return f"opened {self._action_path.value}: {used} pages in use"

    def _play(self) -> str:
        length = self.session.play(int(self._page.value))
        self._quiet = True
        try:
            self._time.max = max(length, 0.008)
            self._time.value = 0.0  # type: ignore[misc]
        finally:
            self._quiet = False
        self._show(self.session.scrub(0.0))
        return f"page {int(self._page.value)}: {length:.2f} s of 8-ms goals; scrub with the time slider"

    def _action_step(self, kind: str, action: Any) -> None:
        """One action-file step; a refused one shows why and changes nothing."""
        with self._lock:
            try:
                text = action()
            except (Op2MotionError, OSError) as exc:
                self.events.append((kind, f"refused: {exc}"))
                self._message.content = f"**refused**: {exc}"
                return
            self.events.append((kind, "applied"))
            self._message.content = text

    def _build_targets(self, readout: Readout) -> None:
        """A draggable target at each hand: dragging moves that arm by the arm IK."""
        for hand in ("left", "right"):
            control = self.server.scene.add_transform_controls(f"/target/{hand}", scale=0.06, disable_rotations=True,
                                                               position=readout.hands[f"{hand}_hand"])
            control.on_update(self._target_handler(hand, control))
            self._targets[hand] = control

    def _target_handler(self, hand: str, control: Any) -> Any:
        def dragged(_: Any) -> None:
            self._dragging = True
            try:
                self._edit("target", lambda: self._reach(hand, tuple(control.position)))
            finally:
                self._dragging = False
        return dragged

    def _reach(self, hand: str, target: tuple[float, float, float]) -> Readout:
        readout, left = self.session.reach(hand, target)
        self._target_goal[hand] = target
        self._verdict.content = (f"{hand} hand {left * 1000:.1f} mm from its target"
                                 + ("" if left < 0.002 else " (out of the arm's reach: optimise to get there)"))
        return readout

    def _slider_handler(self, name: str, slider: Any) -> Any:
        def moved(_: Any) -> None:
            if not self._quiet:                   # not when the page follows the pose
                self._edit("slider", lambda: self.session.set_joint(name, slider.value))
        return moved

    def _jog_handler(self, name: str) -> Any:
        def jogged(event: Any) -> None:
            self._edit("jog", lambda: self.session.jog(name, float(str(event.target.value).rstrip("°"))))
        return jogged

    def _edit(self, kind: str, action: Any) -> None:
        """Apply one edit; a refused one leaves the pose and shows why."""
        with self._lock:
            try:
                readout = action()
            except Op2MotionError as exc:
                self.events.append((kind, f"refused: {exc}"))
                self._message.content = f"**refused**: {exc}"
                return
            self.events.append((kind, "applied"))
            self._message.content = ""
            self._show(readout)

    def _show(self, readout: Readout) -> None:
        """Draw the pose and its readout."""
        s = self.session
        rot, origin = root_in_sole(self.spec, s.servo, s.support.stance)
        self.server.scene.add_frame("/robot", wxyz=_wxyz(rot), position=tuple(origin), show_axes=False)
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
        self._quiet = True                    # the sliders follow the pose without editing it again
        try:
            for state in readout.joints:
                if abs(self._sliders[state.name].value - state.degrees) > 1e-6:
                    self._sliders[state.name].value = state.degrees
        finally:
            self._quiet = False
        marks = [f"{j.name} {j.degrees:+.1f}° ({j.ticks}){' outside cable-safe' if j.outside_cable_safe else ''}"
                 for j in readout.joints if j.outside_cable_safe]
        tint = "red" if readout.colliding else "green"
        self._readout.content = ("\n\n".join(readout.lines()) + f"\n\n<span style='color:{tint}'>"
                                 f"{'self-collision' if readout.colliding else 'no self-collision'}</span>"
                                 + ("\n\n" + "\n\n".join(marks) if marks else ""))

    # -- long work ----------------------------------------------------------------------------------------------
    def _start_check(self) -> None:
        self.events.append(("check", "started"))
        self._verdict.content = "physics: checking…"
        threading.Thread(target=self._check, daemon=True).start()

    def _check(self) -> None:
        from op2motion.physics import Schedule, Setup, check

        s = self.session
        try:
            run = check(Schedule.hold(s.servo.copy(), s.support, self.spec, CHECK_SECONDS), self.spec,
                        setup=Setup(keep_track=True)).run
        except Op2MotionError as exc:
            self._verdict.content = f"physics: **could not check**: {exc}"
            self.events.append(("check", f"refused: {exc}"))
            return
        verdict = "STANDS" if run.stable else "FALLS" if run.fell else "FAILS"
        self._verdict.content = (f"physics: **{verdict}** ({', '.join(run.reasons) or 'no failure'}), margin "
                                 f"{run.support_margin_m * 1000:+.1f} mm, {run.engine} {run.seconds:g} s ({run.ended})")
        self._draw_ghost(run.track.q[-1])
        self.events.append(("check", verdict))

    def _start_optimise(self) -> None:
        hand = self._hand.value
        target = self._target_goal.get(hand, tuple(self._targets[hand].position))
        if self.session.support.is_double:
            self._message.content = "**refused**: the optimiser stands on one foot: choose left or right support"
            self.events.append(("optimise", "refused: double support"))
            return
        self.events.append(("optimise", "started"))
        self._progress.visible = True
        self._progress.value = 0.0  # type: ignore[misc]
        threading.Thread(target=self._optimise, args=(hand, target), daemon=True).start()

    def _optimise(self, hand: str, target: tuple[float, float, float]) -> None:
        from op2motion.posture.cost import PostureProblem
        from op2motion.posture.pso import PSOSettings
        from op2motion.workflow import solve

        settings, done = PSOSettings(), [0]

        def tick(_: float) -> None:
            done[0] += 1
            if done[0] % 10 == 0:
                self._progress.value = min(100.0, 100.0 * done[0] / settings.iterations)  # type: ignore[misc]
        try:
            problem = PostureProblem(self.session.support.value, hand, target, 1.0)
            outcome = solve(problem, self.spec, settings, restarts=0, on_iteration=tick)
        except Op2MotionError as exc:
            self._message.content = f"**could not optimise**: {exc}"
            self.events.append(("optimise", f"refused: {exc}"))
            return
        finally:
            self._progress.visible = False
        result = outcome.result
        self._verdict.content = f"optimiser: {result.message}"
        if outcome.ok:
            self._edit("optimise", lambda: self._adopt(outcome.pose(self.session.name, self.spec).servo))
        self.events.append(("optimise", "reached" if outcome.ok else "not reached"))

    def _adopt(self, servo: np.ndarray) -> Readout:
        self.session.servo = np.array(servo, dtype=float)
        return self.session.readout()

    def _draw_ghost(self, settled: np.ndarray) -> None:
        from viser.extras import ViserUrdf

        if self._ghost is None:
            self._ghost = ViserUrdf(self.server, self._urdf, root_node_name="/ghost", load_meshes=False,
                                    load_collision_meshes=True, collision_mesh_color_override=(*GREY, 0.35))
        rot, origin = root_in_sole(self.spec, settled, self.session.support.stance)
        self.server.scene.add_frame("/ghost", wxyz=_wxyz(rot), position=tuple(origin), show_axes=False)
        by_name = dict(zip(self.spec.joint_names, settled))
        self._ghost.update_cfg(np.array([by_name[n] for n in self._order]))

    def _save(self) -> None:
        try:
            path = self.session.save(self._path.value)
        except (Op2MotionError, OSError) as exc:
            self._message.content = f"**not saved**: {exc}"
            self.events.append(("save", f"refused: {exc}"))
            return
        self._message.content = f"saved {path}"
        self.events.append(("save", str(path)))

    def stop(self) -> None:
        """End the server."""
        self.server.stop()
