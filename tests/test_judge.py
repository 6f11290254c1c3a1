"""The judge, one failure reason at a time, on made-up tracks (no simulation): each reason fires exactly when its
rule says, at the sample it names, and the engines' agreement compares what happened."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from op2motion.physics.judge import (
    COM_DROP_FRACTION,
    LIMIT_AT_RAD,
    LIMIT_AWAY_RAD,
    LIMIT_HOLD_S,
    LOADING_TILT_LIMIT_DEG,
    SATURATION_FRACTION,
    SATURATION_SHARE,
    SLIP_LIMIT_M,
    SLIP_LOAD_SHARE,
    com_drop_failure,
    first_held,
    floor_failures,
    joint_limit_failure,
    saturation_failure,
    self_collision_failure,
    slip,
    supporting_soles,
    tilt_failure,
    tilts,
)
from op2motion.physics.loop import StartFacts
from op2motion.physics.plan import RAMP_S, STEADY_S, Plan, PlannedStates
from op2motion.physics.report import CheckReport, EngineReport, Failure, PushResult, RunReport
from op2motion.physics.track import Track

DT_S = 0.01                    # the judge's sample period [s]
RUN_S = 3.0
NAMES = tuple(f"j{i}" for i in range(20))
TIMES = np.arange(1, int(RUN_S / DT_S) + 1) * DT_S
LOADED = int(np.searchsorted(TIMES, RAMP_S))


def _at(seconds: float) -> int:
    return int(np.searchsorted(TIMES, seconds - 1e-9))


# --- tilt ------------------------------------------------------------------------------------------------------

def test_tilt_fires_where_the_turn_after_loading_passes_the_limit():
    tilt = np.where(TIMES > 2.0, 12.0, 3.0)
    from_start = tilt + 4.0                          # the 4° of loading sag is not counted
    f = tilt_failure(TIMES, tilt, from_start, LOADED, 10.0)
    assert f is not None and f.reason == "tilt" and f.time_s == pytest.approx(TIMES[_at(2.0) + 1])
    assert tilt_failure(TIMES, np.full(TIMES.size, 9.9), from_start, LOADED, 10.0) is None


def test_a_fall_while_loading_is_a_tilt_from_its_start():
    from_start = np.where(TIMES < 0.5, 0.0, LOADING_TILT_LIMIT_DEG + 5.0)
    f = tilt_failure(TIMES, np.zeros(TIMES.size), from_start, LOADED, 10.0)
    assert f is not None and f.time_s == pytest.approx(TIMES[_at(0.5)])
    calm = np.full(TIMES.size, LOADING_TILT_LIMIT_DEG - 1.0)     # sagging while loading is no fall
    assert tilt_failure(TIMES, np.zeros(TIMES.size), calm, LOADED, 10.0) is None


def test_tilts_are_seen_from_the_plan_and_counted_from_the_loaded_attitude():
    """A torso turning about y from 0° to 20° (planned upright): from the start it has turned that far, from its
    loaded attitude (the turn at RAMP_S) that much less."""
    angle = np.radians(np.linspace(0.0, 20.0, TIMES.size))
    c, s = np.cos(angle), np.sin(angle)
    rot = np.zeros((TIMES.size, 3, 3))
    rot[:, 0, 0], rot[:, 0, 2], rot[:, 1, 1], rot[:, 2, 0], rot[:, 2, 2] = c, s, 1.0, -s, c
    track = _track(rot=rot)
    plan = Plan.hold(np.zeros(20), "left", RUN_S, np.full(20, 32.0))
    start = StartFacts(None, PlannedStates(np.eye(3)[None], (), "left", 0.0, np.zeros(3), np.eye(3)), False)  # type: ignore[arg-type]
    turned = tilts(track, start, plan)
    from_start, tilt, loaded = turned.from_start, turned.tilt, turned.loaded
    assert loaded == LOADED
    assert from_start == pytest.approx(np.degrees(angle), abs=1e-6)
    assert tilt[loaded:] == pytest.approx(np.degrees(angle[loaded:] - angle[loaded]), abs=1e-6)


# --- centre of mass --------------------------------------------------------------------------------------------

def test_com_drop_against_the_plan():
    planned = np.full(TIMES.size, 0.20)
    com = np.where(TIMES > 1.5, (1.0 - COM_DROP_FRACTION) * 0.20 - 0.001, 0.19)
    f = com_drop_failure(TIMES, com, planned)
    assert f is not None and f.reason == "com_drop" and f.time_s == pytest.approx(TIMES[_at(1.5) + 1])
    crouch = np.full(TIMES.size, 0.12)                       # a planned crouch is no drop
    assert com_drop_failure(TIMES, crouch, crouch) is None


# --- the floor and self-collisions -----------------------------------------------------------------------------

FOOT_LINKS = {"l_ank_roll_link": "left", "r_ank_roll_link": "right"}


def test_a_lifted_foot_or_another_link_on_the_floor():
    lifted = [frozenset({"right"})] * TIMES.size
    ground = [frozenset({"l_ank_roll_link"})] * TIMES.size
    assert floor_failures(TIMES, ground, lifted, FOOT_LINKS) == []
    touched = list(ground)
    touched[100] = frozenset({"l_ank_roll_link", "r_ank_roll_link"})
    touched[200] = frozenset({"l_ank_roll_link", "l_el_link"})
    found = floor_failures(TIMES, touched, lifted, FOOT_LINKS)
    assert [(f.reason, f.time_s) for f in found] == [("swing_foot_contact", TIMES[100]), ("ground_contact", TIMES[200])]
    assert "l_el_link" in found[1].detail
    both_down = [frozenset({"left", "right"}) - frozenset({"left", "right"})] * TIMES.size    # nothing lifted
    assert floor_failures(TIMES, [frozenset(FOOT_LINKS)] * TIMES.size, both_down, FOOT_LINKS) == []


def test_self_collision_names_the_pair_when_it_first_pressed():
    pairs = [frozenset()] * TIMES.size
    assert self_collision_failure(TIMES, pairs) is None
    pairs[42] = frozenset({("body_link", "l_el_link")})
    f = self_collision_failure(TIMES, pairs)
    assert f is not None and f.time_s == TIMES[42] and f.detail == "body_link against l_el_link"


# --- torques and joint limits ----------------------------------------------------------------------------------

def test_torque_saturation_over_the_steady_window():
    available = np.full((TIMES.size, 20), 2.0)
    torque = np.zeros((TIMES.size, 20))
    steady = TIMES >= TIMES[-1] - STEADY_S + 1e-9
    idx = np.flatnonzero(steady)
    torque[idx[: int(0.6 * idx.size)], 7] = -SATURATION_FRACTION * 2.0          # 60 % of the window, braking sign
    f = saturation_failure(TIMES, torque, available, NAMES)
    assert f is not None and f.reason == "torque_saturation" and "j7" in f.detail and f.time_s == TIMES[idx[0]]
    torque[:, 7] = 0.0
    torque[idx[: int((SATURATION_SHARE - 0.1) * idx.size)], 7] = 2.0            # too short a share
    torque[~steady, 3] = 2.0                                                     # saturated before the window
    assert saturation_failure(TIMES, torque, available, NAMES) is None


def test_joint_limit_needs_the_stop_away_from_the_goal_for_long_enough():
    limits = np.array([np.full(20, -1.0), np.full(20, 1.0)])
    q, goals = np.zeros((TIMES.size, 20)), np.zeros((TIMES.size, 20))
    hold = int(round(LIMIT_HOLD_S / DT_S))
    q[50:50 + hold + 1, 4] = 1.0 - LIMIT_AT_RAD / 2                              # on the stop, goal 0: held 0.2 s
    f = joint_limit_failure(TIMES, q, goals, limits, NAMES)
    assert f is not None and f.time_s == TIMES[50] and f.detail.startswith("j4 lies on its stop")
    goals[:, 4] = 1.0 - LIMIT_AWAY_RAD / 2                                      # its goal is at the stop: fine
    assert joint_limit_failure(TIMES, q, goals, limits, NAMES) is None
    q[:, 4], goals[:, 4] = 0.0, 0.0
    q[50:50 + hold - 5, 4] = -1.0                                                # too short
    assert joint_limit_failure(TIMES, q, goals, limits, NAMES) is None


def test_first_held_counts_a_run_that_reaches_the_end():
    mask = TIMES > RUN_S - 0.15
    assert first_held(mask, TIMES, 0.1) == _at(RUN_S - 0.15) + 1
    assert first_held(mask, TIMES, 5.0) is None                  # shorter than min(hold, the steady window)


# --- slip ------------------------------------------------------------------------------------------------------

def test_slip_of_a_supporting_sole_from_where_its_support_began():
    xy = np.zeros((TIMES.size, 2))
    xy[150:, 0] = np.linspace(0.0, 0.015, TIMES.size - 150)                  # slides 15 mm
    soles = {"left": xy, "right": np.zeros((TIMES.size, 2))}
    supporting = {"left": np.ones(TIMES.size, bool), "right": np.ones(TIMES.size, bool)}
    start = {"left": np.zeros(2), "right": np.zeros(2)}
    worst, f = slip(TIMES, soles, supporting, start)
    first_bad = int(np.argmax(xy[:, 0] > SLIP_LIMIT_M))
    assert worst == pytest.approx(0.015) and f is not None and f.time_s == TIMES[first_bad]
    supporting["left"][140:] = False                                          # it was lifted: a swing, no slip
    assert slip(TIMES, soles, supporting, start)[1] is None
    supporting["left"][:] = True
    supporting["left"][149] = False                                          # support begins again at 150
    worst, f = slip(TIMES, soles, supporting, start)
    assert f is not None and worst == pytest.approx(0.015)
    supporting["left"][200] = False                                          # re-anchored mid-slide: each < 1 cm
    assert slip(TIMES, soles, supporting, start)[1] is None


def test_in_a_motion_a_sole_supports_only_while_it_carries_load():
    light = [{"left": (40.0, np.zeros(2)), "right": (SLIP_LOAD_SHARE * 40.0, np.zeros(2))}] * TIMES.size
    track = _track(feet=tuple(light))
    held = Plan.hold(np.zeros(20), "double", RUN_S, np.full(20, 32.0))
    motion = replace(held, kind="motion", goals=np.zeros((2, 20)), p_gains=np.full((2, 20), 32.0),
                     supports=held.supports * 2)
    assert supporting_soles(track, held)["right"].all()                    # a held pose: its support's feet
    right = supporting_soles(track, motion)["right"]
    assert not right.any()                                                 # 1/6 of the load: unloading


# --- agreement -------------------------------------------------------------------------------------------------

def _run(*reasons: str) -> RunReport:
    template = RunReport("pybullet", "servo", 0.001, RUN_S, (), 0.02, 0.02, None, (0.0, 0.0, 0.2), (0.0, 0.0, 0.2),
                         0.0, 0.0, 0.0, 0.0, 0.0, 0.0, "left", (), (), 0.0, 0.0, "j0", 0.0, {})
    return replace(template, failures=tuple(Failure(r, 1.0 + k, "") for k, r in enumerate(reasons)))


def test_engines_agree_on_what_happened_not_only_on_the_verdict():
    def agree(a: RunReport, b: RunReport) -> bool:
        return CheckReport({"pybullet": EngineReport("pybullet", a), "mujoco": EngineReport("mujoco", b)}).agree

    assert agree(_run(), _run())
    assert agree(_run("tilt", "slip", "com_drop"), _run("slip", "tilt", "ground_contact"))   # both fell
    assert not agree(_run("tilt"), _run("self_collision"))          # one fell, the other only touched itself
    assert not agree(_run("slip"), _run())
    assert agree(_run("slip", "self_collision"), _run("self_collision", "slip"))
    assert not agree(_run("slip"), _run("slip", "self_collision"))


def test_the_check_reports_its_problem_in_one_phrase():
    ok = CheckReport({"pybullet": EngineReport("pybullet", _run())})
    assert ok.problem() is None and ok.stable and not ok.fell
    pushed = PushResult("left", 5.0, 2.0, 0.1, _run("tilt"))
    with_push = CheckReport({"pybullet": EngineReport("pybullet", _run(), (pushed,))})
    assert with_push.problem() == "fails when pushed 5 N left (tilt, pybullet)" and not with_push.pushes_survived
    split = CheckReport({"pybullet": EngineReport("pybullet", _run()), "mujoco": EngineReport("mujoco", _run("tilt"))})
    assert split.problem().startswith("the engines disagree (pybullet: stands, mujoco: tilt")


def _track(**given: object) -> Track:
    n = TIMES.size
    base = {"times": TIMES, "rows": np.zeros(n, int), "rot": np.repeat(np.eye(3)[None], n, axis=0),
            "com": np.zeros((n, 3)), "soles": {"left": np.zeros((n, 3)), "right": np.zeros((n, 3))},
            "q": np.zeros((n, 20)), "goals": np.zeros((n, 20)), "torque": np.zeros((n, 20)),
            "available": np.ones((n, 20)), "cop": (None,) * n, "feet": ({},) * n, "ground": (frozenset(),) * n,
            "self_pairs": (frozenset(),) * n, "states": ()}
    return Track(**{**base, **given})  # type: ignore[arg-type]
