"""The ROBOTIS framework's action-page player, tick for tick (``Action::Process()`` of the OP2 Linux framework).

The robot's motion timer calls ``Process()`` every 8 ms. A step of a page runs in sections: PRE (A ticks, the speed
ramps from where the last step left it to the step's cruise speed), MAIN (T - 2A ticks at cruise speed), POST (A
ticks, ramping to zero, or keeping the speed into the next step), then PAUSE (P ticks) if the step has a pause; each
change of section costs one call that writes no new goal. With the page's ``speed`` s and ``accel`` a, a time-base
step of ``time`` t moves for T = max(1, t s >> 5) ticks and pauses P = (pause << 5) / s ticks; A = a, or
(T - 1) >> 1 if T <= 2a, and a step whose A comes out 0 does not move at all (T = 0). A joint keeps its speed into
the next step only when its targets run strictly one way through this step into the next and the step has no pause
and is not the last one played. Page chaining is decided as the last step of a page begins: the ``exit`` page after
a stop request, otherwise the same page while ``repeat`` lasts, then ``next``; page 0, or a page without steps or
repeat, ends playback. A goal word with bit 0x4000 keeps the previous target. Each joint's compliance byte sets its
P gain, (256 >> (byte >> 4)) << 2, written with every goal.

This is an emulation in the framework's integer arithmetic (C division truncating towards zero, arithmetic shifts,
16-bit and 8-bit wrap-around where the framework stores into short or char variables), written from the documented
algorithm; its goals match an independent emulation tick for tick on the stock pages (tests). Playback starts from
the last commanded goals (the robot's own convention), given here as a start pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.formats.action import ActionFile
from op2motion.formats.actionlayout import (
    NUM_PAGES,
    SPEED_BASE_SCHEDULE,
    TIME_BASE_SCHEDULE,
    RawPage,
    parse_page,
    reset_page,
)
from op2motion.robot.framework import CONTROL_PERIOD_S, DEFAULT_P_GAIN, p_gain_of_slope
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.spec import Spec

INVALID_BIT = 0x4000
MAX_TICK = 4095                    # the 4096 build clamps every goal to 0..4095
SPEED_LIMIT = 1023                 # the cruise speed clamp, in the framework's speed units
IDS = tuple(range(1, 21))          # the joints the player drives (Dynamixel IDs 1-20)
MAX_CALLS = 1_000_000              # a runaway chain (a page that loops on itself forever) stops here
PRE, MAIN, POST, PAUSE = 0, 1, 2, 3
ZERO_FINISH, KEEP_SPEED = 0, 1


def _tdiv(a: int, b: int) -> int:
    """C integer division: truncated towards zero."""
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def _s16(x: int) -> int:
    x &= 0xFFFF
    return x - 0x10000 if x & 0x8000 else x


def _ramp(last: int, speed_step: int, c: int) -> int:
    """Distance [ticks] covered after c ticks of a linear speed ramp that started at ``last`` (speed units), as the
    framework computes it: (last + half the speed gained) x c x 144/15, in 1/512 ticks."""
    return _tdiv((last + (speed_step >> 1)) * c * 144, 15) >> 9


@dataclass(frozen=True)
class StepTiming:
    """A time-base step's movement ``total`` (T), ramp ``accel`` (A) and ``pause`` (P), in ``Process()`` calls."""

    total: int
    accel: int
    pause: int


def step_timing(time: int, pause: int, speed: int, accel: int) -> StepTiming:
    """A time-base step's :class:`StepTiming`: T = max(1, time x speed >> 5), A = accel or (T - 1) >> 1 when
    T <= 2 accel (a step whose A is then 0 does not move: T = 0), P = (pause << 5) / speed."""
    if speed == 0:
        raise InputError("a page has speed 0 (the robot's firmware divides by it)", "page")
    total = ((time * speed) >> 5) & 0xFFFF or 1
    return StepTiming(*_ramps(total, accel), _tdiv(pause << 5, speed) & 0xFFFF)


