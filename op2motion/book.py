"""The book's known answers, in one place: shared by the library defaults, the CLI, ``bench`` and the tests.

Source: Jong-Wook Kim, "Robotis OP", chapter 2 (seed 001): the standing pose (code 2.4), the PSO search box
(code 2.10 ``pso_posture_opt``), the four posture scenarios (figs. 2.44-2.47), the Taylor arm-IK runs it prints
(``change_posture_pb``, code 2.15/2.17) and its MATLAB timings. Plain data only: this module imports nothing of
op2motion, so every layer may read it.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The standing pose (code 2.4) [deg]: arms hanging straight, legs straight, head up.
STANDING_TH_DEG = (90.0, 0.0, 0.0, 180.0, 0.0, 0.0, 180.0, 0.0, 180.0, 0.0, 0.0)
STANDING_PHI_DEG = (0.0, 0.0, 180.0, 0.0, 180.0, 180.0)
STANDING_PSI_DEG = (0.0, 0.0, 0.0)
#: The PSO search box (code 2.10) [deg], in the vector order [th(11), phi(6), psi(3)].
PSO_LOWER_DEG = (30, 0, -90, 90, -90, -30, 90, 0, 90, 0, -40, -30, -30, 150, -30, 180, 90, -30, -30, -20)
PSO_UPPER_DEG = (90, 60, 0, 270, 0, 30, 270, 90, 270, 90, 40, 30, 30, 210, 30, 270, 180, 30, 30, 20)
#: PSO settings of code 2.10: swarm size, iterations, inertia weight, acceleration constants.
PSO_PARTICLES, PSO_ITERATIONS, PSO_W, PSO_C1, PSO_C2 = 50, 200, 0.8, 2.0, 2.0
#: The number of full-body evaluations the book timed (and ``op2motion bench`` scales its figures to).
TIMED_POSES = 40_000
#: The book's MATLAB timings of those 40 000 full-body evaluations (i5-2400) [ms].
MATLAB_40K_MS = {"pb": 780.0, "dh": 3350.0}


@dataclass(frozen=True)
class Scenario:
    """A posture problem: ``hand`` to ``target`` [m] in the support-foot frame, standing on ``support``, with
    the CoM inside the support rectangle shrunk by ``br``; ``pose`` names the committed solution in ``poses/``."""

    support: str
    hand: str
    target: tuple[float, float, float]
    br: float
    pose: str = ""


#: The default problem of ``op2motion optimize`` and ``bench``: fig. 2.44's target with br 0.7.
DEFAULT_PROBLEM = Scenario("left", "left", (0.10, 0.05, 0.07), 0.7)
#: Figs. 2.44-2.47.
SCENARIOS = (
    Scenario("left", "left", (0.1, 0.05, 0.07), 1.0, "book_2_44"),
    Scenario("left", "left", (0.1, -0.05, 0.07), 0.7, "book_2_45"),
    Scenario("right", "left", (0.1, 0.05, 0.07), 1.0, "book_2_46"),
    Scenario("right", "right", (0.1, -0.05, 0.07), 0.4, "book_2_47"),
)


@dataclass(frozen=True)
class ArmRun:
    """One printed arm-IK run: start pose [deg] (left support, psi 0), hand, displacement [m], the printed
    joint changes [deg] (upper th, lower th, phi) and the printed achieved displacement ``eep_dif`` [m]."""

    hand: str
    th_deg: tuple[float, ...]
    phi_deg: tuple[float, ...]
    delta_m: tuple[float, float, float]
    deltas_deg: tuple[float, float, float]
    eep_dif_m: tuple[float, float, float]


_LEFT_TH = (90, 0, 0, 180, 0, 0, 200, 100, 180, 0, 0)
_LEFT_PHI = (0, 0, 180, 0, 200, 180)
_RIGHT_TH = (90, 0, 0, 180, 0, 0, 180, 0, 200, 100, 0)
_RIGHT_PHI = (0, 0, 180, 0, 180, 160)
#: The book prints two decimals of degrees and eep_dif to 0.01 m.
ARM_RUNS = (
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (0.02, 0, 0), (17.87, -21.16, 0.00), (0.02, -0.01, 0.00)),
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (-0.02, 0, 0), (-17.87, 21.16, 0.00), (-0.02, 0.00, 0.00)),
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (0, 0.02, 0), (0.00, 0.00, 10.09), (-0.01, 0.02, -0.00)),
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (0, -0.02, 0), (0.00, 0.00, -10.09), (0.01, -0.02, 0.00)),
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (0, 0, 0.02), (10.32, -1.30, 0.00), (-0.00, 0.00, 0.02)),
    ArmRun("left", _LEFT_TH, _LEFT_PHI, (0, 0, -0.02), (-10.32, 1.30, 0.00), (-0.00, -0.01, -0.02)),
    ArmRun("right", _RIGHT_TH, _RIGHT_PHI, (0.03, 0.03, 0.03), (42.29, -33.68, 15.13), (0.03, 0.03, 0.04)),
)
#: The pose of the book's code 2.6 example (a full-body pose with every variable non-zero) [deg].
CODE_2_6_TH_DEG = (80, 10, 0, 210, -10, -5, 170, 10, 200, 20, 0)
CODE_2_6_PHI_DEG = (-10, 5, 170, 10, 200, 170)
