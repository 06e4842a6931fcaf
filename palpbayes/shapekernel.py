"""A model's shape function in the form the compiled loops take (:mod:`palpbayes._kernels`).

The exact engine, the paper's least squares and the depth check evaluate s(d) = F/E* [m²] at
every sample below every trial surface: (nodes × samples) evaluations, the hot loop of a fit.
The compiled loops do it without forming that array, with the law given as

* a **power law** s = g·d^m, evaluated exactly, for every half-space law that is one
  (flat punch, paraboloid, cone, power-law profile: :func:`palpbayes.contact.exponent`);
* a **table** otherwise (Sneddon's exact sphere, a finite layer, the specimen twin): s on the
  nodes d_i = d_top·(i/N)², N = :data:`TABLE_INTERVALS`, i.e. uniform in x = N·sqrt(d/d_top),
  in which every law is smooth down to d = 0 (a power law d^m is x^(2m)), and interpolated by
  the cubic through the four nearest nodes (error O(N^-4)).  Measured against the laws of
  :mod:`palpbayes.contact` (``tests/unit/test_shapekernel.py``): below 1e-14·s(d_top) for
  Sneddon's sphere; below 5e-8·s(d_top) for a layer, whose own factor
  (:mod:`palpbayes.contact.layer`) is a table with kinks.  d_top is the depth asked for,
  rounded up to a power of 2^(1/4), so that calls with nearby depth ranges share one table
  (an LRU cache per model).

Python sees only this module: the compiled loops are private.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import _kernels
from .contact import prefactor
from .errors import InputError
from .modelspec import ModelSpec

__all__ = ["CompiledShape", "compiled_shape", "cross_sums", "scale_rss", "TABLE_INTERVALS"]

#: Intervals of a shape table.
TABLE_INTERVALS = 4096
#: Tables are built up to a depth rounded up to a power of this factor.
_BUCKET = 2.0 ** 0.25


@dataclass(frozen=True, eq=False)
class CompiledShape:
    """A model's shape function s(d) [m²] for the compiled loops.

    Attributes
    ----------
    kind
        0: the power law ``g``·d^``m``; 1: the ``table`` on d_i = ``d_top``·(i/N)².
    g, m
        [m^(2−m)], [-] The power law's factor and exponent (NaN for a table).
    table
        [m²] s at the table's nodes (two zeros for a power law).
    d_top
        [m] Deepest node of the table (inf for a power law: any depth).
    """

    kind: int
    g: float
    m: float
    table: np.ndarray
    d_top: float

    def args(self) -> tuple:
        """The law's arguments of the compiled loops."""
        return self.kind, self.g, self.m, self.table, self.d_top

    def __call__(self, depth) -> np.ndarray:
        """s(d) [m²] at ``depth`` [m] (any shape; 0 at non-positive depth)."""
        d = np.asarray(depth, dtype=float)
        self._covers(float(np.max(d, initial=0.0)))
        flat = _kernels.shape_values(np.ascontiguousarray(d.ravel()), *self.args())
        return flat.reshape(d.shape)

    def _covers(self, d_max: float) -> None:
        if d_max > self.d_top * (1 + 1e-12):
            raise ValueError(f"depth {d_max:.6g} m beyond the shape table's {self.d_top:.6g} m")


def compiled_shape(model: ModelSpec, d_max: float) -> CompiledShape:
    """The shape function of a concrete ``model`` for depths up to ``d_max`` [m].

    Parameters
    ----------
    model
        A concrete contact model (:attr:`ModelSpec.is_concrete`).
    d_max
        [m] Deepest depth the caller will ask for (a table covers it; a power law any depth).
    """
    power = _power(model)
    if power is not None:
        return power
    d_max = float(d_max)
    if not math.isfinite(d_max):
        raise InputError(f"the depths of {model.describe()} are not finite (deepest "
                         f"{d_max}); the heights or the surface nodes hold NaN or inf")
    d_max = max(d_max, 1e-12)  # nothing in contact: any table serves
    d_top = _BUCKET ** math.ceil(math.log(d_max, _BUCKET))
    while d_top < d_max:  # rounding of the logarithm
        d_top *= _BUCKET
    return _table(model, d_top)


