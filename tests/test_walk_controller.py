"""The walk controller, the joint-speed limit and the robustness family: fast checks of what each piece promises
(the walks themselves run in tests/test_walk_robust.py, physics lane)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers import run_cli

from op2motion.errors import InputError
from op2motion.gait import load_preset
from op2motion.gait.controller import OPEN_LOOP, STOCK_GYRO_GAINS_S, Feedback, WalkController
from op2motion.gait.speeds import SPEED_SHARE, gait_within_speed, speed_check
from op2motion.gait.stabilised import _swing_phase
from op2motion.kinematics.leg_ik import leg_fk
from op2motion.physics import family
from op2motion.physics.robust import FRICTION_RANGE, LATENCY_S, STIFFNESS_RANGE, UNSTATED_TORSO
from op2motion.robot.spec import GRAVITY_M_S2
from op2motion.robot.specfile import default_spec

SHORT_STEPS = 4
RATE_RAD_S = 0.5            # a made-up torso rate for the damping's direction
TURN_SHARE = 0.01           # the damping turns a sole about the axis asked; the others at most 1 % of that


@pytest.fixture(scope="module")
def spec():
    return default_spec()


@pytest.fixture(scope="module")
def controller(spec):
    return WalkController.from_preset("forward", steps=SHORT_STEPS, spec=spec)


@pytest.fixture(scope="module")
def longer(spec):
    """Eight steps: the six between the first and the closing one swing alike."""
    return WalkController.from_preset("forward", steps=2 * SHORT_STEPS, spec=spec)


def _foot_in_torso(controller, goals, side):
    leg = controller.legs[side]
    return leg_fk(leg, np.asarray(goals)[list(leg.index)])[1][0]


@pytest.mark.parametrize("axis", [0, 1])
def test_gyro_damping_turns_the_body_against_its_rate(controller, spec, axis):
    """A torso turning about +x (roll) or +y (pitch) gets legs that turn it back: with the soles fixed, each sole
    turns in the torso frame the same way the torso turns in the world, i.e. the torso turns the other way."""
    rate = np.zeros(3)
    rate[axis] = RATE_RAD_S
    base = controller.gait.joints[0]
    damped = base + controller._damping(rate)
    for side in ("left", "right"):
        before, after = _foot_in_torso(controller, base, side), _foot_in_torso(controller, damped, side)
        turn = before.T @ after                                     # the sole's own turn, torso frame
        about = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]]) / 2.0
        assert about[axis] > 0.0, (side, about)
        assert abs(about[1 - axis]) < TURN_SHARE * about[axis] and abs(about[2]) < TURN_SHARE * about[axis], about


def test_stock_gains_are_the_frameworks_in_si():
    # Walking.cpp: gain x 4 ticks per gyro count; 1 tick = 360/4096 deg... the framework's 0.088 deg; 1 count =
    # 3.125 deg/s. Ankle roll 1.0 -> 4 x 0.088 / 3.125 = 0.113 s.
    tick, count = 0.088, 3.125
    expected = [g * 4 * tick / count for g in (0.5, 0.3, 0.9, 1.0)]
    assert np.allclose(STOCK_GYRO_GAINS_S, expected, atol=5e-4)


def test_open_loop_sends_the_plan(controller, spec):
    """Without feedback the controller is the planned schedule, tick for tick, whatever the IMU says."""
    open_loop = WalkController(controller.gait, spec, OPEN_LOOP)
    start = open_loop.start({n: 0.0 for n in spec.joint_names})
    assert start == controller.schedule.start({n: 0.0 for n in spec.joint_names})
    for t in (0.5, 1.7, 2.9):
        goals = open_loop.step(t, np.array([0.3, -0.2, 0.1]), np.array([1.0, 0.5, GRAVITY_M_S2]),
                               dict(zip(spec.joint_names, controller.gait.joints[0])))
        assert np.allclose([goals[n] for n in spec.joint_names], controller.schedule.goals_at(t))


def test_at_rest_upright_on_plan_the_controller_adds_nothing(spec, controller):
    """Still, upright and on the planned joints, every correction is zero: the goals are the plan's."""
    ctl = WalkController(controller.gait, spec)
    ctl.start({n: 0.0 for n in spec.joint_names})
    t = 0.1                                              # the lead-in: the plan's first row
    goals = ctl.step(t, np.zeros(3), np.array([0.0, 0.0, GRAVITY_M_S2]),
                     dict(zip(spec.joint_names, ctl.gait.joints[0])))
    assert np.allclose([goals[n] for n in spec.joint_names], ctl.schedule.goals_at(t), atol=1e-9)


