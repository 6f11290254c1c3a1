"""The pose studio's long work, each on a worker thread so the page stays live: the physics check (with the settled
pose drawn as a grey ghost), the optimiser to a hand target, and "balance" (the optimiser from the pose as it is,
keeping a hand and the pinned joints). One check and one optimisation at a time: a second click while one runs is
refused (so clicks cannot pile up threads and memory). While the optimiser runs, edits are refused
(:mod:`.edits`) and its result is adopted whole. A mixin of :class:`.server.Studio`."""

from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, as_side
from op2motion.studio.root_pose import root_in_sole, wxyz
from op2motion.studio.session import PoseEdit, Readout

CHECK_SECONDS = 3.0
GREY = (0.6, 0.6, 0.6)


class LongWork:
    """Check, optimise, balance (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    spec: Spec
    session: PoseEdit
    server: Any
    events: Any
    busy: dict[str, bool]
    _lock: Any
    _message: Any
    _verdict: Any
    _progress: Any
    _hand: Any
    _pins: Any
    _targets: dict[str, Any]
    _target_goal: dict[str, tuple[float, float, float]]
    _ghost: Any
    _urdf: Any
    _order: list[str]

    _show: Callable[[Readout], None]               # the page's own, from Studio
    _pen: Callable[[Any], str | None]
    _refused: Callable[..., None]

    def _begin(self, kind: str, event: Any, needs_pen: bool) -> bool:
        """Mark ``kind`` (check or optimise) busy, unless it already runs (or the tab may not edit)."""
        with self._lock:
            why = self._pen(event) if needs_pen else None
            if why is None and self.busy[kind]:
                why = f"{'a physics check' if kind == 'check' else 'the optimiser'} is already running: one at a time"
            if why is not None:
                self._refused(kind, why, event)
                return False
            self.busy[kind] = True
            return True

    def _start_check(self, event: Any = None) -> None:
        if not self._begin("check", event, needs_pen=False):
            return
        self.events.append(("check", "started"))
        self._verdict.content = "physics: checking…"
        with self._lock:
            servo, support = self.session.servo.copy(), self.session.support
        threading.Thread(target=self._check, args=(servo, support), daemon=True).start()

    def _check(self, servo: np.ndarray, support: Any) -> None:
        from op2motion.physics import Schedule, Setup, check

        try:
            run = check(Schedule.hold(servo, support, self.spec, CHECK_SECONDS), self.spec,
                        setup=Setup(keep_track=True)).run
        except Op2MotionError as exc:
            self._verdict.content = f"physics: **could not check**: {exc}"
            self.events.append(("check", f"refused: {exc}"))
            return
        finally:
            self.busy["check"] = False
        verdict = "STANDS" if run.stable else "FALLS" if run.fell else "FAILS"
        self._verdict.content = (f"physics: **{verdict}** ({', '.join(run.reasons) or 'no failure'}), margin "
                                 f"{run.support_margin_m * 1000:+.1f} mm, {run.engine} {run.seconds:g} s ({run.ended})")
        self._draw_ghost(run.track.q[-1])
        self.events.append(("check", verdict))

    def _start_optimise(self, event: Any = None) -> None:
        hand = self._hand.value
        if hand not in self._targets:
            self._refused("optimise", f"expected the left or the right hand, got {str(hand)[:20]!r}", event)
            return
        if self.session.support.is_double:
            self._message.content = "**refused**: the optimiser stands on one foot: choose left or right support"
            self.events.append(("optimise", "refused: double support"))
            return
        if not self._begin("optimise", event, needs_pen=True):
            return
        target = self._target_goal.get(hand, tuple(self._targets[hand].position))
        self.events.append(("optimise", "started"))
        self._progress.visible = True
        self._progress.value = 0.0
        threading.Thread(target=self._optimise, args=(hand, target), daemon=True).start()

    def _optimise(self, hand: Side, target: tuple[float, float, float]) -> None:
        from op2motion.posture.cost import PostureProblem
        from op2motion.posture.pso import PSOSettings
        from op2motion.workflow import solve

        settings = PSOSettings()
        try:
            problem = PostureProblem(as_side(self.session.support.value, "support"), as_side(hand, "hand"), target,
                                     1.0)
            outcome = solve(problem, self.spec, settings, restarts=0, on_iteration=self._ticker(settings.iterations))
            result = outcome.result
            self._verdict.content = f"optimiser: {result.message}"
            if outcome.ok:
                self._adopt(outcome.pose(self.session.name, self.spec).servo)
            self.events.append(("optimise", "reached" if outcome.ok else "not reached"))
        except Op2MotionError as exc:
            self._refuse("optimise", exc, "could not optimise")
        finally:
            self._progress.visible = False
            self.busy["optimise"] = False

    def _start_balance(self, event: Any = None) -> None:
        hand = self._hand.value
        pins = [p.strip() for p in str(self._pins.value).split(",") if p.strip()]
        if not self._begin("optimise", event, needs_pen=True):
            return
        self.events.append(("balance", "started"))
        self._progress.visible = True
        threading.Thread(target=self._balance, args=(hand, pins), daemon=True).start()

    def _refuse(self, kind: str, exc: Exception, what: str = "refused") -> None:
        """Show why a piece of work did not happen, and record it."""
        self._message.content = f"**{what}**: {exc}"
        self.events.append((kind, f"refused: {exc}"))

    def _ticker(self, iterations: int) -> Any:
        """An ``on_iteration`` callback that moves the progress bar (every tenth iteration of one solve)."""
        done = [0]

        def tick(_: float) -> None:
            done[0] += 1
            if done[0] % 10 == 0:
                self._progress.value = min(100.0, 100.0 * done[0] / iterations)
        return tick

    def _balance(self, hand: Side, pins: list[str]) -> None:
        from op2motion.posture.pso import PSOSettings

        try:
            readout, message = self.session.balance(hand, pins, self._ticker(PSOSettings().iterations))
            self._verdict.content = f"balance: {message}"
            with self._lock:
                self._show(readout)
            self.events.append(("balance", message.split(":")[0]))
        except Op2MotionError as exc:
            self._refuse("balance", exc)
        finally:
            self._progress.visible = False
            self.busy["optimise"] = False

    def _adopt(self, servo: np.ndarray) -> None:
        """The optimiser's pose replaces the pose as a whole (no edit ran meanwhile: they were refused)."""
        with self._lock:
            self.session.servo = np.array(servo, dtype=float)
            self._show(self.session.readout())

    def _draw_ghost(self, settled: np.ndarray) -> None:
        from viser.extras import ViserUrdf

        if self._ghost is None:
            self._ghost = ViserUrdf(self.server, self._urdf, root_node_name="/ghost", load_meshes=False,
                                    load_collision_meshes=True, collision_mesh_color_override=(*GREY, 0.35))
        rot, origin = root_in_sole(self.spec, settled, self.session.support.stance)
        self.server.scene.add_frame("/ghost", wxyz=wxyz(rot), position=tuple(origin), show_axes=False)
        by_name = dict(zip(self.spec.joint_names, settled))
        self._ghost.update_cfg(np.array([by_name[n] for n in self._order]))