@lru_cache(maxsize=256)
def _power(model: ModelSpec) -> CompiledShape | None:
    """The model's power law, None when its law is none (looked up once per model)."""
    if model.exponent is None:
        return None
    return CompiledShape(0, float(prefactor(model.tip)), float(model.exponent), np.zeros(2),
                         math.inf)


@lru_cache(maxsize=256)
def _table(model: ModelSpec, d_top: float) -> CompiledShape:
    nodes = d_top * (np.arange(TABLE_INTERVALS + 1) / TABLE_INTERVALS) ** 2
    table = np.ascontiguousarray(model.shape(nodes), dtype=float)
    return CompiledShape(1, math.nan, math.nan, table, d_top)


def _same_rows(z: np.ndarray, x: np.ndarray, name: str) -> None:
    """The compiled loops read ``x`` row by row with ``z``: the lengths must agree."""
    if z.ndim != 1 or x.shape[0] != z.size:
        raise InputError(f"{name} has {x.shape[0]} rows for {z.size} heights z")


def _law_for(model: ModelSpec, nodes: np.ndarray, z: np.ndarray,
             d_max: float | None = None) -> CompiledShape:
    power = _power(model)
    if power is not None:  # any depth: no need to know the deepest
        return power
    need = float(np.max(nodes)) - float(np.min(z)) if nodes.size and z.size else 0.0
    return compiled_shape(model, need if d_max is None else max(need, float(d_max)))


def cross_sums(nodes, z, C, model: ModelSpec, lag: bool, d_max: float | None = None
               ) -> tuple[np.ndarray, ...]:
    """Sums over the samples of s_t = s(z_s − z_t) at every trial surface z_s.

    Parameters
    ----------
    nodes
        [m] Trial surface heights (G,).
    z
        [m] Sample heights in time order (k,).
    C
        (k, q) Fixed columns (e.g. 1, the baseline's regressor, the force).
    model
        The concrete contact model.
    lag
        Also the lag-one cross-products (AR(1) noise).
    d_max
        [m] The deepest depth of the caller's whole problem (e.g. the top of a surface
        prior less the lowest sample), so that a tabulated law is built once for all the
        calls of a refinement; default: this call's.

    Returns
    -------
    ss, sc, l00, l0c, lc0, s_first, s_last, n_contact
        Σ s², Σ s·C_j, Σ s_t·s_(t−1), Σ s_t·C_(t−1)j, Σ s_(t−1)·C_tj (zeros without
        ``lag``), s at the first and at the last sample, and the count of s > 0; one row per
        node.
    """
    nodes = np.ascontiguousarray(nodes, dtype=float)
    z = np.ascontiguousarray(z, dtype=float)
    C = np.ascontiguousarray(C, dtype=float)
    _same_rows(z, C, "C")
    return _kernels.cross_sums(nodes, z, C, *_law_for(model, nodes, z, d_max).args(),
                               bool(lag))


def scale_rss(nodes, z, force, model: ModelSpec) -> tuple[np.ndarray, np.ndarray]:
    """The paper's profile least squares F = E*·s(z_s − z) at each trial surface z_s.

    Parameters
    ----------
    nodes
        [m] Trial surface heights (G,).
    z, force
        [m], [N] The fitted samples.
    model
        The concrete contact model.

    Returns
    -------
    rss, estar
        L(z_s) = Σ (F − E*·s)² [N²] (summed from the residuals: no cancellation near a
        perfect fit) and E*(z_s) = Σ s·F / Σ s² [Pa]; Σ F² and 0 with no sample in contact.
    """
    nodes = np.ascontiguousarray(np.atleast_1d(nodes), dtype=float)
    z = np.ascontiguousarray(z, dtype=float)
    f = np.ascontiguousarray(force, dtype=float)
    _same_rows(z, f, "force")
    return _kernels.scale_rss(nodes, z, f, *_law_for(model, nodes, z).args())
