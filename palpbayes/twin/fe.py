"""Axisymmetric linear elasticity on scikit-fem: the specimen twin's solid.

A body of revolution on (r, z) with displacement (u_r, u_z), Taylor–Hood elements (P2
displacement, P1 pressure) so that nothing locks up to the incompressible limit nu = 0.5
(docs/design.md, the specimen twin).  With E = 1 (forces then scale with E) the mixed weak form
is, for all test functions (v, q)::

    ∫ 2·mu·eps(u):eps(v)·r  +  ∫ p·div(v)·r            = ∫ t·v·r   (on the boundary)
    ∫ q·div(u)·r           −  ∫ p·q/lambda·r           = 0

with eps_rr = du_r/dr, eps_zz = du_z/dz, eps_tt = u_r/r (the hoop strain), eps_rz =
(du_r/dz + du_z/dr)/2, div u = eps_rr + eps_zz + eps_tt, p = lambda·div u, mu = 1/(2(1 + nu))
and lambda = nu/((1 + nu)(1 − 2·nu)) (Zienkiewicz & Taylor, *The Finite Element Method*,
vol. 1, 7th ed., 2013, ch. 11; the axisymmetric strains ch. 9).  At nu = 0.5 the last term
vanishes; at nu = 0 the pressure is 0 and its block is left out.  Quadrature points never lie on
the axis, where u_r = 0 is imposed.  Forces of the weak form are per radian: the physical force
is 2·pi times their sum.

scikit-fem assembles; SuperLU (:func:`scipy.sparse.linalg.splu`) factorizes once per body and
boundary condition (in its symmetric mode: a minimum-degree ordering of A + A' with diagonal
pivots, 3–4 times less fill than its default for these matrices, partial pivoting where a
pivot vanishes), and every load case after is a back substitution.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import Basis, BilinearForm, ElementTriP1, ElementTriP2, ElementVector, MeshTri, asm

__all__ = ["AxisymmetricSolid", "Factorized", "lame"]


def lame(nu: float) -> tuple[float, float]:
    """(mu, lambda) [-] of a material with E = 1 and Poisson ratio ``nu`` (lambda = inf at
    0.5)."""
    mu = 1.0 / (2.0 * (1.0 + nu))
    lam = np.inf if nu >= 0.5 else nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return mu, lam


def _strains(u, r):
    """(eps_rr, eps_zz, eps_tt, eps_rz) of a vector field at quadrature points."""
    return (u.grad[0, 0], u.grad[1, 1], u[0] / r, 0.5 * (u.grad[0, 1] + u.grad[1, 0]))


@BilinearForm
def _deviatoric(u, v, w):
    r = w.x[0]
    a, b = _strains(u, r), _strains(v, r)
    return 2.0 * w["mu"] * (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + 2.0 * a[3] * b[3]) * r


@BilinearForm
def _divergence(u, q, w):
    r = w.x[0]
    return (u.grad[0, 0] + u.grad[1, 1] + u[0] / r) * q * r


@BilinearForm
def _mass(p, q, w):
    return p * q * w["inv"] * w.x[0]


@dataclass
class Factorized:
    """The body's matrix with some degrees of freedom prescribed, factorized once.

    Attributes
    ----------
    free, fixed
        Global indices of the unknown and the prescribed degrees of freedom.
    """

    matrix: sp.csr_matrix
    free: np.ndarray
    fixed: np.ndarray
    lu: spla.SuperLU

    def solve(self, load: np.ndarray, prescribed: np.ndarray | None = None) -> np.ndarray:
        """Every degree of freedom [-] for nodal ``load`` (global length, or columns of
        loads) and the ``prescribed`` values of the fixed ones (default 0)."""
        load = np.asarray(load, dtype=float)
        rhs = load[self.free]
        x = np.zeros(load.shape)
        if prescribed is not None:
            x[self.fixed] = prescribed
            rhs = rhs - self.matrix[self.free][:, self.fixed] @ x[self.fixed]
        x[self.free] = self.lu.solve(rhs)
        return x

    def columns(self, dofs: np.ndarray) -> np.ndarray:
        """The response at ``dofs`` to a unit load at each of ``dofs``: the flexibility matrix
        (``dofs`` must be free), symmetric by construction and symmetrized against round-off.
        """
        pos = np.searchsorted(self.free, dofs)
        if not np.array_equal(self.free[np.minimum(pos, self.free.size - 1)], dofs):
            raise ValueError("flexibility asked at prescribed degrees of freedom")
        rhs = np.zeros((self.free.size, dofs.size))
        rhs[pos, np.arange(dofs.size)] = 1.0
        out = self.lu.solve(rhs)[pos]
        return 0.5 * (out + out.T)

    def reaction(self, x: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """The nodal forces [-] the supports exert at ``dofs`` for the solution ``x``."""
        return self.matrix[dofs] @ x


class AxisymmetricSolid:
    """A body of revolution meshed on the tensor grid ``r_nodes`` × ``z_nodes`` (each
    triangle a half of a grid cell), with E = 1 and Poisson ratio ``nu``.

    Parameters
    ----------
    r_nodes, z_nodes
        Increasing grid coordinates [-] (the caller's length unit); ``r_nodes[0]`` = 0 (the
        axis).
    nu
        Poisson ratio, 0 <= nu <= 0.5.
    modulus
        Optional ``modulus(r, z)`` -> E / E_ref [-] at quadrature points (arrays of any
        shape): a heterogeneous body (mu and lambda both scale with it, nu is uniform).
        None: E = 1 everywhere.
    """

    def __init__(self, r_nodes: np.ndarray, z_nodes: np.ndarray, nu: float,
                 modulus: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
                 ) -> None:
        r_nodes = np.asarray(r_nodes, dtype=float)
        z_nodes = np.asarray(z_nodes, dtype=float)
        if r_nodes[0] != 0.0 or np.any(np.diff(r_nodes) <= 0) or np.any(np.diff(z_nodes) <= 0):
            raise ValueError("grid nodes must increase, r from the axis (0)")
        if not 0.0 <= nu <= 0.5:
            raise ValueError(f"Poisson ratio {nu!r} outside [0, 0.5]")
        self.nu = float(nu)
        self.r_max, self.z_min, self.z_max = r_nodes[-1], z_nodes[0], z_nodes[-1]
        self.mesh = MeshTri.init_tensor(r_nodes, z_nodes)
        self.basis = Basis(self.mesh, ElementVector(ElementTriP2()), intorder=4)
        mu, lam = lame(self.nu)
        scale = self._scale(self.basis, modulus)
        a = asm(_deviatoric, self.basis, mu=mu if scale is None else mu * scale)
        n_u = self.basis.N
        if self.nu == 0.0:  # lambda = 0: no volumetric stiffness, the pressure is 0
            self.matrix = a.tocsr()
        else:
            pbasis = Basis(self.mesh, ElementTriP1(), intorder=4)
            b = asm(_divergence, self.basis, pbasis)
            ps = self._scale(pbasis, modulus)
            c = (sp.csr_matrix((pbasis.N, pbasis.N)) if np.isinf(lam)
                 else asm(_mass, pbasis, inv=1.0 if ps is None else 1.0 / ps) / lam)
            self.matrix = sp.bmat([[a, b.T], [b, -c]], format="csr")
        self.n_u = n_u
        comp = self.basis.split_indices()
        self._dofs = {"r": comp[0], "z": comp[1]}
        self._locs = {k: self.basis.doflocs[:, v] for k, v in self._dofs.items()}

    @staticmethod
    def _scale(basis: Basis, modulus) -> np.ndarray | None:
        """E / E_ref at ``basis``' quadrature points (elements, points); None if uniform."""
        if modulus is None:
            return None
        x = basis.mapping.F(basis.X)
        s = np.asarray(modulus(x[0], x[1]), dtype=float)
        if s.shape != x[0].shape or not np.all(np.isfinite(s) & (s > 0)):
            raise ValueError("modulus(r, z) must be positive and finite at every point")
        return s

    @property
    def size(self) -> int:
        """Number of unknowns (displacements and pressures)."""
        return self.matrix.shape[0]

    def dofs(self, component: str, where: Callable[[np.ndarray, np.ndarray], np.ndarray]
             ) -> np.ndarray:
        """Global indices of the ``component`` (``"r"`` or ``"z"``) displacement at the
        nodes where ``where(r, z)`` holds, sorted by r then z."""
        idx, (r, z) = self._dofs[component], self._locs[component]
        pick = np.flatnonzero(where(r, z))
        order = np.lexsort((z[pick], r[pick]))
        return idx[pick[order]]

    def location(self, dofs: np.ndarray) -> np.ndarray:
        """(r, z) of global displacement ``dofs``, shape (2, n)."""
        return self.basis.doflocs[:, dofs]

    def on_axis(self, r: np.ndarray, z: np.ndarray) -> np.ndarray:
        return r <= 1e-12 * self.r_max

    def on_top(self, r: np.ndarray, z: np.ndarray) -> np.ndarray:
        return np.abs(z - self.z_max) <= 1e-12 * (self.z_max - self.z_min)

    def on_bottom(self, r: np.ndarray, z: np.ndarray) -> np.ndarray:
        return np.abs(z - self.z_min) <= 1e-12 * (self.z_max - self.z_min)

    def factorize(self, fixed: np.ndarray) -> Factorized:
        """:class:`Factorized` with the degrees of freedom ``fixed`` prescribed."""
        fixed = np.unique(np.asarray(fixed, dtype=np.intp))
        free = np.setdiff1d(np.arange(self.size), fixed)
        block = self.matrix[free][:, free].tocsc()
        try:  # the matrix is symmetric: an A + A' ordering, diagonal pivots (3-4x less fill)
            lu = spla.splu(block, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
        except RuntimeError:  # a zero pivot (the pressure block): partial pivoting
            lu = spla.splu(block)
        return Factorized(self.matrix, free, fixed, lu)
