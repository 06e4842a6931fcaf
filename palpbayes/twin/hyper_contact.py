"""Frictionless contact of a rigid tip with the hyperelastic twin: the tip's true surface.

The tip is a rigid body of revolution whose apex sits at height z0 (the top face of the
specimen at Z = H, the depth d = H − z0).  A point x = (r, z) of the specimen's top surface in
the deformed configuration has the signed distance g(x) to the tip's surface (positive outside
the tip, negative inside it), its gradient n = dg/dx (the tip's outward normal at the closest
point) and its Hessian.  The contact is a penalty on the penetration integrated over the
reference top face Gamma_0 (docs/design.md §14):

    Pi_c = ∫_Gamma_0 1/(2k)·<lambda − k·g(x)>²·R dS,    residual −∫ <lambda − k·g> n·v,
    tangent ∫ k·H(lambda − k·g)·(n·du)(n·v) − <lambda − k·g>·v·Hess(g)·du,

with lambda the contact pressure of an augmented Lagrangian (Uzawa's updates after each
converged step until the penetration is below its tolerance; lambda = 0, the pure penalty,
when it is already), so the force acts along the tip's normal in the deformed configuration
(a sphere's centre direction, 30° off vertical at a/R = 0.5), not along z.  The curvature
term (the Hessian's) is left out of the tangent on a step's first Newton iteration, when the
penetration is about the step's size (design.md §14: with it the prototype inverted
elements).  The tip's force is the vertical resultant of the penalty forces.

Surfaces (:func:`tip_surface`):

* sphere: g = |x − c| − R_s, c the centre, exactly (above the centre, the wall of its stem,
  a cylinder of radius R_s: a sphere-tipped rod, for depths beyond R_s);
* paraboloid, cone, power-law profile z = z0 + f(r): the closest point (s, z0 + f(s)) by a
  few Newton steps on (s − r) + (z0 + f(s) − z)·f'(s) = 0 (s >= 0), g = (x − x_s)·n,
  n = (f', −1)/sqrt(1 + f'²), Hess g = f''/((1 + f'²)^(3/2)·G_s)·(1, f')⊗(1, f'),
  G_s = 1 + f'² + (z0 + f − z)·f''; a kind registered later falls back on its law's
  ``profile`` with derivatives by central differences;
* flat punch of radius a: the signed distance to a solid cylinder, its face with its edge:
  the face below it, the edge's corner beside it (mesh graded towards r = a).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import BilinearForm, FacetBasis, LinearForm, asm

from ..contact import Tip, get_law
from ..errors import GeometryError
from .hyper import HyperSolid, _raw

__all__ = ["TipSurface", "tip_surface", "PenaltyContact"]


@dataclass(frozen=True)
class TipSurface:
    """A rigid tip's surface as a signed-distance function.

    Attributes
    ----------
    kind
        The tip's kind.
    distance
        ``distance(r, z, z0) -> (g, n, hess)``: signed distance [L] of the points (r, z) to
        the surface of the tip whose apex is at height z0, its gradient n (2, ...) and
        Hessian (2, 2, ...) [1/L].
    """

    kind: str
    distance: Callable[[np.ndarray, np.ndarray, float], tuple[np.ndarray, np.ndarray,
                                                               np.ndarray]]


def _sphere(radius: float):
    """The sphere on its stem (a cylinder of its radius above its centre): exact below the
    equator, the stem's wall above it (reached only deeper than the radius)."""
    def distance(r, z, z0):
        dr, dz = r, np.minimum(z - (z0 + radius), 0.0)
        rho = np.sqrt(dr * dr + dz * dz)
        n = np.stack([dr / rho, dz / rho])
        eye = np.eye(2).reshape((2, 2) + (1,) * r.ndim)
        hess = np.where(dz < 0, (eye - n[:, None] * n[None, :]) / rho, 0.0)
        return rho - radius, n, hess
    return distance