def _ramps(total: int, accel: int) -> tuple[int, int]:
    if total <= 2 * accel:
        accel = 0 if total == 0 else (total - 1) >> 1
        if accel == 0:
            total = 0                          # shorter than 3 ticks: the step does not move
    return total, accel


def step_calls(time: int, pause: int, speed: int = 32, accel: int = 32) -> int:
    """``Process()`` calls a time-base step takes: T + 3, plus P + 1 with a pause."""
    timing = step_timing(time, pause, speed, accel)
    total, pause_ticks = timing.total, timing.pause
    return total + 3 + (pause_ticks + 1 if pause_ticks else 0)


@dataclass(frozen=True)
class Playback:
    """What the player sent, one row per ``Process()`` call (row 0: the start): goal ticks (calls + 1, 20) and P
    gains (calls + 1, 20) of IDs 1-20, the pages played in order (repeats included)."""

    goals: np.ndarray
    p_gains: np.ndarray
    pages: tuple[int, ...]

    @property
    def calls(self) -> int:
        """``Process()`` calls from the start up to the one that ended playback."""
        return len(self.goals) - 1

    @property
    def duration_s(self) -> float:
        """Playback time [s]: calls x 8 ms."""
        return self.calls * CONTROL_PERIOD_S


class ActionPlayer:
    """The player's state, as the framework keeps it between calls."""

    def __init__(self, action: ActionFile | bytes, start_ticks: Sequence[int]):
        action = action if isinstance(action, ActionFile) else ActionFile(bytes(action))
        if len(start_ticks) != len(IDS):
            raise InputError(f"expected {len(IDS)} start ticks (IDs 1-20), got {len(start_ticks)}", "start")
        self.action = action
        n = len(IDS)
        self.value = [int(t) for t in start_ticks]     # the goals sent (the joint values)
        self.gain = [DEFAULT_P_GAIN] * n
        self.start = [0] * n
        self.target = [0] * n
        self.moving = [0] * n
        self.main_angle = [0] * n
        self.accel_angle = [0] * n
        self.main_speed = [0] * n
        self.last_out = [0] * n
        self.goal_speed = [0] * n
        self.finish = [ZERO_FINISH] * n
        self.playing = self.first_call = self.finished = self.stop_requested = False
        self.count = self.num = self.pause_ticks = self.total = self.accel = 0
        self.section = PAUSE
        self.step_index = self.repeat_left = self.page_index = self.next_index = 0
        self.page: RawPage = action.raw(0)          # a placeholder until start_page (page 0 is never played)
        self.next_page: RawPage = self.page
        self.played: list[int] = []

    def _load(self, index: int) -> RawPage:
        page = self.action.raw(index)
        return page if page.valid else parse_page(reset_page(), 0)   # a bad page plays as a reset page

    def start_page(self, index: int) -> None:
        """``Start(page)``: playback begins at the next call."""
        if not 1 <= index < NUM_PAGES:
            raise InputError(f"expected a page from 1 to {NUM_PAGES - 1}, got {index}", "page")
        if self.playing:
            raise InputError("a page is already playing", "page")
        page = self.action.raw(index)
        if not page.playable:
            why = "fails its checksum" if not page.valid else "holds no steps" if not page.stepnum else "has repeat 0"
            raise InputError(f"page {index} {why}: the robot would not play it", "page")
        self.page, self.page_index = page, index
        self.playing = self.first_call = True

    def stop(self) -> None:
        """``Stop()``: the exit page is chosen when the last step of the playing page begins."""
        self.stop_requested = True

    def brake(self) -> None:
        """``Brake()``: playback ends at once; the goals stay where they are."""
        self.playing = False

    def process(self) -> None:
        """One ``Process()`` call (8 ms)."""
        if not self.playing:
            return
        if self.first_call:
            self.first_call = self.finished = self.stop_requested = False
            self.count = self.num = self.pause_ticks = 0
            self.section, self.step_index, self.next_index = PAUSE, 0, 0
            self.repeat_left = self.page.repeat
            self.target = list(self.value)
            self.last_out = [0] * len(IDS)
            self.moving = [0] * len(IDS)
            self.goal_speed = [0] * len(IDS)
            self.played.append(self.page_index)
        if self.count < self.num:
            self.count = (self.count + 1) & 0xFFFF
            if self.section != PAUSE:
                self._output(self.count, self.num)
            return
        self._next_section()

    def _output(self, c: int, n: int) -> None:
        slopes = self.page.slopes
        for j, ident in enumerate(IDS):
            start, last = self.start[j], self.last_out[j]
            if self.moving[j] == 0:
                out = start
            elif self.section == PRE:
                step = _s16(_tdiv((self.main_speed[j] - last) * c, n))
                self.goal_speed[j] = _s16(last + step)
                self.accel_angle[j] = _s16(_ramp(last, step, c))
                out = start + self.accel_angle[j]
            elif self.section == MAIN:
                out = start + _s16(_tdiv(self.main_angle[j] * c, n))
                self.goal_speed[j] = self.main_speed[j]
            elif c == n - 1:                      # POST: the exact target one tick before the end
                out = self.target[j]
            elif self.finish[j] == ZERO_FINISH:   # POST ramping down to rest
                step = _s16(_tdiv(-last * c, n))
                self.goal_speed[j] = _s16(last + step)
                out = start + _s16(_ramp(last, step, c))
            else:                                 # POST keeping the speed into the next step
                out = start + _s16(_tdiv(self.main_angle[j] * c, n))
                self.goal_speed[j] = self.main_speed[j]
            self.value[j] = min(max(out, 0), MAX_TICK)
            self.gain[j] = p_gain_of_slope(slopes[ident])

    def _next_section(self) -> None:
        self.count = 0
        self.start = list(self.value)
        self.last_out = list(self.goal_speed)
        t, a = self.total, self.accel
        if self.section == PRE:
            self.section, self.num = MAIN, (t - 2 * a) & 0xFFFF
            for j in range(len(IDS)):
                if self.finish[j] == KEEP_SPEED:
                    self.main_angle[j] = 0 if t - a == 0 else _s16(
                        _tdiv((self.moving[j] - self.accel_angle[j]) * self.num, t - a))
                else:
                    self.main_angle[j] = _s16(self.moving[j] - self.accel_angle[j]
                                              - _s16(_tdiv(self.main_speed[j] * a * 12, 5) >> 8))
        elif self.section == MAIN:
            self.section, self.num = POST, a
            for j in range(len(IDS)):             # what POST still has to cover
                self.main_angle[j] = _s16(self.moving[j] - self.main_angle[j] - self.accel_angle[j])
        elif self.section == POST:
            if self.pause_ticks:
                self.section, self.num = PAUSE, self.pause_ticks
            else:
                self.section = PRE
        else:
            self.section = PRE
            self.last_out = [0] * len(IDS)
        if self.section == PRE:
            self._prepare_step()

    def _choose_follower(self, page: RawPage) -> None:
        if self.stop_requested:
            self.next_index = page.exit
        else:
            self.repeat_left = (self.repeat_left - 1) & 0xFF
            self.next_index = self.page_index if self.repeat_left > 0 else page.next
        if self.next_index == 0:
            self.finished = True
            return
        self.next_page = page if self.next_index == self.page_index else self._load(self.next_index)
        if self.next_page.repeat == 0 or self.next_page.stepnum == 0:
            self.finished = True

    def _prepare_step(self) -> None:
        if self.finished:
            self.playing = False
            return
        self.step_index += 1
        if self.step_index > self.page.stepnum:   # on to the follower chosen at the last step
            self.page = self.next_page
            if self.page_index != self.next_index:
                self.repeat_left = self.page.repeat
            self.step_index, self.page_index = 1, self.next_index
            self.played.append(self.page_index)
        page = self.page
        last_step = self.step_index == page.stepnum
        if last_step:
            self._choose_follower(page)
        k = self.step_index - 1
        timing = step_timing(page.time[k], page.pause[k], page.speed, page.accel)
        ticks, self.pause_ticks = timing.total, timing.pause
        largest = 0
        for j, ident in enumerate(IDS):
            self.accel_angle[j] = 0
            prev = self.target[j]
            word = int(page.words[k, ident])
            now = prev if word & INVALID_BIT else word
            if last_step:
                after = now if self.finished else int(self.next_page.words[0, ident])
            else:
                after = int(page.words[k + 1, ident])
            after = now if after & INVALID_BIT else after
            self.start[j], self.target[j] = prev, now
            self.moving[j] = _s16(now - prev)
            one_way = prev < now < after or prev > now > after
            self.finish[j] = KEEP_SPEED if one_way and not self.pause_ticks and not self.finished else ZERO_FINISH
            if page.schedule == SPEED_BASE_SCHEDULE:
                largest = max(largest, abs(self.moving[j]))
        total = ticks if page.schedule == TIME_BASE_SCHEDULE else _tdiv(largest * 40, ticks * 3) & 0xFFFF
        self.total, self.accel = total, accel = _ramps(total, page.accel)
        whole, ramps = 2 * total, 2 * accel
        keep = (ramps + 2 * (whole - ramps)) or 1
        stop = 2 * (whole - ramps) or 1
        for j in range(len(IDS)):
            distance = _tdiv(self.moving[j] * 2560, 12) - self.last_out[j] * ramps
            speed = _s16(_tdiv(distance, stop if self.finish[j] == ZERO_FINISH else keep))
            self.main_speed[j] = min(max(speed, -SPEED_LIMIT), SPEED_LIMIT)
        self.num = accel


