"""The rolling planner: a walk planned one phase at a time while it walks, the same pipeline as a planned walk.

A planned walk (:func:`.generator.generate_gait`) sees every footstep before the first; a steered one knows only the
command of the moment. :class:`RollingPlanner` plans the next phase (:mod:`.phases`: a standing spell, the start, a
step, the end) shortly before it begins (:data:`PLAN_AHEAD_ROWS`), over a window that reaches past it:

1. the phase, then the phases the current command predicts (:func:`.phases.predict`) as far as the ZMP preview looks
   (``preview_s``) plus :data:`LOOKAHEAD_S`: their ZMP reference and soles;
2. the cart-table preview controller (:mod:`.preview`) run from the cart's state where the last phase left it
   (:class:`.preview.CartState`: position, velocity, acceleration and the integral's summed error), so the CoM path
   runs on without a seam whatever the command did;
3. the whole body as in a planned walk: the torso's height, lean and heading, its horizontal position fitted until the
   full-model CoM lies on the cart's path, the legs by the closed-form IK; the multibody ZMP of that motion
   (pinocchio) against the reference, the error run through the preview again and added to the CoM path
   (``zmp_passes`` times), each pass's correction also carried from phase to phase (a state per pass); the last
   :data:`HISTORY_ROWS` rows already played lead the window, so the derivatives are right at its start;
4. the servo feed-forward of the phase's rows (:func:`.generator.servo_feedforward`); then only the phase's own rows
   are kept (:class:`.rows.RowBuffer`), the window's tail is planned again with the next phase.

The work is cut into stages (:meth:`RollingPlanner.tick` runs one per control tick), so a robot's 8 ms loop never
waits for a whole phase; whatever is left when the phase is due runs at once. The command is read when a phase's
planning begins: a command takes effect from the next step that begins at least :data:`PLAN_AHEAD_ROWS` ticks later.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator, Mapping

import numpy as np

from op2motion.formats.action import ActionFile
from op2motion.gait.envelope import Envelope
from op2motion.gait.generator import COM_PASSES, _Body, arm_rows, servo_feedforward, standing_height, torso_rotations
from op2motion.gait.params import GaitParams
from op2motion.gait.phases import Intent, Phase, WalkState, initial_state, next_phase, predict
from op2motion.gait.preview import CartState, preview_gains, run_cart
from op2motion.gait.rows import REACH_SHARE, RowBuffer, chunk_fields, torso_yaw
from op2motion.gait.timeline import Timeline
from op2motion.kinematics.leg_ik import Leg, rot_z
from op2motion.motion.checks import SMOOTH_ROWS
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import LIFTED_M, SIDES, Side, SupportName, other_side

HISTORY_ROWS = 8            # rows already planned that lead each window (the differences at its start are right)
LOOKAHEAD_S = 0.64          # the body is planned this far beyond the phase (the multibody correction's own preview: two
                            # steps; with one, the next lift-off fell near the window's end and its ZMP swung 60 mm)
TAIL_ROWS = 8               # rows planned past the window and thrown away: the multibody ZMP's differences take the
                            # rest padding there (the robot is not really about to stop)
PLAN_AHEAD_ROWS = 24        # a phase's planning begins this many rows (192 ms) before the phase does: its 20 stages
                            # (one a tick) are done before it begins
DAMPING_FADE_S = 0.3        # standing still after walking, the gyro damping of stiff servos fades out over this long
                            # [s] (and back in to walk again; the controller decides whose, by their measured
                            # stiffness); before the first step it stays
KEEP_S = 2.0                # rows older than this [s] behind the one playing are dropped


@dataclass
class _Window:
    """A window's rows (history first, then the phase and the phases predicted after it): soles, contact, ZMP
    reference, torso poses, arms, servo angles, and the CoM path they are fitted to."""

    feet: dict[str, np.ndarray]
    contact: tuple[SupportName, ...]
    ref: np.ndarray
    pos: np.ndarray
    rot: np.ndarray
    target: np.ndarray
    joints: np.ndarray
    body: Any
    history: int
    rows: int                        # the phase's own rows


@dataclass
class History:
    """The last :data:`HISTORY_ROWS` rows planned: soles, contact, torso poses, joints, ZMP reference."""

    feet: dict[str, np.ndarray]
    contact: tuple[SupportName, ...]
    pos: np.ndarray
    rot: np.ndarray
    joints: np.ndarray
    ref: np.ndarray

    @classmethod
    def of(cls, w: _Window, rows: slice) -> History:
        """The rows ``rows`` of a window."""
        return cls({s: w.feet[s][rows].copy() for s in SIDES}, w.contact[rows], w.pos[rows].copy(),
                   w.rot[rows].copy(), w.joints[rows].copy(), w.ref[rows].copy())


@dataclass
class Seed:
    """A walk planned so far by other means (a planned walk stopped early, :mod:`.planned_stop`), for the planner
    to go on from: the state between two phases, its rows (ending there), the last :data:`HISTORY_ROWS` of them,
    the preview controller's cart there and the multibody corrections of the reference from there on (R, 2) [m],
    the pendulum's height [m]."""

    state: WalkState
    rows: RowBuffer
    history: History
    cart: CartState
    delta: np.ndarray
    com_height: float


