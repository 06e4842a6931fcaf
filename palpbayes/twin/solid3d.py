"""Three-dimensional linear elasticity of a cuboid specimen: the yardstick of the twin.

The specimen twin (:mod:`.palpation`, :mod:`.compression`) models a block L × W × H as the
cylinder of equal footprint area, which is axisymmetric and cheap.  This module solves the
block itself, in 3-D, so that the error of that equivalence can be measured
(``benchmarks/bench_twin_3d.py``, ``tests/statistical/test_twin_3d.py``).  It is a reference,
not part of the fits: one solve takes seconds to minutes where the axisymmetric twin takes a
fraction of a second.

**Model.**  Linear elasticity with E = 1 (forces scale with E), pure displacement
formulation on triquadratic 27-node hexahedra (:class:`skfem.ElementHex2`, isoparametric on a
:class:`skfem.MeshHex2`, so that circles are curved edges); the stiffness is assembled by
scikit-fem from the gradient products D_kl = ∫ ∂_k φ_a ∂_l φ_b (one scalar
:class:`~skfem.BilinearForm` per pair k <= l), K_kl = lambda·D_kl + mu·D_lk + mu·δ_kl·Σ_m D_mm:
:func:`skfem.models.elasticity.linear_elasticity` on ``ElementVector(ElementHex2())`` to
round-off, assembled fifteen times as fast.
Without a pressure unknown the quadratic elements lock as nu → 0.5: the module accepts
nu <= 0.45 only (the axisymmetric twin's mixed P2/P1 elements reach 0.5).

**Palpation** (:func:`palpation_force_3d`, :class:`Palpation3D`).  A quarter of the block,
x in [0, L/2], y in [0, W/2], z in [0, H] (u_x = 0 on x = 0, u_y = 0 on y = 0: symmetry), the
tip on the axis x = y = 0 of the top face z = H, the base z = 0 bonded (u = 0) or free
(u_z = 0).  The footprint is an O-grid: a core block around the axis, then rings on exact
circles out to the contact zone's edge, then rings blending from the circles into the
rectangle's edges, extruded over a grid graded towards the top face.  A flat punch's grid is
graded towards its edge r = a from both sides (the edge is singular), with the circle r = a a
mesh line.  A curved tip's contact is solved as in :mod:`.palpation`: the top face's
flexibility at the candidate nodes (every top-face node up to 1.3 contact radii) gives the
linear complementarity problem of a frictionless contact, solved by
:func:`scipy.optimize.nnls`; the flexibility is the inverse of the Schur complement of the
candidates, read off the trailing block of the LU factors with the candidates ordered last
(one factorization, no back substitution).  A flat punch pushes the face r <= a down
(prescribed u_z); the force is the reaction there.  The force of the whole block is four times
the quarter's.

**Compression** (:func:`compression_factor_3d`).  An eighth of the block, the mid-plane
z = 0 held (u_z = 0), the platen pushing the face z = H/2 down by a unit strain, bonded
(u_x = u_y = 0 there too) or lubricated (free); E_app = (F/A)/(delta/H).  The tensor grid is
graded towards the platen's edges, where the bonded corner is singular.  Lubricated platens
give uniaxial stress, which the quadratic elements hold exactly: E_app/E = 1 to round-off.

**Solver.**  SuperLU (:func:`scipy.sparse.linalg.splu`) in natural order on the matrix
permuted by a nested dissection computed here (recursive bisection of the elements across the
axis and near the median centroid that give the smallest separator, the separator being the
nodes both halves share), without pivoting (the matrix is symmetric positive definite once
supported).  SuperLU's default ordering (COLAMD) filled a 37,500-unknown test block three times
as much and factorized it seven times as slowly; its minimum degree on A + A' comes closer
(+15 % fill) but would not keep the contact candidates last.  The cost grows as the unknowns
squared: ~12 s for 30,000 unknowns, ~60 s and 2.5 GB for 75,000
(``benchmarks/bench_twin_3d.py``).
"""

# Long module: one job, the 3-D linear-elastic yardstick; its palpation and compression solves
#   share the factorized solid, so they stay with it.

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import nnls
from skfem import Basis, BilinearForm, ElementHex2, MeshHex, asm
from skfem.models.elasticity import lame_parameters

from ..contact import Tip, get_law, youngs_modulus
from ..errors import GeometryError
from .mesh import graded
from .mesh3d import (
    Resolution3D,
    compression_mesh,
    footprint_mesh,
    nested_dissection,
    resolution_3d,
    towards_top,
)