def test_swing_phase_runs_zero_to_one_in_each_single_support():
    phase = _swing_phase(("double", "double", "left", "left", "left", "double", "right", "right"))
    assert phase.tolist() == pytest.approx([0, 0, 1 / 3, 2 / 3, 1, 0, 0.5, 1])


@pytest.mark.parametrize("field, value", [("kp", (1.0,)), ("ki", (-1.0, 0.0)), ("gyro", (0.1, 0.1, 0.1)),
                                          ("gyro", (0.1, 0.1, float("nan"), 0.1)), ("heading", -0.1),
                                          ("joint_ki", 1e9), ("attitude_tau_s", 0.0), ("heading_ki", -1.0),
                                          ("cross_track", float("inf")), ("learn_gain", 1.5),
                                          ("learn_shift_rows", 2.5), ("latency_s", 1.0), ("soft_kp", (-0.1, 0.0)),
                                          ("calibrate", 1), ("accel_tau_s", -0.1), ("accel_tau_s", 2.0),
                                          ("soft_gyro", -1.0), ("placement", 2.0), ("accept_landing", "yes")])
def test_bad_feedback_gains_are_refused_by_name(field, value):
    with pytest.raises(InputError) as err:
        Feedback(**{field: value})
    assert err.value.param == field


def test_the_forward_preset_is_within_the_servos_speed(spec):
    check = speed_check(gait_within_speed(load_preset("forward").with_steps(SHORT_STEPS), spec), spec)
    assert check.ok and check.limit_rad_s == pytest.approx(SPEED_SHARE * spec.servo.no_load_speed_rad_s)


def test_a_plan_too_fast_is_refused_naming_the_joint_or_re_timed(spec):
    fast = replace(load_preset("forward").with_steps(SHORT_STEPS), step_s=0.24, step_height_m=0.03)
    with pytest.raises(InputError) as err:
        gait_within_speed(fast, spec)
    assert err.value.param == "preset" and "knee" in str(err.value) and "step_s" in str(err.value)
    gait = gait_within_speed(fast, spec, retime=True)
    assert gait.params.step_s > fast.step_s and speed_check(gait, spec).ok
    assert gait.params.step_length_m == fast.step_length_m


def test_the_cli_refuses_a_too_fast_preset_in_one_line(capsys, tmp_path):
    preset = tmp_path / "fast.toml"
    preset.write_text('name = "fast"\nsteps = 4\nstep_length_m = 0.08\nstep_s = 0.24\nstep_height_m = 0.03\n'
                      'hip_lower_m = 0.04\n')
    code, out, err = run_cli(capsys, "walk", "--preset", str(preset))
    assert code == 2 and "knee" in err and len(err.strip().splitlines()) == 1
    code, out, err = run_cli(capsys, "walk", "--preset", str(preset), "--retime", "--json")
    assert code == 0 and '"step_s"' in out


def test_robust_needs_validate(capsys):
    code, _, err = run_cli(capsys, "walk", "--robust")
    assert code == 2 and "--validate" in err


def test_the_family_spans_the_specs_uncertainty(spec):
    members = family(spec)
    torso = spec.inertial(spec.root_link).uncertainty
    assert members[0].name == "nominal" and len(members) == 15 and len({m.name for m in members}) == 15
    xs = {m.com_shift_m[0] for m in members}
    ys = {m.com_shift_m[1] for m in members}
    assert min(xs) == torso.com_m[0][0] and max(xs) == torso.com_m[0][1]
    assert min(ys) == torso.com_m[1][0] and max(ys) == torso.com_m[1][1]
    assert {m.mass_scale for m in members} == {1.0, 1.0 - torso.mass_fraction, 1.0 + torso.mass_fraction}
    assert {m.stiffness for m in members} == {1.0, *STIFFNESS_RANGE}
    assert {m.friction for m in members} >= set(FRICTION_RANGE)
    assert all(m.setup().sensors.latency_s == LATENCY_S for m in members)
    heavy = next(m for m in members if m.mass_scale > 1.0 and m.stiffness == 1.0)
    body = heavy.body(spec)
    assert body.inertial(spec.root_link).mass == pytest.approx(spec.inertial(spec.root_link).mass * heavy.mass_scale)