class RollingPlanner:
    """Plans a steered walk phase by phase (see the module docstring). Rows are numbered from the walk's first;
    with a :class:`Seed` the planner goes on from a walk planned so far (its rows, extended in place)."""

    def __init__(self, params: GaitParams, spec: Spec, envelope: Envelope, legs: Mapping[str, Leg],
                 action: ActionFile | None = None, seed: Seed | None = None):
        self.params, self.spec, self.envelope, self.legs, self.action = params, spec, envelope, dict(legs), action
        self.pending_kick: Side | None = None                    # a kick asked for (right or left), not yet planned
        self.row_now = -1                                       # the last row handed to the controller
        self.state: WalkState = initial_state(params, spec) if seed is None else seed.state
        self.height = standing_height(params, spec)
        self.rows = RowBuffer(len(spec.joints)) if seed is None else seed.rows
        self.phases: list[tuple[int, Phase]] = []              # (first row, phase) of the phases planned
        self.task: Iterator[None] | None = None
        self.keep_all = False                                   # keep every row and phase (a dry run's plan)
        self.stand_since: int | None = None                     # first row of the standing that was planned last
        if seed is None:
            self._standing_rows()
        else:
            self.com_height, self.cart, self._delta, self.history = seed.com_height, seed.cart, seed.delta, seed.history
            self.gains = preview_gains(CONTROL_PERIOD_S, self.com_height, params.preview_s, params.zmp_weight,
                                       params.jerk_weight)

    def _standing_rows(self) -> None:
        """The robot standing where the feet are (before the first phase, and after a kick): the history that leads
        the next window, the cart at rest over the middle of the feet, the pendulum's height and the preview
        gains."""
        p = self.params
        feet = {side: np.repeat(np.array([[self.state.foot(side).x, self.state.foot(side).y, 0.0,
                                            self.state.foot(side).yaw]]), HISTORY_ROWS, axis=0) for side in SIDES}
        double: tuple[SupportName, ...] = ("double",)
        standing = double * HISTORY_ROWS
        window = self._window(feet, standing, np.zeros((HISTORY_ROWS, 2)), 0, HISTORY_ROWS)
        com = window.body.com(window.body.configs(window.joints, window.pos, window.rot))
        middle = 0.5 * (feet["left"][0, :2] + feet["right"][0, :2])
        window.target = np.repeat(middle[None], HISTORY_ROWS, axis=0)
        self._fit(window)
        self.com_height = p.com_height_m or float(com[0, 2])
        self.gains = preview_gains(CONTROL_PERIOD_S, self.com_height, p.preview_s, p.zmp_weight, p.jerk_weight)
        self.cart = CartState.rest(middle)
        self._delta = np.zeros((0, 2))
        window.ref = np.repeat(middle[None], HISTORY_ROWS, axis=0)
        self.history = History.of(window, slice(0, HISTORY_ROWS))

    @property
    def standing_goals(self) -> np.ndarray:
        """The planned joints (20,) [rad] of the standing robot before the first phase."""
        goals: np.ndarray = self.history.joints[-1].copy()
        return goals

    def _window(self, feet: dict[str, np.ndarray], contact: tuple[SupportName, ...], ref: np.ndarray, history: int,
                rows: int) -> _Window:
        """A window over these rows: torso poses from the soles, its height constant, positions between the
        feet to start from."""
        rot = torso_rotations(feet, self.params)
        pos = np.zeros((len(contact), 3))
        pos[:, 2] = self.height
        pos[:, :2] = 0.5 * (feet["left"][:, :2] + feet["right"][:, :2])
        timeline = Timeline(np.arange(len(contact)) * CONTROL_PERIOD_S, np.zeros(len(contact), dtype=int), contact,
                            contact, ref, feet)
        body = _Body(self.spec, timeline)
        joints = body.goals(arm_rows(self.params, timeline, self.spec, rot, pos), pos, rot, REACH_SHARE)
        return _Window(feet, contact, ref, pos, rot, pos[:, :2].copy(), joints, body, history, rows)

    def _fit(self, w: _Window) -> None:
        """Move the new rows' torsos until the whole-body CoM lies on the window's CoM path."""
        for _ in self._fit_stages(w):
            pass

    def _fit_stages(self, w: _Window) -> Iterator[None]:
        """:meth:`_fit` a fixed-point pass at a time (a stage each)."""
        timeline = w.body.timeline
        new = slice(w.history, None)
        for _ in range(COM_PASSES):
            com = w.body.com(w.body.configs(w.joints, w.pos, w.rot))
            w.pos[new, :2] += w.target[new] - com[new, :2]
            arms = arm_rows(self.params, timeline, self.spec, w.rot, w.pos)
            w.joints[new] = w.body.goals(arms, w.pos, w.rot, REACH_SHARE)[new]
            yield

    # -- planning, one stage at a time --------------------------------------------------------------------------

    def tick(self, k: int, intent: Callable[[], Intent]) -> None:
        """Row ``k`` is about to play: make sure it is planned (finishing any planning at once if it must), begin
        planning the next phase when it is :data:`PLAN_AHEAD_ROWS` away (reading ``intent()``), run one stage."""
        self.row_now = k
        while self.rows.end <= k:
            if self.task is None:
                self.task = self._plan(intent())
            for _ in self.task:
                pass
            self.task = None
        if self.task is None and self.rows.end - k <= PLAN_AHEAD_ROWS:
            self.task = self._plan(intent())
        if self.task is not None and next(self.task, "done") == "done":
            self.task = None
        if not self.keep_all:
            self.rows.trim(k - int(round(KEEP_S / CONTROL_PERIOD_S)))

    def stop(self) -> None:
        """A stop asked now: drop the planning in progress (it read the intent before; it starts again at the next
        tick, finishing at once if the phase is due before its stages are through). A step already planned to begin
        after it is walked; then the half step and the closing one (:func:`.phases.next_phase`): the preview sees
        the closing step a step ahead, which closing right after the planned step would not give it."""
        self.task = None

    def _plan(self, intent: Intent) -> Iterator[None]:
        """Plan the next phase (the module docstring's steps), yielding between stages; commit it at the end. A kick
        asked for stops the walk first, and is the next phase once it stands."""
        if self.pending_kick is not None:
            if self.state.mode == "stand":
                yield
                self._kick(self.pending_kick)
                return
            intent = replace(intent, stop=True)
        phase, after = next_phase(self.state, intent, self.params, self.spec, self.envelope)
        preview = len(self.gains.gp)
        ahead = predict(after, intent, self.params, self.spec, self.envelope,
                        int(round(LOOKAHEAD_S / CONTROL_PERIOD_S)) + preview)
        yield
        h = self.history
        planned = [phase] + ahead
        feet = {s: np.vstack([h.feet[s]] + [ph.feet[s] for ph in planned]) for s in SIDES}
        ref = np.vstack([h.ref] + [ph.zmp_ref for ph in planned])
        contact = tuple(h.contact) + tuple(c for ph in planned for c in ph.contact)
        rows = phase.rows + int(round(LOOKAHEAD_S / CONTROL_PERIOD_S))
        span = HISTORY_ROWS + rows + TAIL_ROWS
        w = self._window({s: feet[s][:span] for s in SIDES}, contact[:span], ref[:span], HISTORY_ROWS, phase.rows)
        w.pos[:HISTORY_ROWS], w.rot[:HISTORY_ROWS], w.joints[:HISTORY_ROWS] = h.pos, h.rot, h.joints
        aim = ref[HISTORY_ROWS:]
        delta = self._carried_delta(rows)
        yield
        for p in range(self.params.zmp_passes + 1):
            aimed = aim.copy()
            aimed[:rows] += delta
            aimed[rows:] += delta[-1]
            cart, self._next_cart = run_cart(self.gains, aimed, rows + TAIL_ROWS, self.cart, phase.rows)
            w.target = np.vstack([np.zeros((HISTORY_ROWS, 2)), cart.com])
            yield from self._fit_stages(w)
            com, zmp = w.body.zmp(w.body.configs(w.joints, w.pos, w.rot))
            if p < self.params.zmp_passes:
                delta = delta + (aim[:rows] - zmp[HISTORY_ROWS:HISTORY_ROWS + rows])
            yield
        self._delta = delta[phase.rows:]
        com, zmp = com[:HISTORY_ROWS + rows], zmp[:HISTORY_ROWS + rows]
        self._commit(phase, after, w, com, zmp)

    def _carried_delta(self, rows: int) -> np.ndarray:
        """The multibody correction of the reference (rows, 2) [m] a window starts from: what the last window found
        for the rows it planned beyond its phase (which this window begins with), held at its last value beyond."""
        out = np.zeros((rows, 2))
        overlap = min(len(self._delta), rows)
        if overlap:
            out[:overlap] = self._delta[:overlap]
            out[overlap:] = self._delta[overlap - 1]
        return out

    def _commit(self, phase: Phase, after: WalkState, w: _Window, com: np.ndarray, zmp: np.ndarray) -> None:
        """Keep the phase's own rows (with their feed-forward and what the controller needs per row); carry the
        cart's states and the last rows on to the next window."""
        n, h0 = phase.rows, HISTORY_ROWS
        mine = slice(h0, h0 + n)
        pad = SMOOTH_ROWS
        span = slice(h0 - pad, h0 + n + pad)
        configs, v, a = w.body.last_motion
        p_gains = np.full((n, len(self.spec.joints)), float(self.params.p_gain))
        ff = servo_feedforward(self.spec, configs[span], v[span], a[span], w.contact[span], p_gains[0])[pad:-pad]
        goals = w.joints[mine] + ff if self.params.servo_feedforward else w.joints[mine].copy()
        feet = {s: w.feet[s][mine] for s in SIDES}
        contact = w.contact[mine]
        before = float(self.rows.numeric["plan_yaw"][-1]) if self.rows.end > self.rows.first else None
        chunk: dict[str, Any] = {
            "joints": w.joints[mine], "goals": goals, "p_gains": p_gains, "torso_pos": w.pos[mine],
            "torso_rot": w.rot[mine], "plan_yaw": torso_yaw(w.rot[mine], before),
            "velocity": np.repeat(self._velocity(phase)[None], n, axis=0), "zmp_ref": w.ref[mine],
            "zmp": zmp[mine], "com": com[mine], "contact": contact, "open": np.zeros(n),
            "damping": self._damping(phase.kind != "stand" or self.state.steps == 0, n),
            "support": tuple(c if c == "double" or feet[other_side(c)][i, 2] >= LIFTED_M else "double"
                             for i, c in enumerate(contact)),
            **self._step_objects(phase), **chunk_fields(self.legs, feet, contact, w.pos[mine], w.rot[mine])}
        start = self.rows.end
        self.rows.append(chunk)
        self.phases.append((start, phase))
        if not self.keep_all:
            del self.phases[:-8]
        if phase.kind != "stand":
            self.stand_since = None
        elif self.stand_since is None:
            self.stand_since = start
        self.state, self.cart = after, self._next_cart
        self.history = History.of(w, slice(h0 + n - HISTORY_ROWS, h0 + n))

    def _kick(self, side: Side) -> None:
        """Commit a kick phase (:mod:`.kick`) from the standing robot; afterwards it stands where it stood."""
        from op2motion.gait.kick import kick_chunk

        stand = self.rows.get("goals", self.rows.end - 1).copy()
        kick = kick_chunk(self.spec, self.legs, self.state, stand, float(self.params.p_gain), side, self.action)
        n, feet, contact, pos, rot = len(kick.contact), kick.feet, kick.contact, kick.torso_pos, kick.torso_rot
        before = float(self.rows.numeric["plan_yaw"][-1])
        zmp_ref = kick.com[:, :2]
        chunk = {"joints": kick.goals, "goals": kick.goals, "p_gains": kick.p_gains, "torso_pos": pos,
                 "torso_rot": rot, "com": kick.com, "contact": contact,
                 "plan_yaw": torso_yaw(rot, before), "velocity": np.zeros((n, 2)),
                 "zmp_ref": zmp_ref, "zmp": zmp_ref, "open": np.ones(n), "damping": np.zeros(n),
                 "support": tuple(c if c == "double" or feet[other_side(c)][i, 2] >= LIFTED_M else "double"
                                  for i, c in enumerate(contact)),
                 "learn": [None] * n, "landing": [None] * n, **chunk_fields(self.legs, feet, contact, pos, rot)}
        start = self.rows.end
        self.rows.append(chunk)
        where = {s: feet[s] for s in SIDES}
        self.phases.append((start, Phase("kick", where, contact, zmp_ref, swing=side)))
        self.pending_kick, self.stand_since = None, None
        self.state = replace(self.state, row=self.state.row + n)
        self._standing_rows()

    def _damping(self, on: bool, n: int) -> np.ndarray:
        """The gyro damping's share over a phase's ``n`` rows: towards 1 (``on``: stepping or about to) or 0
        (standing still) from where the last row left it, over :data:`DAMPING_FADE_S`."""
        before = self.rows.value("damping", self.rows.end - 1) if self.rows.end > self.rows.first else 1.0
        step = CONTROL_PERIOD_S / DAMPING_FADE_S
        ramp = before + step * np.arange(1, n + 1) * (1.0 if on else -1.0)
        share: np.ndarray = np.clip(ramp, 0.0, 1.0)
        return share

    def _velocity(self, phase: Phase) -> np.ndarray:
        """The planned stride velocity (2,) [m/s] of a phase in the world frame (zero unless stepping)."""
        if phase.kind != "step" or phase.closing:
            return np.zeros(2)
        yaw = self.state.centre[2]
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * phase.stride.dx - s * phase.stride.dy,
                         s * phase.stride.dx + c * phase.stride.dy]) / self.params.step_s

    def _step_objects(self, phase: Phase) -> dict[str, list[Any]]:
        """Per row: the step learner's place (swing side, row in the step, the swing's shape) and, at the first
        row on both feet after a swing, the leg odometry's landing (the foot stepped from, the one that landed,
        whether it closed the feet, the rows of that double support)."""
        n = phase.rows
        learn: list[Any] = [None] * n
        landing: list[Any] = [None] * n
        if phase.kind == "step" and phase.swing is not None:
            shape = _shape(self.state, phase)
            learn = [(phase.swing, r, shape, phase.step) for r in range(n)]
            first_double = phase.contact.index("double")
            landing[first_double] = (other_side(phase.swing), phase.swing, phase.closing, n - first_double)
        return {"learn": learn, "landing": landing}


def _shape(state: WalkState, phase: Phase) -> np.ndarray:
    """A step's swing in its stance foot's frame: start (x, y), end (x, y) [m], start and end yaw [rad] (two steps
    alike in this are alike for the servos)."""
    stand = state.foot(other_side(phase.swing or "left"))
    foot = phase.feet[phase.swing or "left"]
    to_stance = rot_z(-stand.yaw)[:2, :2]
    out = []
    for row in (foot[0], foot[-1]):
        out.extend(to_stance @ (row[:2] - np.array([stand.x, stand.y])))
    out.extend([foot[0, 3] - stand.yaw, foot[-1, 3] - stand.yaw])
    return np.array(out)
