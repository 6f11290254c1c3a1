"""The action-page player against the robot's own arithmetic: hand-computed steps, the stock pages' lengths, and an
independent emulation of the framework's ``Action::Process()`` tick for tick."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from helpers import DATA

from op2motion.errors import InputError
from op2motion.formats.actionlayout import PAGE_SIZE, PageHeader, StepBytes, encode_page, parse_page, reset_file
from op2motion.motion.player import play

STOCK = (DATA / "motion_4096.bin").read_bytes()
REST = 2048
FREE = [REST] * 20                      # start goals of the synthetic pages (IDs 1-20)


def stock_init() -> list[int]:
    """The robot's start for the stock pages: page 1 (init)'s last step."""
    page = parse_page(STOCK, 1)
    return [int(page.words[page.stepnum - 1, i]) for i in range(1, 21)]


def file_with(pages: dict[int, bytes]) -> bytes:
    data = bytearray(reset_file())
    for index, page in pages.items():
        data[index * PAGE_SIZE:(index + 1) * PAGE_SIZE] = page
    return bytes(data)


def one_joint(goals: list[tuple[int, int, int]], accel: int = 5, **page) -> bytes:
    """A page moving ID 1 through (goal tick, time, pause) steps; the other joints not specified."""
    return encode_page("test", [StepBytes({1: g}, pause, time) for g, time, pause in goals],
                       PageHeader(accel=accel, **page))


@pytest.mark.parametrize("page, calls", [(1, 257), (9, 129), (4, 464), (12, 231)])
def test_stock_pages_take_as_long_as_on_the_robot(page, calls):
    assert play(STOCK, page, stock_init()).calls == calls


@pytest.mark.parametrize("page", [1, 9, 4, 12])
def test_every_goal_equals_the_independent_emulation(page):
    """tests/data/action_traces: goals per call of an emulation written separately from the same documented
    algorithm (row 0 is the start)."""
    with open(DATA / "action_traces" / f"page_{page:02d}.csv", newline="") as f:
        reference = np.array([[int(v) for v in row[1:]] for row in list(csv.reader(f))[1:]])
    assert np.array_equal(play(STOCK, page, stock_init()).goals, reference)


def _closed_form_calls(data: bytes, index: int) -> tuple[int, list[int]]:
    """1 + the sum over every step played of T + 3 (+ P + 1 with a pause), following repeat and next."""
    total, pages, page = 1, [], parse_page(data, index)
    repeat = page.repeat
    while True:
        pages.append(index)
        for k in range(page.stepnum):
            t = max(1, (page.time[k] * page.speed) >> 5)
            a = page.accel
            if t <= 2 * a and (a := (t - 1) >> 1) == 0:
                t = 0
            p = (page.pause[k] << 5) // page.speed
            total += t + 3 + (p + 1 if p else 0)
        repeat = (repeat - 1) & 0xFF
        follower = index if repeat > 0 else page.next
        nxt = parse_page(data, follower) if follower else None
        if nxt is None or not nxt.valid or not nxt.repeat or not nxt.stepnum:
            return total, pages
        if follower != index:
            repeat = nxt.repeat
        index, page = follower, nxt


def test_every_stock_page_and_chain_lasts_its_closed_form_length():
    checked = 0
    for index in range(1, 256):
        if parse_page(STOCK, index).playable:
            calls, pages = _closed_form_calls(STOCK, index)
            result = play(STOCK, index, stock_init())
            assert (result.calls, list(result.pages)) == (calls, pages), index
            checked += 1
    assert checked == 45


def test_a_trapezoid_step_by_hand():
    """ID 1 from 2048 to 2248 (D = 200 ticks) in time 20 at speed 32 (T = 20 ticks), accel 5 (A = 5), from rest to
    rest. Cruise speed v = (200 x 2560 / 12) / (4 (T - A)) = 42666 / 60 = 711 units. PRE, c = 1..5: speed step
    711 c / 5 = 142, 284, 426, 568, 711; distance ((0 + step/2) c 144 / 15) >> 9 = 1, 5, 11, 21, 33. MAIN covers
    200 - 33 - ((711 x 5 x 12 / 5) >> 8 = 33) = 134 ticks in 10 calls (134 c / 10). POST ramps 711 -> 0 over 5
    calls from 2215: 12, 21, 28, then the exact target one call early, then the ramp's own 33."""
    goals = play(file_with({10: one_joint([(2248, 20, 0)])}), 10, FREE).goals[:, 0]
    pre = [2049, 2053, 2059, 2069, 2081]
    main = [2094, 2107, 2121, 2134, 2148, 2161, 2174, 2188, 2201, 2215]
    post = [2227, 2236, 2243, 2248, 2248]
    # call 1 prepares the step; each section change is a call that repeats the last goal; the last call ends
    assert list(goals) == [REST, REST, *pre, pre[-1], *main, main[-1], *post, post[-1]]
    assert len(goals) - 1 == 1 + 20 + 3