def start_ticks(servo: np.ndarray, spec: Spec) -> list[int]:
    """The goal ticks of IDs 1-20 (the player's order) for servo angles (20,) [rad] in the spec's joint order."""
    by_id = {j.id: int(t) for j, t in zip(spec.joints, servo_to_ticks(servo, spec))}
    return [by_id[i] for i in IDS]


def check_chain(action: ActionFile, page: int) -> None:
    """Refuse (bad input on ``page``) a page whose ``next`` links lead back to a page already in the chain: the
    framework would play it until stopped. Found from the links alone, before any playing."""
    seen: list[int] = []
    index = page
    while 1 <= index < NUM_PAGES and index not in seen:
        raw = action.raw(index)
        if not raw.valid or raw.repeat == 0 or raw.stepnum == 0:
            return
        seen.append(index)
        index = raw.next
    if index in seen:
        loop = " -> ".join(map(str, seen[seen.index(index):] + [index]))
        raise InputError(f"page {page} never ends: its next links loop ({loop}); the robot would play it until "
                         f"stopped", "page")


def play(action: ActionFile | bytes, page: int, start_ticks: Sequence[int], stop_at: int | None = None,
         brake_at: int | None = None) -> Playback:
    """Play ``page`` of an action file from ``start_ticks`` (IDs 1-20) to its end; ``stop_at`` / ``brake_at`` call
    ``Stop()`` / ``Brake()`` just before that call."""
    player = ActionPlayer(action, start_ticks)
    check_chain(player.action, page)
    player.start_page(page)
    goals, gains = [list(player.value)], [list(player.gain)]
    call = 0
    while player.playing:
        call += 1
        if call > MAX_CALLS:
            raise InputError(f"page {page} plays for more than {MAX_CALLS} calls (an endless chain?)", "page")
        if call == stop_at:
            player.stop()
        if call == brake_at:
            player.brake()
            break
        player.process()
        goals.append(list(player.value))
        gains.append(list(player.gain))
    return Playback(np.array(goals, dtype=np.int64), np.array(gains, dtype=np.int64), tuple(player.played))
