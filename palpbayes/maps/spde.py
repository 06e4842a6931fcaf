"""The latent Gaussian model of a stiffness map at fixed hyperparameters (sparse algebra only).

Observation i (log E_i summarised as Normal(y_i, s_i²)) at lattice node j(i)::

    y_i = beta + u_j(i) + e_i,   e_i ~ Normal(0, s_i² + tau²),

u ~ Normal(0, Q⁻¹) the SPDE field of Lindgren, Rue & Lindström (2011) for alpha = 2 (Matérn
nu = 1 in 2-D) on a lattice of step h with free (Neumann) boundary::

    K = kappa²h²·I + L,   Q = (tau_f²/h²)·K·K,   kappa = sqrt(8)/range,
    tau_f² = 1 / (4·pi·kappa²·sigma_f²),

(L: :func:`~palpbayes.maps.lattice.laplacian`), which makes the marginal variance sigma_f²
away from the boundary and the correlation ≈ 0.13 at distance ``range``; and
beta ~ Normal(m0, v0).  The latent vector x = (u, beta) has prior precision
Q_aug = blockdiag(Q, 1/v0) and mean x0 = (0, m0); A (n_obs × n_latent) holds a 1 in the node
column and a 1 in the beta column of each observation; S = diag(s² + tau²).

Posterior precision P = Q_aug + Aᵀ S⁻¹ A.  Its one dense row and column (beta's) are taken
out by block elimination: only the field block P_uu = Q + diag(d), d_j = Σ_{i at j} 1/(s_i² +
tau²), is factorised, with SuperLU (``scipy.sparse.linalg.splu``, symmetric mode, no
pivoting: P_uu is SPD), and beta enters through the Schur complement
g = P_bb − p_ubᵀ P_uu⁻¹ p_ub (p_ub = d, P_bb = 1/v0 + Σ_i 1/(s_i² + tau²)), so that
log|P| = log|P_uu| + log g and every solve with P is two solves with P_uu.  P_uu has the
same sparsity at every theta: it is assembled from fixed arrays on one pattern, and its
fill-reducing ordering (SuperLU's minimum degree on Aᵀ + A) is computed once per model and
reused (:meth:`SpdeModel.factor`).  With r0 = y − A x0 and b = Aᵀ S⁻¹ r0, the exact marginal
likelihood is::

    log p(y | theta) = −n/2 log 2pi − ½ log|S| + ½ log|Q_aug| − ½ log|P| + ½ bᵀP⁻¹b − ½ r0ᵀS⁻¹r0

with log|K| = Σ log(kappa²h² + lambda_jk) in closed form (lambda: the DCT eigenvalues of L).
No dense n × n matrix is formed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .lattice import Lattice, laplacian, laplacian_eigenvalues

__all__ = ["SpdeModel", "SpdeFactor", "spde_scales", "sample_field"]


def spde_scales(sigma_f: float, range_m: float, step: float) -> tuple[float, float]:
    """``(kappa²h², tau_f²/h²)`` of the lattice SPDE for marginal sd ``sigma_f`` [log E],
    range ``range_m`` [m] and step ``step`` [m] (both dimensionless)."""
    kh2 = 8.0 * (step / range_m) ** 2
    return kh2, 1.0 / (4.0 * np.pi * kh2 * sigma_f**2)


def sample_field(lattice: Lattice, sigma_f: float, range_m: float, rng: np.random.Generator,
                 n: int = 1) -> np.ndarray:
    """``n`` exact prior draws of the SPDE field u [log E] on ``lattice``, ``(n, ny, nx)``.

    u = K⁻¹w / sqrt(tau_f²/h²), w ~ Normal(0, I), has covariance K⁻²·h²/tau_f² = Q⁻¹.  Near
    the free boundary the variance is inflated (≈ 2·sigma_f² along an edge, ≈ 4·sigma_f² in a
    corner): simulate on a padded lattice (:func:`~palpbayes.maps.lattice.pad`) to mimic
    :func:`~palpbayes.maps.gmrf.fit_field`.
    """
    kh2, c = spde_scales(sigma_f, range_m, lattice.step)
    K = (kh2 * sp.identity(lattice.n_nodes) + laplacian(lattice.nx, lattice.ny)).tocsc()
    lu = splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})
    u = lu.solve(rng.standard_normal((lattice.n_nodes, int(n)))) / np.sqrt(c)
    return u.T.reshape(int(n), lattice.ny, lattice.nx)


@dataclass
class SpdeFactor:
    """The factorised posterior precision P at one theta (see :meth:`SpdeModel.factor`).

    ``lu`` factorises the field block P_uu with its rows and columns in the order ``order``
    (``P_uu[order][:, order]``); ``z`` = P_uu⁻¹ p_ub and ``schur`` = P_bb − p_ubᵀ z carry beta
    (module docstring).
    """

    sigma_f: float
    range_m: float
    tau: float
    lu: object  # scipy.sparse.linalg.SuperLU of P_uu[order][:, order]
    w: np.ndarray  # 1 / (s² + tau²), per observation
    kh2: float
    c: float
    order: np.ndarray  # fill-reducing order of the field nodes
    d: np.ndarray  # p_ub: per node, the sum of w over its observations
    z: np.ndarray  # P_uu⁻¹ p_ub
    schur: float  # P_bb − p_ubᵀ P_uu⁻¹ p_ub (> 0)

    def solve_uu(self, b: np.ndarray) -> np.ndarray:
        """P_uu⁻¹ b for b ``(n_nodes,)`` or ``(n_nodes, k)``."""
        out = np.empty_like(b)
        out[self.order] = self.lu.solve(np.ascontiguousarray(b[self.order]))
        return out

    def solve(self, b: np.ndarray) -> np.ndarray:
        """P⁻¹ b for b ``(n_latent,)`` or ``(n_latent, k)`` (beta last), by block elimination."""
        b = np.asarray(b, dtype=float)
        yu = self.solve_uu(b[:-1])
        xb = (b[-1] - self.d @ yu) / self.schur
        out = np.empty_like(b)
        out[-1] = xb
        out[:-1] = yu - (np.multiply.outer(self.z, xb) if yu.ndim == 2 else self.z * xb)
        return out

    def log_det(self) -> float:
        """log det P = log det P_uu + log schur."""
        return float(np.sum(np.log(np.abs(self.lu.U.diagonal()))) + np.log(self.schur))


class SpdeModel:
    """Observations on a (padded) lattice and the algebra of the model at any theta.

    Parameters
    ----------
    lattice
        The lattice of the field (including any padding).
    node
        Node number of each observation in ``lattice``.
    y, s
        Observed log-moduli [log(E/Pa)] and their sd.
    m0, v0
        Prior mean and variance of beta.
    """

    def __init__(self, lattice: Lattice, node, y, s, m0: float, v0: float):
        self.lattice = lattice
        self.node = np.asarray(node, dtype=np.int64)
        self.y = np.asarray(y, dtype=float)
        self.s = np.asarray(s, dtype=float)
        self.m0, self.v0 = float(m0), float(v0)
        n, n_obs = lattice.n_nodes, self.y.size
        self.n_nodes, self.n_latent, self.n_obs = n, n + 1, n_obs
        L = laplacian(lattice.nx, lattice.ny)
        self._I, self._L, self._L2 = sp.identity(n, format="csc"), L, (L @ L).tocsc()
        self._eig = laplacian_eigenvalues(lattice.nx, lattice.ny).ravel()
        rows = np.repeat(np.arange(n_obs), 2)
        cols = np.column_stack([self.node, np.full(n_obs, n)]).ravel()
        self.A = sp.csr_matrix((np.ones(2 * n_obs), (rows, cols)), shape=(n_obs, n + 1))
        self.At = self.A.T.tocsr()
        # P_uu = c·(kh2²·I + 2·kh2·L + L²) + diag(d) on one fixed pattern (that of L², which
        # holds I's and L's), its rows and columns in a fill-reducing order found once
        pattern = (abs(self._I) + abs(L) + abs(self._L2)).tocsc()
        pattern.sum_duplicates()
        pattern.sort_indices()
        cols_of = np.repeat(np.arange(n), np.diff(pattern.indptr))
        rows_of = pattern.indices

        def on_pattern(M: sp.spmatrix) -> np.ndarray:
            return np.asarray(M.tocsr()[rows_of, cols_of], dtype=float).ravel()

        self._parts = np.stack([on_pattern(self._I), on_pattern(L), on_pattern(self._L2)])
        self._diag_at = np.flatnonzero(rows_of == cols_of)  # pattern entry of node j's diagonal
        probe = sp.csc_matrix((self._parts.sum(axis=0) + 2.0 * self._parts[0],
                               pattern.indices, pattern.indptr), shape=(n, n))
        perm_c = splu(probe, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                      options={"SymmetricMode": True}).perm_c
        self._order = np.argsort(perm_c)  # P_uu[order][:, order] is the matrix in that order
        # where each entry of the reordered matrix comes from in the pattern's data
        idx = sp.csc_matrix((np.arange(1, pattern.nnz + 1, dtype=float), pattern.indices,
                             pattern.indptr), shape=(n, n))
        idx = idx[self._order][:, self._order].tocsc()
        idx.sort_indices()
        self._src = idx.data.astype(np.int64) - 1
        self._ord_indices, self._ord_indptr = idx.indices.copy(), idx.indptr.copy()

    # -- prior -------------------------------------------------------------------------------
    def precision(self, sigma_f: float, range_m: float) -> sp.csc_matrix:
        """Field precision Q (n_nodes × n_nodes, [1/log E²])."""
        kh2, c = spde_scales(sigma_f, range_m, self.lattice.step)
        return (c * (kh2**2 * self._I + 2 * kh2 * self._L + self._L2)).tocsc()

    def log_det_q(self, sigma_f: float, range_m: float) -> float:
        """log det Q in closed form (DCT eigenvalues of the Neumann Laplacian)."""
        kh2, c = spde_scales(sigma_f, range_m, self.lattice.step)
        return float(self.n_nodes * np.log(c) + 2.0 * np.sum(np.log(kh2 + self._eig)))

    # -- posterior at fixed theta -------------------------------------------------------------
    def _at_w(self, v: np.ndarray) -> np.ndarray:
        """Aᵀ v for a vector or an (n_obs, k) array."""
        return self.At @ v

    def posterior_precision(self, sigma_f: float, range_m: float, tau: float
                            ) -> tuple[sp.csc_matrix, np.ndarray]:
        """P = Q_aug + Aᵀ S⁻¹ A and the weights 1/(s² + tau²)."""
        w = 1.0 / (self.s**2 + tau**2)
        q = self.precision(sigma_f, range_m)
        P = sp.block_diag([q, sp.csc_matrix(np.array([[1.0 / self.v0]]))], format="csc")
        P = P + (self.At @ sp.diags(w) @ self.A)
        return P.tocsc(), w

    def field_block(self, sigma_f: float, range_m: float, tau: float
                    ) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        """P_uu in the model's fill-reducing order (``P_uu[order][:, order]``), the weights
        w = 1/(s² + tau²) per observation and d (their sums per node)."""
        kh2, c = spde_scales(sigma_f, range_m, self.lattice.step)
        w = 1.0 / (self.s**2 + tau**2)
        d = np.bincount(self.node, weights=w, minlength=self.n_nodes)
        data = (c * kh2**2) * self._parts[0] + (2 * c * kh2) * self._parts[1] \
            + c * self._parts[2]
        data[self._diag_at] += d
        Puu = sp.csc_matrix((data[self._src], self._ord_indices, self._ord_indptr),
                            shape=(self.n_nodes, self.n_nodes))
        return Puu, w, d

    def factor(self, sigma_f: float, range_m: float, tau: float) -> SpdeFactor:
        """Factorisation of P at theta: SuperLU of the field block P_uu (symmetric mode, the
        model's minimum-degree order) and beta's Schur complement (module docstring).

        Raises
        ------
        RuntimeError
            SuperLU finds P_uu numerically singular (far out in theta).
        """
        Puu, w, d = self.field_block(sigma_f, range_m, tau)
        lu = splu(Puu, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
        kh2, c = spde_scales(sigma_f, range_m, self.lattice.step)
        order = self._order
        z = np.empty(self.n_nodes)
        z[order] = lu.solve(d[order])
        schur = 1.0 / self.v0 + float(np.sum(w)) - float(d @ z)
        if not schur > 0:
            raise RuntimeError("the posterior precision is numerically singular "
                               f"(Schur complement of beta {schur!r})")
        return SpdeFactor(sigma_f, range_m, tau, lu, w, kh2, c, order, d, z, schur)

    def log_marginal(self, f: SpdeFactor) -> tuple[float, np.ndarray]:
        """Exact log p(y | theta) and the conditional posterior mean of x = (u, beta)."""
        r0 = self.y - self.m0
        b = self._at_w(f.w * r0)
        sol = f.solve(b)
        logdet_p = f.log_det()
        logdet_qaug = self.log_det_q(f.sigma_f, f.range_m) - np.log(self.v0)
        ll = (-0.5 * self.n_obs * np.log(2 * np.pi) + 0.5 * np.sum(np.log(f.w))
              + 0.5 * logdet_qaug - 0.5 * logdet_p + 0.5 * float(b @ sol)
              - 0.5 * float(f.w @ r0**2))
        mean = sol.copy()
        mean[-1] += self.m0
        return float(ll), mean

    def draw(self, f: SpdeFactor, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` exact draws of x = (u, beta) | y, theta, shape ``(n_latent, n)``.

        Perturbation-optimisation: with Q = MᵀM, M = sqrt(c)·K (K symmetric),
        x = P⁻¹(Q_aug x0 + AᵀS⁻¹y + Mᵀw1 + AᵀS^-1/2 w2 + w3/sqrt(v0)·e_beta), w ~ N(0, I),
        has mean P⁻¹(Q_aug x0 + AᵀS⁻¹y) and covariance P⁻¹(MᵀM + AᵀS⁻¹A + e eᵀ/v0)P⁻¹ = P⁻¹.
        """
        w1 = rng.standard_normal((self.n_nodes, n))
        w2 = rng.standard_normal((self.n_obs, n))
        w3 = rng.standard_normal(n)
        rhs = self._at_w((f.w * self.y)[:, None] + np.sqrt(f.w)[:, None] * w2)
        rhs[:-1] += np.sqrt(f.c) * (f.kh2 * w1 + self._L @ w1)
        rhs[-1] += self.m0 / self.v0 + w3 / np.sqrt(self.v0)
        return f.solve(rhs)
