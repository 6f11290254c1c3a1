"""The pose studio's long work, each on a worker thread so the page stays live: the physics check (with the settled
pose drawn as a grey ghost), the optimiser to a hand target, and "balance" (the optimiser from the pose as it is,
keeping a hand and the pinned joints). A mixin of :class:`.server.Studio`."""

from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.robot.spec import Spec
from op2motion.studio.place import root_in_sole, wxyz
from op2motion.studio.session import Readout, Session

CHECK_SECONDS = 3.0
GREY = (0.6, 0.6, 0.6)


class LongWork:
    """Check, optimise, balance (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    spec: Spec
    session: Session
    server: Any
    events: list[tuple[str, str]]
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
    _edit: Callable[[str, Any], None]

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
        self._progress.value = 0.0
        threading.Thread(target=self._optimise, args=(hand, target), daemon=True).start()

    def _optimise(self, hand: str, target: tuple[float, float, float]) -> None:
        from op2motion.posture.cost import PostureProblem
        from op2motion.posture.pso import PSOSettings
        from op2motion.workflow import solve

        settings = PSOSettings()
        try:
            problem = PostureProblem(self.session.support.value, hand, target, 1.0)
            outcome = solve(problem, self.spec, settings, restarts=0, on_iteration=self._ticker(settings.iterations))
        except Op2MotionError as exc:
            self._refuse("optimise", exc, "could not optimise")
            return
        finally:
            self._progress.visible = False
        result = outcome.result
        self._verdict.content = f"optimiser: {result.message}"
        if outcome.ok:
            self._edit("optimise", lambda: self._adopt(outcome.pose(self.session.name, self.spec).servo))
        self.events.append(("optimise", "reached" if outcome.ok else "not reached"))

    def _start_balance(self) -> None:
        pins = [p.strip() for p in str(self._pins.value).split(",") if p.strip()]
        self.events.append(("balance", "started"))
        self._progress.visible = True
        threading.Thread(target=self._balance, args=(self._hand.value, pins), daemon=True).start()

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

    def _balance(self, hand: str, pins: list[str]) -> None:
        from op2motion.posture.pso import PSOSettings

        with self._lock:
            try:
                readout, message = self.session.balance(hand, pins, self._ticker(PSOSettings().iterations))
            except Op2MotionError as exc:
                self._refuse("balance", exc)
                return
            finally:
                self._progress.visible = False
            self._verdict.content = f"balance: {message}"
            self._show(readout)
        self.events.append(("balance", message.split(":")[0]))

    def _adopt(self, servo: np.ndarray) -> Readout:
        self.session.servo = np.array(servo, dtype=float)
        return self.session.readout()

    def _draw_ghost(self, settled: np.ndarray) -> None:
        from viser.extras import ViserUrdf

        if self._ghost is None:
            self._ghost = ViserUrdf(self.server, self._urdf, root_node_name="/ghost", load_meshes=False,
                                    load_collision_meshes=True, collision_mesh_color_override=(*GREY, 0.35))
        rot, origin = root_in_sole(self.spec, settled, self.session.support.stance)
        self.server.scene.add_frame("/ghost", wxyz=wxyz(rot), position=tuple(origin), show_axes=False)
        by_name = dict(zip(self.spec.joint_names, settled))
        self._ghost.update_cfg(np.array([by_name[n] for n in self._order]))
