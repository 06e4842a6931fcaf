"""Apparent modulus of a block hiding a spherical inclusion, seen by a palpating tip.

**Model.**  A block of thickness H [m] and background modulus E_b holds a sphere of radius R
whose centre lies at lateral (x_c, y_c) and depth D >= R below the surface, modulus
E_i = ratio·E_b.  A tip pressed at (x, y) with contact radius a (:func:`contact_radius`) reads
the Reuss (series, compliance) average of 1/E weighted by the Boussinesq stress under it::

    1/E_app(x, y) = ∫_0^H ω(z) ∫∫ K(r, z) / E(ξ, η, z) dξ dη dz
    K(r, z) = 3h³ / (2π (h² + r²)^(5/2)),   h = z + a,        ∫∫ K dA = 1 at every depth
    ω(z)   ∝ 1 − z³ / (a² + z²)^(3/2)  on [0, H],            ∫_0^H ω dz = 1

K is the vertical-stress distribution of a point load (Boussinesq 1885) applied a above the
surface, which spreads it over about the contact area; ω is the on-axis vertical stress under
a uniform disk load of radius a (Love 1929).  With the inclusion::

    E_app / E_b = 1 / (1 − (1 − 1/ratio)·V(s)),      s = |(x, y) − (x_c, y_c)|
    V(s) = ∫ ω(z) L(s, ρ(z), z) dz  over [D − R, D + R] ∩ [0, H],  ρ(z) = sqrt(R² − (z − D)²)
    L(s, ρ, z) = ∫∫ K dA over the inclusion's slice, a disk of radius ρ at distance s

V ∈ [0, 1] is the stress-weighted volume fraction of the inclusion.  For a centred disk
L(0, ρ, z) = 1 − h³/(h² + ρ²)^(3/2).  :func:`sensitivity` computes V by Gauss–Legendre
quadrature: depth slices z = D + R·sin t (smooth at the sphere's poles) and, on each slice,
polar angle θ about the tip's axis over [0, π] (doubled by symmetry) with the radial integral
of K done in closed form (for a disk that does not contain the axis, θ runs over the
tangent angle through sin θ = (ρ/s)·sin φ, which removes the square-root endpoint).
:class:`palpbayes.inclusion_table.SensitivityTable` tabulates V for fast use inside a
likelihood.

**References.**  J. Boussinesq (1885), *Application des potentiels à l'étude de l'équilibre
et du mouvement des solides élastiques* (point load on a half-space); A. E. H. Love (1929),
Phil. Trans. R. Soc. A 228, 377–420 (uniform load on a circular area); A. Reuss (1929),
ZAMM 9, 49–58 (the series/compliance average).

**Limits** (this is a screening model for simulation and inference, *not* a finite-element
solution):

* the inclusion is assumed not to change the contact radius or the power-law shape of a
  trace: each trace is simulated as a homogeneous block of modulus E_app at that point;
* the depth dependence of E_app within one indentation is neglected (E_app uses the contact
  radius at the commanded depth);
* a Reuss average is a lower bound on the stiffness: it understates the contrast of stiff
  inclusions (ratio > 1) and is only indicative for large ratios.  Measured against the
  finite-element twin (a lump on the tip's axis, :class:`palpbayes.twin.palpation.
  CentredLump`; ``benchmarks/bench_lump_depth.py``, ``reports/active/lump_depth*.csv``): a
  sphere of radius 5 mm, its centre 5-10 mm deep in a 20 mm block, under the paper's
  paraboloid pressed 2 mm, reads an apparent ratio of 2.14-1.20 in the twin and 1.24-1.04
  here at ratio 10 (3.4-4.4 times less log excess), 1.49-1.11 and 1.17-1.03 at ratio 3
  (2.6-3.6 times less); a soft lump (ratio 0.3) is within 14 %.  The Hill average on the same
  V matches ratio 10 within 19 % but is 33-47 % low at ratio 3: the weight V, not only the
  average, is too small near a stiff lump.  From a 10 % to a 20 % press the model's centre
  signature changes like the twin's (it falls, by 6-42 % in log excess);
* lateral stress spreading beyond the Boussinesq kernel, the finite block width and the
  bottom boundary are ignored, except through the truncation of ω at H.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .arguments import finite, positive
from .contact import Tip, get_law, registered_laws
from .errors import InputError

__all__ = [
    "Inclusion",
    "contact_radius",
    "depth_weight",
    "sensitivity",
    "apparent_ratio",
    "apparent_modulus",
]

#: Quadrature nodes per dimension of :func:`sensitivity` (error < 1e-5 for the paper's tips).
DEFAULT_NODES = 48
_CHUNK = 1 << 21  # elements per temporary array in sensitivity


@dataclass(frozen=True)
class Inclusion:
    """A spherical inclusion in the block.

    Parameters
    ----------
    x, y
        [m] Lateral position of the centre (same frame as the palpation positions).
    depth
        [m] Depth of the centre below the surface, >= ``radius`` (buried or touching).
    radius
        [m] Radius R > 0.
    ratio
        E_inclusion / E_background > 0 (> 1: a stiff lump, < 1: a soft one).

    Raises
    ------
    InputError
        A non-finite value, radius <= 0, depth < radius or ratio <= 0.
    """

    x: float
    y: float
    depth: float
    radius: float
    ratio: float

    def __post_init__(self) -> None:
        r, d, _, _ = _check_geometry(self.radius, self.depth, 1.0, 1.0)
        for name, v in (("x", finite(self.x, "inclusion centre x [m]")),
                        ("y", finite(self.y, "inclusion centre y [m]")),
                        ("radius", r), ("depth", d),
                        ("ratio", positive(self.ratio, "inclusion modulus ratio E_i/E_b"))):
            object.__setattr__(self, name, v)


def contact_radius(tip: Tip, depth: float) -> float:
    """Contact radius a [m] of ``tip`` pressed ``depth`` [m] into a half-space: the tip's
    contact law's own (:attr:`palpbayes.contact.ContactLaw.contact_radius`: the punch's radius,
    Hertz's sqrt(R·d), the exact Sneddon sphere's, a cone's 2·d·tan(alpha)/pi, ...), so that a
    tip kind registered later maps and searches with no edit here.

    Raises
    ------
    InputError
        ``tip`` is not a :class:`~palpbayes.contact.Tip`, its law has no contact radius, or
        ``depth`` is not positive.
    """
    if not isinstance(tip, Tip):
        raise InputError(f"tip must be a palpbayes.contact.Tip, got {type(tip).__name__}")
    d = positive(depth, "indentation depth [m]")
    law = get_law(tip)
    if law.contact_radius is None:
        kinds = [k.kind for k in registered_laws() if k.contact_radius is not None]
        raise InputError(f"the inclusion model needs a tip with a contact radius "
                         f"({', '.join(kinds)}), got {tip.kind!r}")
    return float(law.contact_radius(np.array([d]), tip)[0])


def _omega_integral(z, a: float):
    """∫_0^z (1 − t³/(a² + t²)^(3/2)) dt [m] (closed form)."""
    q = np.sqrt(a * a + np.asarray(z, dtype=float) ** 2)
    return z - q - a * a / q + 2.0 * a


def depth_weight(z, *, contact_radius: float, thickness: float) -> np.ndarray:
    """The normalised depth weight ω(z) [1/m] on [0, H] (0 outside)."""
    a, H = float(contact_radius), float(thickness)
    z = np.asarray(z, dtype=float)
    w = (1.0 - z**3 / (a * a + z * z) ** 1.5) / _omega_integral(H, a)
    return np.where((z >= 0) & (z <= H), w, 0.0)


@lru_cache(maxsize=16)
def _legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def _check_geometry(radius, depth, a, H) -> tuple[float, float, float, float]:
    R = positive(radius, "inclusion radius [m]")
    D = finite(depth, "inclusion depth [m]")
    if D < R:
        raise InputError(f"inclusion depth {D:g} m (of the centre) is less than its radius "
                         f"{R:g} m, so the sphere would stick out of the surface; give a "
                         "depth >= radius")
    return (R, D, positive(a, "contact radius [m]"), positive(H, "block thickness [m]"))


def _slices(R: float, D: float, a: float, H: float, n: int):
    """Depth nodes of the sphere: h = z + a, slice radius ρ and weight ω(z)·dz per node."""
    zlo, zhi = max(0.0, D - R), min(H, D + R)
    if zlo >= zhi:
        return None
    x, w = _legendre(n)
    t0, t1 = math.asin(max(-1.0, (zlo - D) / R)), math.asin(min(1.0, (zhi - D) / R))
    t = 0.5 * (t1 + t0) + 0.5 * (t1 - t0) * x
    z = D + R * np.sin(t)
    rho = R * np.cos(t)
    wz = 0.5 * (t1 - t0) * w * rho * depth_weight(z, contact_radius=a, thickness=H)
    return z + a, rho, wz


def _disk_fraction(s: np.ndarray, rho: np.ndarray, h: np.ndarray, n: int) -> np.ndarray:
    """L(s, ρ, z): the share of ∫∫ K dA on a disk of radius ρ at distance s (broadcast)."""
    x, w = _legendre(n)
    s, rho, h = (v[..., None] for v in np.broadcast_arrays(s, rho, h))
    h2, h3 = h * h, h * h * h
    inside = s < rho
    # axis inside the disk: θ ∈ [0, π], r from 0 to the far edge
    th = 0.5 * math.pi * (x + 1.0)
    r2 = s * np.cos(th) + np.sqrt(np.maximum(rho * rho - (s * np.sin(th)) ** 2, 0.0))
    L_in = 1.0 - 0.5 * np.sum(w * h3 / (h2 + r2 * r2) ** 1.5, axis=-1)
    # axis outside: sin θ = k·sin φ, φ ∈ [0, π/2], r between the near and far edge
    k = np.where(inside, 0.0, rho / np.where(s > 0, s, 1.0))
    phi = 0.25 * math.pi * (x + 1.0)
    sin_th = k * np.sin(phi)
    cos_th = np.sqrt(1.0 - sin_th * sin_th)
    c = rho * np.cos(phi)
    near, far = s * cos_th - c, s * cos_th + c
    g = h3 / (h2 + near * near) ** 1.5 - h3 / (h2 + far * far) ** 1.5
    L_out = 0.25 * np.sum(w * g * k * np.cos(phi) / cos_th, axis=-1)
    return np.where(inside[..., 0], L_in, L_out)


def sensitivity(s, *, radius: float, depth: float, contact_radius: float, thickness: float,
                nodes: int = DEFAULT_NODES) -> np.ndarray:
    """The weighted volume fraction V(s) ∈ [0, 1] of the inclusion (module docstring).

    Parameters
    ----------
    s
        [m] Lateral distance(s) from the inclusion's axis, >= 0 (any shape).
    radius, depth
        [m] Radius R and centre depth D >= R of the sphere.
    contact_radius, thickness
        [m] Contact radius a of the tip and block thickness H.
    nodes
        Gauss–Legendre nodes in depth and in angle (absolute error < 1e-5 at 48 for the
        paper's geometries; tested by doubling).

    Returns V shaped like ``s``; raises InputError for a negative or non-finite s or an
    invalid geometry.
    """
    R, D, a, H = _check_geometry(radius, depth, contact_radius, thickness)
    s = np.asarray(s, dtype=float)
    if s.size and not (np.all(np.isfinite(s)) and s.min() >= 0):
        raise InputError("lateral distances s [m] must be finite and >= 0")
    out = np.zeros(s.shape)
    sl = _slices(R, D, a, H, int(nodes))
    if sl is None or s.size == 0:
        return out
    h, rho, wz = sl
    flat, step = s.ravel(), max(1, _CHUNK // int(nodes) ** 2)
    res = np.concatenate([_disk_fraction(flat[i:i + step, None], rho, h, int(nodes)) @ wz
                          for i in range(0, flat.size, step)])
    return np.clip(res, 0.0, 1.0).reshape(s.shape)


def apparent_ratio(V, ratio) -> np.ndarray:
    """E_app/E_b = 1/(1 − (1 − 1/ratio)·V): the Reuss average for volume fraction V.

    ``ratio`` may be ``inf`` (a rigid inclusion: 1/(1 − V)).  Exactly 1 for ratio = 1.
    """
    V = np.asarray(V, dtype=float)
    excess = 1.0 - 1.0 / np.asarray(ratio, dtype=float)
    return 1.0 / (1.0 - excess * V)


def apparent_modulus(x, y, *, E_background: float, inclusion: Inclusion | None,
                     contact_radius: float, thickness: float) -> np.ndarray:
    """The apparent modulus E_app [Pa] read by a tip at lateral position(s) (x, y) [m].

    ``inclusion`` None (or ratio 1) gives E_background everywhere, exactly.  Uses the exact
    quadrature of :func:`sensitivity`.
    """
    E_b = positive(E_background, "background modulus [Pa]")
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    if inclusion is None or inclusion.ratio == 1.0:
        return np.full(x.shape, E_b)
    if not isinstance(inclusion, Inclusion):
        raise InputError(f"inclusion must be an Inclusion or None, got "
                         f"{type(inclusion).__name__}")
    s = np.hypot(x - inclusion.x, y - inclusion.y)
    V = sensitivity(s, radius=inclusion.radius, depth=inclusion.depth,
                    contact_radius=contact_radius, thickness=thickness)
    return E_b * apparent_ratio(V, inclusion.ratio)
