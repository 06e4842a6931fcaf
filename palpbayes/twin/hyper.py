"""The twin made hyperelastic: an axisymmetric solid at finite strain on scikit-fem.

**Kinematics** (total Lagrangian, reference coordinates (R, Z); docs/design.md §14).  The
displacement (u_r, u_z) gives

    F = [[1 + du_r/dR, du_r/dZ, 0], [du_z/dR, 1 + du_z/dZ, 0], [0, 0, 1 + u_r/R]],

whose principal stretches are those of the in-plane block C = F^T F (2 × 2, eigenvalues
lambda_1², lambda_2², eigenvectors N_1, N_2 in closed form) and the hoop stretch lambda_3 =
1 + u_r/R.  Integrals carry the weight R (× 2·pi for a physical force).

**Constitutive law** only through :class:`~palpbayes.material.MaterialLaw`: the principal
Kirchhoff stresses tau_i and their tangent dtau_i/d ln lambda_j of W~, so that every
registered law works with no code of its own.  The second Piola–Kirchhoff stress is S = sum
S_i N_i⊗N_i, S_i = tau_i/lambda_i², and its tangent in principal form (Simo & Taylor 1991,
Comput. Methods Appl. Mech. Eng. 85:273; Miehe 1994, Int. J. Numer. Methods Eng. 37:1981;
Holzapfel 2000, *Nonlinear Solid Mechanics*, §6.6):

    dS = sum_ab D_ab e_bb M_a + 2·G_12·e_12·(N_1⊗N_2 + N_2⊗N_1),
    D_ab = (dtau_ab − 2·tau_a·delta_ab)/(lambda_a² lambda_b²),
    G_12 = (S_2 − S_1)/(lambda_2² − lambda_1²),

with e_ab = N_a·dE·N_b and M_a = N_a⊗N_a.  At equal in-plane stretches (the undeformed state)
G_12 takes its limit (dtau_11 − dtau_12 − 2 tau_1 + dtau_22 − dtau_21 − 2 tau_2)/(4 lambda⁴),
exact for a symmetric W; the quotient is used when the stretches differ by more than 1e-6
(relative), where its cancellation error is below 1e-10.  The hoop pairs carry no shear
(E_r3 = E_z3 = 0 in axisymmetry).  The first elasticity tensor A = dP/dF (5 × 5 in (F_rr,
F_rz, F_zr, F_zz, F_tt)) is built from dS at the quadrature points; the weak forms only
contract it (:class:`~skfem.BilinearForm`, :class:`~skfem.LinearForm`).

**Near-incompressibility**: the volumetric term kappa/2·(ln J)² by a perturbed Lagrangian
with a P1 pressure p conjugate to ln J on P2 displacements (Taylor–Hood, as the linear twin):

    Pi(u, p) = ∫ W~(F) + p·ln J − p²/(2·kappa) dV,

so that tau_i = tau~_i + p, and the pressure equation is ∫ q·(ln J − p/kappa) dV = 0; at
nu = 0.5 (kappa = inf) it is the constraint ln J = 0.  A law without a bulk term (the foam,
kappa = 0) is solved in the displacements alone.

Newton's method and the load steps are in :mod:`.hyper_newton`.  The tangent is checked
against central differences of the residual in ``tests/unit/test_hyper.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    LinearForm,
    MeshTri,
    asm,
)

from ..material import MaterialLaw, material_law

__all__ = ["HyperSolid", "QuadratureState", "GRAD_INDEX"]

#: (i, J) of the four in-plane components of F in the 5-vector (F_rr, F_rz, F_zr, F_zz, F_tt).
GRAD_INDEX = ((0, 0), (0, 1), (1, 0), (1, 1))
#: Relative gap of the in-plane stretches below which G_12 takes its limit.
_DEGENERATE = 1e-6


def _raw(w, name: str) -> np.ndarray:
    """The array passed to a form as ``name`` (scikit-fem wraps it in a DiscreteField, whose
    indexing copies it)."""
    return np.asarray(w[name])


def _gradient5(u, r):
    """(5, ...) components of grad u in F's order, the hoop one u_r/R."""
    g = u.grad
    return (g[0, 0], g[0, 1], g[1, 0], g[1, 1], np.asarray(u)[0] / r)


#: Entries of F's 5-vector that the r and z components of a displacement reach: u_r gives
#: F_rr, F_rz and the hoop F_tt; u_z gives F_zr and F_zz.
_COMPONENT = {"r": (0, 1, 4), "z": (2, 3)}


