"""Physics: does the robot do what it was told, on the MX-28 servo model, in PyBullet and MuJoCo?

One entry, :func:`check`: a :class:`Controller` (here :class:`Schedule`, the open-loop player of a held pose, a
motion, a played action page or a gait; or your own closed-loop one) runs every 8 ms in each engine asked for, the
servo model drives the joints at 1 kHz, and each run is judged with named reasons (:data:`REASONS`) against the
controller's :class:`Plan`. The result is a typed :class:`CheckReport`::

    from op2motion.physics import Schedule, check
    report = check(Schedule.hold(pose.servo, pose.support, spec), spec, engines=("pybullet", "mujoco"))
    report.stable, report.agree, report.run.reasons, report.engines["mujoco"].run.support_margin_m

:func:`robust_check` runs the same check over :func:`family`, the bodies and floors of what we do not know.
"""

from __future__ import annotations

from op2motion.physics.ball import BALL_MASS_KG, BALL_RADIUS_M, Ball, BallReport
from op2motion.physics.body import LYING, margin_to
from op2motion.physics.controller import Controller, ControllerHooks, GoalMerger, Goals, Schedule, hooks_of
from op2motion.physics.engine import Engine, make_engine
from op2motion.physics.loop import StartFacts
from op2motion.physics.plan import (
    DEFAULT_SECONDS,
    MAX_SECONDS,
    MIN_SECONDS,
    MOTION_HOLD_S,
    MOTION_SETTLE_S,
    RAMP_S,
    Plan,
    WalkClock,
)
from op2motion.physics.report import (
    FALL_REASONS,
    REASONS,
    CheckReport,
    EngineReport,
    Failure,
    FootLoad,
    MotionMeasures,
    PushResult,
    RunMeasures,
    RunReport,
    TrialsResult,
    WorstTorque,
)
from op2motion.physics.robust import Member, RobustReport, RobustRun, family, robust_check, robust_runs, stands
from op2motion.physics.robust_table import pose_robust_table, robust_markdown, robust_summary
from op2motion.physics.runner import MAX_PUSH_N, Pushes, Setup, Trials, check, check_runs, check_work
from op2motion.physics.scene import ENGINES, FLOOR_FRICTION, TIME_STEP_S, EngineName
from op2motion.physics.sensors import Sensors
from op2motion.physics.track import Track

__all__ = ["BALL_MASS_KG", "BALL_RADIUS_M", "Ball", "BallReport",
           "DEFAULT_SECONDS", "ENGINES", "FALL_REASONS", "FLOOR_FRICTION", "MAX_PUSH_N", "MAX_SECONDS",
           "LYING", "MIN_SECONDS", "MOTION_HOLD_S", "MOTION_SETTLE_S", "RAMP_S", "REASONS", "TIME_STEP_S",
           "CheckReport", "Controller", "ControllerHooks", "Engine", "EngineName", "EngineReport",
           "Failure", "FootLoad", "GoalMerger", "Goals", "hooks_of",
           "Member", "MotionMeasures", "Plan", "PushResult", "Pushes", "RobustReport", "RobustRun", "RunMeasures",
           "RunReport",
           "Schedule", "Sensors", "Setup", "StartFacts", "Track", "Trials",
           "TrialsResult", "WalkClock", "WorstTorque", "check", "check_runs", "check_work", "family", "make_engine",
           "margin_to",
           "pose_robust_table", "robust_check", "robust_markdown", "robust_runs", "robust_summary", "stands"]