def _profile(f: Callable, df: Callable, d2f: Callable):
    def distance(r, z, z0):
        s = np.maximum(r, 0.0)
        for _ in range(20):
            h, q, c = z0 + f(s), df(s), d2f(s)
            gs = 1.0 + q * q + (h - z) * c
            gs = np.where(gs > 0.1, gs, 1.0 + q * q)
            step = ((s - r) + (h - z) * q) / gs
            s = np.maximum(s - step, 0.0)
            if np.all(np.abs(step) <= 1e-13 * (1.0 + np.abs(s))):
                break
        h, q, c = z0 + f(s), df(s), d2f(s)
        norm = np.sqrt(1.0 + q * q)
        n = np.stack([q / norm, -1.0 / norm])
        g = (r - s) * n[0] + (z - h) * n[1]
        gs = np.maximum(1.0 + q * q + (h - z) * c, 1e-3)
        t = np.stack([np.ones_like(q), q])
        hess = (c / (norm ** 3 * gs)) * t[:, None] * t[None, :]
        hess = np.where(s > 0, hess, 0.0)
        return g, n, hess
    return distance


def _punch(a: float):
    def distance(r, z, z0):
        face, side = z - z0, r - a  # > 0: above the face, beyond the side
        inside = (face > 0) & (side < 0)
        below_face = (face <= 0) & (side <= 0)
        corner_dr, corner_dz = np.maximum(side, 0.0), np.minimum(face, 0.0)
        rho = np.sqrt(corner_dr ** 2 + corner_dz ** 2)
        on_face = inside & (face <= -side)
        g = np.where(below_face, face * -1.0, np.where(side > 0, np.where(face > 0, side, rho),
                                                       0.0))
        g = np.where(inside, np.where(on_face, -face, side), g)
        safe = np.where(rho > 0, rho, 1.0)
        n_corner = np.stack([corner_dr / safe, corner_dz / safe])
        down, out = np.stack([0.0 * r, -1.0 + 0.0 * r]), np.stack([1.0 + 0.0 * r, 0.0 * r])
        corner = (side > 0) & (face <= 0)
        use_down = below_face | on_face
        n = np.where(use_down, down, np.where(corner, n_corner, out))
        eye = np.eye(2).reshape((2, 2) + (1,) * r.ndim)
        hess = np.where(corner & (rho > 0), (eye - n_corner[:, None] * n_corner[None, :]) / safe,
                        0.0)
        return g, n, hess
    return distance


def _numeric(tip: Tip):
    law = get_law(tip)
    h = 1e-6 * (tip.radius if getattr(tip, "radius", None) else 1.0)

    def f(s):
        return np.asarray(law.profile(s, tip), dtype=float)

    def df(s):
        return (f(s + h) - f(np.maximum(s - h, 0.0))) / (s + h - np.maximum(s - h, 0.0))

    def d2f(s):
        return (df(s + h) - df(np.maximum(s - h, 0.0))) / (s + h - np.maximum(s - h, 0.0))
    return _profile(f, df, d2f)


def tip_surface(tip: Tip) -> TipSurface:
    """The signed-distance function of ``tip`` (module docstring).

    Raises
    ------
    GeometryError
        A tip whose law has no profile.
    """
    law = get_law(tip)
    if law.profile is None:
        raise GeometryError(f"tip '{tip.kind}' has no profile: it cannot be pressed into the "
                            "hyperelastic twin")
    kind = tip.kind
    if kind == "sphere":
        return TipSurface(kind, _sphere(float(tip.radius)))
    if kind == "flat":
        return TipSurface(kind, _punch(float(tip.radius)))
    if kind == "paraboloid":
        rr = float(tip.radius)
        return TipSurface(kind, _profile(lambda s: s * s / (2 * rr), lambda s: s / rr,
                                         lambda s: 0.0 * s + 1.0 / rr))
    if kind == "cone":
        cot = 1.0 / math.tan(float(tip.half_angle))
        return TipSurface(kind, _profile(lambda s: cot * s, lambda s: 0.0 * s + cot,
                                         lambda s: 0.0 * s))
    if kind == "power":
        c, m = float(tip.c), float(tip.n)
        tiny = 1e-12

        def f(s):
            return c * np.power(np.maximum(s, 0.0), m)

        def df(s):
            return c * m * np.power(np.maximum(s, tiny), m - 1.0)

        def d2f(s):
            return c * m * (m - 1.0) * np.power(np.maximum(s, tiny), m - 2.0)
        return TipSurface(kind, _profile(f, df, d2f))
    return TipSurface(kind, _numeric(tip))