def _parts(phi, comp: str, r):
    """dF of a scalar shape function ``phi`` moving component ``comp``, on its entries."""
    g = phi.grad
    return (g[0], g[1], np.asarray(phi) / r) if comp == "r" else (g[0], g[1])


def _block(a: str, b: str) -> BilinearForm:
    """The (a, b) component block of the tangent, ∫ dF(v_a) : A : dF(u_b) R, on the scalar
    P2 basis (4 blocks of 36 pairs instead of the vector element's 144: 4-5 times faster)."""
    ia, ib = _COMPONENT[a], _COMPONENT[b]

    @BilinearForm
    def form(u, v, w):
        r, mat = w.x[0], _raw(w, "A")
        du, dv = _parts(u, b, r), _parts(v, a, r)
        out = 0.0
        for i, vi in zip(ia, dv, strict=True):
            row = 0.0
            for j, uj in zip(ib, du, strict=True):
                row = row + mat[i, j] * uj
            out = out + vi * row
        return out * r
    return form


_BLOCKS = {(a, b): _block(a, b) for a in "rz" for b in "rz" if (a, b) != ("z", "r")}


def _coupling(comp: str) -> BilinearForm:
    """∫ q·F^-T : dF(u_comp) R: the pressure's coupling to one displacement component."""
    idx = _COMPONENT[comp]

    @BilinearForm
    def form(u, q, w):
        du, b = _parts(u, comp, w.x[0]), _raw(w, "B")
        out = 0.0
        for i, uj in zip(idx, du, strict=True):
            out = out + b[i] * uj
        return q * out * w.x[0]
    return form


_COUPLING = {c: _coupling(c) for c in "rz"}


@BilinearForm
def _pp(p, q, w):
    return p * q * w.x[0]


@LinearForm
def _ru(v, w):
    dv, pk = _gradient5(v, w.x[0]), _raw(w, "P")
    return (pk[0] * dv[0] + pk[1] * dv[1] + pk[2] * dv[2] + pk[3] * dv[3] + pk[4] * dv[4]) \
        * w.x[0]


@LinearForm
def _rp(q, w):
    return np.asarray(q) * _raw(w, "g") * w.x[0]


@dataclass
class QuadratureState:
    """The solid's stresses at the quadrature points of a state (arrays (nel, nqp)).

    Attributes
    ----------
    P
        (5, nel, nqp) first Piola–Kirchhoff stress in F's order [E0].
    A
        (5, 5, nel, nqp) dP/dF at fixed pressure [E0].
    B
        (5, nel, nqp) F^-T = d ln J/dF (the pressure's coupling).
    lnJ
        ln J [-].
    stretch
        (nel, nqp, 3) principal stretches (lambda_1, lambda_2 in-plane, lambda_3 hoop).
    """

    P: np.ndarray
    A: np.ndarray
    B: np.ndarray
    lnJ: np.ndarray
    stretch: np.ndarray


