"""ZMP preview control of the cart-table model (Kajita et al. 2003, with Katayama's integral action).

The centre of mass at constant height ``z_c`` moves as a cart on a table: with the state ``x = (c, ċ, c̈)`` of one
horizontal axis and the CoM jerk as input, sampled every ``dt``::

    x[k+1] = A x[k] + B u[k],      p[k] = C x[k],      C = (1, 0, -z_c / g)

where ``p`` is the ZMP. The controller minimises ``Σ Q e[k]² + R u[k]²`` with ``e = p - p_ref`` over an infinite
horizon, on the system augmented with the summed ZMP error (integral action: no steady offset), and looks
``preview_s`` ahead along the reference::

    u[k] = -G_i Σ_{i<=k} e[i] - G_x x[k] - Σ_{j=1..N} G_p[j] p_ref[k+j]

The gains come from scipy's discrete algebraic Riccati solver. Both horizontal axes share the gains and run as
the two columns of one array.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.spec import GRAVITY_M_S2


@dataclass(frozen=True)
class PreviewGains:
    """Gains of one preview controller: integral ``gi``, state ``gx`` (3,), preview ``gp`` (N,) for the
    reference 1..N ticks ahead, and the model they were made for."""

    dt: float
    com_height: float
    gi: float
    gx: np.ndarray
    gp: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray


def preview_gains(dt: float, com_height: float, preview_s: float, q: float = 1.0, r: float = 1e-6) -> PreviewGains:
    """Gains for control period ``dt`` [s], CoM height ``com_height`` [m], preview horizon ``preview_s`` [s],
    ZMP error weight ``q`` and jerk weight ``r``."""
    from scipy.linalg import solve_discrete_are

    for name, value in (("dt", dt), ("com_height", com_height), ("preview_s", preview_s), ("q", q), ("r", r)):
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(f"expected a positive number, got {value!r}", name)
    a = np.array([[1.0, dt, dt * dt / 2.0], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    b = np.array([[dt ** 3 / 6.0], [dt * dt / 2.0], [dt]])
    c = np.array([[1.0, 0.0, -com_height / GRAVITY_M_S2]])
    # augmented system: (summed ZMP error, state)
    aa = np.zeros((4, 4))
    aa[0, 0], aa[0, 1:], aa[1:, 1:] = 1.0, (c @ a)[0], a
    bb = np.vstack([c @ b, b])
    qq = np.zeros((4, 4))
    qq[0, 0] = q
    p = solve_discrete_are(aa, bb, qq, np.array([[r]]))
    scale = 1.0 / (r + (bb.T @ p @ bb).item())
    k = scale * (bb.T @ p @ aa)[0]
    closed = aa - bb @ k[None]
    n = max(1, int(round(preview_s / dt)))
    gp = np.empty(n)
    x = -closed.T @ p @ np.array([1.0, 0.0, 0.0, 0.0])
    gp[0] = -k[0]
    for j in range(1, n):
        gp[j] = scale * float(bb[:, 0] @ x)
        x = closed.T @ x
    return PreviewGains(dt, com_height, float(k[0]), k[1:].copy(), gp, a, b, c[0])


@dataclass(frozen=True)
class CartTrack:
    """What the controller produced, per tick: CoM position, velocity, acceleration (K, 2) [m, m/s, m/s²] and the
    cart-table ZMP (K, 2) [m]."""

    com: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    zmp: np.ndarray


@dataclass(frozen=True)
class CartState:
    """Where the cart is between two ticks: its state ``x`` (3, 2) (position [m], velocity [m/s], acceleration
    [m/s²] of both axes) and the summed ZMP error (2,) [m] of the integral action. A walk planned in pieces carries
    it from one piece to the next, so the CoM path runs on as if it had been planned in one go."""

    x: np.ndarray
    summed: np.ndarray

    @classmethod
    def rest(cls, at: np.ndarray) -> "CartState":
        """At rest over ``at`` (2,) [m], no error summed."""
        x = np.zeros((3, 2))
        x[0] = np.asarray(at, dtype=float)
        return cls(x, np.zeros(2))


def _check_ref(ref: np.ndarray) -> np.ndarray:
    ref = np.asarray(ref, dtype=float)
    if ref.ndim != 2 or ref.shape[1] != 2 or len(ref) < 1 or not np.all(np.isfinite(ref)):
        raise InputError(f"expected a finite ZMP reference of shape (K, 2), got {ref.shape}", "zmp_ref")
    return ref


def run_cart(gains: PreviewGains, zmp_ref: np.ndarray, rows: int, state: CartState, keep: int | None = None
             ) -> tuple[CartTrack, CartState]:
    """Run the controller from ``state`` for ``rows`` ticks along ``zmp_ref`` (at least ``rows`` long; rows beyond
    are its preview, held at the last value beyond the end); the track, and the state after ``keep`` ticks
    (default: after all of them)."""
    ref = _check_ref(zmp_ref)
    n = len(gains.gp)
    padded = np.vstack([ref, np.repeat(ref[-1:], n + 1, axis=0)])
    # the preview sum of every tick at once: window[k, j] = ref[k + 1 + j]
    windows = np.lib.stride_tricks.sliding_window_view(padded[1:], n, axis=0)[:rows]   # (rows, 2, N)
    preview = windows @ gains.gp                                                        # (rows, 2)
    x, summed = state.x.copy(), state.summed.copy()
    keep = rows if keep is None else keep
    kept = CartState(x.copy(), summed.copy())
    out = np.empty((rows, 4, 2))
    for i in range(rows):
        if i == keep:
            kept = CartState(x.copy(), summed.copy())
        p = gains.c @ x
        summed += p - ref[i]
        u = -gains.gi * summed - gains.gx @ x - preview[i]
        out[i, :3], out[i, 3] = x, p
        x = gains.a @ x + gains.b @ u[None]
    if keep >= rows:
        kept = CartState(x.copy(), summed.copy())
    return CartTrack(out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy(), out[:, 3].copy()), kept


def track_reference(gains: PreviewGains, zmp_ref: np.ndarray, start: np.ndarray | None = None) -> CartTrack:
    """Run the controller along ``zmp_ref`` (K, 2) [m] (held at its last value beyond the end for the preview),
    from the CoM at rest over ``start`` (2,) [m] (default: the first reference point)."""
    ref = _check_ref(zmp_ref)
    return run_cart(gains, ref, len(ref), CartState.rest(ref[0] if start is None else start))[0]
