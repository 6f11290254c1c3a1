"""Getting up: :class:`GetUp`, a physics controller that reads its IMU, decides how the robot lies and plays a way up.

Every 8 ms it gets what every controller gets (:mod:`op2motion.physics.controller`) and goes through:

1. **settle**: hold the joints where they were at the start until the body has kept still (:mod:`.stillness`, at
   least :data:`SETTLE_S`, at most :data:`SETTLE_MAX_S`), the accelerometer low-passed meanwhile;
2. **decide** (:func:`.lying.lying_side`): face down, face up, on the left or right side, or upright;
   the way up is planned beside the loop (a thread) while the robot holds still :data:`PLAN_S`, so no tick waits
   for the planner (on the robot a tick must stay within 20 ms; in physics the plan is taken at the same
   simulated moment whatever the machine, so runs stay deterministic);
3. **play** the way up from that side (:mod:`.getup_ways`: the stock pages 10/11 when the action file given has them,
   op2motion's own get-up motions otherwise; from a side, a roll onto the back first, after which it decides again);
4. **check**: hold the last goal until still; upright (the torso within :data:`~.lying.UPRIGHT_TILT_DEG` of vertical
   by the accelerometer) is done; otherwise try again from 1, at most :data:`MAX_TRIES` ways in all (then it gives
   up: :attr:`GetUp.done` with :attr:`GetUp.stood` false).

``GetUp()`` needs no arguments (the shipped spec, op2motion's own motions). Its :attr:`plan`, for a physics check,
holds :data:`LYING_POSE_DEG` for :data:`GETUP_S`: check it with ``Setup(lying="front")`` (or ``back``, ``left``,
``right``) to start lying, and ``full_length`` (a run that starts lying has no standing plan to end early on).
:attr:`GetUp.events` lists what it did and when.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.formats.action import ActionFile
from op2motion.motion.getup_ways import Ways
from op2motion.motion.lying import UPRIGHT_TILT_DEG, lying_side, tilt_deg
from op2motion.motion.stillness import Stillness
from op2motion.physics import ControllerHooks, Plan
from op2motion.robot.framework import CONTROL_PERIOD_S, DEFAULT_P_GAIN
from op2motion.robot.spec import Spec

SETTLE_S = 0.3              # still this long before deciding [s]
SETTLE_MAX_S = 3.0          # ... or decide anyway after this long [s]
CHECK_MAX_S = 2.0           # after a way, wait at most this long for the body to keep still [s]
ACCEL_TAU_S = 0.1           # the accelerometer's low-pass [s]
MAX_TRIES = 4               # ways tried (a roll counts) before giving up
PLAN_S = 0.5                # the way up is planned beside the loop this long (the robot holds still) [s]
GETUP_S = 20.0              # the plan's length for a physics check [s]
#: The pose a run of :class:`GetUp` starts lying in: arms down by the sides, legs straight (servo degrees).
LYING_POSE_DEG = {"r_sho_roll": -45.0, "l_sho_roll": 45.0, "r_el": -90.0, "l_el": 90.0}


class GetUp(ControllerHooks):
    """Gets the robot up from lying (see the module docstring)."""

    p_gains: dict[str, float] | None = None     # the way's P gains while it plays (a hook: ControllerHooks)

    def __init__(self, spec: Spec | None = None, action: ActionFile | str | Path | None = None,
                 seconds: float = GETUP_S):
        from op2motion.robot.specfile import default_spec

        self.spec = spec or default_spec()
        if action is not None and not isinstance(action, ActionFile):
            action = ActionFile.read(action)
        self.ways = Ways(self.spec, action)
        lying = np.radians([LYING_POSE_DEG.get(n, 0.0) for n in self.spec.joint_names])
        self.plan = Plan.hold(lying, "double", seconds, np.full(len(self.spec.joints), float(DEFAULT_P_GAIN)))
        self._reset(lying)

    def _reset(self, joints: np.ndarray) -> None:
        self.phase, self.since, self.tries = "settle", 0.0, 0
        self.hold = np.asarray(joints, dtype=float).copy()
        self.rows: np.ndarray | None = None
        self.gains: np.ndarray | None = None
        self.row = 0
        self.planning: _Planning | None = None
        self.accel: np.ndarray | None = None
        self.stillness = Stillness()
        self.events: list[tuple[float, str]] = []
        self.p_gains = None

    @property
    def done(self) -> bool:
        """Standing again, or given up (:attr:`stood` says which)."""
        return self.phase in ("standing", "gave_up")

    @property
    def stood(self) -> bool:
        """Standing again."""
        return self.phase == "standing"

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """Start over: hold the joints where they are."""
        self._reset(np.array([joint_positions.get(n, 0.0) for n in self.spec.joint_names]))
        return dict(zip(self.spec.joint_names, self.hold.tolist()))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The goals at ``t_s`` [s] (see the module docstring)."""
        joints = np.array([joint_positions[n] for n in self.spec.joint_names])
        accel = np.asarray(accel_m_s2, dtype=float)
        blend = CONTROL_PERIOD_S / (ACCEL_TAU_S + CONTROL_PERIOD_S)
        self.accel = accel.copy() if self.accel is None else self.accel + blend * (accel - self.accel)
        self.stillness.update(np.asarray(gyro_rad_s, dtype=float), joints)
        if self.phase == "settle":
            waited = t_s - self.since
            if (waited >= SETTLE_S and self.stillness.still) or waited >= SETTLE_MAX_S:
                self._decide(t_s, joints)
        elif self.phase == "plan":
            if t_s - self.since >= PLAN_S:
                self._take_plan(t_s)
        elif self.phase == "play":
            if self.rows is None or self.gains is None:
                raise Op2MotionError("GetUp plays a way it has not planned")
            self.hold = self.rows[self.row]
            self.p_gains = dict(zip(self.spec.joint_names, self.gains[self.row].tolist()))
            self.row += 1
            if self.row >= len(self.rows):
                self.phase, self.since = "check", t_s
        elif self.phase == "check":
            waited = t_s - self.since
            if (waited >= SETTLE_S and self.stillness.still) or waited >= CHECK_MAX_S:
                self._checked(t_s)
        return dict(zip(self.spec.joint_names, self.hold.tolist()))

    def _decide(self, t_s: float, joints: np.ndarray) -> None:
        """Lying how? Play the way up from there (or check the standing robot)."""
        if self.accel is None:
            raise Op2MotionError("GetUp decides before any accelerometer reading")
        side = lying_side(self.accel)
        self.events.append((t_s, f"lying {side}" if side != "upright" else "upright"))
        if side in ("upright", "head") or self.tries >= MAX_TRIES:
            self.phase, self.since = "check", t_s
            return
        self.tries += 1
        self.planning = _Planning(self.ways, side, joints)
        self.phase, self.since = "plan", t_s

    def _take_plan(self, t_s: float) -> None:
        """The way planned beside the loop (waited for only if the planner took longer than :data:`PLAN_S`)."""
        if self.planning is None:
            raise Op2MotionError("GetUp plays a way it has not planned")
        way = self.planning.result()
        self.planning = None
        self.events.append((t_s, f"plays {way.name}"))
        self.rows, self.gains, self.row, self.phase = way.goals, way.p_gains, 0, "play"

    def _checked(self, t_s: float) -> None:
        """After a way: standing, or try again (or give up)."""
        if self.accel is None:
            raise Op2MotionError("GetUp decides before any accelerometer reading")
        if tilt_deg(self.accel) < UPRIGHT_TILT_DEG:
            self.phase = "standing"
            self.events.append((t_s, "standing"))
        elif self.tries >= MAX_TRIES:
            self.phase = "gave_up"
            self.events.append((t_s, f"gave up after {self.tries} ways"))
        else:
            self.phase, self.since = "settle", t_s
            self.stillness = Stillness()


class _Planning:
    """One way up from lying ``lying`` (front, back, left, right) planned in a thread of its own (:meth:`result` waits
    for it and raises what it raised)."""

    def __init__(self, ways: Ways, lying: str, joints: np.ndarray):
        self.way: Any = None
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._plan, args=(ways, lying, joints.copy()), name="op2-getup-plan",
                                       daemon=True)
        self.thread.start()

    def _plan(self, ways: Ways, lying: str, joints: np.ndarray) -> None:
        try:
            self.way = ways.way(lying, joints)
        except BaseException as exc:          # noqa: BLE001 (raised again in the loop's thread by result())
            self.error = exc

    def result(self) -> Any:
        """The planned way."""
        self.thread.join()
        if self.error is not None:
            raise self.error
        return self.way