def test_a_spec_without_a_torso_uncertainty_gets_the_issues_box(spec):
    bare = replace(spec, inertials=tuple(replace(i, uncertainty=None) for i in spec.inertials))
    xs = {m.com_shift_m[0] for m in family(bare)}
    assert max(xs) == UNSTATED_TORSO.com_m[0][1] == 0.02


def test_a_turns_planned_heading_is_continuous_past_half_a_turn(spec):
    """The heading correction compares the integrated gyro with the plan's heading: a turn of more than 180° must
    not jump by 360° where the angle wraps (it would steer the wrong way at full strength)."""
    ctl = WalkController.from_preset("turn_left", steps=16, spec=spec)
    assert ctl.plan_yaw[-1] > np.pi
    assert np.max(np.abs(np.diff(ctl.plan_yaw))) < 0.1


YAW_RATE_RAD_S = 0.05       # a made-up steady turn to the left the plan did not ask for


def test_a_steady_unplanned_turn_is_steered_back_and_its_sideways_error_counted(spec, controller):
    """A torso turning left that the plan does not turn: the heading error and its integral grow, the dead-reckoned
    position drifts to the left of the planned line, and the swing foot is steered to the right, more and more
    (PI plus line); without the integral and the line term the steer only follows the error."""
    def run(feedback):
        ctl = WalkController(controller.gait, spec, feedback)
        ctl.start({n: 0.0 for n in spec.joint_names})
        steer = []
        for k in range(ctl.lead, ctl.lead + 100):
            ctl.step(k * ctl.gait.dt, np.array([0.0, 0.0, YAW_RATE_RAD_S]), np.array([0.0, 0.0, GRAVITY_M_S2]),
                     dict(zip(spec.joint_names, ctl.gait.joints[k - ctl.lead])))
            steer.append(ctl._heading(0.0, k - ctl.lead))
        return ctl, np.array(steer)

    full, steer = run(Feedback())
    assert full.state.yaw_integral > 0.0 and full.state.offset[1] > 0.0       # left of the line
    assert steer[-1] < steer[10] < 0.0                                          # to the right, growing
    _, plain = run(replace(Feedback(), heading_ki=0.0, cross_track=0.0))
    assert steer[-1] < plain[-1] < 0.0


