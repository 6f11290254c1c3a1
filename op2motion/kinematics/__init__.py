"""Full-body forward kinematics: the D-H and projection models, one result type (:class:`BodyPoints`)."""

from __future__ import annotations

from typing import Iterable, get_args

from op2motion.errors import InputError, ModelError
from op2motion.kinematics.dh import forward_dh
from op2motion.kinematics.points import POINT_NAMES, BodyPoints, ModelName
from op2motion.kinematics.projection import forward_pb
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import Spec

MODELS: tuple[ModelName, ...] = get_args(ModelName)

__all__ = ["MODELS", "POINT_NAMES", "BodyPoints", "ModelName", "forward", "forward_dh", "forward_pb"]


def forward(angles: BookAngles, spec: Spec, model: ModelName = "dh", sp: Iterable[float] = (0.0, 0.0, 0.0),
            gamma: float = 0.0, full_com: bool = False) -> BodyPoints:
    """Body points of a batch of poses with ``model`` ("dh" or "pb"), support sole centre at ``sp`` [m],
    heading ``gamma`` [rad] about Z (book fig. 2.17); with ``full_com`` also the full-inertia CoM (D-H only)."""
    if model == "dh":
        points = forward_dh(angles, spec, full_com)
    elif model == "pb":
        if full_com:
            raise ModelError("the full-inertia CoM needs the link frames of the D-H model; choose dh", "model")
        points = forward_pb(angles, spec)
    else:
        raise InputError(f"expected 'dh' or 'pb', got {model!r}", "model")
    sp = tuple(sp)
    if gamma != 0.0 or any(v != 0.0 for v in sp):
        points = points.placed(sp, gamma)
    return points
