"""The steered walk's phase program: which phase comes next, given the walk so far and what it is asked.

A steered walk is a sequence of phases, each a run of 8 ms rows with both soles' paths, the planned contact and the
ZMP reference (:class:`Phase`):

* ``stand``: both feet down, the reference between them (:data:`STAND_S` at a time) while the command is zero;
* ``start``: the reference moves onto the first support foot (``start_s``), as a planned walk starts;
* ``step``: single support while the swing foot travels to its new place, then double support while the reference
  moves onto it (:mod:`.timeline`'s swing path and ZMP points, the same as a planned walk's);
* ``end``: after the step that closes the feet side by side, the reference held between them (``end_s``).

:func:`next_phase` decides from :class:`WalkState` (where the feet are, the body's path, the stride of the last step,
which foot swings next) and :class:`Intent` (the commanded stride, and whether to stop): each step's stride moves
towards the commanded one within the acceleration limits (:meth:`.envelope.Envelope.towards`); a zero command brings
the stride down the same way (to within :data:`CLOSE_SHARE` of the envelope) and then stops as a stop does;
:meth:`Intent.stop` takes a step at half the stride (in place from a standstill: the robot has just started) and
then the one that closes the feet. The body's path advances by the stride per step and each foot lands half the step
width beside it (:mod:`.footsteps`); a step whose side step or turn would bring the swing foot within
:data:`~.footsteps.FOOT_GAP_M` of the standing one takes less of them (:func:`_clear_stride`).
The same program, run ahead on a copy of the state, predicts the phases the ZMP preview looks at.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping

import numpy as np

from op2motion.gait.envelope import Envelope, Stride
from op2motion.gait.footsteps import Footstep, foot_at, leading_side, moved, step_width, swing_clear
from op2motion.gait.params import GaitParams
from op2motion.gait.timeline import LEAD_S, landing, quintic_blend, swing_path, ticks, zmp_point
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, SupportName, other_side

STAND_S = 0.16              # a standing phase [s] (the command is looked at again after each)
CLOSE_SHARE = 0.5           # a zero command closes the feet once the stride is within this share of the envelope's
SHRINK = (1.0, 0.75, 0.5, 0.25, 0.0)   # shares of a side step and turn tried until the swing foot stays clear


@dataclass(frozen=True)
class Intent:
    """What the walk is asked for the next phase: the commanded ``stride`` (clamped to the envelope) and ``stop``."""

    stride: Stride = Stride()
    stop: bool = False


@dataclass(frozen=True)
class Phase:
    """One phase's rows: each sole (n, 4) (x, y, z [m], yaw [rad]), the planned contact, the ZMP reference (n, 2)
    [m]; the stride it stepped, which foot swung (steps), whether it closed the feet, the step's number."""

    kind: str
    feet: Mapping[str, np.ndarray]
    contact: tuple[SupportName, ...]
    zmp_ref: np.ndarray
    stride: Stride = Stride()
    swing: Side | None = None
    closing: bool = False
    step: int = -1

    @property
    def rows(self) -> int:
        """Rows in the phase."""
        return len(self.contact)


@dataclass(frozen=True)
class WalkState:
    """Where a steered walk is between phases: the placed feet, the body path's last pose (x [m], y [m], yaw
    [rad]), the last step's stride, the foot to swing next, the mode (``stand``, ``walk`` or ``end``), the row the
    next phase begins at, the row before which no step may begin (the servos are measured standing first), whether
    a stop's halving step was taken, and the steps so far."""

    left: Footstep
    right: Footstep
    centre: tuple[float, float, float]
    stride: Stride = Stride()
    swing: Side = "left"
    mode: str = "stand"
    row: int = 0
    first_step_row: int = 0
    halved: bool = False
    steps: int = 0

    def foot(self, side: Side) -> Footstep:
        """The ``side`` foot's placement."""
        return self.left if side == "left" else self.right

    def placed(self, step: Footstep) -> "WalkState":
        """This state with ``step``'s foot placed there."""
        return replace(self, left=step) if step.side == "left" else replace(self, right=step)


def initial_state(params: GaitParams, spec: Spec) -> WalkState:
    """Standing with the feet side by side at the origin, facing +X; the first step not before the planned walk's
    own first one would begin (:data:`~.timeline.LEAD_S` + ``start_s``: the calibration's time)."""
    width = step_width(params, spec)
    centre = np.zeros(3)
    return WalkState(foot_at("left", centre, width), foot_at("right", centre, width), (0.0, 0.0, 0.0),
                     first_step_row=ticks(LEAD_S) + ticks(params.start_s))


def _where(state: WalkState) -> dict[str, np.ndarray]:
    return {side: np.array([state.foot(side).x, state.foot(side).y, 0.0, state.foot(side).yaw])
            for side in ("left", "right")}


def _hold(state: WalkState, n: int, ref: np.ndarray) -> tuple[dict[str, np.ndarray], tuple[SupportName, ...],
                                                           np.ndarray]:
    where = _where(state)
    double: tuple[SupportName, ...] = ("double",)
    return ({side: np.repeat(where[side][None], n, axis=0) for side in where}, double * n,
            np.broadcast_to(ref, (n, 2)).copy())


def _middle(state: WalkState) -> np.ndarray:
    return 0.5 * np.array([state.left.x + state.right.x, state.left.y + state.right.y])