def test_the_learner_feeds_a_swing_legs_miss_forward_to_the_next_step_of_that_side(longer):
    """What the swing leg missed in one left step, shifted by the servo lag, is added to the goals of the next left
    step (smoothed, bounded); the stance leg learns nothing; a reset forgets."""
    from op2motion.gait.learning import MAX_LEARNED_RAD, PlannedLearner

    ctl = longer
    legs = {side: np.array(leg.index) for side, leg in ctl.legs.items()}
    shift, gain, miss_rad = 2, 0.5, 0.02
    learner = PlannedLearner.of(ctl.gait, legs, gain, shift)
    first, side = int(learner.first_row[1]), learner.side_of_step[1]
    other = "right" if side == "left" else "left"
    miss = np.full(learner.size, miss_rad)
    for k in range(first, first + 2 * learner.rows):             # steps 1 and 2
        assert not learner.correction(k).any()                   # nothing learnt yet for either side
        learner.learn(k, miss)
    step3 = int(learner.first_row[3])                            # the next step of the same side as step 1
    assert learner.side_of_step[3] == side
    middle = learner.correction(step3 + learner.rows // 2)
    assert np.allclose(middle[legs[side]], gain * miss_rad, atol=1e-12)
    assert not middle[legs[other]].any() and not np.delete(middle, np.r_[legs["left"], legs["right"]]).any()
    for _ in range(200):                                         # a miss that never goes away stays bounded
        for k in range(first, first + learner.rows):
            learner.correction(k)
            learner.learn(k + shift, np.full(learner.size, 1.0))
    assert np.abs(learner.memory[side]).max() <= MAX_LEARNED_RAD
    learner.reset()
    assert not learner.correction(first + 5).any()


STIFFNESS_TOL = 1e-9        # the least-squares fit of an exact sag recovers the stiffness to rounding
TILT_RAD = 0.05             # a made-up steady forward lean (2.9°)
TILT_TOL_RAD = 0.005        # the filtered estimate's mean within 0.3° of the lean
WALK_BIAS_RAD = 0.02        # each raw sample's tilt, averaged, is off by more than 1.1° under these impacts


@pytest.mark.parametrize("stiffness", [0.6, 1.0, 1.6])
def test_the_standing_calibration_measures_the_servos_stiffness(controller, stiffness):
    """Joints that sag by the feed-forward over the stiffness give that stiffness back; a softer servo gets the
    feed-forward it lacks (ramped in before the first step), a stiffer one nothing taken away."""
    from op2motion.gait.calibration import PlannedCalibration

    gait = controller.gait
    cal = PlannedCalibration.of(gait, controller.leg_index)
    assert cal.start_row < cal.end_row < cal.first_step
    size = gait.joints.shape[1]
    for k in range(cal.first_step):
        cal.observe(k, gait.goals[k], gait.goals[k] - (gait.goals[k] - gait.joints[k]) / stiffness)
    assert cal.estimate == pytest.approx(stiffness, abs=STIFFNESS_TOL)
    assert cal.softness == pytest.approx(float(np.clip((1.0 - stiffness) / 0.4, 0.0, 1.0)))
    assert not cal.compensation(cal.end_row - 1, size).any()
    later = cal.compensation(cal.first_step + 10, size)
    ff = gait.goals[cal.first_step + 10] - gait.joints[cal.first_step + 10]
    want = np.zeros(size)
    want[controller.leg_index] = max(1.0 / stiffness - 1.0, 0.0) * ff[controller.leg_index]
    assert np.allclose(later, want, atol=1e-12)
    cal.reset()
    assert cal.estimate == 1.0


def test_the_attitude_filter_is_not_biased_by_the_steps_impacts(spec, controller):
    """A body leaning steadily forward whose accelerometer also feels the steps: zero-mean forward jolts that come
    with a dip of the vertical reading (as at each touchdown). The tilt of each raw sample, averaged, is biased; the
    tilt of the low-passed vector is not."""
    def mean_tilt(feedback):
        ctl = WalkController(controller.gait, spec, feedback)
        ctl.start({n: 0.0 for n in spec.joint_names})
        estimates = []
        for i in range(2000):
            phase = (i % 40) / 40.0
            jolt = 8.0 * np.sin(2 * np.pi * phase) * (phase < 0.5)       # forward, then back
            jolt -= np.mean(8.0 * np.sin(2 * np.pi * np.arange(40) / 40.0) * (np.arange(40) < 20))
            dip = -9.0 if phase < 0.1 else 0.0                            # the vertical reading dips at impact
            dip -= -9.0 * 4 / 40                                          # zero mean
            accel = np.array([-GRAVITY_M_S2 * np.sin(TILT_RAD) + jolt, 0.0,
                              GRAVITY_M_S2 * np.cos(TILT_RAD) + dip])
            ctl._estimate(np.zeros(2), accel, 0)
            estimates.append(ctl.state.attitude[0])
        return float(np.mean(estimates[500:]))

    assert abs(mean_tilt(Feedback()) - TILT_RAD) < TILT_TOL_RAD
    assert abs(mean_tilt(replace(Feedback(), accel_tau_s=0.0)) - TILT_RAD) > WALK_BIAS_RAD


SHIFT_M = 0.01              # a made-up landing miss
ODOMETRY_TOL_M = 1e-9       # FK of exact joints recovers a miss to rounding


def test_leg_odometry_measures_a_landing_miss_and_moves_the_next_swing_across_the_line(controller):
    """Joints exactly as planned measure no miss; a foot that landed 10 mm to the left measures 10 mm; the next
    swing foot moves against the part across the direction of travel only (a forward walk: y), at most 20 mm; the
    closing step's miss is kept to hold that foot where it landed."""
    from op2motion.gait.odometry import MAX_PLACEMENT_M, PlannedOdometry, across, landing_rows
    from op2motion.kinematics.leg_ik import leg_ik

    gait = controller.gait
    rows = landing_rows(gait.timeline.contact, 4)
    assert len(rows) == len(gait.footsteps.steps)
    for k, (stance, landed) in rows.items():
        assert gait.timeline.contact[k] == "double" and stance != landed
    odo = PlannedOdometry.of(gait, controller.legs, 4)
    k, (stance, landed) = next(iter(rows.items()))
    odo.observe(k, gait.joints[k])
    assert np.allclose(odo.error, 0.0, atol=ODOMETRY_TOL_M)
    leg = controller.legs[landed]
    pos, rot = gait.torso_pos[k], gait.torso_rot[k]
    sole = gait.timeline.feet[landed][k, :3] + np.array([0.0, SHIFT_M, 0.0])
    moved = gait.joints[k].copy()
    moved[list(leg.index)] = leg_ik(leg, rot.T @ (sole - pos), rot.T @ np.eye(3))[0]
    odo.observe(k, moved)
    assert np.allclose(odo.error, [0.0, SHIFT_M], atol=1e-6)
    shift = odo.shift(0.5, np.array([0.25, 0.0]))
    assert np.allclose(shift, [0.0, -0.5 * SHIFT_M, 0.0], atol=1e-6)
    assert np.allclose(across(np.array([0.03, 0.02]), np.array([0.25, 0.0])), [0.0, 0.02])
    assert np.allclose(across(np.array([0.03, 0.02]), np.zeros(2)), [0.03, 0.02])   # in place: all of it
    odo.error = np.array([0.0, 1.0])
    assert np.hypot(*odo.shift(1.0, np.zeros(2))[:2]) == pytest.approx(MAX_PLACEMENT_M)
    assert odo.last is None
    odo.observe(max(rows), gait.joints[max(rows)])
    assert odo.last is not None and odo.last[0] == rows[max(rows)][1]
    odo.reset()
    assert odo.last is None and not odo.error.any()


def test_the_learner_leaves_out_the_first_and_the_closing_steps(longer):
    """The first step starts beside the other foot and the closing step ends beside it: their swings are not like
    the others, so they neither learn nor use what was learnt."""
    alike = longer.learner.alike
    assert not alike[0] and not alike[-1] and alike[1:-1].all()
    first, last = int(longer.learner.first_row[0]), int(longer.learner.first_row[-1])
    longer.learner.learn(first + 5, np.ones(longer.learner.size))
    assert not longer.learner._pending["left"].any() and not longer.learner._pending["right"].any()
    assert not longer.learner.correction(last + 3).any()


def test_soft_servos_get_the_stock_gyro_gains(spec, controller):
    """At the model's stiffness the damping is 0.6 of the stock gains; servos measured at 0.6 of it get all of them."""
    from op2motion.gait.feedback import SOFT_GYRO

    ctl = WalkController(controller.gait, spec)
    rate = np.array([RATE_RAD_S, RATE_RAD_S, 0.0])
    nominal = ctl._damping(rate)
    ctl.calibration.sums = np.array([1.0 / 0.6, 1.0])                  # sag = feed-forward / 0.6
    assert ctl.calibration.softness == pytest.approx(1.0)
    assert np.allclose(ctl._damping(rate), (1.0 + SOFT_GYRO) * nominal)
    assert np.allclose((1.0 + SOFT_GYRO) * np.array(Feedback().gyro), STOCK_GYRO_GAINS_S, atol=1e-3)


def test_stiff_servos_lose_gyro_damping_by_the_presets_share(spec, controller):
    """gyro_stiff_share 1: servos measured 1.5 times as stiff get 1/1.5 of the gains (the damping torque stays the
    model's); 0 (the default) leaves them alone; servos softer than the model are not touched by it."""
    from dataclasses import replace

    rate = np.array([RATE_RAD_S, RATE_RAD_S, 0.0])
    plain = WalkController(controller.gait, spec)
    shared = WalkController(replace(controller.gait, params=replace(controller.gait.params, gyro_stiff_share=1.0)),
                            spec)
    assert np.allclose(shared._damping(rate), plain._damping(rate))      # nothing measured yet: stiffness 1
    for ctl in (plain, shared):
        ctl.calibration.sums = np.array([1.0 / 1.5, 1.0])                 # sag = feed-forward / 1.5
    assert plain.calibration.estimate == pytest.approx(1.5)
    assert np.allclose(shared._damping(rate), plain._damping(rate) / 1.5)
