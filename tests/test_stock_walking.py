"""The stock ROBOTIS Walking module emulated (op2motion.gait.stock_walking, stock_config): the framework's published
stance and timing reproduced tick for tick, the config file read and written with every key Walking.cpp reads."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import STOCK

from op2motion.errors import InputError
from op2motion.formats.action import ActionFile
from op2motion.gait.stock_config import KEYS, StockConfig, parse_stock_config, stock_config_text
from op2motion.gait.stock_walking import JOINTS, TIME_UNIT_MS, StockWalking, ticks_of_stance
from op2motion.robot.joints import servo_to_ticks

WALK_READY_PAGE = 9
EXACT = ("r_hip_pitch", "l_hip_pitch", "r_knee", "l_knee", "r_ank_pitch", "l_ank_pitch", "r_ank_roll", "l_ank_roll",
         "r_hip_yaw", "l_hip_yaw", "r_sho_pitch", "l_sho_pitch")
STANCE_DEG = {"r_hip_pitch": -36.1, "r_knee": 53.2, "r_ank_pitch": 30.0}   # op2_facts.md: IK 23.1° + 13° lean
TICK_DEG = 0.088


def test_the_stance_is_the_frameworks_walk_ready_page(spec):
    """Before the first step the module holds the stance (x -10, y ±2.5, z 20 mm): the stock page 9 ("walk
    ready"), tick for tick on every joint but the hip rolls (page 9 holds them 5 ticks nearer zero)."""
    stance = ticks_of_stance(StockConfig(), spec)
    page = servo_to_ticks(ActionFile.read(STOCK).pose(WALK_READY_PAGE, spec).servo, spec)
    for name in EXACT:
        assert stance[name] == page[spec.joint_names.index(name)], name
    for name, degrees in STANCE_DEG.items():
        assert (stance[name] - 2048) * TICK_DEG == pytest.approx(degrees, abs=0.15)
    assert stance["r_hip_roll"] + stance["l_hip_roll"] == 4096          # mirror images


def test_the_timing_of_a_period(spec):
    """At the defaults (600 ms, 10 % double support) each foot swings 270 ms, left first, the feet lift
    foot_height and come down, and the walk halts at a timing latch after stop."""
    walk = StockWalking(StockConfig(), spec)
    walk.command(20.0)
    walk.start()
    swings = [walk.tick().swinging for _ in range(int(600 / TIME_UNIT_MS) * 3)]
    period = swings[-75:]
    assert period.count("left") * TIME_UNIT_MS == pytest.approx(270, abs=TIME_UNIT_MS)
    assert period.count("right") * TIME_UNIT_MS == pytest.approx(270, abs=TIME_UNIT_MS)
    first = next(k for k, s in enumerate(swings) if s)
    assert swings[first] == "left"
    walk.stop()
    for _ in range(200):
        walk.tick()
    assert not walk.real_running


def test_a_forward_step_moves_the_feet_apart_and_swings_the_arms(spec):
    walk = StockWalking(StockConfig(), spec)
    walk.command(30.0)
    walk.start()
    ticks = np.array([[walk.tick().ticks[n] for n in JOINTS] for _ in range(150)])
    spread = ticks[:, JOINTS.index("r_hip_pitch")] + ticks[:, JOINTS.index("l_hip_pitch")] - 4096
    assert np.ptp(spread) > 100                                      # the thighs swing against each other
    assert np.ptp(ticks[:, JOINTS.index("r_sho_pitch")]) > 5 * 1.5 / TICK_DEG     # ±1.5° per mm ... swung


def test_gyro_balance_moves_the_named_joints_by_the_gains(spec):
    config = StockConfig()
    still = StockWalking(config, spec).tick().ticks
    rolled = StockWalking(config, spec).tick(rl_gyro_counts=10.0).ticks
    pitched = StockWalking(config, spec).tick(fb_gyro_counts=10.0).ticks
    assert abs(rolled["r_hip_roll"] - still["r_hip_roll"]) == int(10 * config.balance_hip_roll_gain * 4)
    assert abs(rolled["r_ank_roll"] - still["r_ank_roll"]) == int(10 * config.balance_ankle_roll_gain * 4)
    assert abs(pitched["r_knee"] - still["r_knee"]) == int(10 * config.balance_knee_gain * 4)
    assert abs(pitched["l_ank_pitch"] - still["l_ank_pitch"]) == int(10 * config.balance_ankle_pitch_gain * 4)
    assert rolled["r_knee"] == still["r_knee"] and pitched["r_hip_roll"] == still["r_hip_roll"]


def test_the_config_file_round_trips_with_every_key():
    tuned = StockConfig().with_values(period_time_ms=520.0, x_offset_mm=-5.5, p_gain=40, x_move_amplitude_mm=35.0)
    text = stock_config_text(tuned, "tuned by op2motion")
    assert all(f"\n{key} = " in text for key in KEYS) and text.startswith("; tuned by op2motion\n[Walking Config]")
    assert parse_stock_config(text) == tuned
    assert parse_stock_config("[Walking Config]\nperiod_time = 500\n") == StockConfig(period_time_ms=500.0)


@pytest.mark.parametrize("text, words", [
    ("[Walking Config]\nperiod_tme = 500\n", "unknown key"),
    ("[Walking Config]\nperiod_time = fast\n", "number"),
    ("[Walking Config]\nperiod_time = 50\n", "period_time"),
    ("[Walking Config]\ndsp_ratio = nan\n", "dsp_ratio"),
    ("[Walking Config]\np_gain = 3.5\n", "whole"),
    ("[Other]\nx = 1\n", "Walking Config"),
    ("not an ini", "ini"),
])
def test_bad_config_files_are_refused_naming_the_key(text, words):
    with pytest.raises(InputError, match=words):
        parse_stock_config(text, "mine.ini")


@pytest.mark.physics
def test_the_stock_walk_plays_in_physics_with_its_gyro_balance(spec):
    """20 stock steps of 20 mm at the defaults in MuJoCo: no fall, the speed the module's own stride makes (two
    amplitudes a step), and the balance's gyro words read the IMU as the framework does."""
    from op2motion.gait.stock_controller import StockCommand, StockWalkController
    from op2motion.physics import check

    controller = StockWalkController(StockConfig(), spec, 20, StockCommand(20.0))
    assert controller.plan.walk is not None and controller.plan.walk.walking_s > 20 * 0.3
    run = check(controller, spec, ("mujoco",)).run
    stride_speed = 2 * 0.020 / (StockConfig().period_time_ms / 2000.0)
    assert not run.fell and run.walk is not None
    assert run.walk.mean_speed_mps == pytest.approx(stride_speed, rel=0.3)
