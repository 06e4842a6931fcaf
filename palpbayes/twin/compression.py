"""The compression test of the specimen twin: what an Instron reads on this block.

A compression test divides the platen force by the block's area and the crosshead travel by
its height: E_app = (F/A)/(delta/H).  Between frictionless (lubricated) platens the block is in
uniaxial stress and E_app = E exactly.  Bonded platens (or enough friction that the faces do
not slide) hold the faces' lateral expansion: the block bulges at its free side only, and
E_app > E, by how much depending on nu and the shape factor S = loaded area / free lateral
area (D/(4H) for a cylinder).  For a thin incompressible layer E_app → 2·S²·E (the "pressure
solution"; Gent & Lindley 1959 write E·(1 + 2·S²)), for a thin compressible one Chalhoub &
Kelly (1990)'s E_app = K·[1 − 2·I1(x)/(x·I0(x))], x² = 48·G·S²/K, and as S → ∞ the constrained
(oedometric) modulus E·(1 − nu)/((1 + nu)(1 − 2·nu)); the twin is checked against each
(``tests/unit/test_twin.py``).

**Model.**  The half of an axisymmetric cylinder (the cuboid's twin: the cylinder of equal
area, :class:`~palpbayes.specimen.Specimen`) above its mid-plane (u_z = 0 there, u_r
free: symmetry), the platen pushing its top face down by a unit strain: u_z prescribed, u_r = 0
(bonded) or free (lubricated).  The force is the platen's reaction; the mesh is graded towards
the platen's edge, where the bonded corner's stresses are singular.

References: A. N. Gent, P. B. Lindley, Proc. Inst. Mech. Eng. 173, 111–122 (1959);
M. S. Chalhoub, J. M. Kelly, J. Eng. Mech. 116, 1755–1770 (1990) (effect of bulk
compressibility on the stiffness of cylindrical bearings).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import GeometryError
from .cache import load_arrays, save_arrays
from .mesh import RESOLUTIONS, Resolution, compression_grid

__all__ = ["PLATENS", "compression_factor", "platen_factor", "oedometric_factor",
           "pressure_solution_factor"]

#: Platen conditions of a compression test: ``lubricated`` (frictionless: E exactly),
#: ``bonded`` (the faces cannot slide), ``unknown`` (either: an interval spanning both).
PLATENS = ("lubricated", "bonded", "unknown")


def platen_factor(radius_over_height: float, nu: float, platens: str,
                  resolution: str | Resolution = "default") -> float:
    """E_app/E [-] of a cylinder of radius/height ``radius_over_height`` compressed between
    ``platens`` (``"lubricated"`` or ``"bonded"``) (module docstring).  Lubricated platens give
    1 exactly (uniaxial stress; the finite elements reproduce it to 1e-12,
    ``tests/unit/test_twin.py``).

    Raises
    ------
    GeometryError
        An unknown platen condition or a non-positive aspect ratio.
    """
    if platens not in PLATENS[:2]:
        raise GeometryError(f"platens {platens!r}: the twin computes 'lubricated' or 'bonded' "
                            "(an unknown condition spans both)")
    if not (math.isfinite(radius_over_height) and radius_over_height > 0):
        raise GeometryError(f"radius/height {radius_over_height!r} must be positive")
    if platens == "lubricated":
        return 1.0
    key = resolution if isinstance(resolution, str) else None
    if key is not None:
        return _cached(round(float(radius_over_height), 9), round(float(nu), 9), platens, key)
    return _solve(float(radius_over_height), float(nu), platens, resolution)


#: Changes whenever the compression model or its mesh does (part of the disk cache's key).
_COMPRESSION_VERSION = 1


@functools.lru_cache(maxsize=512)
def _cached(aspect: float, nu: float, platens: str, resolution: str) -> float:
    """The factor of a named resolution, from memory, the disk cache
    (:mod:`palpbayes.twin.cache`: a fit needs the budget's five nodes of nu, each a finite
    element solve of ~0.15 s, in every process) or solved and stored."""
    key = {"kind": "compression", "version": _COMPRESSION_VERSION, "aspect": aspect, "nu": nu,
           "platens": platens, "resolution": resolution,
           "mesh": repr(RESOLUTIONS[resolution])}
    stored = load_arrays(key)
    if stored is not None and "factor" in stored and stored["factor"].shape == ():
        return float(stored["factor"])
    factor = _solve(aspect, nu, platens, RESOLUTIONS[resolution])
    save_arrays(key, {"factor": np.array(factor)})
    return factor


def _solve(aspect: float, nu: float, platens: str, res: Resolution) -> float:
    from .fe import AxisymmetricSolid  # scikit-fem is imported when a twin is first solved

    r_nodes, z_nodes = compression_grid(aspect, 0.5, res)
    solid = AxisymmetricSolid(r_nodes, z_nodes, nu)
    platen_z = solid.dofs("z", solid.on_top)
    fixed = [solid.dofs("r", solid.on_axis), solid.dofs("z", solid.on_bottom), platen_z]
    if platens == "bonded":
        fixed.append(solid.dofs("r", solid.on_top))
    fac = solid.factorize(np.concatenate(fixed))
    prescribed = np.zeros(fac.fixed.size)
    prescribed[np.isin(fac.fixed, platen_z)] = -0.5  # unit strain over the half-height 0.5
    x = fac.solve(np.zeros(solid.size), prescribed)
    force = -2.0 * math.pi * fac.reaction(x, platen_z).sum()
    return float(force / (math.pi * aspect * aspect))  # stress over unit strain, E = 1


def compression_factor(specimen, nu: float, platens: str,
                       resolution: str | Resolution = "default") -> float:
    """E_app/E [-] of the :class:`~palpbayes.specimen.Specimen` between ``platens``
    (its equal-area cylinder)."""
    return platen_factor(specimen.radius / specimen.height, nu, platens, resolution)


def oedometric_factor(nu: float) -> float:
    """The constrained modulus over E, (1 − nu)/((1 + nu)(1 − 2·nu)) [-]: a bonded block of
    infinite shape factor (inf at nu = 0.5)."""
    return math.inf if nu >= 0.5 else (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def pressure_solution_factor(shape_factor: float, nu: float) -> float:
    """Chalhoub & Kelly (1990)'s thin bonded cylinder, E_app/E [-] (E = 1): K·[1 −
    2·I1(x)/(x·I0(x))], x² = 48·G·S²/K; 2·S² at nu = 0.5 (the incompressible pressure
    solution).  Valid for S >> 1 and a nearly incompressible material: it takes the axial
    stress as the pressure alone, leaving out the shear's part (~4G/3, small only when
    K >> G).

    Raises
    ------
    ValueError
        For nu < 0.45, where that term is not small (at nu 0.3 the form falls below 1).
    """
    from scipy.special import ive

    if nu < 0.45:
        raise ValueError(f"the pressure solution holds for nearly incompressible layers "
                         f"(nu >= 0.45), not nu = {nu!r}; use oedometric_factor for a wide "
                         "compressible block")
    s = float(shape_factor)
    if nu >= 0.5:
        return 2.0 * s * s
    g = 1.0 / (2.0 * (1.0 + nu))
    k = 1.0 / (3.0 * (1.0 - 2.0 * nu))
    x = math.sqrt(48.0 * g * s * s / k)
    return k * (1.0 - 2.0 * ive(1, x) / (x * ive(0, x)))