class HyperSolid:
    """A body of revolution at finite strain, meshed on the tensor grid ``r_nodes`` ×
    ``z_nodes`` (P2 triangles, P1 pressure where the law has a bulk term).

    Parameters
    ----------
    r_nodes, z_nodes
        Increasing grid coordinates [L]; ``r_nodes[0]`` = 0 (the axis).
    law
        A registered :class:`~palpbayes.material.MaterialLaw` or its name.
    params
        The law's natural parameters (stresses in the caller's unit, E0 = 1 for tables).
    nu
        The small-strain Poisson ratio of a law that is not a foam (0.5: incompressible).
    """

    def __init__(self, r_nodes: np.ndarray, z_nodes: np.ndarray, law: str | MaterialLaw,
                 params: Mapping[str, float], nu: float = 0.5, intorder: int = 4) -> None:
        r_nodes, z_nodes = np.asarray(r_nodes, float), np.asarray(z_nodes, float)
        if r_nodes[0] != 0.0 or np.any(np.diff(r_nodes) <= 0) or np.any(np.diff(z_nodes) <= 0):
            raise ValueError("grid nodes must increase, r from the axis (0)")
        self.law = material_law(law)
        self.law.check(params)
        self.params = dict(params)
        self.nu = float(self.law.nu0(self.params, nu))
        self.kappa = float(self.law.bulk(self.params, self.nu))
        self.r_max, self.z_min, self.z_max = r_nodes[-1], z_nodes[0], z_nodes[-1]
        self.mesh = MeshTri.init_tensor(r_nodes, z_nodes)
        self.basis = Basis(self.mesh, ElementVector(ElementTriP2()), intorder=intorder)
        self.n_u = self.basis.N
        self.mixed = self.kappa > 0.0
        if self.mixed:
            self.pbasis = Basis(self.mesh, ElementTriP1(), intorder=intorder)
            self.n_p = self.pbasis.N
            mass = asm(_pp, self.pbasis).tocsr()
            self._cpp = (sp.csr_matrix(mass.shape) if np.isinf(self.kappa)
                         else (-1.0 / self.kappa) * mass)
        else:
            self.pbasis, self.n_p = None, 0
        self.sbasis = Basis(self.mesh, ElementTriP2(), intorder=intorder)
        self.radius = np.asarray(self.basis.global_coordinates())[0]
        comp = self.basis.split_indices()
        self._perm = np.concatenate(comp)  # [r dofs, z dofs] -> the vector basis's dofs
        self._dofs = {"r": comp[0], "z": comp[1]}
        self._locs = {k: self.basis.doflocs[:, v] for k, v in self._dofs.items()}

    # ----------------------------------------------------------------- degrees of freedom
    @property
    def size(self) -> int:
        """Number of unknowns (displacements, then pressures)."""
        return self.n_u + self.n_p

    def dofs(self, component: str, where: Callable[[np.ndarray, np.ndarray], np.ndarray]
             ) -> np.ndarray:
        """Global indices of the ``component`` (``"r"``/``"z"``) displacement at the nodes
        where ``where(R, Z)`` holds, sorted by R then Z."""
        idx, (r, z) = self._dofs[component], self._locs[component]
        pick = np.flatnonzero(where(r, z))
        return idx[pick[np.lexsort((z[pick], r[pick]))]]

    def location(self, dofs: np.ndarray) -> np.ndarray:
        """(R, Z) of global displacement ``dofs``, shape (2, n)."""
        return self.basis.doflocs[:, dofs]

    def on_axis(self, r, z):
        return r <= 1e-12 * self.r_max

    def on_top(self, r, z):
        return np.abs(z - self.z_max) <= 1e-12 * (self.z_max - self.z_min)

    def on_bottom(self, r, z):
        return np.abs(z - self.z_min) <= 1e-12 * (self.z_max - self.z_min)

    def on_side(self, r, z):
        return np.abs(r - self.r_max) <= 1e-12 * self.r_max

    # ------------------------------------------------------------------- constitutive
    def state(self, x: np.ndarray) -> QuadratureState | None:
        """Stresses and tangent at the quadrature points of the unknowns ``x``; None when a
        quadrature point is inadmissible (J <= 0 or a hoop stretch <= 0)."""
        uf = self.basis.interpolate(x[:self.n_u])
        g = uf.grad
        f11, f12, f21, f22 = 1.0 + g[0, 0], g[0, 1], g[1, 0], 1.0 + g[1, 1]
        f33 = 1.0 + np.asarray(uf)[0] / self.radius
        det2 = f11 * f22 - f12 * f21
        if not (np.all(det2 > 0) and np.all(f33 > 0)):
            return None
        c11, c22 = f11 * f11 + f21 * f21, f12 * f12 + f22 * f22
        c12 = f11 * f12 + f21 * f22
        half_tr, rad = 0.5 * (c11 + c22), np.sqrt(0.25 * (c11 - c22) ** 2 + c12 * c12)
        ca = half_tr + rad
        cb = det2 * det2 / ca  # the smaller root without cancellation (c_a·c_b = det²)
        theta = 0.5 * np.arctan2(2.0 * c12, c11 - c22)
        n1 = np.stack([np.cos(theta), np.sin(theta)])
        n2 = np.stack([-n1[1], n1[0]])
        c = np.stack([ca, cb, f33 * f33], axis=-1)
        lam = np.sqrt(c)
        tau = np.asarray(self.law.tau(lam, self.params), float)
        dtau = np.asarray(self.law.dtau(lam, self.params), float)
        lnj = np.log(det2) + np.log(f33)
        p = None
        if self.mixed:
            p = np.asarray(self.pbasis.interpolate(x[self.n_u:]))
            tau = tau + p[..., None]
        s = tau / c
        d = (dtau - 2.0 * tau[..., :, None] * np.eye(3)) / (c[..., :, None] * c[..., None, :])
        gap = ca - cb
        limit = (dtau[..., 0, 0] - dtau[..., 0, 1] - 2 * tau[..., 0] + dtau[..., 1, 1]
                 - dtau[..., 1, 0] - 2 * tau[..., 1]) / (4.0 * ca * cb)
        close = gap <= _DEGENERATE * (ca + cb)
        g12 = np.where(close, limit, (s[..., 1] - s[..., 0]) / np.where(close, 1.0, -gap))
        # S in (R, Z): S_IJ = sum_a S_a N_aI N_aJ
        s2 = (s[..., 0] * n1[:, None] * n1[None, :] + s[..., 1] * n2[:, None] * n2[None, :])
        fm = np.array([[f11, f12], [f21, f22]])
        pk2 = np.einsum("iKeq,KJeq->iJeq", fm, s2)
        pk = np.stack([pk2[0, 0], pk2[0, 1], pk2[1, 0], pk2[1, 1], f33 * s[..., 2]])
        amat = np.empty((5, 5) + f33.shape)
        for k in range(5):
            dfm = np.zeros((2, 2) + f33.shape)
            df33 = np.zeros(f33.shape)
            if k < 4:
                dfm[GRAD_INDEX[k]] = 1.0
            else:
                df33 = np.ones(f33.shape)
            de = 0.5 * (np.einsum("kIeq,kJeq->IJeq", fm, dfm)
                        + np.einsum("kIeq,kJeq->IJeq", dfm, fm))
            e11 = np.einsum("Ieq,IJeq,Jeq->eq", n1, de, n1)
            e22 = np.einsum("Ieq,IJeq,Jeq->eq", n2, de, n2)
            e12 = np.einsum("Ieq,IJeq,Jeq->eq", n1, de, n2)
            e33 = f33 * df33
            ee = np.stack([e11, e22, e33], axis=-1)
            ds = np.einsum("eqab,eqb->eqa", d, ee)
            sh = 2.0 * g12 * e12
            ds2 = (ds[..., 0] * n1[:, None] * n1[None, :] + ds[..., 1] * n2[:, None] * n2[None, :]
                   + sh * (n1[:, None] * n2[None, :] + n2[:, None] * n1[None, :]))
            dp2 = (np.einsum("iKeq,KJeq->iJeq", dfm, s2) + np.einsum("iKeq,KJeq->iJeq", fm, ds2))
            amat[:, k] = np.stack([dp2[0, 0], dp2[0, 1], dp2[1, 0], dp2[1, 1],
                                   df33 * s[..., 2] + f33 * ds[..., 2]])
        inv = np.stack([f22 / det2, -f21 / det2, -f12 / det2, f11 / det2, 1.0 / f33])
        return QuadratureState(pk, amat, inv, lnj, lam)

    # ------------------------------------------------------------------------ forms
    def residual(self, x: np.ndarray, st: QuadratureState) -> np.ndarray:
        """The internal-force residual [E0·L² per radian] (displacements), then the pressure
        equations, at the state ``st`` of ``x``."""
        ru = asm(_ru, self.basis, P=st.P)
        if not self.mixed:
            return ru
        p = x[self.n_u:]
        rp = asm(_rp, self.pbasis, g=st.lnJ) + self._cpp @ p
        return np.concatenate([ru, rp])

    def tangent(self, st: QuadratureState) -> sp.csr_matrix:
        """d(residual)/dx at the state ``st`` (symmetric)."""
        sb = self.sbasis
        krr, krz, kzz = (asm(_BLOCKS[k], sb, A=st.A) for k in (("r", "r"), ("r", "z"),
                                                               ("z", "z")))
        blocks = [[krr, krz], [krz.T, kzz]]  # rows test, columns trial; K_zr = K_rz^T
        if self.mixed:
            kp = [asm(_COUPLING[c], sb, self.pbasis, B=st.B) for c in "rz"]
            blocks = [row + [kp[i].T] for i, row in enumerate(blocks)] + [kp + [self._cpp]]
        k = sp.bmat(blocks, format="coo")
        perm = np.r_[self._perm, np.arange(self.n_u, self.size)]
        return sp.csr_matrix((k.data, (perm[k.row], perm[k.col])), shape=k.shape)
