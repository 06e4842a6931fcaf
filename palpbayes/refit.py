"""E under another contact model: refit a fitted force curve with E* linear.

A fit gives a force curve F̂ = E*·s(d) at the fitted depths.  Read with another contact model
s' (another tip radius, a layer instead of a half-space, the other base condition), the same
curve gives E*' = E*·(Σ s·s') / (Σ s'²) — the least-squares E* of F̂ under s'.  This is how the
uncertainty budget propagates a tip-radius or Poisson-ratio error, how a least-squares row says
what the layer correction would do to it, and how the two base conditions of a layer are set
side by side.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

__all__ = ["refit_factor", "fitted_depths", "layer_alternatives", "ALTERNATIVE_COLUMNS"]


def fitted_depths(z_surf: float, z: np.ndarray) -> np.ndarray:
    """[m] The depths in contact, z_surf − z > 0, of the fitted heights ``z`` [m]."""
    d = z_surf - np.asarray(z, dtype=float)
    return d[d > 0]


def refit_factor(depth: np.ndarray, shape_from: Callable[[np.ndarray], np.ndarray],
                 shape_to: Callable[[np.ndarray], np.ndarray]) -> float:
    """E*'/E* [-]: the factor by which E* changes when the curve E*·``shape_from`` at
    ``depth`` [m] is read with ``shape_to`` (least squares, E* linear); 1 without contact."""
    s = shape_from(depth)
    s2 = shape_to(depth)
    den = float(s2 @ s2)
    return float(s @ s2 / den) if den > 0 else 1.0


#: ``summary.csv`` columns of :func:`layer_alternatives`.
ALTERNATIVE_COLUMNS = ("E_halfspace_pa", "E_bonded_pa", "E_free_pa")


def layer_alternatives(E: float, z_surf: float, z: np.ndarray, fitted, model) -> dict:
    """E of the same fitted curve read as a half-space and as a bonded and a free layer [Pa].

    Parameters
    ----------
    E
        [Pa] The row's modulus, fitted with the concrete model ``fitted``.
    z_surf, z
        [m] The fit's surface and the fitted heights (the curve's depths).
    fitted
        The concrete :class:`~palpbayes.fitdata.ModelSpec` E belongs to.
    model
        The model with the specimen's layer (its known thickness, or the fitted one when
        ``fitted`` has a layer): bonded and free are NaN without a thickness, and the
        specimen's twin (:mod:`palpbayes.twin`) when ``model`` has a specimen.
    """
    out = dict.fromkeys(ALTERNATIVE_COLUMNS, float("nan"))
    depth = fitted_depths(z_surf, z)
    if not (np.isfinite(E) and depth.size):
        return out
    out["E_halfspace_pa"] = E * refit_factor(depth, fitted.shape, fitted.half_space().shape)
    h = model.thickness if model.thickness is not None else fitted.thickness
    if h is not None and np.isfinite(h):
        source = fitted if model.specimen is None else replace(fitted, specimen=model.specimen,
                                                               thickness=None)
        for base in ("bonded", "free"):
            alt = source.variant(thickness=h, base=base)
            out[f"E_{base}_pa"] = E * refit_factor(depth, fitted.shape, alt.shape)
    return out
