"""The steered walk without physics: command timelines (and their bad input), the envelope and its acceleration
limits, the phase program (standing, starting, stopping within two steps), the rolling planner (rows without seams,
the dry run equal to the walk), commands taking effect from the next step, and ``done``."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from helpers import run_cli

from op2motion.errors import InputError
from op2motion.gait import WalkController
from op2motion.gait.commands import MAX_DURATION_S, MAX_ENTRIES, parse_csv, parse_json, read_commands, timeline_of
from op2motion.gait.envelope import STEER_ENVELOPE, Envelope, Stride
from op2motion.gait.phases import Intent, initial_state, next_phase
from op2motion.gait.presets import load_preset
from op2motion.gait.steer import LEAD_S, SteerableWalk
from op2motion.robot.spec import GRAVITY_M_S2
from op2motion.robot.specfile import default_spec

DT = 0.008
STEP_S = 0.32
JOINT_JUMP_RAD = 0.0415     # no planned joint moves more than this between two rows: 90 % of the MX-28's no-load
                            # speed (5.18 rad/s at 12 V) for 8 ms, what a planned walk's joints keep within
COM_JUMP_M = 0.003          # ... nor the planned CoM more than this


@pytest.fixture(scope="module")
def spec():
    return default_spec()


@pytest.fixture(scope="module")
def params():
    return load_preset("steer")


def test_the_readme_import_path_gives_the_walk_controller():
    from op2motion.gait.controller import WalkController as Direct

    assert WalkController is Direct


def test_the_walk_controller_makes_the_steered_walk(spec):
    """``WalkController.steerable()``: the way to a steered walk from the walk controller (a class method, no patched
    attribute), the same walk as ``SteerableWalk.make()``; both walks share the stabilised walk."""
    from op2motion.gait.stabilised import StabilisedWalk

    walk = WalkController.steerable(spec, "steer")
    assert isinstance(walk, SteerableWalk) and isinstance(walk, StabilisedWalk)
    assert walk.params == SteerableWalk.make(spec, "steer").params and issubclass(WalkController, StabilisedWalk)


# -- command timelines ------------------------------------------------------------------------------------------


def test_a_csv_timeline_reads_commands_and_events_in_degrees_at_the_edge():
    timeline = parse_csv("# a walk\nt_s,vx_m_s,vy_m_s,yaw_rate_deg_s,event\n0,0,0,0,\n2,0.1,0,30,\n5,,,,kick_right\n"
                         "7,,,,stop\n")
    assert [e.t_s for e in timeline.entries] == [0, 2, 5, 7]
    assert timeline.entries[1].command == pytest.approx((0.1, 0.0, math.radians(30.0)))
    assert timeline.command_at(4.0) == pytest.approx((0.1, 0.0, math.radians(30.0)))
    assert timeline.command_at(8.0) == (0.0, 0.0, 0.0)
    assert [e.event for e in timeline.due(2.0, 7.0)] == ["kick_right", "stop"]


@pytest.mark.parametrize("text, where", [
    ("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s\n0,0,0,0\n1,0.1,0\n", "line 3"),          # a speed missing
    ("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s\n0,0,0,0\n1,nan,0,0\n", "line 3: vx_m_s"),
    ("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s\n0,0,0,0\n1,0,0,999\n", "line 3: yaw_rate_deg_s"),
    ("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s\n2,0,0,0\n1,0,0,0\n", "line 3: t_s"),      # not increasing
    ("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s,event\n0,,,,jump\n", "line 2: event"),
    ("t_s,vx,vy\n0,0,0\n", "line 1"),                                              # unknown columns
    (f"t_s,event\n{MAX_DURATION_S + 1},stop\n", "line 2: t_s"),                     # beyond the duration cap
    ("", "expected a header"),
])
def test_bad_csv_rows_are_named_by_file_and_line(text, where):
    with pytest.raises(InputError) as err:
        parse_csv(text, "walk.csv")
    assert err.value.param == "commands" and "walk.csv" in str(err.value) and where in str(err.value)


def test_json_timelines_and_their_bad_entries(tmp_path):
    good = {"schema": "op2motion.commands/1",
            "commands": [{"t_s": 0, "vx_m_s": 0, "vy_m_s": 0, "yaw_rate_deg_s": 0}, {"t_s": 3, "event": "stop"}]}
    assert [e.event for e in parse_json(good).entries] == [None, "stop"]
    bad = dict(good, commands=[{"t_s": 0, "vx_m_s": "fast", "vy_m_s": 0, "yaw_rate_deg_s": 0}])
    with pytest.raises(InputError, match=r"commands\[0\]: vx_m_s"):
        parse_json(bad, "walk.json")
    with pytest.raises(InputError, match="schema"):
        parse_json({"commands": []}, "walk.json")
    with pytest.raises(InputError, match=r"commands\[0\].*extra"):
        parse_json(dict(good, commands=[{"t_s": 0, "event": "stop", "extra": 1}]), "walk.json")
    path = tmp_path / "walk.json"
    path.write_text('{"schema": "op2motion.commands/1", "commands": [], "commands": []}')
    with pytest.raises(InputError, match="twice"):
        read_commands(path)
    many = {"schema": "op2motion.commands/1", "commands": [{"t_s": i * 0.01, "event": "stop"}
                                                             for i in range(MAX_ENTRIES + 1)]}
    with pytest.raises(InputError, match=f"at most {MAX_ENTRIES}"):
        parse_json(many)


def test_the_cli_refuses_a_bad_command_file_in_one_line(capsys, tmp_path):
    path = tmp_path / "walk.csv"
    path.write_text("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s\n0,0,0,0\n1,5,0,0\n")
    code, _, err = run_cli(capsys, "walk", "--commands", str(path))
    assert code == 2 and err.startswith("op2motion: error: --commands:") and "line 3" in err
    assert len(err.strip().splitlines()) == 1
    code, _, err = run_cli(capsys, "walk", "--commands", str(path), "--steps", "4")
    assert code == 2 and "--steps" in err


def test_the_cli_plans_a_commanded_walk(capsys, tmp_path):
    path = tmp_path / "walk.json"
    path.write_text(json.dumps({"schema": "op2motion.commands/1", "commands": [
        {"t_s": 0, "vx_m_s": 0, "vy_m_s": 0, "yaw_rate_deg_s": 0},
        {"t_s": 1, "vx_m_s": 0.15, "vy_m_s": 0, "yaw_rate_deg_s": 0}, {"t_s": 4, "event": "stop"}]}))
    code, out, _ = run_cli(capsys, "walk", "--commands", str(path), "--json")
    result = json.loads(out)
    assert code == 0 and result["preset"] == "steer" and result["planned"]["steps"] >= 4
    assert result["planned"]["end_pose"]["x_m"] > 0.2 and result["commands"]["events"] == ["stop"]


# -- the envelope and the phase program --------------------------------------------------------------------------


def test_the_envelope_clamps_each_axis_and_their_sum_keeping_the_turn():
    env = Envelope(forward_m_s=0.2, backward_m_s=0.1, sideways_m_s=0.05, turn_rad_s=0.5, combined=1.2)
    assert env.clamp(1.0, 0.0, 0.0) == pytest.approx((0.2, 0.0, 0.0))
    assert env.clamp(-1.0, 0.0, 0.0) == pytest.approx((-0.1, 0.0, 0.0))
    assert env.clamp(0.1, 0.0, 0.25) == pytest.approx((0.1, 0.0, 0.25))       # shares 0.5 + 0.5: inside
    vx, vy, w = env.clamp(0.2, 0.02, 0.5)                  # too much together: the steps shorten, the turn stays
    assert w == pytest.approx(0.5) and vx / 0.2 + vy / 0.05 == pytest.approx(0.2) and vx / vy == pytest.approx(10.0)
    with pytest.raises(InputError):
        env.clamp(float("nan"), 0.0, 0.0)


def test_strides_change_within_the_acceleration_limits(params, spec):
    state = initial_state(params, spec)
    intent = Intent(STEER_ENVELOPE.stride(0.25, 0.0, 0.0, params.step_s))
    strides = []
    for _ in range(40):
        phase, state = next_phase(state, intent, params, spec, STEER_ENVELOPE)
        if phase.kind == "step":
            strides.append(phase.stride.dx)
    most = STEER_ENVELOPE.accel_x_m_s2 * params.step_s ** 2
    assert np.all(np.diff([0.0, *strides]) <= most + 1e-12)
    assert strides[-1] == pytest.approx(0.25 * params.step_s)


def test_the_robot_stands_while_the_command_is_zero_and_stops_within_two_steps(params, spec):
    state = initial_state(params, spec)
    for _ in range(20):                                    # zero command: standing phases only
        phase, state = next_phase(state, Intent(), params, spec, STEER_ENVELOPE)
        assert phase.kind == "stand"
    walk = Intent(STEER_ENVELOPE.stride(0.25, 0.0, 0.0, params.step_s))
    while state.stride.dx < 0.25 * params.step_s - 1e-9:
        phase, state = next_phase(state, walk, params, spec, STEER_ENVELOPE)
    kinds = []
    for _ in range(4):
        phase, state = next_phase(state, Intent(stop=True), params, spec, STEER_ENVELOPE)
        kinds.append((phase.kind, phase.closing))
    assert kinds[:3] == [("step", False), ("step", True), ("end", False)] and kinds[3][0] == "stand"
    assert abs(state.left.x - state.right.x) < 1e-9 and state.left.yaw == pytest.approx(state.right.yaw)


def test_a_side_step_that_would_bring_the_feet_together_takes_less(params, spec):
    """Stepping right with the left foot swinging narrows the stance: the side step shrinks until the soles keep
    their gap."""
    from op2motion.gait.footsteps import swing_clear

    state = initial_state(params, spec)
    side = Intent(Stride(0.0, -0.05, 0.0))                # far more than the envelope's side step, to the right
    phase, state = next_phase(state, side, params, spec, STEER_ENVELOPE)   # stand (calibration time)
    while phase.kind != "step":
        phase, state = next_phase(state, side, params, spec, STEER_ENVELOPE)
    for _ in range(6):
        before = state
        phase, state = next_phase(state, side, params, spec, STEER_ENVELOPE)
        swing = phase.swing
        other = "left" if swing == "right" else "right"
        assert swing_clear(before.foot(other), before.foot(swing), state.foot(swing), spec)


# -- the rolling planner and the controller ----------------------------------------------------------------------


def _drive(walk: SteerableWalk, seconds: float, spec, at=None) -> dict[int, np.ndarray]:
    """Step ``walk`` with still, upright sensors and the planned joints as measured; ``at``: {time: action}. Its
    planner keeps every phase (for the test to look at)."""
    walk.start({n: 0.0 for n in spec.joint_names})
    walk.planner.keep_all = True
    goals = {}
    for i in range(1, int(round(seconds / DT))):
        t = i * DT
        for when, action in list((at or {}).items()):
            if t >= when:
                action(walk)
                del at[when]
        k = max(walk._row(t), 0)
        joints = walk.rows.get("joints", k) if walk.rows.has(k) else walk.planner.standing_goals
        goals[i] = np.array(list(walk.step(t, np.zeros(3), np.array([0.0, 0.0, GRAVITY_M_S2]),
                                           dict(zip(spec.joint_names, joints))).values()))
    return goals


@pytest.mark.slow
def test_the_rolling_rows_have_no_seams_and_the_dry_run_is_the_walk(spec):
    timeline = timeline_of([(0.0, 0.0, 0.0, 0.0), (1.0, 0.2, 0.0, 0.3), (4.0, 0.0, 0.05, 0.0), (6.0, "stop")])
    walk = SteerableWalk.make(spec, commands=timeline)
    plan = walk.plan
    twin = walk.dry
    assert twin is not None and walk.dry_rows > 700
    rows = twin.rows
    joints, com = rows.numeric["joints"][:walk.dry_rows], rows.numeric["com"][:walk.dry_rows]
    assert np.abs(np.diff(joints, axis=0)).max() < JOINT_JUMP_RAD
    assert np.abs(np.diff(com, axis=0)).max() < COM_JUMP_M
    assert len(plan.goals) == walk.lead + walk.dry_rows
    online = SteerableWalk.make(spec, commands=timeline)
    _drive(online, LEAD_S + 4.0, spec)
    k = online._row(LEAD_S + 4.0) - 1
    assert np.allclose(online.rows.get("goals", k), rows.get("goals", k), atol=1e-12)


@pytest.mark.slow
def test_a_command_takes_effect_from_the_next_step_and_stop_ends_in_done(spec):
    walk = SteerableWalk.make(spec)
    _drive(walk, LEAD_S + 2.0, spec)
    assert not [p for _, p in walk.planner.phases if p.kind == "step"]        # zero command: it stands
    issued = walk._row(LEAD_S + 2.0)
    _drive_more(walk, LEAD_S + 2.0, 4.0, spec, lambda w: w.command(0.15, 0.0, 0.0))
    steps = [(first, p) for first, p in walk.planner.phases if p.kind == "step"]
    assert steps and steps[0][1].stride.dx > 0.0
    assert all(first > issued for first, _ in steps)
    stop_row = walk._row(LEAD_S + 6.0)
    _drive_more(walk, LEAD_S + 6.0, 4.0, spec, lambda w: w.stop())
    after = [p for first, p in walk.planner.phases if p.kind == "step" and first > stop_row]
    assert len(after) <= 3 and after[-1].closing
    assert walk.done


BRANCH_LEAD_S = 0.32        # the stop tests' shared walk ends this long before their earliest stop [s]
STOP_END_S = 1.05           # a stop at 0.25 m/s has closed the feet this soon [s]: up to three steps of 0.32 s
STOP_ZMP_MARGIN_M = 0.0     # ... with the planned ZMP inside the soles all the way [m]
#: A stop as the first step is planned [m]: inside the soles from a slow command; from 0.25 m/s the first step, planned
#: already at the command's stride, leaves the planned ZMP 8 mm outside (it was 29 mm: docs/steering.md)
JUST_STARTED_MARGIN_M = {0.08: 0.0, 0.25: -0.010}


@pytest.fixture(scope="module")
def walking(spec) -> SteerableWalk:
    """A walk commanded forward at LEAD_S + 1 s, driven to :data:`BRANCH_LEAD_S` before LEAD_S + 4 s, at a tick
    with no planning in progress (so that a copy of it walks on exactly as it would have)."""
    walk = SteerableWalk.make(spec)
    _drive(walk, LEAD_S + 1.0, spec)
    _drive_more(walk, LEAD_S + 1.0, 3.0 - BRANCH_LEAD_S, spec, lambda w: w.command(0.25, 0.0, 0.0))
    assert walk.planner.task is None
    return walk


@pytest.mark.parametrize("late", range(0, 40, 4))
def test_a_stop_at_any_tick_closes_the_feet_after_a_half_step_with_the_zmp_inside(spec, walking, late):
    """Whenever in a step the stop comes (a phase's planning may have begun with the walking command): the step
    already planned then (if any), a half step, the step that closes the feet; the feet closed within
    :data:`STOP_END_S`, and the planned ZMP inside the soles all the way (closing right after a step planned before
    the stop had put it 63 mm outside at this speed: the preview had not seen the closing step coming)."""
    from op2motion.gait.rows import planned_zmp_margins

    walk = copy.deepcopy(walking)
    _drive_more(walk, LEAD_S + 4.0 - BRANCH_LEAD_S, BRANCH_LEAD_S + late * DT, spec, lambda w: None)
    t = LEAD_S + 4.0 + late * DT
    stop_row = walk._row(t)
    walking_stride = walk.planner.state.stride.dx
    _drive_more(walk, t, 2.5, spec, lambda w: w.stop())
    after = [(first, p) for first, p in walk.planner.phases if p.kind == "step" and first > stop_row]
    assert 2 <= len(after) <= 3 and after[-1][1].closing
    assert after[-2][1].stride.dx == pytest.approx(0.5 * walking_stride)            # the half step before closing
    end = next(first for first, p in walk.planner.phases if p.kind == "end" and first > stop_row)
    assert (end - stop_row) * DT <= STOP_END_S
    rows = walk.rows
    assert planned_zmp_margins(rows, spec, rows.end - rows.first).min() >= STOP_ZMP_MARGIN_M


@pytest.mark.slow
@pytest.mark.parametrize("speed", [0.25, 0.08])
def test_a_commanded_stop_anywhere_in_a_step_keeps_the_planned_zmp_inside_the_soles(spec, speed):
    """A stop in a command timeline at five points of one step (at 3.856 s the next step is already planned:
    closing right after it put the planned ZMP 62 mm outside the soles at 0.25 m/s), a zero command from the same
    walk (closing at once from a slow stride put it 22 mm outside): the planned ZMP inside the soles all the way; and a
    stop as the walk has just started (closing at once from the start put it 28 mm outside)."""
    from op2motion.gait.steer import planned_summary

    def margin(rows: str) -> float:
        timeline = parse_csv(f"t_s,vx_m_s,vy_m_s,yaw_rate_deg_s,event\n0,0,0,0,\n1.6,{speed},0,0,\n{rows}")
        return planned_summary(SteerableWalk.make(spec, commands=timeline)).zmp_margin_min_m

    for t_s in 3.6 + np.arange(5) * STEP_S / 5:
        assert margin(f"{t_s:.3f},,,,stop\n") >= STOP_ZMP_MARGIN_M, t_s
    assert margin("3.6,0,0,0,\n6,,,,stop\n") >= STOP_ZMP_MARGIN_M
    assert margin("2.2,,,,stop\n") >= JUST_STARTED_MARGIN_M[speed]


def test_a_copied_walk_walks_on_as_the_original(spec, walking):
    """The stop tests branch from one walk: a copy steps exactly as a walk driven from the start."""
    walk = SteerableWalk.make(spec)
    _drive(walk, LEAD_S + 1.0, spec)
    _drive_more(walk, LEAD_S + 1.0, 3.0, spec, lambda w: w.command(0.25, 0.0, 0.0))
    copied = copy.deepcopy(walking)
    _drive_more(copied, LEAD_S + 4.0 - BRANCH_LEAD_S, BRANCH_LEAD_S, spec, lambda w: None)
    assert [(k, p.kind) for k, p in copied.planner.phases] == [(k, p.kind) for k, p in walk.planner.phases]
    k = walk._row(LEAD_S + 4.0)
    assert np.array_equal(copied.rows.get("joints", k), walk.rows.get("joints", k))


def _drive_more(walk: SteerableWalk, t0: float, seconds: float, spec, first) -> None:
    """Go on stepping ``walk`` from ``t0`` [s] for ``seconds``, calling ``first(walk)`` before the first tick."""
    first(walk)
    for i in range(1, int(round(seconds / DT)) + 1):
        t = t0 + i * DT
        k = walk._row(t)
        joints = walk.rows.get("joints", min(k, walk.rows.end - 1))
        walk.step(t, np.zeros(3), np.array([0.0, 0.0, GRAVITY_M_S2]), dict(zip(spec.joint_names, joints)))


def test_a_planned_walk_is_done_once_its_plan_has_run_out_and_the_body_is_still(spec):
    ctl = WalkController.from_preset("forward", steps=2, spec=spec)
    ctl.start({n: 0.0 for n in spec.joint_names})
    still = (np.zeros(3), np.array([0.0, 0.0, GRAVITY_M_S2]))
    t = 0.0
    while t < ctl.plan.end_s:
        t += DT
        ctl.step(t, *still, dict(zip(spec.joint_names, ctl.gait.joints[0])))
        assert not ctl.done or t >= ctl.plan.end_s
    for _ in range(100):
        t += DT
        ctl.step(t, *still, dict(zip(spec.joint_names, ctl.gait.joints[-1])))
    assert ctl.done
    ctl.step(t + DT, np.array([0.0, 3.0, 0.0]), still[1], dict(zip(spec.joint_names, ctl.gait.joints[-1])))
    assert not ctl.done                                    # moving again: not still


def test_commands_not_followed_are_reported(capsys, tmp_path):
    """A command beyond the envelope is named with what it walks; a plan that ends far from where the commands end
    says so, both in the text and the JSON's warnings (the result said nothing)."""
    path = tmp_path / "fast.csv"
    path.write_text("t_s,vx_m_s,vy_m_s,yaw_rate_deg_s,event\n0,0.40,0,0,\n4,,,,stop\n")
    code, out, err = run_cli(capsys, "walk", "--commands", str(path), "--json")
    warnings = json.loads(out)["warnings"]
    assert code == 0 and any("0 s: the command (+0.400 m/s forward" in w and "it walks (+0.250 m/s" in w
                             for w in warnings), warnings
    assert any(w.startswith("the plan ends at") for w in warnings), warnings
    from helpers import ROOT

    from op2motion.gait.envelope import STEER_ENVELOPE

    example = read_commands(f"{ROOT}/examples/steer_commands.csv")        # the shipped example asks for no more
    assert all(STEER_ENVELOPE.clamp(*e.command) == e.command for e in example.entries if e.command is not None)