def test_a_pause_holds_the_goal_and_costs_its_ticks_plus_one():
    """Pause 10 at speed 32 is 10 calls (+1 to enter it); the goal holds through it."""
    plain = play(file_with({10: one_joint([(2248, 20, 0)])}), 10, FREE)
    paused = play(file_with({10: one_joint([(2248, 20, 10)])}), 10, FREE)
    assert paused.calls == plain.calls + 11
    assert np.all(paused.goals[-12:, 0] == 2248)


def test_speed_and_accel_bytes_scale_time_and_pause():
    """At speed 64 a step of time 20 moves for 40 calls and a pause of 10 lasts 5."""
    fast = play(file_with({10: one_joint([(2248, 20, 10)], speed=64)}), 10, FREE)
    assert fast.calls == 1 + 40 + 3 + 5 + 1


def test_a_joint_running_one_way_keeps_its_speed_into_the_next_step():
    """2048 -> 2148 -> 2248 without a pause: the joint does not stop at 2148. With the second step turning back
    (2148 -> 2048) it comes to rest at 2148 first."""
    through = play(file_with({10: one_joint([(2148, 20, 0), (2248, 20, 0)])}), 10, FREE).goals[:, 0]
    back = play(file_with({10: one_joint([(2148, 20, 0), (2048, 20, 0)])}), 10, FREE).goals[:, 0]
    boundary = 1 + 20 + 3                          # the call that prepares the second step
    # the second step's first call: at the kept speed (about 300 units, 5.6 ticks a call), or ramping up from rest
    assert through[boundary + 1] - through[boundary] >= 5
    assert abs(back[boundary + 1] - back[boundary]) <= 1
    assert through[-1] == 2248 and back[-1] == 2048


def test_the_speed_clamp_leaves_the_rest_to_main():
    """600 ticks in 20 calls needs 2133 units > 1023: the ramps run at the clamp (PRE ends 47 ticks out) and MAIN
    jumps 600 - 47 - 47 = 506 ticks in 10 calls, about 51 a call (the clamp itself is 19 a call)."""
    goals = play(file_with({10: one_joint([(2648, 20, 0)])}), 10, FREE).goals[:, 0]
    assert goals[6] == REST + 47
    assert int(np.max(np.diff(goals))) in (50, 51) and goals[-1] == 2648


def test_repeat_next_and_exit_chains():
    """Page 10 (two steps) repeats twice then goes to 11. A stop during its first step goes to its exit page 12
    after this play; once its last step has begun the follower is chosen, so the stop waits one more play; a stop
    before the first call is lost (the first call clears it)."""
    data = file_with({10: one_joint([(2148, 10, 0), (2248, 10, 0)], repeat=2, next=11, exit=12),
                      11: one_joint([(2048, 10, 0)]), 12: one_joint([(1948, 10, 0)])})
    assert play(data, 10, FREE).pages == (10, 10, 11)
    stopped = play(data, 10, FREE, stop_at=5)
    assert stopped.pages == (10, 12) and stopped.goals[-1, 0] == 1948
    assert play(data, 10, FREE, stop_at=20).pages == (10, 10, 12)    # call 20 is in the last step
    assert play(data, 10, FREE, stop_at=1).pages == (10, 10, 11)


def test_brake_freezes_the_goals_at_once():
    full = play(file_with({10: one_joint([(2248, 20, 0)])}), 10, FREE)
    braked = play(file_with({10: one_joint([(2248, 20, 0)])}), 10, FREE, brake_at=9)
    assert braked.calls == 8 and np.array_equal(braked.goals, full.goals[:9])


def test_unspecified_joints_hold_and_compliance_sets_the_p_gain():
    """Walkready (page 9) leaves no joint unspecified but sets 0x77 on the shoulder rolls (IDs 3, 4): P gain 8."""
    result = play(STOCK, 9, stock_init())
    assert set(result.p_gains[-1, [2, 3]]) == {8} and set(np.delete(result.p_gains[-1], [2, 3])) == {32}
    synthetic = play(file_with({10: one_joint([(2248, 20, 0)])}), 10, FREE)
    assert np.all(synthetic.goals[:, 1:] == REST)


@pytest.mark.parametrize("page, needle", [(7, "no steps"), (0, "1 to 255"), (256, "1 to 255")])
def test_pages_the_robot_would_not_play(page, needle):
    with pytest.raises(InputError, match=needle):
        play(STOCK, page, stock_init())