__all__ = ["MAX_NU_3D", "Solid3D", "Palpation3D", "Compression3D", "palpation_force_3d",
           "compression_factor_3d", "solve_compression_3d"]

#: Largest Poisson ratio of the pure displacement formulation (locking beyond).
MAX_NU_3D = 0.45
#: Candidate contact nodes reach this many times the mesh's contact radius.
_REACH = 1.3
_BASES = ("bonded", "free")


def _check(nu: float, *sizes: float) -> None:
    if not 0.0 <= nu <= MAX_NU_3D:
        raise GeometryError(f"Poisson ratio {nu!r}: the 3-D model (pure displacement "
                            f"formulation) takes 0 <= nu <= {MAX_NU_3D}")
    if not all(math.isfinite(s) and s > 0 for s in sizes):
        raise GeometryError(f"block sizes {sizes} must be positive and finite")


# ---------------------------------------------------------------------------------------------
# the solid


def _gradient_product(k: int, l_: int) -> BilinearForm:
    @BilinearForm
    def form(u, v, w):
        return u.grad[l_] * v.grad[k]
    return form


@dataclass
class Factorized3D:
    """The solid's matrix with some degrees of freedom prescribed, factorized once.

    Attributes
    ----------
    unknowns
        Global indices of the unknown degrees of freedom, in the factor's order (the ones
        asked ``last`` at the end).
    fixed
        Global indices of the prescribed ones.
    seconds
        Wall time of the factorization [s].
    """

    matrix: sp.csr_matrix
    unknowns: np.ndarray
    fixed: np.ndarray
    n_last: int
    lu: spla.SuperLU
    seconds: float

    def solve(self, prescribed: np.ndarray | None = None,
              load: np.ndarray | None = None) -> np.ndarray:
        """Every degree of freedom [-] for the ``prescribed`` values of the fixed ones
        (default 0) and nodal ``load`` (global length, default 0)."""
        n = self.matrix.shape[0]
        x = np.zeros(n)
        rhs = np.zeros(self.unknowns.size) if load is None else np.asarray(load)[self.unknowns]
        if prescribed is not None:
            x[self.fixed] = prescribed
            rhs = rhs - self.matrix[self.unknowns][:, self.fixed] @ x[self.fixed]
        x[self.unknowns] = self.lu.solve(rhs)
        return x

    def reaction(self, x: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """Nodal forces [-] the supports exert at ``dofs`` for the solution ``x``."""
        return self.matrix[dofs] @ x

    def flexibility(self) -> np.ndarray:
        """Flexibility matrix [-] of the ``last`` degrees of freedom (the response of each to
        a unit load at each), the inverse of their Schur complement: the trailing block of
        the LU factors (by back substitutions when SuperLU moved them)."""
        n, k = self.unknowns.size, self.n_last
        pr, pc = self.lu.perm_r[n - k:], self.lu.perm_c[n - k:]
        if pr.min() >= n - k and pc.min() >= n - k:
            low = self.lu.L[n - k:, n - k:].toarray()
            up = self.lu.U[n - k:, n - k:].toarray()
            schur = (low @ up)[np.ix_(pr - (n - k), pc - (n - k))]
            flex = np.linalg.inv(0.5 * (schur + schur.T))
        else:  # pragma: no cover - SuperLU keeps a trailing clique last in natural order
            rhs = np.zeros((n, k))
            rhs[np.arange(n - k, n), np.arange(k)] = 1.0
            flex = self.lu.solve(rhs)[n - k:]
        return 0.5 * (flex + flex.T)


class Solid3D:
    """A linear-elastic body (E = 1, Poisson ratio ``nu``) meshed by ``mesh`` (hexahedra),
    on triquadratic elements.

    Degrees of freedom are numbered component-major: u_k at node a is ``k·N + a`` (k = 0, 1,
    2 for x, y, z; N nodes).

    Parameters
    ----------
    mesh
        A :class:`skfem.MeshHex` or :class:`skfem.MeshHex2` [L] (any length unit L).
    nu
        Poisson ratio [-], 0 <= nu <= 0.45.
    """

    def __init__(self, mesh: MeshHex, nu: float) -> None:
        _check(nu, 1.0)
        self.nu = float(nu)
        self.mesh = mesh
        self.basis = Basis(mesh, ElementHex2(), intorder=4)
        det = mesh._mapping().detDF(self.basis.X)  # skfem's hexahedra: all of one sign
        if not (np.all(det > 0) or np.all(det < 0)):
            raise RuntimeError("3-D mesh has inverted cells")
        lam, mu = lame_parameters(1.0, nu)
        d = {(k, m): asm(_gradient_product(k, m), self.basis).tocsr()
             for k in range(3) for m in range(k, 3)}

        def block(k: int, m: int) -> sp.csr_matrix:
            return d[(k, m)] if k <= m else d[(m, k)].T.tocsr()

        trace = d[(0, 0)] + d[(1, 1)] + d[(2, 2)]
        self.matrix = sp.bmat([[lam * block(k, m) + mu * block(m, k)
                                + (mu * trace if k == m else 0.0 * trace)
                                for m in range(3)] for k in range(3)], format="csr")
        self.n_nodes = self.basis.N
        self.locs = self.basis.doflocs
        self._order: np.ndarray | None = None

    @property
    def size(self) -> int:
        """Number of unknowns (three displacements per node)."""
        return 3 * int(self.n_nodes)

    def dofs(self, component: int, where: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Global indices of displacement ``component`` (0, 1, 2: x, y, z) at the nodes whose
        location (3, n) satisfies ``where``."""
        return component * self.n_nodes + np.flatnonzero(where(self.locs))

    def factorize(self, fixed: np.ndarray, last: np.ndarray | None = None) -> Factorized3D:
        """:class:`Factorized3D` with the degrees of freedom ``fixed`` prescribed and ``last``
        (unknown) numbered last, for their :meth:`Factorized3D.flexibility`."""
        t0 = time.perf_counter()
        if self._order is None:
            centroids = self.mesh.p[:, self.mesh.t].mean(axis=1)
            self._order = nested_dissection(self.basis.element_dofs, centroids, self.n_nodes)
        order = (np.arange(3)[None, :] * self.n_nodes + self._order[:, None]).ravel()
        fixed = np.unique(np.asarray(fixed, dtype=np.intp))
        last = np.zeros(0, np.intp) if last is None else np.asarray(last, dtype=np.intp)
        if np.intersect1d(fixed, last).size:
            raise ValueError("a degree of freedom cannot be both fixed and last")
        drop = np.zeros(self.size, dtype=bool)
        drop[fixed] = True
        drop[last] = True
        unknowns = np.r_[order[~drop[order]], last]
        a = self.matrix[unknowns][:, unknowns].tocsc()
        lu = spla.splu(a, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        return Factorized3D(self.matrix, unknowns, fixed, last.size, lu,
                            time.perf_counter() - t0)


# ---------------------------------------------------------------------------------------------
# palpation


def _profile_law(tip: Tip):
    law = get_law(tip)
    if law.profile is None or law.profile_exponent is None:
        raise GeometryError(f"tip '{tip.kind}' has no profile: it cannot be pressed into the "
                            "3-D block")
    return law


class Palpation3D:
    """A quarter block meshed and factorized once for a tip pressed at the centre of its top
    face: every curved tip and depth whose contact stays inside the mesh's contact zone, or a
    flat punch of the mesh's radius at any depth.

    Parameters
    ----------
    length, width, height
        The block [L] (any length unit L, the tip's too).
    nu
        Poisson ratio [-], 0 <= nu <= 0.45.
    base
        ``"bonded"`` (u = 0 at z = 0) or ``"free"`` (u_z = 0 only).
    contact_radius
        [L] The largest contact radius the mesh is made for (a curved tip: the candidate
        contact nodes reach 1.3 times it), or the punch's radius (``punch=True``).
    punch
        Mesh for a flat punch of radius ``contact_radius`` (graded towards its edge).
    resolution
        A name of :data:`RESOLUTIONS_3D` or a :class:`Resolution3D`.

    Attributes
    ----------
    size
        Number of unknowns.
    seconds
        Wall time of the set-up (mesh, assembly, factorization, flexibility) [s].
    """

    def __init__(self, length: float, width: float, height: float, nu: float, base: str,
                 contact_radius: float, punch: bool = False,
                 resolution: str | Resolution3D = "default") -> None:
        t0 = time.perf_counter()
        _check(nu, length, width, height, contact_radius)
        if base not in _BASES:
            raise GeometryError(f"unknown base {base!r}; use one of {', '.join(_BASES)}")
        res = resolution_3d(resolution)
        self.nu, self.base, self.punch = float(nu), base, bool(punch)
        self.length, self.width, self.height = float(length), float(width), float(height)
        a = float(contact_radius)
        half = 0.5 * min(length, width)
        if punch:
            b = 0.5 * a
            first = res.punch_first * a
            inner = a - graded(0.0, a - b, first, res.punch_growth)[::-1]
            zone = min(_REACH * a, a + 0.5 * (half - a))
            ring = a + graded(0.0, zone - a, first, res.punch_growth)
            circles = np.unique(np.r_[b, inner, ring])
            z_first = first
        else:
            b = res.core * a
            reach = _REACH * a
            n = max(2, math.ceil((reach - b) / a * res.per_radius))
            circles = np.linspace(b, reach, n + 1)
            z_first = res.top * a
        if circles[-1] >= 0.9 * half:
            raise GeometryError(f"a contact zone of radius {circles[-1]:.4g} does not fit well "
                                f"inside the block's half width {half:.4g}: the 3-D model "
                                "needs the contact well inside the top face")
        self.zone = float(circles[-1])
        step = circles[-1] - circles[-2]
        outer = graded(circles[-1], half, step * res.outer, res.outer)
        outer = (outer[1:] - circles[-1]) / (half - circles[-1])
        z_nodes = towards_top(height, z_first, res.punch_growth if punch else res.vertical)
        mesh = footprint_mesh(0.5 * length, 0.5 * width, circles, outer, z_nodes, res.angular)
        self.solid = solid = Solid3D(mesh, nu)
        tol = 1e-9 * max(length, width, height)
        x, y, z = solid.locs
        top = np.abs(z - height) <= tol
        fixed = [solid.dofs(0, lambda p: p[0] <= tol), solid.dofs(1, lambda p: p[1] <= tol),
                 solid.dofs(2, lambda p: p[2] <= tol)]
        if base == "bonded":
            fixed += [solid.dofs(k, lambda p: p[2] <= tol) for k in (0, 1)]
        support = np.unique(np.concatenate(fixed))
        r = np.hypot(x, y)
        if punch:
            self.face = 2 * solid.n_nodes + np.flatnonzero(top & (r <= a * (1 + 1e-9)))
            self.radius = a
            fac = solid.factorize(np.r_[support, self.face])
            prescribed = np.zeros(fac.fixed.size)
            prescribed[np.isin(fac.fixed, self.face)] = -1.0
            u = fac.solve(prescribed)
            self._per_depth = youngs_modulus(-4.0 * fac.reaction(u, self.face).sum(), nu)
        else:
            nodes = np.flatnonzero(top & (r <= self.zone * (1 + 1e-9)))
            nodes = nodes[np.argsort(r[nodes], kind="stable")]
            self.candidates = 2 * solid.n_nodes + nodes
            self.r_candidates = r[nodes]
            # a contact reaching the outermost ring of candidates has no room to grow
            self._r_limit = float(circles[-2]) * (1 + 1e-9)
            fac = solid.factorize(support, last=self.candidates)
            self._flex = fac.flexibility()
            self._chol = np.linalg.cholesky(self._flex)
        self.factor_seconds = fac.seconds
        del fac
        self.size = solid.size
        self.seconds = time.perf_counter() - t0

    def shape(self, tip: Tip, depth: float) -> tuple[float, float]:
        """(F/E* [L²], contact radius [L]) of ``tip`` pressed ``depth`` [L] into the block's
        centre (E* = E/(1 − nu²); the contact radius is the outermost node in contact, the
        punch's radius for a flat punch).

        Raises
        ------
        GeometryError
            A tip without profile, a punch of another radius than the mesh's, or a contact
            that reaches the last ring of candidate nodes (mesh a wider contact zone).
        """
        law = _profile_law(tip)
        if not (math.isfinite(depth) and depth > 0):
            raise GeometryError(f"depth {depth!r} must be positive")
        if math.isinf(law.profile_exponent(tip)):
            if not self.punch or not math.isclose(float(tip.radius), self.radius,
                                                  rel_tol=1e-9):
                raise GeometryError("this block is meshed for another flat punch")
            return float(self._per_depth * depth), self.radius
        if self.punch:
            raise GeometryError("this block is meshed for a flat punch")
        g = np.asarray(law.profile(self.r_candidates, tip), dtype=float)
        keep = np.isfinite(g)
        # a sphere narrower than the zone: the nodes beyond it cannot touch
        chol = (self._chol if keep.all()
                else np.linalg.cholesky(self._flex[np.ix_(keep, keep)]))
        gap = depth - g[keep]
        f, _ = nnls(chol.T, np.linalg.solve(chol, gap), maxiter=50 * int(keep.sum()))
        touching = self.r_candidates[keep][f > 0]
        a = float(touching.max()) if touching.size else 0.0
        if a > self._r_limit:
            raise GeometryError(f"the contact (radius {a:.4g}) reaches the edge of the mesh's "
                                f"contact zone ({self.zone:.4g}): mesh a wider one")
        return float(youngs_modulus(4.0 * f.sum(), self.nu)), a


def palpation_force_3d(length: float, width: float, height: float, tip: Tip, nu: float,
                       base: str, depth: float, resolution: str | Resolution3D = "default"
                       ) -> float:
    """F/E* [L²] of a rigid frictionless ``tip`` pressed ``depth`` into the centre of the top
    face of a block ``length`` × ``width`` × ``height`` on a rigid plate (module docstring).

    Parameters
    ----------
    length, width, height
        The block [L] (any length unit L, the tip's and the depth's too: F/E* is in L²;
        metres give m²).
    tip
        A tip with a profile (flat, sphere, paraboloid, cone, power).
    nu
        Poisson ratio [-], 0 <= nu <= 0.45 (E* = E/(1 − nu²)).
    base
        ``"bonded"`` (u = 0 at z = 0) or ``"free"`` (frictionless: u_z = 0 only).
    depth
        [L] Indentation depth, positive.
    resolution
        A name of :data:`RESOLUTIONS_3D` or a :class:`Resolution3D`.

    Raises
    ------
    GeometryError
        A tip without profile, nu out of range, an unknown base, or a contact too wide for
        the block.
    """
    law = _profile_law(tip)
    if math.isinf(law.profile_exponent(tip)):
        model = Palpation3D(length, width, height, nu, base, float(tip.radius), punch=True,
                            resolution=resolution)
        return model.shape(tip, depth)[0]
    a = float(law.contact_radius(np.array([float(depth)]), tip)[0])
    while True:
        model = Palpation3D(length, width, height, nu, base, a, resolution=resolution)
        try:
            return model.shape(tip, depth)[0]
        except GeometryError as err:
            if "reaches the edge" not in str(err):
                raise
        a *= _REACH


# ---------------------------------------------------------------------------------------------
# compression


@dataclass(frozen=True)
class Compression3D:
    """A 3-D compression test's result.

    Attributes
    ----------
    factor
        E_app/E [-].
    dofs
        Unknowns of the finite-element model.
    seconds
        Wall time of the solve (mesh, assembly, factorization) [s].
    """

    factor: float
    dofs: int
    seconds: float


def compression_factor_3d(length: float, width: float, height: float, nu: float,
                          platens: str, resolution: str | Resolution3D = "default") -> float:
    """E_app/E [-] of the block ``length`` × ``width`` × ``height`` [L] compressed between
    ``platens`` (module docstring): E_app = (F/A)/(delta/H).

    Parameters
    ----------
    length, width, height
        The block [L] (any length unit L; the factor has none).
    nu
        Poisson ratio [-], 0 <= nu <= 0.45.
    platens
        ``"bonded"`` (the faces cannot slide: u_x = u_y = 0 there) or ``"lubricated"``
        (frictionless: exactly 1).
    resolution
        A name of :data:`RESOLUTIONS_3D` or a :class:`Resolution3D`.

    Raises
    ------
    GeometryError
        An unknown platen condition, nu out of range, or a non-positive size.
    """
    return solve_compression_3d(length, width, height, nu, platens, resolution).factor


def solve_compression_3d(length: float, width: float, height: float, nu: float,
                         platens: str, resolution: str | Resolution3D = "default"
                         ) -> Compression3D:
    """:func:`compression_factor_3d` with the model's size and wall time
    (:class:`Compression3D`)."""
    t0 = time.perf_counter()
    _check(nu, length, width, height)
    if platens not in ("bonded", "lubricated"):
        raise GeometryError(f"platens {platens!r}: use 'bonded' or 'lubricated'")
    res = resolution_3d(resolution)
    half = 0.5 * height
    solid = Solid3D(compression_mesh(0.5 * length, 0.5 * width, half, res), nu)
    tol = 1e-9 * max(length, width, height)
    platen = solid.dofs(2, lambda p: p[2] >= half - tol)
    fixed = [solid.dofs(0, lambda p: p[0] <= tol), solid.dofs(1, lambda p: p[1] <= tol),
             solid.dofs(2, lambda p: p[2] <= tol), platen]
    if platens == "bonded":
        fixed += [solid.dofs(k, lambda p: p[2] >= half - tol) for k in (0, 1)]
    fac = solid.factorize(np.concatenate(fixed))
    prescribed = np.zeros(fac.fixed.size)
    prescribed[np.isin(fac.fixed, platen)] = -half  # a unit strain over the half height
    u = fac.solve(prescribed)
    force = -4.0 * fac.reaction(u, platen).sum()
    return Compression3D(float(force / (length * width)), solid.size,
                         time.perf_counter() - t0)
