"""BodyPoints: the one result type of both kinematic models.

Every joint centre under its official joint name, the hands, sole centres, pelvis centre (midpoint of the hip-yaw
joints), neck (the torso origin: shoulder-pitch height on the centre line), head top and the four corners of each
foot, for N poses, in the world frame (support-foot sole centre, X forward, Y left, Z up; ``sp`` shifts it,
``gamma`` turns it). Joints whose axes intersect share a row (hip roll/pitch, ankle pitch/roll).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Literal

import numpy as np

from op2motion.errors import ModelError
from op2motion.robot.spec import Foot
from op2motion.robot.support import Side, Support, as_side, other_side

#: Unique point rows, in storage order.
#: The full-body kinematic model: the book's D-H chain (``dh``) or its projection formulas (``pb``).
ModelName = Literal["dh", "pb"]
ROWS: tuple[str, ...] = (
    "l_ankle", "l_knee", "l_hip", "l_hip_yaw", "r_ankle", "r_knee", "r_hip", "r_hip_yaw",
    "pelvis", "neck", "head_pan", "head_tilt", "head_top",
    "l_sho_pitch", "l_sho_roll", "l_el", "left_hand", "r_sho_pitch", "r_sho_roll", "r_el", "right_hand",
    "left_sole", "right_sole",
)
#: Foot corners in each foot's frame order: front-left, front-right, back-right, back-left.
CORNER_ROWS: tuple[str, ...] = tuple(f"{side}_foot_{i}" for side in ("left", "right") for i in range(4))
ALL_ROWS = ROWS + CORNER_ROWS
ROW = {name: i for i, name in enumerate(ALL_ROWS)}
#: Public point names -> storage rows (official joint names share rows where axes intersect).
ALIASES: dict[str, str] = {
    "l_ank_pitch": "l_ankle", "l_ank_roll": "l_ankle", "r_ank_pitch": "r_ankle", "r_ank_roll": "r_ankle",
    "l_hip_pitch": "l_hip", "l_hip_roll": "l_hip", "r_hip_pitch": "r_hip", "r_hip_roll": "r_hip",
    "l_knee": "l_knee", "r_knee": "r_knee", "l_hip_yaw": "l_hip_yaw", "r_hip_yaw": "r_hip_yaw",
}
POINT_NAMES: tuple[str, ...] = tuple(
    n for n in ("r_sho_pitch", "l_sho_pitch", "r_sho_roll", "l_sho_roll", "r_el", "l_el", "r_hip_yaw", "l_hip_yaw",
                "r_hip_roll", "l_hip_roll", "r_hip_pitch", "l_hip_pitch", "r_knee", "l_knee", "r_ank_pitch",
                "l_ank_pitch", "r_ank_roll", "l_ank_roll", "head_pan", "head_tilt", "left_hand", "right_hand",
                "left_sole", "right_sole", "pelvis", "neck", "head_top"))


def row_of(name: str) -> int:
    """Storage row of a public point name or row name."""
    return ROW[ALIASES.get(name, name)]


def new_slab(n: int) -> np.ndarray:
    """An uninitialised (rows, 3, N) array for a model to fill."""
    return np.empty((len(ALL_ROWS), 3, n))


@dataclass(frozen=True)
class BodyPoints:
    """Named body points for N poses: ``data`` is (rows, 3, N) [m] in the world frame; ``com`` is the lumped-mass
    centre of mass (3, N) [m] (book table 2.8 masses, see :mod:`op2motion.kinematics.com`)."""

    data: np.ndarray
    com: np.ndarray
    support: Support | Side
    model: ModelName
    com_full: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Number of poses."""
        return int(self.data.shape[2])

    def full(self) -> np.ndarray:
        """The full-inertia centre of mass (3, N) [m]; the points must have been made with ``full_com``."""
        if self.com_full is None:
            raise ModelError("the full-inertia CoM was not computed: evaluate the points with full_com", "full_com")
        return self.com_full

    @property
    def swing(self) -> Side:
        """The swing side (``left`` or ``right``)."""
        return other_side(self.support)

    def point(self, name: str) -> np.ndarray:
        """Point ``name`` for every pose, (N, 3) [m]."""
        rows: np.ndarray = self.data[row_of(name)].T
        return rows

    def foot_corners(self, side: Support | Side) -> np.ndarray:
        """Corners of the ``left`` or ``right`` foot sole, (N, 4, 3) [m] (front-left, front-right, back-right,
        back-left)."""
        start = ROW[f"{side}_foot_0"]
        return self.data[start:start + 4].transpose(2, 0, 1)

    @property
    def swing_foot_corners(self) -> np.ndarray:
        """Corners of the swing foot's sole, (N, 4, 3) [m]."""
        return self.foot_corners(self.swing)

    @property
    def swing_foot_min_z(self) -> np.ndarray:
        """Lowest swing-foot corner height, (N,) [m] (book code 2.11 ``sft_z_min``)."""
        start = ROW[f"{self.swing}_foot_0"]
        lowest: np.ndarray = self.data[start:start + 4, 2].min(axis=0)
        return lowest

    def placed(self, sp: Iterable[float] = (0.0, 0.0, 0.0), gamma: float = 0.0) -> "BodyPoints":
        """The same points with the support sole centre moved to ``sp`` [m] and turned by ``gamma`` [rad] about Z."""
        c, s = np.cos(gamma), np.sin(gamma)
        shift = np.asarray(tuple(sp), dtype=float)

        def move(v: np.ndarray) -> np.ndarray:      # (..., 3, N) points
            out = v.copy()
            out[..., 0, :], out[..., 1, :] = c * v[..., 0, :] - s * v[..., 1, :], s * v[..., 0, :] + c * v[..., 1, :]
            moved: np.ndarray = out + shift[:, None]
            return moved

        return BodyPoints(move(self.data), move(self.com), self.support, self.model,
                          None if self.com_full is None else move(self.com_full))

    def as_dict(self, i: int = 0) -> dict[str, list[float]]:
        """Pose ``i`` as ``{point name: [x, y, z]}`` [m]."""
        return {name: [float(v) for v in self.data[row_of(name), :, i]] for name in POINT_NAMES}


def fill_support_foot(out: np.ndarray, foot: "Foot", support: Support | Side) -> None:
    """Rows of a (rows, 3, N) slab that do not depend on the angles: the support sole (the world origin) and its
    corners on the floor."""
    out[ROW[f"{support}_sole"]] = 0.0
    for i, (dx, dy) in enumerate(foot.corners(as_side(support, "support"))):
        out[ROW[f"{support}_foot_{i}"]] = np.array([dx, dy, 0.0])[:, None]
