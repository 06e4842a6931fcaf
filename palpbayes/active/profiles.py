"""The lump's surface signature that an active search fits: one profile per sphere and depth.

A press at lateral distance s from a buried sphere reads an apparent log-excess
ln(E_app/E_b) (:mod:`palpbayes.inclusion`).  The search's posterior
(:mod:`palpbayes.active.posterior`) models it as beta·phi_kj(s): sphere k (radius R and cover
D − R of :data:`RADII` × :data:`COVERS`), press depth j (its contact radius a_j), and the
amplitude beta, the apparent peak log-excess at the first (reference) depth.

For each sphere the modulus ratio is the one that makes its apparent peak ratio
:data:`A_REF` at the reference depth; phi_kj(s) is the log-excess of that sphere at depth j,
divided by log :data:`A_REF`.  So phi_k0(0) = 1, and phi_kj(0) for a deeper press says how
the same lump's signature changes with depth (the forward model's answer, not an assumption):
its width grows with the contact radius, its peak may fall.  At other amplitudes the shapes
are kept (linear in beta); against the forward model's own profile the error is at most
1.5 % of the peak log-excess for A <= 1.25 and 3.5 % for A <= 1.5
(``tests/unit/test_active_posterior.py``).

The forward model is the screening model's Reuss average.  Against the finite-element twin
(a lump on the tip's axis, ``benchmarks/bench_lump_depth.py``) it understates a stiff lump's
log excess 2.6–4.4 times but gets the change from a 10 % to a 20 % press right in sign and
roughly in size (ratios 0.3, 3 and 10); the search fits the amplitude beta, so what it takes
from the model is the shapes and that change (docs/reference.md, "Active search").  The Hill
average (Reuss and Voigt's mean) matched the twin at ratio 10 only (within 19 %; 33–47 % low
at ratio 3) and is not used.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..errors import InputError
from ..inclusion import sensitivity

__all__ = ["A_REF", "RADII", "COVERS", "profile_table"]

#: Apparent peak ratio at which the profile shapes are taken.
A_REF = 1.15
#: Sphere radii [m] and covers (depth of the top below the surface) [m] of the profile set.
RADII = (2.5e-3, 4e-3, 6e-3, 9e-3)
COVERS = (0.0, 3e-3, 6e-3)
_S_MAX_FACTOR = 8.0  # profiles tabulated out to this × (R + cover + a); zero beyond
_NODES = 481


def _shape(Vs: list[np.ndarray]) -> np.ndarray:
    """phi_j(s) (D, S) of one sphere from its V at each depth (reference first)."""
    g = (1.0 - 1.0 / A_REF) / Vs[0][0]
    if g >= 1.0:  # this sphere cannot look A_REF stiff: V's own linear shape
        return np.array([V / Vs[0][0] for V in Vs])
    return np.array([-np.log1p(-g * V) for V in Vs]) / math.log(A_REF)


@lru_cache(maxsize=8)
def profile_table(contact_radii: tuple[float, ...], thickness: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The profiles of every sphere of :data:`RADII` × :data:`COVERS` that fits in the block
    and shows at the reference (first) depth, at each contact radius.

    Returns
    -------
    s : (S,) [m] uniform distance grid (its last node holds zeros: 0 beyond the table);
    profiles : (D, K, S) phi_kj(s), phi_k0(0) = 1;
    fwhm : (K,) [m] full width at half maximum at the reference depth;
    radius, cover : (K,) [m] the spheres.
    """
    a = tuple(float(v) for v in contact_radii)
    if not a or not all(math.isfinite(v) and v > 0 for v in a):
        raise InputError(f"contact radii {contact_radii!r} must be > 0 [m]")
    reach = max(RADII) + max(COVERS) + max(a)
    s = np.linspace(0.0, _S_MAX_FACTOR * reach, _NODES)  # uniform: LumpHypotheses.profile
    s = np.append(s, s[-1] + s[1])
    rows, fwhm, radii, covers = [], [], [], []
    for r in RADII:
        for cover in COVERS:
            if cover + 2.0 * r > thickness:
                continue
            Vs = [sensitivity(s, radius=r, depth=r + cover, contact_radius=aj,
                              thickness=thickness) for aj in a]
            if not Vs[0][0] > 1e-4:
                continue
            phi = _shape(Vs)
            phi[:, -1] = 0.0
            p0 = phi[0]
            j = int(np.argmax(p0 <= 0.5))
            half = s[j - 1] + (0.5 - p0[j - 1]) * (s[j] - s[j - 1]) / (p0[j] - p0[j - 1])
            rows.append(phi)
            fwhm.append(2.0 * half)
            radii.append(r)
            covers.append(cover)
    if not rows:
        raise InputError(f"the block ({thickness:g} m) is too thin for any lump of the set "
                         f"(radii {RADII} m)")
    return (s, np.ascontiguousarray(np.stack(rows, axis=1)), np.array(fwhm), np.array(radii),
            np.array(covers))