def _small(stride: Stride, envelope: Envelope, step_s: float) -> bool:
    """Short enough to close the feet from at once (within :data:`CLOSE_SHARE` of the envelope on every axis)."""
    limits = (max(envelope.forward_m_s, envelope.backward_m_s), envelope.sideways_m_s, envelope.turn_rad_s)
    return all(abs(v) <= CLOSE_SHARE * lim * step_s + 1e-12
               for v, lim in zip((stride.dx, stride.dy, stride.dyaw), limits))


def _clear_stride(state: WalkState, stride: Stride, width: float, spec: Spec) -> tuple[Stride, Footstep]:
    """The stride the swing foot can take without coming near the standing foot (its side step and turn shrunk as
    :data:`SHRINK` says) and where that foot lands."""
    side = state.swing
    stand, before = state.foot(other_side(side)), state.foot(side)
    for share in SHRINK:
        tried = Stride(stride.dx, stride.dy * share, stride.dyaw * share)
        target = foot_at(side, moved(np.array(state.centre), tried.dx, tried.dy, tried.dyaw), width)
        if swing_clear(stand, before, target, spec):
            return tried, target
    return tried, target


def _step(state: WalkState, stride: Stride, params: GaitParams, spec: Spec, closing: bool = False
          ) -> tuple[Phase, WalkState]:
    """One step of ``stride`` (the closing one puts the swing foot beside the other)."""
    side, width = state.swing, step_width(params, spec)
    stride, target = _clear_stride(state, Stride() if closing else stride, width, spec)
    centre = moved(np.array(state.centre), stride.dx, stride.dy, stride.dyaw)
    stand = state.foot(other_side(side))
    where = _where(state)
    n_single, n_double = ticks(params.single_s), ticks(params.double_s)
    feet: dict[str, np.ndarray] = {side: swing_path(params, where[side], target),
                                   stand.side: np.repeat(where[stand.side][None], n_single, 0)}
    landed = landing(where[side], target)
    placed = state.placed(Footstep(side, float(landed[0]), float(landed[1]), float(landed[3])))
    after = _middle(placed) if closing else zmp_point(target, params)
    ramp = (np.arange(1, n_double + 1) / n_double)[:, None]
    hold_feet, hold_contact, _ = _hold(placed, n_double, after)
    feet = {s: np.vstack([feet[s], hold_feet[s]]) for s in feet}
    start_ref = zmp_point(stand, params)
    ref = np.vstack([np.repeat(start_ref[None], n_single, 0), start_ref + ramp * (after - start_ref)])
    phase = Phase("step", feet, (stand.side,) * n_single + hold_contact, ref, stride, side, closing, state.steps)
    nxt = replace(placed, centre=(float(centre[0]), float(centre[1]), float(centre[2])), stride=stride,
                  swing=stand.side, mode="end" if closing else "walk", row=state.row + phase.rows,
                  steps=state.steps + 1)
    return phase, nxt


def next_phase(state: WalkState, intent: Intent, params: GaitParams, spec: Spec, envelope: Envelope
               ) -> tuple[Phase, WalkState]:
    """The next phase and the state after it (see the module docstring)."""
    if state.mode == "end":
        n = ticks(params.end_s)
        feet, contact, ref = _hold(state, n, _middle(state))
        phase = Phase("end", feet, contact, ref)
        return phase, replace(state, mode="stand", row=state.row + n, stride=Stride(), halved=False)
    n_start = ticks(params.start_s)
    if state.mode == "stand":
        if intent.stop or intent.stride.still or state.row + n_start < state.first_step_row:
            n = ticks(STAND_S)
            feet, contact, ref = _hold(state, n, _middle(state))
            return Phase("stand", feet, contact, ref), replace(state, row=state.row + n)
        swing = leading_side(intent.stride.dy, intent.stride.dyaw)
        support = state.foot(other_side(swing))
        middle = _middle(state)
        blend = quintic_blend(np.arange(1, n_start + 1) / n_start)[:, None]
        feet, contact, _ = _hold(state, n_start, middle)
        yaw = 0.5 * (state.left.yaw + state.right.yaw)
        centre = (float(middle[0]), float(middle[1]), float(yaw))
        phase = Phase("start", feet, contact, middle + blend * (zmp_point(support, params) - middle))
        return phase, replace(state, mode="walk", swing=swing, centre=centre, stride=Stride(),
                              row=state.row + n_start)
    step_s = params.step_s
    if intent.stop or (intent.stride.still and _small(state.stride, envelope, step_s)):
        # a stop (or a zero command) comes unannounced: the preview has not seen the closing step, which a half step
        # first gives it time to (closing at once put the planned ZMP outside the soles from any stride:
        # docs/steering.md)
        if state.halved:
            return _step(state, Stride(), params, spec, closing=True)
        phase, nxt = _step(state, state.stride.scaled(0.5), params, spec)
        return phase, replace(nxt, halved=True)
    phase, nxt = _step(state, envelope.towards(state.stride, intent.stride, step_s), params, spec)
    return phase, replace(nxt, halved=False)


def predict(state: WalkState, intent: Intent, params: GaitParams, spec: Spec, envelope: Envelope,
            rows: int) -> list[Phase]:
    """The phases that follow ``state`` if ``intent`` holds, until they cover ``rows`` rows."""
    out: list[Phase] = []
    covered = 0
    while covered < rows:
        phase, state = next_phase(state, intent, params, spec, envelope)
        out.append(phase)
        covered += phase.rows
    return out
