"""A rigid frictionless tip pressed into the twin of a specimen: force against depth.

The specimen is a cylinder of radius ``radius`` and height ``height`` on a rigid base, bonded
to it (u = 0) or lying on it without friction (u_z = 0); its side is free.  The tip presses the
top face at its centre, without friction (the surface may slide under it).

**The contact.**  The top face's vertical flexibility at the nodes the tip may reach (up to 1.3
times the half-space contact radius of the deepest depth asked) is computed once, one back
substitution per node; at each depth d the nodal forces f >= 0 then solve the linear
complementarity problem

    w = C·f >= d − g(r),    f >= 0,    f·(w − d + g(r)) = 0,

(w the surface's downward displacement, g the tip's profile, C the flexibility): the
surface touches the tip where it pushes, and lies below it elsewhere.  It is the quadratic
programme min ½·f'Cf − f'(d − g) over f >= 0, solved as a non-negative least-squares problem
(Lawson & Hanson's active set, :func:`scipy.optimize.nnls`) on the Cholesky factor of C; so
the contact radius is solved, not imposed.  A flat punch is in contact over its face at every
depth (its pressure is positive everywhere): its face is pushed down by d, and the force is the
reaction there.

**A lump under the tip** (:class:`CentredLump`): a sphere of another modulus on the axis,
its centre ``depth`` below the top face — the one placement of an inclusion that keeps the
body axisymmetric.  The mesh gets nodes across the sphere (:data:`LUMP_NODES` per radius) and
every quadrature point inside it the lump's modulus, so the force is the linear-elastic
answer to the inclusion that :mod:`palpbayes.inclusion`'s screening model (a Reuss average,
a lower bound for a stiff lump) only estimates.

Checked (``tests/unit/test_twin.py``): a paraboloid and a sphere in a deep, wide block against
Hertz and Sneddon, a flat punch and a paraboloid in a wide layer against
:mod:`palpbayes.contact.layer`, each within 0.1 %; the contact radius against Hertz's.  The
lump (``tests/unit/test_twin_lump.py``): a lump of ratio 1 is the homogeneous block on the same
mesh, a stiff one raises the force and a soft one lowers it, and a stiff one's apparent ratio
lies above the screening model's lower bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from ..contact import Tip, get_law, youngs_modulus
from ..errors import GeometryError
from .mesh import RESOLUTIONS, Resolution, contact_grid, depth_grid, punch_grid

__all__ = ["PalpationCurve", "solve_palpation", "TWIN_BASES", "CentredLump", "lump_ratio",
           "pressed_ratio"]

#: Base conditions of the twin: bonded to the plate, or lying on it without friction.
TWIN_BASES = ("bonded", "free")
#: Candidate contact nodes reach this many times the deepest half-space contact radius.
_REACH = 1.3
#: Mesh nodes per lump radius, across the lump (radially and vertically).
LUMP_NODES = 16


@dataclass(frozen=True)
class CentredLump:
    """A sphere of modulus ``ratio`` × the block's on the tip's axis.

    Parameters
    ----------
    radius
        [L] The sphere's radius.
    depth
        [L] Its centre's depth below the top face (>= radius: under the surface).
    ratio
        E_lump / E_block [-], positive.
    """

    radius: float
    depth: float
    ratio: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.radius) and self.radius > 0 and math.isfinite(self.ratio)
                and self.ratio > 0 and math.isfinite(self.depth)
                and self.depth >= self.radius):
            raise GeometryError(f"a lump needs a positive radius and ratio and its centre at "
                                f"least one radius deep, got {self}")

    def modulus(self, height: float):
        """``modulus(r, z)`` [-] for :class:`~palpbayes.twin.fe.AxisymmetricSolid` in a body
        whose top face is at z = ``height``."""
        zc = height - self.depth

        def field(r: np.ndarray, z: np.ndarray) -> np.ndarray:
            return np.where(r**2 + (z - zc) ** 2 < self.radius**2, self.ratio, 1.0)

        return field

    def nodes(self, r_nodes: np.ndarray, z_nodes: np.ndarray, height: float
              ) -> tuple[np.ndarray, np.ndarray]:
        """``r_nodes`` and ``z_nodes`` with :data:`LUMP_NODES` per radius across the lump
        (nodes closer than 1e-3 of that spacing to one already there are not added)."""
        h = self.radius / LUMP_NODES
        zc = height - self.depth
        r_new = np.arange(0.0, self.radius + 0.5 * h, h)
        z_new = np.arange(max(zc - self.radius, 0.0), min(zc + self.radius, height) + 0.5 * h,
                          h)
        return _merge(r_nodes, r_new, 1e-3 * h), _merge(z_nodes, z_new[z_new <= height],
                                                         1e-3 * h)


def _merge(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    far = np.min(np.abs(b[:, None] - a[None, :]), axis=1) > tol
    return np.unique(np.r_[a, b[far]])


@dataclass(frozen=True)
class PalpationCurve:
    """Force per unit effective modulus of a tip in the twin, at each depth.

    Attributes
    ----------
    depth
        Depths [L] (the caller's length unit L).
    shape
        F/E* [L²] at each depth (E* = E/(1 − nu²)).
    contact_radius
        [L] Radius of the outermost node in contact (the punch's radius for a flat punch).
    dofs
        Unknowns of the finite-element model.
    """

    depth: np.ndarray
    shape: np.ndarray
    contact_radius: np.ndarray
    dofs: int


def _solid(radius: float, height: float, nu: float, r_nodes: np.ndarray, first: float,
           res: Resolution, lump: CentredLump | None = None):
    from .fe import AxisymmetricSolid  # scikit-fem is imported when a twin is first solved

    z_nodes = depth_grid(height, first, res)
    if lump is None:
        return AxisymmetricSolid(r_nodes, z_nodes, nu)
    if lump.depth + lump.radius > height or lump.radius >= radius:
        raise GeometryError(f"the lump (radius {lump.radius:.4g}, centre {lump.depth:.4g} "
                            f"deep) does not fit in the specimen ({height:.4g} high, radius "
                            f"{radius:.4g})")
    r_nodes, z_nodes = lump.nodes(r_nodes, z_nodes, height)
    return AxisymmetricSolid(r_nodes, z_nodes, nu, modulus=lump.modulus(height))


def _fixed(solid, base: str) -> np.ndarray:
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    fixed = [solid.dofs("r", solid.on_axis), solid.dofs("z", solid.on_bottom)]
    if base == "bonded":
        fixed.append(solid.dofs("r", solid.on_bottom))
    return np.concatenate(fixed)


def solve_palpation(radius: float, height: float, tip: Tip, nu: float, base: str,
                    depths: np.ndarray, resolution: str | Resolution = "default",
                    lump: CentredLump | None = None) -> PalpationCurve:
    """F/E* of ``tip`` pressed ``depths`` into the twin (module docstring).

    Parameters
    ----------
    radius, height
        The cylinder's radius and height [L] (any length unit L, the tip's too).
    tip
        A tip whose law has a ``profile`` (every registered kind).
    nu
        Poisson ratio [-], 0 <= nu <= 0.5.
    base
        ``"bonded"`` or ``"free"``.
    depths
        Depths [L], positive; the deepest sets the mesh.
    resolution
        A name of :data:`~palpbayes.twin.mesh.RESOLUTIONS` or a
        :class:`~palpbayes.twin.mesh.Resolution`.
    lump
        A :class:`CentredLump` in the block (its modulus relative to the block's), or None.

    Raises
    ------
    GeometryError
        A tip without a profile, a contact wider than the specimen, or a depth beyond the
        tip's law.
    """
    res = RESOLUTIONS[resolution] if isinstance(resolution, str) else resolution
    law = get_law(tip)
    if law.profile is None or law.profile_exponent is None:
        raise GeometryError(f"tip '{tip.kind}' has no profile: it cannot be pressed into the "
                            "specimen twin")
    depths = np.asarray(depths, dtype=float)
    if not (depths.size and np.all(np.isfinite(depths)) and np.all(depths > 0)):
        raise GeometryError("twin depths must be positive and finite")
    if math.isinf(law.profile_exponent(tip)):
        return _punch(radius, height, tip, nu, base, depths, res, lump)
    a_top = float(law.contact_radius(np.array([depths.max()]), tip)[0])
    reach = _REACH * a_top
    while True:
        if reach >= radius:
            raise GeometryError(
                f"a contact radius of {a_top:.4g} (half-space, at depth {depths.max():.4g}) "
                f"does not fit well inside the specimen's radius {radius:.4g}: the twin needs "
                "the contact well inside the top face (a shallower depth, a wider specimen)")
        curve = _curved(radius, height, tip, nu, base, depths, res, reach, lump)
        if curve is not None:
            return curve
        reach *= _REACH  # the contact reached the last candidate: a wider zone (pile-up)


# Many parameters: the twin's geometry, tip, material and mesh, as solve_palpation's own.
def _curved(radius: float, height: float, tip: Tip, nu: float, base: str, depths: np.ndarray,
            res: Resolution, reach: float, lump: CentredLump | None = None
            ) -> PalpationCurve | None:
    """The complementarity solution with candidate nodes up to ``reach``; None when the
    contact reaches the last of them."""
    law = get_law(tip)
    a_mesh = reach / _REACH
    solid = _solid(radius, height, nu, contact_grid(a_mesh, radius, res), res.first * a_mesh,
                   res, lump)
    fac = solid.factorize(_fixed(solid, base))
    cand = solid.dofs("z", lambda r, z: solid.on_top(r, z) & (r <= reach * (1 + 1e-9)))
    r_c = solid.location(cand)[0]
    g = np.asarray(law.profile(r_c, tip), dtype=float)
    keep = np.isfinite(g)
    cand, r_c, g = cand[keep], r_c[keep], g[keep]
    chol = np.linalg.cholesky(fac.columns(cand))
    shape = np.empty(depths.size)
    a = np.empty(depths.size)
    for i, d in enumerate(depths):
        f, _ = nnls(chol.T, np.linalg.solve(chol, d - g), maxiter=50 * cand.size)
        touching = np.flatnonzero(f > 0)
        if touching.size and touching[-1] >= cand.size - 2:
            return None
        shape[i] = youngs_modulus(2.0 * math.pi * f.sum(), nu)  # F/E* of F at E = 1
        a[i] = r_c[touching[-1]] if touching.size else 0.0
    return PalpationCurve(depths, shape, a, solid.size)


def _punch(radius: float, height: float, tip: Tip, nu: float, base: str, depths: np.ndarray,
           res: Resolution, lump: CentredLump | None = None) -> PalpationCurve:
    a = float(tip.radius)
    if a >= radius:
        raise GeometryError(f"a flat punch of radius {a:.4g} does not fit on a specimen of "
                            f"radius {radius:.4g}")
    solid = _solid(radius, height, nu, punch_grid(a, radius, res), res.punch_first * a, res,
                   lump)
    face = solid.dofs("z", lambda r, z: solid.on_top(r, z) & (r <= a * (1 + 1e-9)))
    support = _fixed(solid, base)
    fac = solid.factorize(np.r_[support, face])
    prescribed = np.zeros(fac.fixed.size)
    prescribed[np.isin(fac.fixed, face)] = -1.0  # the face pushed down by a unit depth
    x = fac.solve(np.zeros(solid.size), prescribed)
    s1 = youngs_modulus(-2.0 * math.pi * fac.reaction(x, face).sum(), nu)
    return PalpationCurve(depths, s1 * depths, np.full(depths.size, a), solid.size)


# Many parameters: the twin's geometry, tip, material and mesh, as solve_palpation's own.
def _with_and_without(radius, height, tip, nu, base, depths, lump, resolution):
    with_lump = solve_palpation(radius, height, tip, nu, base, depths, resolution, lump)
    same_mesh = CentredLump(lump.radius, lump.depth, 1.0)
    without = solve_palpation(radius, height, tip, nu, base, depths, resolution, same_mesh)
    return with_lump.shape, without.shape


def lump_ratio(radius: float, height: float, tip: Tip, nu: float, base: str,
               depths: np.ndarray, lump: CentredLump,
               resolution: str | Resolution = "default") -> np.ndarray:
    """F_lump / F_block [-] at each of ``depths``: the force of ``tip`` over a centred
    ``lump`` against the same block without it, on the same mesh (the lump's ratio set to
    1), so that the mesh's own error cancels.  The apparent modulus ratio a fit of the press
    to ``depths[i]`` reads is this ratio's weighted mean over the press (module docstring;
    parameters as :func:`solve_palpation`).
    """
    lumped, block = _with_and_without(radius, height, tip, nu, base, depths, lump, resolution)
    return lumped / block


def pressed_ratio(radius: float, height: float, tip: Tip, nu: float, base: str,
                  press_depths, lump: CentredLump, resolution: str | Resolution = "default",
                  points: int = 20) -> np.ndarray:
    """The apparent modulus ratio [-] a press to each of ``press_depths`` [m] reads over a
    centred ``lump``: the least-squares scale k of F_lump(d) = k·F_block(d) over ``points``
    depths evenly up to the press's (5 % to 100 %), i.e. k = Σ F_l·F_b / Σ F_b² — what a fit
    of the press as a homogeneous block reads, relative to the block without the lump.
    Parameters otherwise as :func:`solve_palpation`."""
    p = np.atleast_1d(np.asarray(press_depths, dtype=float))
    frac = np.linspace(0.05, 1.0, int(points))
    d = np.unique(np.concatenate([frac * q for q in p]))
    lumped, block = _with_and_without(radius, height, tip, nu, base, d, lump, resolution)
    out = np.empty(p.size)
    for i, q in enumerate(p):
        m = d <= q * (1 + 1e-9)
        out[i] = np.dot(lumped[m], block[m]) / np.dot(block[m], block[m])
    return out
