"""Spec variants: the torso's centre of mass moved and its mass scaled, checked against pinocchio on the URDF made
from the variant (an independent computation of the whole body)."""

from __future__ import annotations

import numpy as np
import pytest

from op2motion.errors import InputError
from op2motion.model.dynamics import dynamics_for
from op2motion.physics.sweeps import servo_pose
from op2motion.robot.variant import spec_variant

COM_TOL_M = 1e-9


def _torso(spec):
    return next(i for i in spec.inertials if i.link == spec.root_link)


def test_a_torso_shift_moves_the_whole_body_by_its_mass_share(spec):
    shift = np.array([0.02, -0.01, 0.005])
    variant = spec_variant(spec, shift)
    pose = servo_pose(spec)
    moved = dynamics_for(variant).com(pose, "double") - dynamics_for(spec).com(pose, "double")
    share = _torso(spec).mass / dynamics_for(spec).total_mass
    assert moved == pytest.approx(share * shift, abs=COM_TOL_M)      # standing upright: torso frame = world
    assert variant.sha256 != spec.sha256 and spec_variant(spec) is spec


def test_a_heavier_torso_adds_its_mass_and_keeps_its_centre(spec):
    variant = spec_variant(spec, torso_mass_scale=1.15)
    added = dynamics_for(variant).total_mass - dynamics_for(spec).total_mass
    assert added == pytest.approx(0.15 * _torso(spec).mass, rel=1e-9)
    assert _torso(variant).com == _torso(spec).com
    assert np.allclose(np.array(_torso(variant).inertia), 1.15 * np.array(_torso(spec).inertia))


def test_variants_out_of_range_are_refused(spec):
    with pytest.raises(InputError, match="torso_com_shift_m"):
        spec_variant(spec, (0.5, 0.0, 0.0))
    with pytest.raises(InputError, match="torso_mass_scale"):
        spec_variant(spec, torso_mass_scale=float("nan"))
