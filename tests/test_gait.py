"""Walking: the preview controller against the LIPM's own answer, the leg IK against the D-H model, footsteps that
never let the feet touch, presets, the generator's plan, a short walk in PyBullet and the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import run_cli

from op2motion.errors import InputError
from op2motion.gait import PRESETS, GaitParams, gait_schedule, generate_gait, preset_path, read_preset, walk_summary
from op2motion.gait.footsteps import place_footsteps
from op2motion.gait.preview import preview_gains, track_reference
from op2motion.gait.timeline import build_timeline
from op2motion.kinematics.dh import forward_dh_frames
from op2motion.kinematics.dh_chain import matrix_plan
from op2motion.kinematics.leg_ik import leg_fk, leg_ik, leg_of
from op2motion.physics import check
from op2motion.physics.body import Body
from op2motion.robot.joints import servo_to_book
from op2motion.robot.spec import GRAVITY_M_S2

IK_TOL_M = 1e-4             # the 0.1 mm
IK_ANGLE_TOL_RAD = 1e-9     # the closed form recovers the angles exactly in the hip-above-ankle domain
LIPM_TOL_M = 0.002          # the preview-controlled CoM against the LIPM's bounded answer to a ZMP step
ZMP_SETTLED_M = 0.001       # the cart's ZMP on the new reference one second after the step
PLAN_MARGIN_M = 0.010       # the issue: planned ZMP at least 10 mm inside the sole(s)
FLAT_TOL_RAD = 1e-9         # planned soles parallel to the floor
FOOT_TOL_M = 1e-6           # planned joints put the soles where the timeline wants them
WALK_DISTANCE_SHARE = 0.85  # a 4-step walk in PyBullet covers at least this share of its planned distance
COP_INSIDE = 0.95           # the issue: measured CoP inside the support polygon >= 95 % of the time
TURN_RATE_DEG_S = 30.0      # the issue: turning in place at >= 30 deg/s
SETTLE_TRAVEL_M = 0.001     # without swing_settle the foot still travels this far in the last 15 % of its swing


def test_preview_tracks_a_zmp_step_as_the_lipm_predicts():
    dt, zc, t0 = 0.008, 0.2, 2.0
    gains = preview_gains(dt, zc, 1.6)
    t = np.arange(int(5.0 / dt)) * dt
    step = 0.05
    ref = np.column_stack([np.where(t >= t0, step, 0.0), np.zeros_like(t)])
    track = track_reference(gains, ref)
    omega = math.sqrt(GRAVITY_M_S2 / zc)
    # the bounded LIPM solution of c - c''/omega^2 = p for a ZMP step: half-way at the step, exponential both sides
    lipm = np.where(t < t0, 0.5 * step * np.exp(omega * (t - t0)), step - 0.5 * step * np.exp(-omega * (t - t0)))
    assert np.max(np.abs(track.com[:, 0] - lipm)) < LIPM_TOL_M
    assert abs(track.com[int(t0 / dt), 0] - 0.5 * step) < LIPM_TOL_M
    late = t >= t0 + 1.0
    assert np.max(np.abs(track.zmp[late, 0] - step)) < ZMP_SETTLED_M
    assert np.max(np.abs(track.com[:, 1])) == 0.0


def _torso_from_dh(frames, slots, zero_frames, zero_points):
    """Torso rotation and origin (mid shoulder-pitch axes) in the D-H world, from frame 6 (fixed to the pelvis)."""
    t6_0 = zero_frames[slots["6"], 0]
    origin0 = 0.5 * (zero_points.point("l_sho_pitch")[0] + zero_points.point("r_sho_pitch")[0])
    c_rot, c_pos = t6_0[:3, :3].T, t6_0[:3, :3].T @ (origin0 - t6_0[:3, 3])
    t6 = frames[slots["6"]]
    return t6[:, :3, :3] @ c_rot, t6[:, :3, 3] + t6[:, :3, :3] @ c_pos


@pytest.mark.parametrize("support", ["left", "right"])
def test_leg_ik_inverts_the_dh_leg_fk(spec, rng, support):
    n = 300
    servo = np.zeros((n, len(spec.joints)))
    low, high = np.array([-0.5, -0.3, -1.0, 0.05, -0.8, -0.4]), np.array([0.5, 0.3, 0.3, 1.6, 0.8, 0.4])
    for side in ("left", "right"):
        leg = leg_of(spec, side)
        servo[:, list(leg.index)] = rng.uniform(low, high, (n, 6)) * leg.sign
    slots = matrix_plan(spec, support).slots
    zero_points, zero_frames = forward_dh_frames(servo_to_book(np.zeros((1, 20)), support, spec), spec)
    points, frames = forward_dh_frames(servo_to_book(servo, support, spec), spec)
    rot_t, pos_t = _torso_from_dh(frames, slots, zero_frames, zero_points)
    swing = "right" if support == "left" else "left"
    r12 = frames[slots["12"]][:, :3, :3]                       # D-H frame 12: x down, y left, z forward
    soles = {support: (np.zeros((n, 3)), np.broadcast_to(np.eye(3), (n, 3, 3))),
             swing: (points.point(f"{swing}_sole"), np.stack([r12[:, :, 2], r12[:, :, 1], -r12[:, :, 0]], -1))}
    for side, (pos, rot) in soles.items():
        rel_pos = np.einsum("nji,nj->ni", rot_t, pos - pos_t)
        rel_rot = np.transpose(rot_t, (0, 2, 1)) @ rot
        leg = leg_of(spec, side)
        angles = leg_ik(leg, rel_pos, rel_rot)
        back_pos, back_rot = leg_fk(leg, angles)
        assert np.max(np.linalg.norm(back_pos - rel_pos, axis=1)) < IK_TOL_M
        assert np.max(np.abs(back_rot - rel_rot)) < IK_TOL_M
        assert np.max(np.abs(angles - servo[:, list(leg.index)])) < IK_ANGLE_TOL_RAD


def test_leg_ik_refuses_a_foot_beyond_reach(spec):
    leg = leg_of(spec, "left")
    with pytest.raises(InputError, match="within 0.1860 m"):
        leg_ik(leg, np.array([[0.0, 0.037, -0.5]]), np.eye(3)[None])


def test_footsteps_alternate_and_close_the_feet(spec):
    params = GaitParams(steps=6, step_length_m=0.05)
    plan = place_footsteps(params, spec)
    assert [s.side for s in plan.steps] == ["left", "right"] * 3
    assert [round(s.x, 6) for s in plan.steps] == [0.05, 0.1, 0.15, 0.2, 0.25, 0.25]
    assert all(abs(abs(s.y) - spec.geometry.hip_half_width) < 1e-12 for s in plan.steps)   # width 0: the hips'
    right = place_footsteps(GaitParams(steps=4, turn_deg=-10.0, step_width_m=0.08), spec)
    assert right.steps[0].side == "right" and right.steps[-1].yaw == pytest.approx(math.radians(-30.0))


def test_footsteps_that_would_touch_are_refused(spec):
    with pytest.raises(InputError, match="apart") as info:
        place_footsteps(GaitParams(steps=4, step_side_m=0.04, step_width_m=0.06), spec)
    assert info.value.param == "footsteps"


def test_walk_to_a_target_ends_there(spec):
    params = read_preset(preset_path("forward"))
    gait = generate_gait(params, spec, target=(0.3, 0.05, math.radians(20.0)))
    end = gait.end_pose()
    assert end == pytest.approx([0.3, 0.05, math.radians(20.0)], abs=1e-9)


def test_shipped_presets_load_and_bad_ones_are_refused(tmp_path):
    for name in PRESETS:
        assert read_preset(preset_path(name)).name == name
    bad = tmp_path / "bad.toml"
    bad.write_text('step_s = 0.3\nstep_lenght_m = 0.05\n')
    with pytest.raises(InputError, match="step_lenght_m"):
        read_preset(bad)
    bad.write_text('step_s = "fast"\n')
    with pytest.raises(InputError, match="step_s: expected a number"):
        read_preset(bad)
    with pytest.raises(InputError, match="no such file|expected a gait preset"):
        read_preset(preset_path(str(tmp_path / "missing.toml")))


def test_planned_walk_keeps_the_zmp_inside_and_the_soles_flat_where_planned(spec):
    params = read_preset(preset_path("forward")).with_steps(6)
    gait = generate_gait(params, spec)
    assert gait.zmp_margin.min() >= PLAN_MARGIN_M
    body = Body(spec)
    for i in range(0, len(gait.times), 7):
        state = body.state(gait.torso_pos[i], gait.torso_rot[i], gait.joints[i])
        for side in ("left", "right"):
            pos, rot = state.soles[side]
            want = gait.timeline.feet[side][i]
            assert np.linalg.norm(pos - want[:3]) < FOOT_TOL_M
            assert abs(rot[2, 2] - 1.0) < FLAT_TOL_RAD
    # every swing lands at rest: the foot's height and speed are zero on the landing row
    z = {s: gait.timeline.feet[s][:, 2] for s in ("left", "right")}
    for side in ("left", "right"):
        landing = np.flatnonzero((z[side][:-1] > 0.0) & (z[side][1:] == 0.0))
        assert len(landing) == 3
        assert np.all(np.abs(np.diff(gait.timeline.feet[side][:, :2], axis=0)[landing + 1]) < 1e-12)


def test_timeline_marks_single_support_while_the_foot_is_up(spec):
    params = GaitParams(steps=2, step_length_m=0.04)
    timeline = build_timeline(params, place_footsteps(params, spec))
    for i, support in enumerate(timeline.supports):
        if support != "double":
            swing = "left" if support == "right" else "right"
            assert timeline.feet[swing][i, 2] > 0.0


def test_a_settling_swing_is_over_its_place_before_it_lands(spec):
    """``swing_settle``: for the last share of the swing the foot only descends; without it, it still travels."""
    for settle in (0.0, 0.15):
        params = GaitParams(steps=2, step_length_m=0.08, step_s=0.32, double_support_ratio=0.05,
                            swing_settle=settle)
        timeline = build_timeline(params, place_footsteps(params, spec))
        swing = timeline.feet["left"] if timeline.contact[timeline.step.tolist().index(0)] == "right" \
            else timeline.feet["right"]
        rows = np.flatnonzero((timeline.step == 0) & (np.array(timeline.contact) != "double"))
        goal = swing[rows[-1], :2]
        late = rows[int(len(rows) * 0.85) + 1:-1]          # the last 15 % of the swing, the landing row left out
        travelled = np.abs(swing[late, 0] - goal[0])
        assert np.all(swing[late, 2] > 0.0)
        if settle:
            assert np.all(travelled < FOOT_TOL_M)
        else:
            assert np.max(travelled) > SETTLE_TRAVEL_M


@pytest.mark.physics
def test_a_short_walk_walks_in_pybullet(spec):
    gait = generate_gait(read_preset(preset_path("forward")).with_steps(4), spec)
    schedule = gait_schedule(gait, spec)
    report = check(schedule, spec)
    physics = walk_summary(report, schedule.plan.walk.start_s)
    run = physics["engines"]["pybullet"]
    assert run["fell"] is False and physics["fell"] is False
    planned = np.hypot(*gait.end_pose()[:2])
    assert run["distance_m"] > WALK_DISTANCE_SHARE * planned
    assert run["cop_inside_fraction"] >= COP_INSIDE
    assert run["self_collisions"] == []
    assert report.run.engine == "pybullet" and report.run.walk.distance_m == pytest.approx(run["distance_m"], abs=1e-4)


@pytest.mark.physics
def test_turning_in_place_keeps_the_servos_below_their_limit_in_mujoco(spec):
    """The turn preset (8 steps) in MuJoCo, the engine with the rotor inertia the feed-forward is computed for:
    it turns at >= 30 deg/s with no servo at its available torque and the CoP inside the planned soles."""
    gait = generate_gait(read_preset(preset_path("turn_left")).with_steps(8), spec)
    schedule = gait_schedule(gait, spec)
    run = walk_summary(check(schedule, spec, ("mujoco",)), schedule.plan.walk.start_s)["engines"]["mujoco"]
    assert run["fell"] is False and run["reasons"] == []
    assert run["turn_rate_deg_s"] >= TURN_RATE_DEG_S
    assert run["worst_torque"]["limited_share"] == 0.0
    assert run["cop_inside_fraction"] >= COP_INSIDE
    assert run["self_collisions"] == []


def test_walk_cli_writes_csv_and_webots_and_refuses_bad_input(capsys, tmp_path, spec):
    csv, motion = tmp_path / "w.csv", tmp_path / "w.motion"
    code, out, _ = run_cli(capsys, "walk", "--steps", "2", "--out", str(csv), str(motion), "--json")
    assert code == 0
    result = json.loads(out)
    for key in ("steps", "duration_s", "distance_m", "zmp_margin_min_m", "footsteps"):
        assert key in result
    rows = csv.read_text().splitlines()
    assert len(rows) == 1 + round(result["duration_s"] / 0.008) + 1
    lines = motion.read_text().splitlines()
    assert lines[0].startswith("#WEBOTS_MOTION,V1.0,") and len(lines) == len(rows)
    code, _, err = run_cli(capsys, "walk", "--out", str(tmp_path / "w.txt"))
    assert code == 2 and ".csv or .motion" in err and not (tmp_path / "w.txt").exists()
    code, _, err = run_cli(capsys, "walk", "--push", "2")
    assert code == 2 and "--validate" in err
    code, _, err = run_cli(capsys, "walk", "--preset", "nowhere")
    assert code == 2 and "forward" in err