@LinearForm
def _contact_residual(v, w):
    n, v = _raw(w, "n"), np.asarray(v)
    return _raw(w, "t") * (n[0] * v[0] + n[1] * v[1]) * w.x[0]


@BilinearForm
def _contact_tangent(u, v, w):
    n, hs, u, v = _raw(w, "n"), _raw(w, "h"), np.asarray(u), np.asarray(v)
    nu_, nv = n[0] * u[0] + n[1] * u[1], n[0] * v[0] + n[1] * v[1]
    curv = (v[0] * (hs[0, 0] * u[0] + hs[0, 1] * u[1]) + v[1] * (hs[1, 0] * u[0]
                                                                 + hs[1, 1] * u[1]))
    return (_raw(w, "k") * nu_ * nv + _raw(w, "c") * curv) * w.x[0]


class PenaltyContact:
    """The penalty contact of a tip with the top face of a :class:`HyperSolid`.

    Parameters
    ----------
    solid
        The body.
    surface
        The tip's :class:`TipSurface`.
    intorder
        Quadrature order on the top face's edges.
    """

    def __init__(self, solid: HyperSolid, surface: TipSurface, intorder: int = 6) -> None:
        self.solid = solid
        self.surface = surface
        top = solid.mesh.facets_satisfying(lambda x: solid.on_top(x[0], x[1]))
        self.fbasis = FacetBasis(solid.mesh, solid.basis.elem, facets=top, intorder=intorder)
        self.x0 = np.asarray(self.fbasis.global_coordinates())
        self.z_dofs = solid.dofs("z", lambda r, z: np.ones_like(r, dtype=bool))
        #: The augmented Lagrangian's contact pressures [E0] at the face's quadrature points.
        self.multiplier = np.zeros(self.x0.shape[1:])

    def _gap(self, x: np.ndarray, z0: float):
        u = np.asarray(self.fbasis.interpolate(x[:self.solid.n_u]))
        pos = self.x0 + u
        g, n, hess = self.surface.distance(pos[0], pos[1], z0)
        return pos, g, n, hess

    def forces(self, x: np.ndarray, z0: float, k: float, curvature: bool
               ) -> tuple[np.ndarray, sp.csr_matrix]:
        """(residual, tangent) of the penalty ``k`` [E0/L] with the apex at ``z0``, over
        every unknown of the solid (zero on the pressures); the curvature term when
        ``curvature``."""
        _, g, n, hess = self._gap(x, z0)
        pen = np.maximum(self.multiplier / k - g, 0.0)
        active = (pen > 0).astype(float)
        r = asm(_contact_residual, self.fbasis, t=-k * pen, n=n)
        kt = asm(_contact_tangent, self.fbasis, n=n, h=hess, k=k * active,
                 c=-k * pen if curvature else 0.0 * pen)
        size = self.solid.size
        if size > r.size:
            r = np.r_[r, np.zeros(size - r.size)]
            kt = sp.block_diag([kt, sp.csr_matrix((size - kt.shape[0],) * 2)], format="csr")
        return r, kt.tocsr()

    def measure(self, x: np.ndarray, z0: float, k: float) -> tuple[float, float, float]:
        """(force [E0·L²] the tip reads: 2·pi × the penalty's vertical resultant, the contact
        radius [L] in the deformed configuration, the largest penetration [L])."""
        pos, g, n, _ = self._gap(x, z0)
        pen = np.maximum(self.multiplier / k - g, 0.0)
        r = asm(_contact_residual, self.fbasis, t=-k * pen, n=n)
        force = 2.0 * math.pi * r[self.z_dofs].sum()
        touching = pen > 0
        a = float(pos[0][touching].max()) if touching.any() else 0.0
        return float(force), a, float(np.maximum(-g, 0.0).max())

    def augment(self, x: np.ndarray, z0: float, k: float, tolerance: float) -> bool:
        """Uzawa's update of the multipliers, lambda <- <lambda − k·g> (Simo & Laursen
        1992, Comput. Struct. 42:97), when the largest penetration exceeds ``tolerance``
        [L]; True when they changed (the step is to be solved again)."""
        _, g, _, _ = self._gap(x, z0)
        if np.maximum(-g, 0.0).max() <= tolerance:
            return False
        self.multiplier = np.maximum(self.multiplier - k * g, 0.0)
        return True
