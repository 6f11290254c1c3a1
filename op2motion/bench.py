"""``op2motion bench``: speed figures measured in one run, each next to a check that the timed work is right.

40 000 full-body evaluations (every body point plus the lumped CoM) per kinematic model, poses drawn from the
book's PSO box; the best of ``repeat`` runs is reported, so that one run gives comparable ratios. Each figure comes
with a correctness figure of the same computation (e.g. the largest distance between the D-H model's joint centres
and pinocchio's), so a fast but wrong evaluator cannot pass unnoticed.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Sequence

import numpy as np

from op2motion import book
from op2motion.bench_wall import wall_figures
from op2motion.formats.action import ActionFile
from op2motion.jsonout import JsonObject
from op2motion.kinematics import forward
from op2motion.kinematics.dh_chain import matrix_frames
from op2motion.kinematics.shapes import clearances, shape_set
from op2motion.model.dynamics import dynamics_for
from op2motion.physics import DEFAULT_SECONDS, RunReport, Schedule, check
from op2motion.posture.cost import CLEARANCE_EXACT_M, PostureProblem, evaluate_cost
from op2motion.posture.pso import PSOSettings, run_pso
from op2motion.robot.joints import BookAngles, book_to_servo
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

BENCH_POSES = book.TIMED_POSES
CHECK_POSES = 200   # poses compared against pinocchio one by one


def _best_ms(fn: Callable[[], Any], repeat: int, warm: bool = True) -> float:
    """The best of ``repeat`` timed calls of ``fn`` [ms], after one untimed call to warm caches and tables unless
    ``warm`` is false (a physics check after the standing pose's: its engines and tables are warm already, and a
    second walk would only double the bench's time)."""
    if warm:
        fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1000.0


def _dh_vs_pinocchio_m(spec: Spec, poses: BookAngles) -> float:
    """Largest joint-centre distance [m] between the batched D-H model and pinocchio over the first poses."""
    dyn = dynamics_for(spec)
    n = min(CHECK_POSES, poses.n)
    pts = forward(BookAngles(poses.th[:n], poses.phi[:n], poses.psi[:n], poses.support), spec, "dh")
    servo = book_to_servo(BookAngles(poses.th[:n], poses.phi[:n], poses.psi[:n], poses.support), spec)
    worst = 0.0
    for i in range(n):
        ref = dyn.joint_centres(servo[i], poses.support)
        for name in spec.joint_names:
            worst = max(worst, float(np.linalg.norm(pts.point(name)[i] - ref[name])))
    return worst


def _full_com_vs_pinocchio_m(spec: Spec, poses: BookAngles) -> float:
    """Largest distance [m] between the D-H model's batched full-inertia CoM and pinocchio's ``centerOfMass``."""
    dyn = dynamics_for(spec)
    n = min(CHECK_POSES, poses.n)
    sub = BookAngles(poses.th[:n], poses.phi[:n], poses.psi[:n], poses.support)
    full = forward(sub, spec, "dh", full_com=True).full()
    servo = book_to_servo(sub, spec)
    return max(float(np.linalg.norm(full[:, i] - dyn.com(servo[i], poses.support))) for i in range(n))


def _studio_figures(spec: Spec, repeat: int) -> JsonObject:
    """``studio_update_ms``: one joint edit in the pose studio and everything the page shows after it (both CoMs,
    margins, the settled CoM, swing-foot clearance, self-clearance, ticks); the check: the readout of the edit."""
    from op2motion.robot.pose import Pose
    from op2motion.studio.session import PoseEdit

    session = PoseEdit(spec, Pose("bench", Support.LEFT, book_to_servo(BookAngles.standing("left"), spec)[0]))
    angles = iter(np.tile(np.linspace(-30.0, 30.0, 7), 100))
    out: dict[str, Any] = {}
    update_ms = _best_ms(lambda: out.update(r=session.set_joint("l_sho_pitch", next(angles))), max(repeat, 3))
    r = out["r"]
    return {"studio_update_ms": round(update_ms, 2),
            "check_studio_readout": bool(np.isfinite(r.margin_full_m) and np.isfinite(r.self_clearance_m))}


BENCH_PAGE = 4            # the stock "hi" page: 464 ticks from the init pose, three pages chained
READY_PAGE = 9            # the stock walk-ready page (the planning figures' start)


def check_bench_action(action: ActionFile, spec: Spec) -> ActionFile:
    """Refuse at once, before any figure is measured, an action file without the pages the bench plays: the start
    (page 1), :data:`BENCH_PAGE` (played through its chain) and :data:`READY_PAGE`."""
    from op2motion.errors import InputError, Op2MotionError
    from op2motion.motion.pipeline import START_PAGE, play_page

    try:
        for page in (START_PAGE, READY_PAGE):
            action.pose(page, spec)
        play_page(action, BENCH_PAGE, spec)
    except Op2MotionError as exc:
        raise InputError(f"expected an action file with playable pages {START_PAGE}, {BENCH_PAGE} and {READY_PAGE} "
                         f"(the stock file's init, hi and walk-ready): {exc}", "action") from None
    return action


def _motion_figures(spec: Spec, action: ActionFile | None, repeat: int) -> JsonObject:
    """``motion_play_ms``: the page player on one stock page (emulation only); ``motion_validate_ms``: that
    page's goals played into the servo model in PyBullet (plus settling and the final hold). None without a file."""
    if action is None:
        return {"motion_play_ms": None, "motion_validate_ms": None, "check_motion_ticks": None}
    from op2motion.motion.pipeline import START_PAGE
    from op2motion.motion.player import play, start_ticks
    from op2motion.motion.trajectory import from_playback

    ticks = start_ticks(action.pose(START_PAGE, spec).servo, spec)
    out: dict[str, Any] = {}
    play_ms = _best_ms(lambda: out.update(p=play(action, BENCH_PAGE, ticks)), repeat)
    schedule = from_playback(out["p"], spec).schedule(spec)
    validate_ms = _best_ms(lambda: out.update(v=check(schedule, spec).run), 1, warm=False)
    return {"motion_play_ms": round(play_ms, 2), "motion_validate_ms": round(validate_ms, 1),
            "motion_page": BENCH_PAGE, "check_motion_ticks": out["p"].calls,
            "check_motion_stands": bool(out["v"].stable)}


BENCH_ARM_SWING_DEG = {"r_sho_pitch": (69.0, -178.0), "r_sho_roll": (-63.0, -51.0), "r_el": (-29.0, -24.0)}


def _planning_figures(spec: Spec, action: ActionFile | None, repeat: int) -> JsonObject:
    """``route_plan_ms``: planning around a collision (the right arm swung from in front of the hip to behind the
    shoulder, from the stock init pose; the straight line puts the elbow through the hip); ``line_move_ms``: the
    right hand 5 cm forward in 1 s from the stock walk-ready pose (page 9) with the whole-body IK (126 rows).
    Checks: the least clearance along the planned rows, the hand's largest distance from its line. None without
    the stock action file."""
    if action is None:
        return {"route_plan_ms": None, "line_move_ms": None, "check_route_clearance_m": None,
                "check_line_deviation_m": None}
    from op2motion.motion.cartesian import LineRequest, line_move
    from op2motion.motion.checks import clearance
    from op2motion.motion.planner import trajectory_through
    from op2motion.motion.waypoint import Waypoint
    from op2motion.robot.pose import Pose

    init = action.pose(1, spec).servo
    a, b = init.copy(), init.copy()
    for joint, (x, y) in BENCH_ARM_SWING_DEG.items():
        a[spec.joint_names.index(joint)], b[spec.joint_names.index(joint)] = np.radians(x), np.radians(y)
    ends = [Waypoint("front", a, 0.0, 0.0, Support.DOUBLE), Waypoint("back", b, 2.0, 0.0, Support.DOUBLE)]
    out: dict[str, Any] = {}
    route_ms = _best_ms(lambda: out.update(t=trajectory_through(ends, spec, seed=0)), min(repeat, 3))
    ready = Pose("walkready", Support.DOUBLE, action.pose(READY_PAGE, spec).servo)
    line_ms = _best_ms(lambda: out.update(m=line_move(ready, LineRequest("right", 1.0, delta_m=(0.05, 0.0, 0.0)),
                                                        spec)), min(repeat, 3))
    return {"route_plan_ms": round(route_ms, 1), "line_move_ms": round(line_ms, 1),
            "check_route_clearance_m": round(float(clearance(out["t"].goals, spec)[0].min()), 5),
            "check_line_deviation_m": round(float(out["m"].deviation_m.max()), 6)}


def _walk_figures(spec: Spec, repeat: int) -> JsonObject:
    """``walk_plan_ms``: planning the shipped ``forward`` gait (20 steps: footsteps, preview control, multibody
    correction passes, IK); ``walk_validate_ms``: playing it into the servo model in PyBullet."""
    from op2motion.gait import gait_schedule, generate_gait, preset_path, read_preset

    params = read_preset(preset_path("forward")).with_steps(20)
    out: dict[str, Any] = {}
    plan_ms = _best_ms(lambda: out.update(g=generate_gait(params, spec)), min(repeat, 3))
    schedule = gait_schedule(out["g"], spec)
    walk_ms = _best_ms(lambda: out.update(w=check(schedule, spec).run), 1, warm=False)
    walk_mujoco_ms = _best_ms(lambda: out.update(m=check(schedule, spec, ("mujoco",)).run), 1, warm=False)
    run, other = out["w"], out["m"]
    return {"walk_plan_ms": round(plan_ms, 1), "walk_validate_ms": round(walk_ms, 1),
            "walk_validate_mujoco_ms": round(walk_mujoco_ms, 1), "walk_steps": 20,
            "walk_simulated_s": run.seconds, "check_walk_fell": bool(run.fell or other.fell),
            "check_walk_speed_mps": round(min(run.walk.mean_speed_mps, other.walk.mean_speed_mps), 4)}


def _robot_figures(spec: Spec) -> JsonObject:
    """``robot_loop_p99_ms`` and ``robot_status_ms``: the 8 ms loop and a status read through the emulated OP2 in a
    process beside this one (:mod:`op2motion.onrobot.bench`)."""
    from op2motion.onrobot.bench import robot_figures

    return robot_figures(spec)


def run_bench(spec: Spec, n: int = BENCH_POSES, repeat: int = 9, seed: int = 0,
              action: ActionFile | None = None, wall_runs: int = 0, wall_library: bool = True,
              wall_grid: Sequence[str] = ()) -> JsonObject:
    """Time batched forward kinematics + CoM for ``n`` poses with each model, one physics validation, one PSO
    solve and (given an action file's bytes) one page played and validated; figures in milliseconds (scaled to
    40 000 poses), with their correctness checks. The physics validations and the PSO solve are timed
    ``min(repeat, 3)`` times; ``wall_grid``: the library figure's grid flags (default: the default grid)."""
    rng = np.random.default_rng(seed)
    poses_dh = BookAngles.random(n, rng, "left", psi=True)
    poses_pb = BookAngles(poses_dh.th, poses_dh.phi, np.zeros_like(poses_dh.psi), Support.LEFT)
    scale = BENCH_POSES / n
    pb_ms = _best_ms(lambda: forward(poses_pb, spec, "pb").com, repeat) * scale
    dh_ms = _best_ms(lambda: forward(poses_dh, spec, "dh").com, repeat) * scale
    dh_full_ms = _best_ms(lambda: forward(poses_dh, spec, "dh", full_com=True).com_full, repeat) * scale
    dyn = dynamics_for(spec)
    servo = book_to_servo(poses_dh, spec)
    pin_ms = _best_ms(lambda: dyn.com_loop(servo), 1) * scale
    stand = book_to_servo(BookAngles.standing("left"), spec)[0]
    verdict: dict[str, RunReport] = {}
    hold = Schedule.hold(stand, "double", spec, DEFAULT_SECONDS)
    validate_ms = _best_ms(lambda: verdict.update(v=check(hold, spec).run), min(repeat, 3))
    validate_mujoco_ms = _best_ms(lambda: verdict.update(m=check(hold, spec, ("mujoco",)).run), min(repeat, 3))
    swarm = BookAngles.random(PSOSettings().particles, rng, "left")
    frames, shapes = matrix_frames(swarm.vector(), spec, "left"), shape_set(spec, "left")
    clearance_ms = _best_ms(lambda: clearances(frames, shapes, CLEARANCE_EXACT_M), repeat)
    standing = matrix_frames(BookAngles.standing("left").vector(), spec, "left")
    problem = PostureProblem.from_scenario(book.DEFAULT_PROBLEM)
    pso: dict[str, Any] = {}
    pso_ms = _best_ms(lambda: pso.update(r=run_pso(problem, spec, PSOSettings())), min(repeat, 3))
    return {
        "poses": n,
        "repeat": repeat,
        "fk_pb_40k_ms": round(pb_ms, 2),
        "fk_dh_40k_ms": round(dh_ms, 2),
        "fk_dh_full_com_40k_ms": round(dh_full_ms, 2),
        "pinocchio_com_40k_ms": round(pin_ms, 1),
        "validate_ms": round(validate_ms, 1),
        "validate_mujoco_ms": round(validate_mujoco_ms, 1),
        "validate_seconds": DEFAULT_SECONDS,
        "validate_simulated_s": verdict["v"].seconds,
        "validate_ended": verdict["v"].ended,
        "self_clearance_swarm_ms": round(clearance_ms, 2),
        "pso_solve_ms": round(pso_ms, 1),
        "book_matlab_pb_40k_ms": book.MATLAB_40K_MS["pb"],
        "book_matlab_dh_40k_ms": book.MATLAB_40K_MS["dh"],
        "check_dh_vs_pinocchio_m": _dh_vs_pinocchio_m(spec, poses_dh),
        "check_full_com_vs_pinocchio_m": _full_com_vs_pinocchio_m(spec, poses_dh),
        "check_standing_stands": bool(verdict["v"].stable and verdict["m"].stable),
        "check_standing_clearance_m": float(clearances(standing, shapes).min()),
        "check_pso_hand_error_m": float(evaluate_cost(BookAngles.from_vector(pso["r"].x), problem,
                                                      spec).hand_error[0]),
        **_studio_figures(spec, repeat),
        **_motion_figures(spec, action, repeat),
        **_planning_figures(spec, action, repeat),
        **_walk_figures(spec, repeat),
        **_robot_figures(spec),
        **(wall_figures(wall_runs, wall_library, wall_grid) if wall_runs else {}),
    }
