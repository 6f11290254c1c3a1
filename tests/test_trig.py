"""The table-based sincos is full double precision."""

import numpy as np

from op2motion.kinematics.trig import sincos

DOUBLE_TOL = 2e-15


def test_sincos_matches_numpy(rng):
    x = np.concatenate([rng.uniform(-20, 20, 200_000), np.arange(-8, 9) * np.pi / 4, [0.0, 1e-300, -1e-9]])
    s, c = sincos(x)
    assert np.max(np.abs(s - np.sin(x))) < DOUBLE_TOL
    assert np.max(np.abs(c - np.cos(x))) < DOUBLE_TOL
    s2, c2 = sincos(x.reshape(-1, 4)[:, ::2])  # any shape, strided input
    assert np.array_equal(s2, s.reshape(-1, 4)[:, ::2]) and np.array_equal(c2, c.reshape(-1, 4)[:, ::2])
