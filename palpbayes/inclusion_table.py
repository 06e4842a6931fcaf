"""A fast table of the inclusion sensitivity V(s; R, D) of :mod:`palpbayes.inclusion`.

The lump model of a stiffness map (:mod:`palpbayes.maps.lump`) evaluates V hundreds of
thousands of times inside its sampler: :class:`SensitivityTable` tabulates it once per tip and
block and interpolates; :meth:`SensitivityTable.batch` evaluates one profile per walker of an
ensemble in one vectorised call.
"""

from __future__ import annotations

import math

import numpy as np

from .arguments import positive
from .errors import InputError
from .inclusion import sensitivity

__all__ = ["SensitivityTable"]


def _catmull_rom(t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Weights of the nodes at offsets −1, 0, 1, 2 for fractional position t ∈ [0, 1]."""
    t2 = t * t
    t3 = t2 * t
    return (0.5 * (-t + 2 * t2 - t3), 0.5 * (2 - 5 * t2 + 3 * t3),
            0.5 * (t + 4 * t2 - 3 * t3), 0.5 * (t3 - t2))


def _cell(v, lo: float, step: float, n: int):
    """Cell index in [0, n − 2] (also the padded index of node i − 1) and the fraction in it."""
    x = (np.asarray(v, dtype=float) - lo) / step
    i = np.clip(np.floor(x), 0, n - 2).astype(np.intp)
    return i, x - i


class SensitivityTable:
    """V(s; R, D) of :func:`sensitivity` for one tip and block, tabulated and interpolated.

    The table is built once for a contact radius a and thickness H on a regular grid of the
    scaled variables p = ln R, q = ln(1 + (D − R)/a) and u = s/ℓ with ℓ = R + (D − R) + a (the
    profile's width, which makes V(u) nearly the same shape for every sphere), and
    interpolated by tensor-product Catmull–Rom cubics (C¹ in all three variables).  V is even
    in s (the grid is mirrored at s = 0).  Beyond u_max (s > u_max·ℓ, where V < 3e-4 for every
    shape tried) the far-field tail of a buried point load is used,
    V(u) = V(u_max)·((c² + u_max²)/(c² + u²))^(5/2) with c = (D + a)/ℓ.

    Domain: radius ∈ ``radius_range`` (default [0.1·a, H/2]); margin D − R ∈ [0, H] (a sphere
    whose top lies below the block gives V = 0); any s >= 0.  Outside the radius range, or
    for D < R, :class:`InputError` is raised: give a wider ``radius_range``.

    Accuracy (defaults, H = 20 mm, 200 random spheres × 20 distances out to 6ℓ): maximum
    absolute error against :func:`sensitivity` 1.9e-4 for a = 4.8 mm (the paraboloid at 2 mm),
    1.1e-4 for a = 10 mm (the flat punch), 6.6e-4 for a = 1 mm; the test asserts <= 2e-3.
    Building takes about 1 s; a call with scalar radius and depth and 10,000 distances about
    0.2 ms (the fast path for a likelihood), with arrays of radius and depth about 6 ms.

    Parameters
    ----------
    contact_radius, thickness
        [m] Contact radius a of the tip and block thickness H.
    radius_range
        [m] (r_lo, r_hi) of the sphere radius; default (0.1·a, H/2).
    n_radius, n_margin, n_s
        Grid nodes in p, q and u.
    u_max
        Tabulated range of u = s/ℓ (V(u_max) < 3e-4 for the shapes tested).
    nodes
        Quadrature nodes of the exact values (:func:`sensitivity`).
    """

    def __init__(self, contact_radius: float, thickness: float, *,
                 radius_range: tuple[float, float] | None = None, n_radius: int = 16,
                 n_margin: int = 16, n_s: int = 64, u_max: float = 4.0,
                 nodes: int = 32) -> None:
        a = positive(contact_radius, "contact radius [m]")
        H = positive(thickness, "block thickness [m]")
        lo, hi = (0.1 * a, 0.5 * H) if radius_range is None else radius_range
        lo, hi = positive(lo, "smallest tabulated radius [m]"), positive(
            hi, "largest tabulated radius [m]")
        if not lo < hi:
            raise InputError(f"radius_range ({lo:g}, {hi:g}) m must be increasing")
        for n, what in ((n_radius, "n_radius"), (n_margin, "n_margin"), (n_s, "n_s")):
            if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 4:
                raise InputError(f"{what} {n!r} must be an integer >= 4")
        self.contact_radius, self.thickness = a, H
        self.radius_range = (lo, hi)
        self.u_max = positive(u_max, "u_max")
        self._p0, self._dp = math.log(lo), math.log(hi / lo) / (n_radius - 1)
        self._dq = math.log1p(H / a) / (n_margin - 1)
        self._du = self.u_max / (n_s - 1)
        self._n = (int(n_radius), int(n_margin), int(n_s))
        p = self._p0 + self._dp * np.arange(-1, n_radius + 1)
        q = self._dq * np.arange(0, n_margin + 1)
        u = self._du * np.arange(0, n_s + 2)
        T = np.zeros((p.size, n_margin + 2, n_s + 3))
        for i, R in enumerate(np.exp(p)):
            for j, m in enumerate(a * np.expm1(q)):
                ell = R + m + a
                T[i, j + 1, 1:] = sensitivity(u * ell, radius=R, depth=R + m,
                                              contact_radius=a, thickness=H, nodes=nodes)
        T[:, 0, :] = 3 * T[:, 1, :] - 3 * T[:, 2, :] + T[:, 3, :]  # margin < 0: extrapolated
        T[:, :, 0] = T[:, :, 2]  # V is even in s
        self._table = T

    def _locate(self, radius, depth):
        """Cells and weights in p and q, the width ℓ, the tail's c and the 'below' mask."""
        R, D = np.asarray(radius, dtype=float), np.asarray(depth, dtype=float)
        (lo, hi), a, tol = self.radius_range, self.contact_radius, 1e-9 * self.thickness
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(D))):
            raise InputError("radius and depth [m] must be finite")
        if np.any(R < lo - tol) or np.any(R > hi + tol):
            raise InputError(f"inclusion radius outside the table's range [{lo:g}, {hi:g}] m; "
                             "build the SensitivityTable with a wider radius_range")
        m = D - R
        if np.any(m < -tol):
            raise InputError("inclusion depth less than its radius; give depth >= radius")
        ip, tp = _cell(np.log(np.clip(R, lo, hi)), self._p0, self._dp, self._n[0])
        iq, tq = _cell(np.log1p(np.clip(m, 0.0, self.thickness) / a), 0.0, self._dq,
                       self._n[1])
        ell = R + np.maximum(m, 0.0) + a
        return ip, _catmull_rom(tp), iq, _catmull_rom(tq), ell, (D + a) / ell, m >= self.thickness

    def _along(self, line, u, c) -> np.ndarray:
        """Interpolate in u the values ``line(k)`` at grid index k; the tail beyond u_max."""
        nS, um = self._n[2], self.u_max
        iu, tu = _cell(np.minimum(u, um), 0.0, self._du, nS)
        out = sum(w * line(iu + k) for k, w in enumerate(_catmull_rom(tu)))
        far = u > um
        if np.any(far):
            out = np.where(far, line(nS) * ((c * c + um * um) / (c * c + u * u)) ** 2.5, out)
        return np.clip(out, 0.0, 1.0)

    def __call__(self, s, radius, depth) -> np.ndarray:
        """V at distances ``s`` [m] (used as |s|) for spheres of ``radius`` and centre
        ``depth`` [m].

        ``radius`` and ``depth`` may be scalars (the fast path: one interpolation in p and q,
        then one along s) or arrays broadcast with ``s``.  Returns the broadcast shape.
        """
        s = np.abs(np.asarray(s, dtype=float))
        if np.ndim(radius) == 0 and np.ndim(depth) == 0:
            ip, wp, iq, wq, ell, c, below = self._locate(float(radius), float(depth))
            if below:
                return np.zeros(s.shape)
            w = np.outer(wp, wq)
            line = np.tensordot(w, self._table[ip:ip + 4, iq:iq + 4], axes=2)  # V(u) nodes
            return self._along(line.__getitem__, s / ell, c)
        s, R, D = np.broadcast_arrays(s, np.asarray(radius, float), np.asarray(depth, float))
        ip, wp, iq, wq, ell, c, below = self._locate(R, D)
        T = self._table

        def line(k):
            return sum(wp[i] * wq[j] * T[ip + i, iq + j, k] for i in range(4) for j in range(4))

        return np.where(below, 0.0, self._along(line, s / ell, c))

    def batch(self, s: np.ndarray, radius: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """V for one sphere per row: ``s`` (W, n) [m], ``radius`` and ``depth`` (W,) [m].

        The vectorised form of ``__call__`` for an ensemble of W walkers: one interpolation in
        (p, q) per row, then along s; the same values as W scalar calls.
        """
        s = np.abs(np.asarray(s, dtype=float))
        R, D = np.asarray(radius, dtype=float), np.asarray(depth, dtype=float)
        if s.ndim != 2 or R.shape != (s.shape[0],) or D.shape != R.shape:
            raise InputError("batch: s must be (W, n) and radius, depth (W,)")
        ip, wp, iq, wq, ell, c, below = self._locate(R, D)
        k4 = np.arange(4)
        block = self._table[(ip[:, None] + k4)[:, :, None], (iq[:, None] + k4)[:, None, :]]
        w = np.stack(wp, axis=1)[:, :, None] * np.stack(wq, axis=1)[:, None, :]  # (W, 4, 4)
        lines = np.einsum("wij,wijk->wk", w, block)  # (W, n_s + 3): V(u) nodes per row
        u = s / ell[:, None]
        nS, um = self._n[2], self.u_max
        iu, tu = _cell(np.minimum(u, um), 0.0, self._du, nS)
        # gather from the flat lines (row offset added once): the values take_along_axis
        # gives, without its per-call index broadcasting
        flat = lines.ravel()
        iu += (np.arange(lines.shape[0]) * lines.shape[1])[:, None]
        out = sum(wk * flat[iu + k] for k, wk in enumerate(_catmull_rom(tu)))
        far = u > um
        if far.any():  # the tail only where it applies (its power is the costly part)
            row = np.nonzero(far)[0]
            cc, uf = (c * c)[row], u[far]
            out[far] = lines[row, nS] * ((cc + um * um) / (cc + uf * uf)) ** 2.5
        return np.where(below[:, None], 0.0, np.clip(out, 0.0, 1.0))
