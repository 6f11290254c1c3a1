"""Write op2motion's own get-up, roll and kick motions (``poses/motions/getup_*.json``, ``roll_*.json``,
``kick_*.json``) from their key poses.

The key poses are given for the right side in servo degrees (the left side mirrors them: every left joint the negative
of its right twin; head pan 0). Where they come from:

* ``getup_front``, ``getup_back``: the structure and key poses of the stock pages 10 and 11 (``motion_4096.bin``:
  facts about how the OP2 gets up), made left-right symmetric and rounded, planned by op2motion's quintic planner (at
  half the MX-28's no-load speed the planner stretches the fast steps of the pages), and one change found in physics:
  the front get-up's push keeps the shoulders at 20° instead of the page's 32°: with 32° the bodies of the robustness
  family whose torso CoM is 20 mm forward rocked onto their toes after the push and fell on their faces again, in
  PyBullet and MuJoCo alike (docs/motions.md, Falls, getting up and kicks);
* ``roll_left``, ``roll_right``: op2motion's own: lying on a side, the upper arm swings behind the back (shoulder pitch
  130° back, rolled 35° out) and the hips bend 20°, which rolls the body onto its back; then the arms come down by the
  sides. It rolls every member of the family onto its back in both engines;
* ``kick_right``, ``kick_left`` (:func:`kick`): op2motion's own kick from the walk-ready stance, planned with the
  planner's weight shift and lift onto the standing foot.

Run from the repository root: ``python tools/getup_motions.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "poses" / "motions"
#: The right-side joints and their left twins; a key pose gives the right side's servo degrees.
PAIRS = (("r_sho_pitch", "l_sho_pitch"), ("r_sho_roll", "l_sho_roll"), ("r_el", "l_el"), ("r_hip_yaw", "l_hip_yaw"),
         ("r_hip_roll", "l_hip_roll"), ("r_hip_pitch", "l_hip_pitch"), ("r_knee", "l_knee"),
         ("r_ank_pitch", "l_ank_pitch"), ("r_ank_roll", "l_ank_roll"))
READY = {"r_sho_pitch": -45, "r_sho_roll": -18, "r_el": 30, "r_hip_pitch": -36, "r_knee": 53, "r_ank_pitch": 30,
         "r_ank_roll": 1, "head_tilt": 10}
LYING = {"r_sho_roll": -45, "r_el": -90}
ABDUCT_DEG = 8.0        # the kicking leg turned out at the hip (the sole kept level): the feet pass clear


def pose(name: str, right: dict[str, float], asym: dict[str, float] | None = None) -> dict[str, object]:
    """A step's inline pose: the right side's servo degrees mirrored to the left, then ``asym`` (either side)."""
    deg = {"head_pan": 0.0, "head_tilt": float(right.get("head_tilt", 0.0))}
    for r, left in PAIRS:
        deg[r] = float(right.get(r, 0.0))
        deg[left] = -deg[r]
    deg.update(asym or {})
    return {"name": name, "support": "double", "servo_deg": deg}


def step(name: str, right: dict[str, float], duration_s: float | None, pause_s: float = 0.0,
         asym: dict[str, float] | None = None) -> dict[str, object]:
    """One motion step (the first has no duration)."""
    out = pose(name, right, asym)
    if duration_s is not None:
        out["duration_s"] = duration_s
    if pause_s:
        out["pause_s"] = pause_s
    return out


def getup_front() -> list[dict[str, object]]:
    """Face down: arms back, knees in, push back onto the feet, squat, stand."""
    return [step("lying_front", LYING, None),
            step("arms_back", {"r_sho_pitch": -60, "r_sho_roll": -20, "r_el": 70, "r_hip_pitch": -64, "r_knee": 62,
                               "r_ank_pitch": 25, "r_ank_roll": 1, "head_tilt": 40}, 0.8),
            step("tuck", {"r_sho_pitch": 24, "r_sho_roll": -20, "r_el": 70, "r_hip_pitch": -100, "r_knee": 91,
                          "r_ank_pitch": 26, "r_ank_roll": 1, "head_tilt": 40}, 0.2),
            step("push", {"r_sho_pitch": 20, "r_sho_roll": -36, "r_el": -62, "r_hip_pitch": -94, "r_knee": 132,
                          "r_ank_pitch": 74, "head_tilt": 40}, 0.8),
            step("squat", {"r_sho_pitch": 16, "r_sho_roll": -36, "r_el": -62, "r_hip_pitch": -96, "r_knee": 126,
                           "r_ank_pitch": 52, "head_tilt": 40}, 1.0),
            step("ready", READY, 1.0)]


def getup_back() -> list[dict[str, object]]:
    """Face up: arms over the head, knees up, sit up on the hands, crab, throw the weight onto the feet, stand."""
    return [step("lying_back", LYING, None),
            step("arms_up", {"r_sho_pitch": -147, "r_sho_roll": -42, "r_el": 58, "r_hip_pitch": -89, "r_knee": 104,
                             "r_ank_pitch": 37, "r_ank_roll": 1, "head_tilt": 40}, 0.8),
            step("arms_down", {"r_sho_pitch": -147, "r_sho_roll": -42, "r_el": 0, "r_hip_pitch": -89, "r_knee": 104,
                               "r_ank_pitch": 34, "r_ank_roll": 1, "head_tilt": 40}, 0.4),
            step("sit_up", {"r_sho_pitch": -132, "r_sho_roll": -20, "r_el": -53, "r_hip_pitch": 32, "r_knee": 59,
                            "r_ank_roll": 1, "head_tilt": 40}, 0.4, 0.2),
            step("crab", {"r_sho_pitch": -82, "r_sho_roll": -34, "r_el": -77, "r_hip_pitch": 32, "r_knee": 98,
                          "r_ank_pitch": 70, "r_ank_roll": 1, "head_tilt": 40}, 0.6, 0.4),
            step("onto_feet", {"r_sho_pitch": 29, "r_sho_roll": -34, "r_el": -77, "r_hip_pitch": 32, "r_knee": 88,
                               "r_ank_pitch": 76, "r_ank_roll": 1, "head_tilt": -23}, 0.8, 0.2),
            step("ready", READY, 1.0)]


def roll(side: str) -> list[dict[str, object]]:
    """Lying on ``side``: the upper arm behind the back rolls the body onto it; arms down by the sides."""
    upper = "l" if side == "right" else "r"
    sign = 1.0 if upper == "r" else -1.0
    swing = {f"{upper}_sho_pitch": -130.0 * sign, f"{upper}_sho_roll": -80.0 * sign}
    return [step(f"lying_{side}", LYING, None),
            step("arm_behind", {**LYING, "r_hip_pitch": -20}, 0.8, 0.3, swing),
            step("lying_back", LYING, 0.8, 0.5)]


def kick(side: str) -> list[dict[str, object]]:
    """From walk-ready, on the other foot: the kicking leg drawn back, swung through nearly straight, drawn in,
    set down (the planner puts in the weight shift, the lift and the set-down: :mod:`op2motion.motion.shift`)."""
    stand = "left" if side == "right" else "right"
    k = side[0]
    sign = 1.0 if k == "r" else -1.0                  # left servos mirror the right ones

    o = stand[0]

    def leg(hip: float, knee: float, ankle: float) -> dict[str, float]:
        # the kicking leg, and the standing one straighter than walk-ready's (the hip higher: the kicking foot clears
        # the floor as it swings through under it)
        return {f"{k}_hip_pitch": -hip * sign, f"{k}_knee": knee * sign, f"{k}_ank_pitch": ankle * sign,
                f"{k}_hip_roll": ABDUCT_DEG * sign, f"{k}_ank_roll": ABDUCT_DEG * sign,
                f"{o}_hip_pitch": 20.0 * sign, f"{o}_knee": -35.0 * sign, f"{o}_ank_pitch": -15.0 * sign}

    def on_one_foot(name: str, duration: float, pause: float, swing: dict[str, float]) -> dict[str, object]:
        out = step(name, READY, duration, pause, swing)
        out["support"] = stand
        out["servo_deg"] = balanced_on(out["servo_deg"], stand)        # type: ignore[arg-type]
        return out

    return [step("ready", READY, None),
            on_one_foot("draw_back", 1.0, 0.3, leg(10.0, 90.0, 45.0)),
            on_one_foot("through", 0.4, 0.0, leg(30.0, 80.0, 35.0)),
            on_one_foot("kick", 0.3, 0.3, leg(40.0, 35.0, 10.0)),
            on_one_foot("draw_in", 0.8, 0.3, leg(36.0, 80.0, 40.0)),
            step("ready_again", READY, 1.0)]


def balanced_on(servo_deg: dict[str, float], side: str) -> dict[str, float]:
    """A one-foot pose leaned at the ankles until the CoM it settles at on the compliant servos is over the
    ``side`` sole's centre (:func:`op2motion.motion.shift.weight_shift`), rounded to 0.01°."""
    import math

    from op2motion.motion.shift import weight_shift
    from op2motion.robot.specfile import default_spec

    spec = default_spec()
    servo = [math.radians(servo_deg[n]) for n in spec.joint_names]
    leaned = weight_shift(servo, side, spec)
    return {n: round(math.degrees(v), 2) for n, v in zip(spec.joint_names, leaned)}


def motion(name: str, steps: list[dict[str, object]]) -> dict[str, object]:
    """A motion file's document."""
    return {"schema": "op2motion.motion/1", "name": name, "profile": "quintic", "p_gain": 32, "steps": steps}


def main() -> None:
    documents = {"getup_front": getup_front(), "getup_back": getup_back(), "roll_left": roll("left"),
                 "roll_right": roll("right"), "kick_right": kick("right"), "kick_left": kick("left")}
    for name, steps in documents.items():
        path = OUT / f"{name}.json"
        path.write_text(json.dumps(motion(name, steps), indent=2) + "\n", encoding="utf-8")
        print(f"wrote {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
